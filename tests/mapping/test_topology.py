"""The stock topological level read in Python (bootmap.mapping.topology) says what clingo says of it.

A search that leaves the topological level out asks it of every map it finds; under the stock file the
verdict and the reasons for a rejection are read in Python. These tests pin that the Python reading and
clingo's grounding of asp/topological.lp agree on random maps (small ones of every kind of action, and maps
of grid walks with two dstates of one class joined), that the reasons are a fewest set the level rejects
alone, that a changed file is asked of clingo only, and that a search with the Python reading finds the
maps a search with the level grounded finds.
"""

import numpy as np
import pytest
from clingo import Function, Number
from hypothesis import given, settings
from hypothesis import strategies as st

from bootmap.mapping.mapcheck import MapCheck
from bootmap.mapping.resolver import Resolver
from bootmap.mapping.stream import MapStream
from bootmap.mapping.theory import load_theory
from bootmap.mapping.topology import read_links, rejected_links, rejected_rule, rejects
from support.gridworld import random_world, walk

ACTIONS = [Function("travel"), Function("turn", [Number(180)]), Function("turn", [Number(90)]),
           Function("turn", [Number(-90)]), Function("turn", [Number(0)]), Function("turn", [Number(45)]),
           Function("travel", [Number(12)]), Function("travel", [Number(12), Number(-90)]),
           Function("travel", [Number(12), Number(90)]), Function("travel", [Number(12), Number(180)])]


def dstate(k: int, i: int):
    return Function("d", [Function("k", [Number(k)]), Number(i)])


def nxt(a, action, b):
    return Function("next", [a, action, b])


@pytest.fixture(scope="module")
def by_clingo() -> MapCheck:
    check = MapCheck(load_theory(), ("topological",))
    assert check.fast  # the stock file: read in Python unless told otherwise
    check.fast = False
    return check


def clingo_rejects(check: MapCheck, transitions) -> bool:
    dstates = {d for s in transitions for d in (s.arguments[0], s.arguments[2])}
    return check(list(transitions) + [Function("dstate", [d]) for d in dstates]) is None


maps = st.lists(st.tuples(st.integers(0, 5), st.integers(0, 5), st.integers(0, len(ACTIONS) - 1),
                          st.sampled_from([2, 6, 10])), min_size=1, max_size=12)


@settings(max_examples=400, deadline=None)
@given(maps)
def test_the_python_reading_rejects_exactly_the_maps_clingo_rejects(by_clingo, links):
    # (the third number picks among the first 2, 6 or 10 actions: travels and turn-arounds alone accept
    # more maps, where every action mixed is mostly rejected)
    transitions = list(dict.fromkeys(nxt(dstate(a % 3, a), ACTIONS[k % n], dstate(b % 3, b)) for a, b, k, n in links))
    assert rejects(transitions) == clingo_rejects(by_clingo, transitions)
    # read as a few links of a larger map (the reasons' search numbers their dstates afresh): the same rule
    numbered, n = read_links(transitions)
    assert rejected_links(numbered, n + 100) == rejected_rule(transitions)


@pytest.fixture(scope="module")
def by_python() -> MapCheck:
    return MapCheck(load_theory(), ("topological",))


@settings(max_examples=200, deadline=None)
@given(maps, st.booleans())
def test_what_the_python_reading_shows_is_what_clingo_shows(by_clingo, by_python, links, lone):
    # A map the level accepts is shown (places, paths and their directions, the order along paths, the
    # sides), each place and path named by its least dstate in clingo's order of terms: here dstates of
    # three kinds of term, and a dstate no transition touches.
    transitions = list(dict.fromkeys(nxt(dstate(a % 3, a), ACTIONS[k % n], dstate(b % 3, b)) for a, b, k, n in links))
    dstates = {d for s in transitions for d in (s.arguments[0], s.arguments[2])}
    if lone:
        dstates.add(Number(7))
    model = [Function("dstate", [d]) for d in dstates] + transitions + [Function("view_of", [Number(1), Number(2)])]
    shown, expected = by_python(model), by_clingo(model)
    assert (shown is None) == (expected is None)
    if shown is not None:
        assert sorted(map(str, shown)) == sorted(map(str, expected))
        assert any(s.name == "ahead" for s in shown) or not any(s.name == "ahead" for s in expected)
    # asked as a map and its ways to extend, one option at a time (a stream's new transitions)
    if len(transitions) > 1:
        base = [Function("dstate", [d]) for d in dstates] + transitions[:-1]
        options = [[transitions[-1]], []]
        for got, want in zip(by_python.each(base, options), by_clingo.each(base, options)):
            assert (got is None) == (want is None)
            if got is not None:
                assert sorted(map(str, got)) == sorted(map(str, want))


