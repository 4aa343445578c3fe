"""The levels that judge the map alone are asked of each map found, not searched with: the same maps.

A level whose rules read only the map's transitions and dstates (the topological one, or a user's level of
the same kind) is left out of the search and asked of every map the search finds (bootmap.mapping.mapcheck).
These tests pin which levels qualify, and that a resolver doing so gives exactly the maps of one that
searches with every level: where the level accepts every map found, where it rejects some, where it rejects
all of them, where the search is made again with it, and where it rejects every map there is.
"""

from contextlib import contextmanager
from unittest import mock

import clingo
import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from clingo import Function, Number

from bootmap import examples
from bootmap.errors import InconsistentTableau
from bootmap.mapping.facts import add_facts
from bootmap.mapping.grounding import Grounding
from bootmap.mapping.resolver import Resolver
from bootmap.mapping.search import exact
from bootmap.mapping.theory import load_theory
from support.gridworld import random_world, walk
from support.noise import with_misreads, with_odometry_noise



def said(cmap) -> dict:
    """What a map says, its solver figures aside."""
    d = cmap.to_dict()
    d.pop("stats")
    return d


def both(tableau, **kwargs):
    """The map of a resolver that asks the map's levels of each map found, and of one that searches with them."""
    deferred = Resolver(time_limit=120, **kwargs).resolve(tableau)
    searched = Resolver(time_limit=120, defer_map_levels=False, **kwargs).resolve(tableau)
    return deferred, searched


def results(cmap) -> list[str]:
    return [t.result for t in cmap.stats.bounds]


# --- which levels judge the map alone --------------------------------------------------------------------------

def test_the_topological_level_judges_the_map_alone_and_the_causal_and_metrical_levels_do_not():
    assert load_theory().map_levels == ("topological",)
    assert load_theory(levels=["causal", "metrical"]).map_levels == ()


def test_a_users_level_qualifies_by_what_its_rules_read(axioms_copy):
    # Reads only the map: deferred. Reads a time point's view, or an atom classically negated: searched
    # with. Derives what another file reads: searched with. Chooses: searched with. Shows a transition: searched
    # with.
    (axioms_copy / "nocycle.lp").write_text(
        "% No dstate is reached from itself by one travel.\n"
        "self_travel(D) :- next(D, travel, D).\n"
        ":- self_travel(D), dstate(D).\n"
        "#show self_travel/1.\n")
    (axioms_copy / "daylight.lp").write_text("bright(T) :- view(T, V), V != \"dark\".\n")
    (axioms_copy / "feeds.lp").write_text("hub(D) :- next(D, _, _).\n")
    (axioms_copy / "uses.lp").write_text(":- hub(D), time(D).\n")
    (axioms_copy / "chooses.lp").write_text("{ marked(D) } :- dstate(D).\n")
    (axioms_copy / "shows.lp").write_text("loop(D) :- next(D, _, D).\n#show next/3.\n")
    (axioms_copy / "negates.lp").write_text("lit(D) :- dstate(D), -lamp(D).\n")  # reads lamp/1, classically negated
    assert load_theory(axioms_copy).map_levels == ("nocycle", "topological")


def test_a_map_level_that_reads_only_itself_and_the_map_keeps_its_shown_atoms(axioms_copy, paper_tableau):
    # A user's level that only shows what it derives: its atoms are read from the check, and the map is
    # the same either way.
    (axioms_copy / "hubs.lp").write_text("% A dstate with two ways out.\n"
                                         "hub(D) :- next(D, A, _), next(D, B, _), A != B.\n#show hub/1.\n")
    theory = Resolver(axioms=axioms_copy).theory
    assert "hubs" in theory.map_levels
    deferred, searched = both(paper_tableau, axioms=axioms_copy)
    assert said(deferred) == said(searched)


# --- the same maps -------------------------------------------------------------------------------------------

def test_the_papers_tableau_is_found_without_the_topological_level_in_the_search(paper_tableau):
    deferred, searched = both(paper_tableau)
    assert said(deferred) == said(searched)
    assert (deferred.n_dstates, deferred.n_places, deferred.n_paths) == (8, 4, 4) and deferred.unique
    assert "unsettled" not in results(deferred)


