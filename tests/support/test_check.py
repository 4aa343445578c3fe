"""check_map: the independent re-check of the axioms, on maps that must pass and maps that must fail.

The last tests compare it with clingo on the same fixed partition: both read the same .lp rules, one by
grounding them, the other by re-implementing them, so any disagreement is a bug in one of the two.
"""

import re

import clingo
import numpy as np
import pytest
from clingo import Function, Number, String
from hypothesis import given, settings
from hypothesis import strategies as st

from bootmap import examples
from bootmap.mapping.theory import load_theory
from bootmap.mapping.facts import add_facts, tableau_facts
from bootmap.tableau import Tableau
from support.check import LEVELS, check_map, true_partition
from support.gridworld import GridWorld, random_world, scripted, walk

ALL = LEVELS
CAUSAL = ("causal",)
TOPO = ("causal", "topological")
METRIC = ("causal", "metrical")


def tableau(rows):
    """rows: (view, action) with action "T" (travel 2 m), an angle (turn) or None (last step)."""
    steps = []
    for view, a in rows:
        step = {"view": view}
        if a == "T":
            step["action"] = {"type": "travel", "distance_m": 2.0}
        elif a is not None:
            step["action"] = {"type": "turn", "angle_deg": a}
        steps.append(step)
    return Tableau.from_dict({"format": "bootmap.tableau/1", "steps": steps})


def rules_broken(violations):
    return {v.split(":", 1)[0] for v in violations}


# -- maps that pass --------------------------------------------------------------------------------

def test_paper_truth_passes(paper_tableau):
    assert check_map(paper_tableau, true_partition(paper_tableau)) == []


@pytest.mark.parametrize("build", [examples.square_room, examples.corridor, examples.one_way_run])
def test_example_truths_pass(build):
    t = build()
    assert check_map(t, true_partition(t)) == []


def test_true_partition_needs_truth():
    with pytest.raises(ValueError, match="truth"):
        true_partition(tableau([("A", None)]))


def test_partition_length_must_match():
    with pytest.raises(ValueError, match="time points"):
        check_map(tableau([("A", "T"), ("B", None)]), ["S0"])


# -- maps that fail --------------------------------------------------------------------------------

def test_merging_dstates_with_different_views_fails():
    w = GridWorld.from_ascii("+-+-+\n  |\n  +")
    t = walk(w, 40, np.random.default_rng(0), policy="explore")
    truth = true_partition(t)
    a, b = truth[0], next(s for s, step in zip(truth, t.steps) if step.view != t.steps[0].view)
    merged = [a if s == b else s for s in truth]
    assert any(v.startswith(f"one_value_per_feature: {a} shows view") for v in check_map(t, merged, CAUSAL))


def test_breaking_determinism_fails():
    t = tableau([("A", "T"), ("B", 180), ("B'", "T"), ("A", "T"), ("B", None)])
    assert check_map(t, ["S0", "S1", "S2", "S0", "S1"], CAUSAL) == []
    violations = check_map(t, ["S0", "S1", "S2", "S0", "S3"], CAUSAL)
    assert violations == ["deterministic_action: S0 --travel--> S1 and S3 (from t0, t3)"]


def test_paper_fold_of_four_fails_topology_only(paper_tableau):
    """The paper's point: causal experience alone allows 4 dstates; the topology (S4 lies right of a
    path S0's place is on) needs 8."""
    fold = [f"S{t % 4}" for t in range(len(paper_tableau))]
    assert check_map(paper_tableau, fold, CAUSAL) == []
    topo = check_map(paper_tableau, fold, TOPO)
    assert rules_broken(topo) == {"on_path_no_side"}
    assert all("right_by_turn" in v for v in topo)
    assert "on_path_no_side: place {S2,S3} is on S0's path and on its right (right_by_turn)" in topo
    # Heading alone also refutes it: S0 is seen facing 0 and 180 degrees.
    assert rules_broken(check_map(paper_tableau, fold, METRIC)) == {"one_value_per_feature"}


def test_triangle_fold_of_square_room_fails_metrical_only():
    """Four look-alike corners explained as three: consistent causally and topologically, but three
    right turns of 90 degrees are not a whole turn."""
    t = examples.square_room(circuits=3)
    triangle = [f"S{i % 6}" for i in range(len(t))]
    assert check_map(t, triangle, TOPO) == []
    violations = check_map(t, triangle, ALL)
    assert violations and all(v.startswith("one_value_per_feature") and "heading" in v for v in violations)


def test_one_way_run_folded_fails_order():
    t = examples.one_way_run(junctions=4)
    assert check_map(t, ["J"] * 4, METRIC) == []
    assert rules_broken(check_map(t, ["J"] * 4, TOPO)) == {"order_irreflexive", "order_asymmetric"}


def test_odd_turn_arounds_on_a_path_fail_one_direction():
    # A travels to B, B turns around to C, C travels to A: C faces both ways along A's path.
    t = tableau([("A", "T"), ("B", 180), ("C", "T"), ("A", None)])
    assert "one_direction" in rules_broken(check_map(t, ["A", "B", "C", "A"], TOPO))


def test_a_quarter_turn_onto_the_same_path_fails():
    # A turns right to B, and B travels back to A: the turn did not leave A's path.
    t = tableau([("A", -90), ("B", "T"), ("A", None)])
    assert "turn_leaves_path" in rules_broken(check_map(t, ["A", "B", "A"], TOPO))