def walk_transitions(seed: int, steps: int = 120):
    """The true map of a grid walk, as transitions between its true dstates (place and heading)."""
    rng = np.random.default_rng(seed)
    tableau = walk(random_world(rng, 4, 3, extra_edges=2, landmarks=0.4), steps, rng, policy="explore")
    cmap = Resolver(time_limit=60).resolve(tableau)
    names = sorted(set(cmap.dstate_of))
    number = {name: i for i, name in enumerate(names)}
    view = {name: cmap.views[name] for name in names}
    out = set()
    for t, step in enumerate(tableau.steps[:-1]):
        a, b = cmap.dstate_of[t], cmap.dstate_of[t + 1]
        action = step.action
        angle = round(action.angle_deg) if action.kind == "turn" else 0
        symbol = Function("turn", [Number(180 if angle == -180 else angle)]) if action.kind == "turn" else Function("travel")
        out.add((number[a], symbol, number[b]))
    return out, names, view, number


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_on_grid_walks_with_two_dstates_joined_the_verdicts_agree(by_clingo, seed):
    links, names, view, number = walk_transitions(seed)
    rng = np.random.default_rng(seed)

    def as_symbols(merge: dict[int, int]):
        return [nxt(dstate(0, merge.get(a, a)), action, dstate(0, merge.get(b, b))) for a, action, b in links]

    assert not rejects(as_symbols({})) and not clingo_rejects(by_clingo, as_symbols({}))
    # the true map is shown as clingo shows it, places, paths, order and sides
    whole = as_symbols({})
    model = whole + [Function("dstate", [d]) for d in {x for s in whole for x in (s.arguments[0], s.arguments[2])}]
    assert sorted(map(str, MapCheck(load_theory(), ("topological",))(model))) == sorted(map(str, by_clingo(model)))
    # two dstates of one view joined: what a search with a dstate too few tries
    same_view = [(number[x], number[y]) for x in names for y in names if x < y and view[x] == view[y]]
    verdicts = []
    for i in rng.permutation(len(same_view))[:40]:
        x, y = same_view[i]
        transitions = list(dict.fromkeys(as_symbols({y: x})))
        verdicts.append(rejected_rule(transitions))
        assert rejects(transitions) == clingo_rejects(by_clingo, transitions), (x, y)
    assert any(v is not None for v in verdicts)


@settings(max_examples=100, deadline=None)
@given(maps)
def test_the_reasons_are_rejected_alone_and_none_can_be_left_out(links):
    transitions = list(dict.fromkeys(nxt(dstate(0, a), ACTIONS[k % n], dstate(0, b)) for a, b, k, n in links))
    check = MapCheck(load_theory(), ("topological",))
    reasons = check.reasons(transitions)
    if not rejects(transitions):
        assert reasons == []
        return
    assert reasons and set(reasons) <= set(transitions)
    assert rejects(reasons)
    for i in range(len(reasons)):
        assert not rejects(reasons[:i] + reasons[i + 1:])


@settings(max_examples=100, deadline=None)
@given(maps, maps)
def test_the_reasons_for_the_map_just_judged_are_those_of_a_fresh_reading(first, second):
    # A search asks for the reasons right after the verdict, on the same model: its transitions are read
    # once. Judged one map, then asked of another, the reasons are the other's, as a fresh check gives them.
    models = [[Function("dstate", [dstate(0, 9)])] + list(dict.fromkeys(
        nxt(dstate(0, a), ACTIONS[k % n], dstate(0, b)) for a, b, k, n in links)) for links in (first, second)]
    check = MapCheck(load_theory(), ("topological",))
    for judged, asked in ((0, 0), (0, 1), (1, 1)):
        check(models[judged])
        assert check.reasons(models[asked]) == MapCheck(load_theory(), ("topological",)).reasons(models[asked])


def test_a_changed_topological_file_is_asked_of_clingo(axioms_copy):
    copy = axioms_copy
    path = copy / "topological.lp"
    path.write_text(path.read_text() + "\n% a place never lies ahead of itself, said twice\n"
                                       ":- ahead(D, P), place_of(D, P).\n")
    assert not MapCheck(load_theory(copy), ("topological",)).fast
    assert MapCheck(load_theory(), ("topological",)).fast


def test_a_stream_with_the_python_reading_finds_the_maps_of_one_with_clingos(monkeypatch):
    # The stream's slowest steps search with a spare dstate per class: the maps the rest of the theory
    # allows are many, the level accepts a few (the reason the reading is in Python).
    rng = np.random.default_rng(3)
    tableau = walk(random_world(rng, 5, 4, extra_edges=4, landmarks=0.4), 160, rng, policy="explore")
    fast = MapStream(Resolver(time_limit=120))
    fast_maps = [fast.update(tableau.prefix(n)).to_dict() for n in range(60, 161, 4)]
    # the searches found maps the level rejects (and learned from them): the reading was asked
    assert sum(t["rejected"] for m in fast_maps for t in m["stats"]["bounds"]) > 0
    monkeypatch.setattr(MapCheck, "fast", False, raising=False)
    original = MapCheck.__init__

    def clingo_only(self, *args, **kwargs):
        original(self, *args, **kwargs)
        self.fast = False

    monkeypatch.setattr(MapCheck, "__init__", clingo_only)
    slow = MapStream(Resolver(time_limit=120))
    slow_maps = [slow.update(tableau.prefix(n)).to_dict() for n in range(60, 161, 4)]
    for a, b in zip(fast_maps, slow_maps):
        a.pop("stats"), b.pop("stats")
        assert a == b