def grid(seed: int):
    """A short walk of a small grid world (sizes, landmarks, loops and policy vary with the seed)."""
    rng = np.random.default_rng(seed)
    world = random_world(rng, *[(3, 3), (4, 3), (4, 4), (5, 4)][seed % 4], extra_edges=seed % 3,
                         landmarks=[0.0, 0.4][seed % 2])
    return walk(world, 40 + 5 * seed, rng, policy="explore" if seed % 2 else "random")


def not_monotone(axioms_copy):
    """The axiom copy with the topological level's word that it is monotone taken out: a level that judges
    the map alone but may accept a map with more transitions than one it rejects, never learned from."""
    path = axioms_copy / "topological.lp"
    path.write_text("\n".join(line for line in path.read_text().splitlines() if not line.startswith("% Monotone:")))
    assert Resolver(axioms=axioms_copy).theory.monotone_levels == ()
    return axioms_copy


@pytest.mark.parametrize("seed, levels, verdicts", [
    (1, None, "some rejected"),                        # the maps the topological level accepts are the answer
    (0, ["causal", "topological"], "none accepted"),   # none accepted, all enumerated: the bound is proved
    (2, ["causal", "topological"], "searched again"),  # capped before all were enumerated: searched with it
], ids=["some-rejected", "none-accepted", "searched-again"])
def test_where_a_level_not_known_monotone_rejects_maps_found_without_it_its_verdict_is_kept(
        seed, levels, verdicts, monkeypatch, axioms_copy):
    from bootmap.mapping.mapcheck import MapCheck

    axioms = not_monotone(axioms_copy)

    asked = []
    real = MapCheck.__call__

    def recorded(self, model):
        out = real(self, model)
        asked.append(out is not None)
        return out

    monkeypatch.setattr(MapCheck, "__call__", recorded)
    deferred, searched = both(grid(seed), levels=levels, axioms=axioms)
    assert said(deferred) == said(searched)
    assert ("unsettled" in results(deferred)) == (verdicts == "searched again")
    if verdicts == "some rejected":
        assert any(asked) and not all(asked)
    elif verdicts == "none accepted":
        assert asked and not any(asked)
    else:  # a capped enumeration settles nothing whatever the level says: it is not asked
        assert not asked


def test_a_map_level_that_rejects_every_map_gives_the_same_inconsistency(axioms_copy, paper_tableau):
    (axioms_copy / "never.lp").write_text("% No map at all.\n:- dstate(D).\n")
    errors = []
    for defer in (True, False):
        with pytest.raises(InconsistentTableau) as e:
            Resolver(axioms=axioms_copy, defer_map_levels=defer, time_limit=60).resolve(paper_tableau.prefix(40))
        errors.append((str(e.value), e.value.levels))
    assert errors[0] == errors[1] and "never" in errors[0][1]


@settings(max_examples=10, deadline=None)
@given(seed=st.integers(0, 10_000), steps=st.integers(20, 140), size=st.sampled_from([(3, 3), (4, 3), (4, 4)]),
       noisy=st.booleans(), landmarks=st.sampled_from([0.0, 0.4]))
def test_grid_explorations_give_the_same_maps_either_way(seed, steps, size, noisy, landmarks):
    rng = np.random.default_rng(seed)
    tableau = walk(random_world(rng, *size, extra_edges=seed % 3, landmarks=landmarks), steps, rng,
                   policy="explore" if seed % 2 else "random")
    if noisy:
        tableau = with_odometry_noise(tableau, 3.0, 1.2, rng, distance_sd=0.03)
    deferred, searched = both(tableau)
    assert said(deferred) == said(searched)


@pytest.mark.parametrize("seed", [1, 4])
def test_misread_views_give_the_same_maps_either_way(seed):
    tableau, _ = with_misreads(examples.notched_rectangle(6), 0.02, np.random.default_rng(seed))
    deferred, searched = both(tableau)
    assert said(deferred) == said(searched)


# --- learning from a rejected map: the level's word that it is monotone, and the reasons it gives -----------

def test_the_stock_topological_level_says_it_is_monotone_and_a_users_level_only_if_it_says_so(axioms_copy):
    assert load_theory().monotone_levels == ("topological",)
    (axioms_copy / "nocycle.lp").write_text("self_travel(D) :- next(D, travel, D).\n:- self_travel(D), dstate(D).\n")
    (axioms_copy / "hubs.lp").write_text("% Monotone: more transitions only make more hubs.\n"
                                         "hub(D) :- next(D, A, _), next(D, B, _), A != B.\n#show hub/1.\n")
    theory = load_theory(axioms_copy)
    assert theory.map_levels == ("hubs", "nocycle", "topological")
    assert theory.monotone_levels == ("hubs", "topological")