def test_two_dstates_facing_one_way_at_a_place_fail():
    # Two turn-arounds in a row bring the robot back to its heading: a second dstate there is one too many.
    t = tableau([("A", 180), ("B", 180), ("A", None)])
    assert check_map(t, ["S0", "S1", "S0"], TOPO) == []
    assert rules_broken(check_map(t, ["S0", "S1", "S2"], TOPO)) == {"one_dstate_per_place_and_direction"}


def test_a_place_on_both_sides_fails():
    # A turns right and travels to P; A travels on to A2, which turns left and travels to P too. So P
    # is right of A's path (right_by_turn) and left of it (left_by_turn, carried back along the path).
    t = tableau([("a", -90), ("b", "T"), ("p", 180), ("q", "T"), ("b2", -90), ("a", "T"), ("a2", 90),
                 ("e", "T"), ("p", None)])
    names = ["A", "B", "P", "Q", "B2", "A", "A2", "E", "P"]
    violations = check_map(t, names, TOPO)
    assert "one_side: place {P,Q} is both right and left of A's path" in violations
    assert check_map(t, names, CAUSAL) == []


def test_violations_name_real_rules():
    """Every rule a message cites is a %! label of the shipped axioms."""
    labels = {r.name for r in load_theory().rules()}
    t = examples.one_way_run(junctions=4)
    cases = [check_map(examples.notched_rectangle(2), [f"S{i % 4}" for i in range(17)]),
             check_map(t, ["J"] * 4),
             check_map(tableau([("A", "T"), ("B", 180), ("C", "T"), ("A", -90), ("D", "T"), ("B", None)]),
                       ["A", "B", "C", "A", "D", "B"]),
             check_map(tableau([("A", 180), ("B", 180), ("A", None)]), ["S0", "S1", "S2"])]
    cited = set()
    for violations in cases:
        assert violations
        for v in violations:
            cited.add(v.split(":", 1)[0])
            cited |= set(re.findall(r"\((\w+)\)$", v))
    assert cited <= labels, cited - labels


# -- agreement with clingo on fixed partitions -----------------------------------------------------

def clingo_accepts(t: Tableau, dstate_of, levels) -> bool:
    """Ground the level files with each time point's dstate fixed (its only candidate) and solve."""
    theory = load_theory(None, list(levels))
    ctl = clingo.Control(["--warn=none"])
    for path in theory.levels.values():
        ctl.load(str(path))
    fixed = [Function("cand", [Number(i), String(str(d))]) for i, d in enumerate(dstate_of)]
    add_facts(ctl, tableau_facts(t) + fixed)
    ctl.ground([("base", [])])
    return ctl.solve().satisfiable


def coarsen(truth, views, rng, n_buckets):
    """Merge true dstates that share a view into at most n_buckets groups per view, then split a few
    time points off into dstates of their own."""
    bucket = {}
    for s, v in zip(truth, views):
        bucket.setdefault(s, f"{v}#{rng.integers(n_buckets)}")
    out = [bucket[s] for s in truth]
    for i in rng.choice(len(out), size=rng.integers(0, 3), replace=True):
        out[i] = f"{out[i]}~{i}"
    return out


@pytest.mark.parametrize("example", ["notched", "square"])
@pytest.mark.parametrize("levels", [CAUSAL, TOPO, METRIC, ALL], ids="+".join)
def test_agrees_with_clingo_on_folds(example, levels):
    t = examples.notched_rectangle(3) if example == "notched" else examples.square_room(3)
    for period in (2, 4, 6, 8):
        fold = [f"S{i % period}" for i in range(len(t))]
        assert (check_map(t, fold, levels) == []) == clingo_accepts(t, fold, levels), (period, levels)


@settings(max_examples=120, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), size=st.integers(2, 4), extra=st.integers(0, 3),
       n=st.integers(2, 50), n_buckets=st.integers(1, 4),
       levels=st.sampled_from([CAUSAL, TOPO, METRIC, ALL]), bends=st.sampled_from([0.0, 0.5, 1.0]))
def test_agrees_with_clingo_on_random_partitions(seed, size, extra, n, n_buckets, levels, bends):
    # With bends, travels change the heading, so the two must also agree on how a travel adds to it.
    rng = np.random.default_rng(seed)
    w = random_world(rng, size, size, extra_edges=extra, bends=bends)
    t = walk(w, n, rng, policy="random")
    partition = coarsen(true_partition(t), t.views, rng, n_buckets)
    violations = check_map(t, partition, levels)
    assert (violations == []) == clingo_accepts(t, partition, levels), violations


def test_agrees_with_clingo_where_a_fold_is_refuted_by_bends_alone():
    # A hallway whose junctions look alike and whose frames turn by 0, 30, 60, 90, walked east: folded
    # into one dstate it is a travel from that dstate to itself, which the causal level accepts; the
    # bends give the four time points the headings 0, 30, 60, 90, so the metrical level refutes it.
    # The same walk without bends is accepted: only the travels' heading changes make the difference.
    comb = GridWorld.from_ascii("+-+-+-+-+-+\n  | | | |\n  + + + +")
    bent = comb.with_frames({(2, 1): 30, (3, 1): 60, (4, 1): 90})
    fold = ["J"] * 4
    for world, refuted in ((comb, False), (bent, True)):
        t = scripted(world, ((1, 1), 0), ["travel"] * 3)
        violations = check_map(t, fold, METRIC)
        assert bool(violations) == refuted and rules_broken(violations) <= {"one_value_per_feature"}
        assert clingo_accepts(t, fold, METRIC) == (not refuted)
    assert check_map(t, ["J0", "J1", "J2", "J3"], METRIC) == []


def test_docstring_examples():
    import doctest

    import support.check

    assert doctest.testmod(support.check).failed == 0
