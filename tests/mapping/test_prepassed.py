"""Under the stock axioms, what a prepass derives (the classes, the features that tell time points of a
class apart) is worked out from the steps (replay.Prepassed): it must be what clingo's prepass derives,
and a resolution must give the same maps either way."""

import shutil

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from bootmap.examples import notched_rectangle
from bootmap.mapping import Resolver
from bootmap.mapping.facts import read_actions, tableau_facts, travel_lengths
from bootmap.mapping.grounding import Deadline, Grounding, prepass
from bootmap.mapping.replay import Prepassed, covers
from bootmap.mapping.theory import default_axioms_dir
from bootmap.mapping.vocabulary import CLASSES_GIVEN, ONE_PER_CLASS
from support.gridworld import random_world, walk
from support.noise import with_misreads, with_odometry_noise


def _tableau(seed: int, steps: int, noise: bool, misread: float, landmarks: float):
    rng = np.random.default_rng(seed)
    world = random_world(rng, 3 + seed % 3, 3 + (seed // 3) % 2, extra_edges=seed % 4, landmarks=landmarks)
    tableau = walk(world, steps, rng, policy="explore" if seed % 2 else "random")
    if noise:  # learned action types, travel lengths as a robot's odometry reads them
        tableau = with_odometry_noise(tableau, 3.0, 1.2, rng, distance_sd=0.03)
    # (a misread shows another view of the tableau: there must be two)
    return with_misreads(tableau, misread, rng)[0] if misread and len(set(tableau.views)) > 1 else tableau


def _both(tableau, resolver):
    angles, _ = read_actions(tableau)
    lengths = travel_lengths(tableau)
    grounded = prepass(resolver.theory, tableau_facts(tableau, angles=angles, lengths=lengths),
                       resolver.future_depth)
    stock = Prepassed(tableau.steps, angles, lengths, "metrical" in resolver.theory.levels, resolver.future_depth)
    return grounded, stock, angles, lengths


@settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck))
@given(seed=st.integers(0, 10 ** 6), steps=st.integers(2, 160), noise=st.booleans(),
       misread=st.sampled_from([0.0, 0.0, 0.04]), metrical=st.booleans(), landmarks=st.sampled_from([0.0, 0.4]),
       depth=st.sampled_from([1, 3, 8]))