#: turns, a turn-around, a travel; and a log's travels (a length type, one that bent round a corner)
ACTIONS = ([Function("turn", [Number(a)]) for a in (90, -90, 180)] + [Function("travel")]
           + [Function("travel", [Number(20)])] + [Function("travel", [Number(20), Number(c)]) for c in (90, -90)])


def a_map(draw_edges, n: int) -> list:
    """A map's shown symbols: dstates 0..n-1 and the transitions ``(from, action index, to)``."""
    return ([Function("dstate", [Number(d)]) for d in range(n)]
            + [Function("next", [Number(a), ACTIONS[k], Number(b)]) for a, k, b in draw_edges])


edges = st.lists(st.tuples(st.integers(0, 5), st.integers(0, len(ACTIONS) - 1), st.integers(0, 5)), min_size=1, max_size=14,
                 unique=True)


@settings(max_examples=150, deadline=None)
@given(whole=edges, keep=st.lists(st.booleans(), min_size=14, max_size=14))
def test_the_stock_topological_level_is_monotone_as_it_says(whole, keep):
    # A map it rejects stays rejected with more transitions (and dstates): what the search's learning rests on.
    from bootmap.mapping.mapcheck import MapCheck

    check = MapCheck(load_theory(), ["topological"])
    part = [e for e, k in zip(whole, keep) if k]
    used = 1 + max([max(a, b) for a, _, b in part], default=0)
    if check(a_map(part, used)) is None:
        assert check(a_map(whole, 6)) is None


@settings(max_examples=150, deadline=None)
@given(whole=edges, names=st.permutations(range(6)))
def test_the_stock_topological_level_judges_a_map_by_its_shape_not_by_its_dstates_names(whole, names):
    # Renamed, a map is accepted or rejected as it was (the names order the places' and paths' names only):
    # what lets the search rule out a rejected map's reasons under every renaming of their dstates.
    from bootmap.mapping.mapcheck import MapCheck

    check = MapCheck(load_theory(), ["topological"])
    renamed = [(names[a], k, names[b]) for a, k, b in whole]
    assert (check(a_map(whole, 6)) is None) == (check(a_map(renamed, 6)) is None)


@settings(max_examples=60, deadline=None)
@given(whole=edges)
def test_the_reasons_for_a_rejection_are_rejected_alone_and_none_can_be_spared(whole):
    from bootmap.mapping.mapcheck import MapCheck

    check = MapCheck(load_theory(), ["topological"])
    model = a_map(whole, 6)
    reasons = check.reasons(model)
    dstates = [s for s in model if s.match("dstate", 1)]
    if check(model) is not None:
        assert reasons == []
        return
    assert reasons and set(reasons) <= set(model)
    assert check(dstates + reasons) is None
    for left_out in reasons:
        assert check(dstates + [r for r in reasons if r != left_out]) is not None


@contextmanager
def learning(share: float = 1e9):
    """Every search learns from the maps the level rejects (however small: the resolver learns only in large
    ones), for at most ``share`` times its grounding's seconds."""
    with mock.patch.object(exact, "LEARN_MIN_SIZE", 0), mock.patch.object(exact, "LEARN_SHARE", share):
        yield


def test_maps_the_level_rejects_are_learned_from_and_the_maps_are_the_same():
    # The 40-step walk of grid seed 1: maps the topological level rejects are found without it; the search
    # rules each out with the maps that share its reasons and ends at the maps of a search with the level.
    with learning():
        deferred, searched = both(grid(1))
    assert said(deferred) == said(searched)
    assert any(t.rejected for t in deferred.stats.bounds) and "unsettled" not in results(deferred)
    told = deferred.stats.to_dict()["bounds"]
    assert sum(b["rejected"] for b in told) == sum(t.rejected for t in deferred.stats.bounds)


def test_a_map_one_search_sets_aside_is_learned_from_before_the_next_one_solves():
    """A person's apart on a 2,000-step exploration: the search at the bound (103 dstates, no spare)
    finds one map the level rejects and sets it aside (an enumeration never finds a map twice); the search
    a dstate above learns from it before it solves, so no map the level rejects is met twice, and the
    answer is a fresh search's with the level."""
    from bootmap.mapping import mapcheck
    from bootmap.mapping.assertions import parse_assertions

    rng = np.random.default_rng(3)
    tableau = walk(random_world(rng, 6, 5, extra_edges=4, landmarks=0.4), 2000, rng, policy="explore")
    apart = parse_assertions([{"apart": [1000, 1158]}], len(tableau))
    checked = []
    real = mapcheck.MapCheck.__call__

    def check(self, model):
        verdict = real(self, model)
        if verdict is None:
            checked.append(frozenset(str(x) for x in model if x.match("next", 3)))
        return verdict

    solved = []  # the groundings solved, in order
    real_solve = Grounding.solve

    def solve(self, *args, **kwargs):
        solved.append(self)
        return real_solve(self, *args, **kwargs)

    with mock.patch.object(mapcheck.MapCheck, "__call__", check), mock.patch.object(Grounding, "solve", solve):
        cmap = Resolver(time_limit=120).resolve(tableau, assertions=apart)
    tries = [(t.dstates, t.result, t.rejected) for t in cmap.stats.bounds]
    assert [t[:2] for t in tries[-2:]] == [("at most 103 dstates", "unsat"), ("at most 104 dstates", "sat")], tries
    assert tries[-2][2] == 1 and tries[-1][2] >= 1  # one map set aside at 103, learned from at 104
    assert len(checked) == len(set(checked)) == tries[-2][2] + tries[-1][2]  # the set-aside map is not met again
    assert cmap.n_dstates == 104 and cmap.minimal
    # Both bounds were searched on one grounding (104 dstates, the spares held empty for 103), not one each
    # (the first try, one dstate per class, before them on its own).
    assert len(solved) == 3 and solved[1] is solved[2] and solved[0] is not solved[1]


@settings(max_examples=12, deadline=None)
@given(seed=st.integers(0, 10_000), steps=st.integers(30, 120), size=st.sampled_from([(3, 3), (4, 3), (4, 4)]),
       pair=st.tuples(st.floats(0, 1), st.floats(0, 1)))
@pytest.mark.slow
def test_a_bound_searched_with_its_spares_held_empty_gives_the_maps_of_a_search_with_the_level(seed, steps, size,
                                                                                                pair):
    """A person's hard apart of two time points of one class, every search learning (so the search at the
    lower bound is grounded a dstate up, its spare slots held empty, and that grounding serves the search a
    dstate up): the maps of a search with the level, which grounds each bound on its own."""
    from bootmap.mapping.assertions import parse_assertions

    rng = np.random.default_rng(seed)
    tableau = walk(random_world(rng, *size, extra_edges=seed % 3, landmarks=0.4 * (seed % 2)), steps, rng,
                   policy="explore" if seed % 2 else "random")
    a, b = sorted(int(x * (len(tableau) - 1)) for x in pair)
    same_view = [t for t in range(len(tableau)) if tableau.views[t] == tableau.views[a] and t != a]
    b = min(same_view, key=lambda t: abs(t - b), default=None)
    assume(b is not None)
    apart = parse_assertions([{"apart": [a, b]}], len(tableau))
    with learning():
        try:
            deferred = Resolver(time_limit=120).resolve(tableau, assertions=apart)
        except InconsistentTableau:
            deferred = None
        try:
            searched = Resolver(time_limit=120, defer_map_levels=False).resolve(tableau, assertions=apart)
        except InconsistentTableau:
            searched = None
    assert (deferred is None) == (searched is None)
    if deferred is not None:
        assert said(deferred) == said(searched)


@contextmanager
def asked_of_clingo():
    """The topological level's verdicts asked of clingo, as for a level a user changed (not read in Python)."""
    from bootmap.mapping import mapcheck

    real = mapcheck.MapCheck.__init__

    def init(self, *args, **kwargs):
        real(self, *args, **kwargs)
        self.fast = False

    with mock.patch.object(mapcheck.MapCheck, "__init__", init):
        yield


def test_where_learning_would_take_longer_than_grounding_the_level_the_search_grounds_it():
    with learning(share=0.0), asked_of_clingo():  # no time to learn: the first map rejected ends it
        deferred, searched = both(grid(1))
    assert said(deferred) == said(searched)
    assert "unsettled" in results(deferred)