def test_the_steps_give_what_the_prepass_derives(seed, steps, noise, misread, metrical, landmarks, depth):
    tableau = _tableau(seed, steps, noise, misread, landmarks)
    resolver = Resolver(levels=None if metrical else ["causal", "topological"], future_depth=depth)
    grounded, stock, _, _ = _both(tableau, resolver)
    n = len(tableau)
    # The classes: the same key terms, in the same order, the same members.
    classes, mine = grounded.classes(range(n)), stock.classes
    assert [str(k) for k in mine.keys] == [str(k) for k in classes.keys]
    assert (mine.of_time, mine.sizes, mine.prev) == (classes.of_time, classes.sizes, classes.prev)
    # The features: as many at each time point (the lower bounds' greedy order reads the counts), the same
    # time points apart, the same bounds, loners and inflators, with any views left out as suspects.
    theirs, ours = grounded.partial_features(classes.times), stock.features
    assert [len(ours.of[t]) for t in range(n)] == [len(theirs.of[t]) for t in range(n)]
    rng = np.random.default_rng(seed)
    for leave_out in [(), sorted(rng.choice(n, size=min(n, 1 + n // 20), replace=False).tolist()) if n else []]:
        a, b = theirs.without(leave_out), ours.without(leave_out)
        assert [len(a[t]) for t in range(n)] == [len(b[t]) for t in range(n)]
        for c, members in enumerate(_members(classes)):
            for i, s in enumerate(members):
                for u in members[i + 1:]:
                    assert _apart(a[s], a[u]) == _apart(b[s], b[u]), (s, u, leave_out)
        assert ours.lower_bounds(mine, leave_out) == theirs.lower_bounds(classes, leave_out)
        assert ours.loners(mine, leave_out) == theirs.loners(classes, leave_out)
        assert ours.inflators(mine, leave_out) == theirs.inflators(classes, leave_out)
    # Determinism over the classes, where it refutes one dstate per class, refutes it in clingo too.
    if stock.refutes_one_per_class():
        first = Grounding(resolver.theory, tableau_facts(tableau, angles=read_actions(tableau)[0],
                                                         lengths=travel_lengths(tableau)) + [ONE_PER_CLASS()], 0)
        assert not first.ground().solve(Deadline.after(30)).satisfiable


def _members(classes):
    out = [[] for _ in classes.sizes]
    for t, c in zip(classes.times, classes.of_time):
        out[c].append(t)
    return out


def _apart(a, b):
    from bootmap.mapping.grounding import _apart as apart
    return apart(a, b)


@pytest.fixture(scope="module")
def copied_axioms(tmp_path_factory):
    """The stock axioms with a comment added: the same theory, which the resolver no longer recognises
    as stock (so it grounds its prepasses)."""
    axioms = tmp_path_factory.mktemp("copy") / "asp"
    shutil.copytree(default_axioms_dir(), axioms)
    causal = axioms / "causal.lp"
    causal.write_text(causal.read_text() + "\n% a user's note\n")
    return axioms


@pytest.mark.parametrize("seed, steps, noise, misread", [(1, 300, False, 0.0), (2, 300, True, 0.0),
                                                          (3, 400, True, 0.02), (6, 300, False, 0.02),
                                                          (8, 250, False, 0.02), (5, 120, False, 0.0)])
def test_a_resolution_gives_the_same_maps_whether_the_prepass_is_grounded_or_worked_out(
        copied_axioms, seed, steps, noise, misread):
    tableau = _tableau(seed, steps, noise, misread, landmarks=0.3)
    stock, grounded = Resolver(time_limit=60), Resolver(axioms=copied_axioms, time_limit=60)
    assert stock.stock and not grounded.stock and not covers(grounded.theory)
    a, b = stock.resolve(tableau), grounded.resolve(tableau)
    assert (a.dstate_of, list(a.alternatives), a.n_models, a.minimal) == \
           (b.dstate_of, list(b.alternatives), b.n_models, b.minimal)
    assert [s["t"] for s in a.suspect_steps] == [s["t"] for s in b.suspect_steps]
    assert (a.stats.classes, a.stats.lower_bound) == (b.stats.classes, b.stats.lower_bound)


@pytest.mark.parametrize("seed, steps, metrical", [(4, 100, True), (7, 40, False)])
def test_a_search_under_the_stock_axioms_is_given_the_class_keys_and_folds_none(seed, steps, metrical):
    # The layout of a search on classes worked out from the steps gives each time point's key
    # (class_key/2 with classes_given): partition.lp then grounds none of its folding, and the search
    # has the same answers as one whose keys partition.lp folds itself.
    from dataclasses import replace

    tableau = _tableau(seed, steps, True, 0.0, landmarks=0.3)
    resolver = Resolver(levels=None if metrical else ["causal", "topological"])
    _, stock, angles, lengths = _both(tableau, resolver)
    facts = tableau_facts(tableau, angles=angles, lengths=lengths)
    classes = stock.classes
    cmap = resolver.resolve(tableau)
    bound = cmap.n_dstates  # every class with spare slots (each class's lower bound here 1): a search
    answers = {}
    for given in (True, False):
        layout = replace(classes, given=given).layout(bound)
        assert any(CLASSES_GIVEN.matches(x) for x in layout) == given
        grounding = Grounding(resolver.theory, facts + layout, resolver.future_depth, ["0"]).ground()
        atoms = grounding.control.symbolic_atoms
        folded = sum(1 for _ in atoms.by_signature("group_fold", 3))
        assert (folded == 0) == given
        keys = {a.symbol.arguments[0].number: str(a.symbol.arguments[1]) for a in atoms.by_signature("class_key", 2)}
        assert keys == {t: str(classes.keys[c]) for t, c in zip(classes.times, classes.of_time)}
        models = []
        grounding.solve(Deadline.after(60), lambda m: models.append(
            frozenset(str(x) for x in m.symbols(shown=True) if x.name == "is")))
        answers[given] = set(models)
    assert answers[True] == answers[False] and len(answers[True]) == cmap.n_models


def test_one_dstate_per_class_refuted_from_the_steps_is_not_grounded():
    # A 10,000-step exploration's one dstate per class fails by determinism over its classes: its first try
    # is recorded as refuted, with no grounding, and the map is the one a grounded first try leads to.
    from support.gridworld import random_world as world_of
    rng = np.random.default_rng(7)
    tableau = walk(world_of(rng, 5, 5, extra_edges=3, landmarks=0.3), 2000, rng, policy="explore")
    cmap = Resolver(time_limit=60).resolve(tableau)
    assert cmap.stats.bounds[0].dstates == "one dstate per class"
    assert cmap.stats.bounds[0].result == "unsat" and cmap.stats.bounds[0].seconds == 0.0
    assert cmap.n_dstates == 76 and cmap.unique and cmap.minimal
    # The paper's room: determinism over its classes holds, and one dstate per class is the map.
    paper = Resolver(time_limit=60).resolve(notched_rectangle(6))
    assert paper.stats.bounds[0].result == "sat" and paper.stats.bounds[0].seconds > 0


@pytest.mark.parametrize("seed", [1, 2, 22])
def test_a_mistyped_turn_is_retyped_the_same_whether_the_prepass_is_grounded_or_worked_out(copied_axioms, seed):
    # The retyping weighs each suspect action by the dstates the classes' lower bounds prove with and without
    # it retyped: a prepass per trial, grounded or worked out from the steps.
    from support.noise import with_mistyped_action
    rng = np.random.default_rng(seed)
    noisy = with_odometry_noise(walk(random_world(rng, 4, 3, extra_edges=2, landmarks=0.4), 120, rng,
                                     policy="explore"), 3.0, 1.2, rng)
    tableau, at = with_mistyped_action(noisy, rng)
    a = Resolver(time_limit=60).resolve(tableau)
    b = Resolver(axioms=copied_axioms, time_limit=60).resolve(tableau)
    assert [s["t"] for s in a.retyped_steps] == [s["t"] for s in b.retyped_steps]
    assert at in [s["t"] for s in a.retyped_steps]
    assert (a.dstate_of, a.n_models, a.stats.lower_bound) == (b.dstate_of, b.n_models, b.stats.lower_bound)


def _without_timings(cmap) -> dict:
    d = cmap.to_dict()
    d.pop("stats")
    return d


@pytest.mark.parametrize("make", ["paper", "paper, noisy", "paper, no metrical level", "grid prefix", "square room",
                                  "corridor"])
def test_one_dstate_per_class_checked_without_grounding_the_tableau_gives_the_grounded_first_tries_map(
        copied_axioms, make):
    # Where one dstate per class is the map, under the stock axioms it is checked in Python (determinism over
    # the classes, one travel length per dstate) and by the topological level on its dstates alone: the same
    # map, places, paths and sides as the first try grounded over every time point.
    levels = ["causal", "topological"] if make == "paper, no metrical level" else None
    rng = np.random.default_rng(5)
    if make.startswith("paper"):
        tableau = notched_rectangle(12)
        if make == "paper, noisy":
            tableau = with_odometry_noise(tableau, 3.0, 1.2, rng, distance_sd=0.03)
    elif make == "grid prefix":  # a landmark-rich world, early in its exploration
        tableau = walk(random_world(rng, 4, 4, extra_edges=2, landmarks=0.9), 400, rng, policy="explore").prefix(20)
    else:
        from bootmap.examples import corridor, square_room
        tableau = square_room(4) if make == "square room" else corridor(3)
    a = Resolver(levels=levels, time_limit=60).resolve(tableau)
    b = Resolver(axioms=copied_axioms, levels=levels, time_limit=60).resolve(tableau)
    assert a.stats.bounds[0].dstates == b.stats.bounds[0].dstates == "one dstate per class"
    assert a.stats.bounds[0].result == b.stats.bounds[0].result
    assert _without_timings(a) == _without_timings(b)
    if make in ("paper", "paper, noisy"):  # (without headings, the room's corners alias: a search)
        assert a.stats.bounds[0].result == "sat" and len(a.stats.bounds) == 1


@settings(max_examples=30, deadline=None, suppress_health_check=list(HealthCheck))
@given(seed=st.integers(0, 10 ** 6), steps=st.integers(2, 60), noise=st.booleans(), metrical=st.booleans())
def test_short_walks_resolve_to_the_same_maps_whether_the_first_try_is_grounded_or_replayed(
        copied_axioms, seed, steps, noise, metrical):
    # Early in an exploration of a landmark-rich world one dstate per class is often the map (checked from
    # the steps), and where it is not, what refuted it (determinism, a travel's length, the places and paths)
    # must be what the grounded first try finds.
    tableau = _tableau(seed, steps, noise, 0.0, landmarks=0.9)
    levels = None if metrical else ["causal", "topological"]
    a = Resolver(levels=levels, time_limit=60).resolve(tableau)
    b = Resolver(axioms=copied_axioms, levels=levels, time_limit=60).resolve(tableau)
    assert a.stats.bounds[0].result == b.stats.bounds[0].result
    assert _without_timings(a) == _without_timings(b)


@settings(max_examples=10, deadline=None)
@given(seed=st.integers(0, 10_000), spare=st.integers(0, 3))
def test_a_layouts_slots_are_read_from_its_lead_as_from_all_its_facts(seed, spare):
    # The search reads each class's slots from the layout before every grounding (its size, the renamings):
    # from the slots/2 facts that lead it, not from the thousands after them; the same as reading all.
    from bootmap.mapping.search.budget import layout_slots
    from bootmap.mapping.vocabulary import MINIMISE_DSTATES, SLOTS
    rng = np.random.default_rng(seed)
    tableau = walk(random_world(rng, 4, 3, extra_edges=2, landmarks=0.4), 120, rng, policy="explore")
    angles, _ = read_actions(tableau)
    classes = Prepassed(tableau.steps, angles, {}, True, 3).classes
    classes.lower = [1] * len(classes.sizes)
    layout = classes.layout(classes.lower_bound + spare) + [MINIMISE_DSTATES()]
    assert layout_slots(layout) == {key: m.number for key, m in SLOTS.args(layout)}
    assert len(layout_slots(layout)) == len(classes.sizes)