def test_why_the_level_rejected_maps_at_one_bound_is_ruled_out_at_every_later_one():
    """A stream's resolve that climbs (a 6x5 exploration's 265th step: 100 dstates refuted, then the
    fewest within 102 found, 102): the transitions the level rejected a map for at one bound reject any map
    they are in, so every later search rules them out before it solves, and no map it finds holds them
    again."""
    from bootmap.mapping import mapcheck

    rng = np.random.default_rng(71)
    tableau = walk(random_world(rng, 6, 5, extra_edges=4, landmarks=0.4), 2000, rng, policy="explore").prefix(265)
    learned: list[tuple[int, frozenset]] = []  # (the grounding searched, the transitions a rejection was learned for)
    met_again = []
    solved = []
    real_reasons, real_solve = mapcheck.MapCheck.reasons, Grounding.solve

    def reasons(self, model):
        found = real_reasons(self, model)
        transitions, now = {str(x) for x in model if x.match("next", 3)}, id(solved[-1])
        met_again.extend(r for where, r in learned if where != now and r <= transitions)
        learned.append((now, frozenset(str(x) for x in found)))
        return found

    def solve(self, *args, **kwargs):
        solved.append(self)
        return real_solve(self, *args, **kwargs)

    with mock.patch.object(mapcheck.MapCheck, "reasons", reasons), mock.patch.object(Grounding, "solve", solve):
        cmap = Resolver(time_limit=120).resolve(tableau, at_least=100)
    tries = [(t.dstates, t.result, t.rejected > 0) for t in cmap.stats.bounds]
    assert tries == [("at most 100 dstates", "unsat", True), ("at most 102 dstates", "sat", True)], tries
    assert not met_again and len({where for where, _ in learned}) >= 2
    assert cmap.n_dstates == 102 and cmap.minimal


def test_read_in_python_the_level_is_learned_from_to_the_end():
    # Its verdicts cost a millisecond: learning is never given up for a grounding of the level (which the
    # budget, having seen only searches without it, cannot foresee).
    with learning(share=0.0):
        deferred, searched = both(grid(1))
    assert said(deferred) == said(searched)
    assert "unsettled" not in results(deferred) and any(t.rejected for t in deferred.stats.bounds)


@settings(max_examples=10, deadline=None)
@given(seed=st.integers(0, 10_000), steps=st.integers(20, 140), size=st.sampled_from([(3, 3), (4, 3), (4, 4)]),
       noisy=st.booleans(), misreads=st.booleans())
def test_learning_from_rejected_maps_gives_the_maps_of_a_search_with_the_level(seed, steps, size, noisy, misreads):
    rng = np.random.default_rng(seed)
    tableau = walk(random_world(rng, *size, extra_edges=seed % 3, landmarks=0.4 * (seed % 2)), steps, rng,
                   policy="explore" if seed % 2 else "random")
    if noisy:
        tableau = with_odometry_noise(tableau, 3.0, 1.2, rng, distance_sd=0.03)
    if misreads:
        tableau, _ = with_misreads(tableau, 0.03, rng)
    with learning():
        deferred, searched = both(tableau)
    assert said(deferred) == said(searched)


def test_a_renamed_reason_keeps_each_dstate_in_its_class_and_different_dstates_apart():
    # Rejected transitions, renamed: each dstate to a slot of its own class the grounding has, two dstates
    # of one class to two slots, every renamed transition one the grounding has.
    from bootmap.mapping.search.exact import Renamings
    from bootmap.mapping.vocabulary import CANDIDATE_DSTATE, NEXT

    a, b = Function("k", [Number(1)]), Function("k", [Number(2)])
    turn = Function("turn", [Number(180)])
    ctl = clingo.Control(["--warn=none"])
    ctl.add("base", [], "{ next(d(K, I), A, d(K2, J)) : edge(K, I, A, K2, J) }.")
    edges = [(a, i, turn, b, j) for i in range(3) for j in range(2)] + [(b, j, turn, a, i) for i in range(3)
                                                                         for j in range(2)]
    add_facts(ctl, [Function("edge", [k, Number(i), act, k2, Number(j)]) for k, i, act, k2, j in edges])
    ctl.ground([("base", [])])
    # a turn-around from a dstate of class a to one of class b, and back to another dstate of class a
    x, y, z = CANDIDATE_DSTATE(a, 0), CANDIDATE_DSTATE(b, 0), CANDIDATE_DSTATE(a, 1)
    renamings = Renamings(ctl.symbolic_atoms, {a: 3, b: 2})([NEXT(x, turn, y), NEXT(y, turn, z)])
    names = {tuple(str(s) for s, _ in r) for r in renamings}
    assert len(names) == len(renamings) == 3 * 2 * 2  # x: 3 slots, y: 2, z: a slot of a other than x's
    for r in renamings:
        (first, lit1), (second, lit2) = r
        assert first.arguments[2] == second.arguments[0] and first.arguments[0] != second.arguments[2]
        assert ctl.symbolic_atoms[first].literal == lit1 and ctl.symbolic_atoms[second].literal == lit2


def crowded(axioms_copy, most: int):
    """A user's monotone level that rejects a map of more than ``most`` dstates."""
    (axioms_copy / "crowded.lp").write_text(
        "% Monotone: more dstates and transitions never make fewer dstates.\n"
        f"crowded :- #count {{ D : dstate(D) }} > {most}.\n:- crowded.\n")
    theory = load_theory(axioms_copy)
    assert "crowded" in theory.monotone_levels
    return theory


def test_a_reason_is_the_transitions_of_a_map_the_level_rejects_with_no_other_dstate(axioms_copy):
    # Rejected for its dstates, a map's reasons are transitions that reach too many; where its transitions
    # reach few (the other dstates reached by none), there is no reason: a map with those transitions
    # and nothing else is accepted, and nothing may be ruled out beside this map.
    from bootmap.mapping.mapcheck import MapCheck

    check = MapCheck(crowded(axioms_copy, 2), ["crowded"])
    travel = ACTIONS.index(Function("travel"))
    isolated = a_map([(0, travel, 1)], 6)
    assert check(isolated) is None and check.reasons(isolated) == []
    chain = a_map([(0, travel, 1), (1, travel, 2), (2, travel, 3)], 4)
    reasons = check.reasons(chain)
    assert len(reasons) == 2 and check(a_map([(0, travel, 1)], 2)) is not None
    reached = {d for s in reasons for d in (s.arguments[0], s.arguments[2])}
    assert check([Function("dstate", [d]) for d in reached] + reasons) is None


def test_learning_from_a_level_that_counts_dstates_gives_the_maps_of_a_search_with_it(axioms_copy):
    searched = Resolver(time_limit=120, defer_map_levels=False).resolve(grid(1))
    crowded(axioms_copy, searched.n_dstates)
    with learning():
        deferred, searched = both(grid(1), axioms=axioms_copy)
    assert said(deferred) == said(searched)


@settings(max_examples=100, deadline=None)
@given(whole=edges, options=st.lists(edges, min_size=1, max_size=4))
def test_one_grounding_judges_each_way_to_extend_a_map_as_a_check_of_each_would(whole, options):
    # What a stream asks of the maps a new step extends one map into: each option's transitions added to the
    # map (a new dstate 6 among them), in one grounding with each option assumed in turn.
    from bootmap.mapping.mapcheck import MapCheck

    check = MapCheck(load_theory(), ["topological"])
    base = a_map(whole, 6)
    added = [[Function("next", [Number(a), ACTIONS[k], Number(b + (b == 5))]) for a, k, b in o
              if (a, k, b) not in whole] for o in options]
    shown = check.each(base, added)
    for option, got in zip(added, shown):
        alone = check(base + option + [Function("dstate", [Number(6)])] * any(s.arguments[2].number == 6
                                                                               for s in option))
        assert (got is None) == (alone is None)
        if got is not None:
            assert sorted(map(str, got)) == sorted(map(str, alone))


def test_a_search_that_learns_from_many_rejected_maps_is_not_cut_short_by_its_small_grounding():
    # A 287-step exploration of a 6x6 grid, resolved from the 118 dstates a stream of it proves: the
    # topological level rejects 27 maps before the minimal one, each learned from (a few seconds in all),
    # where the search with the level in it took 43 s. Learning once stopped at five times its grounding's
    # time (0.06 s) and gave way to that search; it may now take half the time left.
    rng = np.random.default_rng(23)
    tableau = walk(random_world(rng, 6, 6, extra_edges=4, landmarks=0.4), 2000, rng, policy="explore").prefix(287)
    cmap = Resolver(time_limit=120).resolve(tableau, at_least=118)
    assert [(t.result, t.rejected > 0) for t in cmap.stats.bounds] == [("sat", True)]
    assert cmap.n_dstates == 118 and cmap.minimal
