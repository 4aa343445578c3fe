"""The evaluation SLAM papers report, on hand-made cases with known answers: the map beside its baselines,
loop-closure precision and recall, place recognition as precision-recall."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.distance import cdist

from bootmap.experiments.evaluate import (MATCH_SCORE, against_baselines, loop_closure, place_recognition,
                                          reach_after_joins, reanchored_reach, revisit_candidates,
                                          sector_of_truth, within_reach)
from bootmap.ingest.truth import true_dstates, visit_positions

# Five visits on a line: 0 and 3 at one pose, 4 back near 2, 1 alone; the robot leaves each place between,
# so visit 1 has no earlier candidate (it is the first the robot reaches after leaving 0), 2 has 0, 3 has 0
# and 1, 4 has 0, 1 and 2.
POSES = [(0.0, 0.0, 0.0), (10.0, 0.0, 0.0), (20.0, 0.0, 0.0), (0.0, 0.0, 3.1), (20.5, 0.0, 0.0)]


def _near(poses, radius_m=3.0) -> np.ndarray:
    xy = np.asarray(poses, dtype=float)[:, :2]
    return cdist(xy, xy) <= radius_m


def test_only_earlier_visits_the_robot_has_left_are_candidates():
    # A turn's two ends (0 and 1 at one pose) are not a revisit; 3 comes back to 0 after leaving it.
    c = revisit_candidates([(0, 0), (0, 0), (10, 0), (0, 0)])
    assert [np.flatnonzero(row).tolist() for row in c] == [[], [], [], [0, 1]]


def test_a_perfect_score_matrix_recalls_every_revisit_at_full_precision():
    r = place_recognition(_near(POSES).astype(float), POSES)
    assert (r["visits"], r["queries"], r["revisits"], r["best_correct"]) == (5, 3, 2, 2)
    assert r["recall_at_95_precision"] == r["recall_at_99_precision"] == r["average_precision"] == 1.0


def test_a_reversed_score_matrix_recalls_nothing():
    r = place_recognition(-_near(POSES).astype(float), POSES)
    assert r["best_correct"] == 0
    assert r["recall_at_95_precision"] == r["recall_at_99_precision"] == r["average_precision"] == 0.0


def test_a_confident_wrong_match_costs_precision_at_its_threshold():
    scores = _near(POSES).astype(float)
    scores[2, 0] = 5.0  # visit 2 has no true revisit, yet matches visit 0 above everything else
    r = place_recognition(scores, POSES)
    assert r["curve"][0] == {"threshold": 5.0, "precision": 0.0, "recall": 0.0}
    assert r["curve"][-1]["recall"] == 1.0 and r["curve"][-1]["precision"] == pytest.approx(2 / 3)
    assert r["recall_at_95_precision"] == 0.0


def test_a_look_alike_beyond_odometrys_reach_is_no_match():
    # Visit 2 looks like visit 0 (a score above all), but odometry puts them 20 m apart after 20 m driven:
    # searched within odometry's reach, 2 makes no detection and precision is whole again.
    scores = _near(POSES).astype(float)
    scores[2, 0] = 5.0
    driven = [0.0, 10.0, 20.0, 40.0, 60.0]
    allowed = within_reach(POSES, driven)
    assert not allowed[2, 0] and allowed[3, 0] and allowed[4, 2]
    r = place_recognition(scores, POSES, allowed=allowed)
    assert (r["queries"], r["revisits"], r["best_correct"]) == (3, 2, 2)
    assert r["recall_at_95_precision"] == 1.0 and r["curve"][0]["threshold"] == 1.0


def test_a_true_revisit_odometry_rules_out_is_a_miss():
    # Odometry drifted: visit 3 (a true revisit of 0) is dead-reckoned 30 m from it after 40 m driven.
    odometry = [(0.0, 0.0), (10.0, 0.0), (20.0, 0.0), (30.0, 0.0), (20.5, 0.0)]
    r = place_recognition(_near(POSES).astype(float), POSES, allowed=within_reach(odometry, [0, 10, 20, 40, 60]))
    assert (r["queries"], r["revisits"], r["best_correct"]) == (3, 2, 1)
    assert r["recall_at_99_precision"] == 0.5


@settings(max_examples=40, deadline=None)
@given(poses=st.lists(st.tuples(st.floats(0, 30), st.floats(0, 30)), min_size=2, max_size=25),
       seed=st.integers(0, 2**16))
def test_searching_within_reach_keeps_the_queries_and_revisits_and_never_detects_more(poses, seed):
    rng = np.random.default_rng(seed)
    scores = rng.normal(size=(len(poses), len(poses)))
    odometry = np.asarray(poses) + rng.normal(scale=2.0, size=(len(poses), 2))
    driven = np.cumsum(rng.uniform(0, 20, len(poses)))
    everywhere, reached = place_recognition(scores, poses), place_recognition(scores, poses, allowed=within_reach(
        odometry, driven))
    assert (reached["queries"], reached["revisits"]) == (everywhere["queries"], everywhere["revisits"])
    assert len(reached["curve"]) <= len(everywhere["curve"]) and reached["best_correct"] <= reached["revisits"]
    # Everything allowed is the search of every candidate.
    assert place_recognition(scores, poses, allowed=np.ones((len(poses),) * 2, bool)) == everywhere


def _corridor_twice():
    """A 40 m corridor driven out and back, then out again, a visit every 10 m (the true poses), odometry
    falling behind by 5 cm a metre driven: by the second lap it puts a visit metres from where it was.
    Visits 0-4 go out, 5-8 come back, 9-12 go out again."""
    xs = [0, 10, 20, 30, 40, 30, 20, 10, 0, 10, 20, 30, 40]
    poses = [(float(x), 0.0) for x in xs]
    driven = 10.0 * np.arange(len(xs))
    odometry = [(x - 0.05 * d, 0.0) for x, d in zip(xs, driven)]
    return poses, odometry, driven


def test_a_recognised_revisit_reanchors_the_visits_after_it_and_rules_out_the_look_alike():
    poses, odometry, driven = _corridor_twice()
    scores = _near(poses).astype(float) * 0.8  # each true revisit is recognised
    # the corridor looks alike all along: visit 11 (at 30 m) looks most like visit 2 (at 20 m), 10 m away,
    # which odometry puts 5.5 m away, within the drive's reach (3 m + 5% of 90 m)
    scores[11, 2] = 0.9
    plain = within_reach(odometry, driven)
    assert plain[11, 2]
    reach = reanchored_reach(odometry, driven, scores)
    # visit 10 recognised visit 2: from visit 11 back through that revisit (10 m of drive and a radius's
    # 60 m), odometry puts 2 9.5 m away, out of reach (3 m + 3.5 m); visit 3, its true match, 10 m on from 2,
    # lies where visit 11 is
    assert not reach[11, 2] and reach[11, 3]
    before, after = place_recognition(scores, poses, allowed=plain), place_recognition(scores, poses, allowed=reach)
    assert after["revisits"] == before["revisits"] and after["best_correct"] == before["best_correct"] + 1
    assert before["recall_at_95_precision"] == 0.0 and after["recall_at_95_precision"] == 1.0
    # the map's joins re-anchor the same way: its dstates are the true places here
    assert reach_after_joins(odometry, driven, [x for x, _ in poses])[11].tolist() == reach[11].tolist()


@settings(max_examples=40, deadline=None)
@given(n=st.integers(1, 20), seed=st.integers(0, 2**16), cut=st.integers(1, 20))
def test_reanchored_reach_is_the_drives_until_a_revisit_and_reads_only_what_came_before(n, seed, cut):
    rng = np.random.default_rng(seed)
    odometry = rng.uniform(0, 30, (n, 2))
    driven = np.cumsum(rng.uniform(0, 20, n))
    scores = rng.uniform(0, 1, (n, n))
    lower = np.tril(within_reach(odometry, driven), -1)
    # no match strong enough, no join: the drive's own reach, earlier visits only
    assert (reanchored_reach(odometry, driven, scores * MATCH_SCORE * 0.99) == lower).all()
    assert (reach_after_joins(odometry, driven, range(n)) == lower).all()
    # a visit's reach depends on the visits before it and their matches only (what the robot knew then)
    m = min(cut, n)
    reach = reanchored_reach(odometry, driven, scores)
    assert (reanchored_reach(odometry[:m], driven[:m], scores[:m, :m]) == reach[:m, :m]).all()
    labels = rng.integers(0, 4, n)
    assert (reach_after_joins(odometry[:m], driven[:m], labels[:m]) == reach_after_joins(
        odometry, driven, labels)[:m, :m]).all()


def test_reanchoring_refuses_scores_or_labels_of_the_wrong_size():
    with pytest.raises(ValueError, match="scores of shape"):
        reanchored_reach(POSES, [0, 1, 2, 3, 4], np.zeros((3, 3)))
    with pytest.raises(ValueError, match="labels for 5 visits"):
        reach_after_joins(POSES, [0, 1, 2, 3, 4], "ab")


def test_without_revisits_recall_is_not_measured():
    line = [(10.0 * k, 0.0) for k in range(4)]
    r = place_recognition(np.zeros((4, 4)), line)
    assert r["revisits"] == 0 and r["recall_at_95_precision"] is None and r["average_precision"] is None


def test_a_score_matrix_of_the_wrong_shape_is_refused():
    with pytest.raises(ValueError, match="scores of shape"):
        place_recognition(np.zeros((3, 3)), POSES)


def test_loop_closure_counts_the_joins_against_the_corrected_poses():
    truth = ["P0:E", "P1:E", "P2:E", "P0:W", "P2:E"]
    sectors = [sector_of_truth(t) for t in truth]
    # The map joins 0 with 3 (one place, but facing the other way) and 2 with 4 (right).
    labels = ["S0", "S1", "S2", "S0", "S2"]
    places = loop_closure(labels, POSES)
    assert places == {"joins": 2, "true_joins": 2, "should_join": 2, "precision": 1.0, "recall": 1.0}
    dstates = loop_closure(labels, POSES, sectors=sectors)
    assert dstates == {"joins": 2, "true_joins": 1, "should_join": 1, "precision": 0.5, "recall": 1.0}


def test_a_map_that_joins_nothing_has_no_precision_and_no_recall():
    r = loop_closure([str(k) for k in range(5)], POSES)
    assert r == {"joins": 0, "true_joins": 0, "should_join": 2, "precision": None, "recall": 0.0}


def test_the_map_beside_its_baselines():
    r = against_baselines(0.95, odometry_alone=0.9, own_dstate=0.8)
    assert r["beats_baselines"] and r["better_baseline"] == "odometry_alone" and r["target_met"]
    tie = against_baselines(1.0, odometry_alone=1.0, own_dstate=0.5)
    assert not tie["beats_baselines"] and tie["error_ratio"] == 0.0 and tie["target_met"]
    worse = against_baselines(0.92, odometry_alone=1.0, own_dstate=0.5)
    assert worse["error_ratio"] is None and not worse["target_met"]
    short = against_baselines(0.85, odometry_alone=0.6, own_dstate=0.7)
    assert short["beats_baselines"] and short["error_ratio"] == pytest.approx(0.5) and not short["target_met"]


_poses = st.lists(st.tuples(st.floats(0, 30), st.floats(0, 30)), min_size=2, max_size=25)


@settings(max_examples=40, deadline=None)
@given(poses=_poses, seed=st.integers(0, 2**16))
def test_precision_and_recall_lie_in_0_1_and_recall_only_grows(poses, seed):
    scores = np.random.default_rng(seed).normal(size=(len(poses), len(poses)))
    r = place_recognition(scores, poses)
    recall = [p["recall"] for p in r["curve"]]
    assert all(0.0 <= p["precision"] <= 1.0 and 0.0 <= p["recall"] <= 1.0 for p in r["curve"])
    assert recall == sorted(recall)
    thresholds = [p["threshold"] for p in r["curve"]]
    assert thresholds == sorted(set(thresholds), reverse=True)
    labels = np.random.default_rng(seed).integers(0, 4, len(poses)).tolist()
    loops = loop_closure(labels, poses)
    assert all(x is None or 0.0 <= x <= 1.0 for x in (loops["precision"], loops["recall"]))


@settings(max_examples=40, deadline=None)
@given(poses=_poses)
def test_scores_that_rank_every_true_match_first_recall_everything_at_99_precision(poses):
    xy = np.asarray(poses, dtype=float)
    # The negated distance ranks every match within the radius above every match beyond it.
    r = place_recognition(-cdist(xy, xy), poses)
    assert r["recall_at_99_precision"] in (None, 1.0)
    assert r["best_correct"] == r["revisits"]


_tours = st.lists(st.tuples(st.floats(0, 20), st.floats(0, 20), st.floats(-3.1, 3.1), st.booleans()),
                  min_size=2, max_size=30)


@settings(max_examples=60, deadline=None)
@given(tour=_tours)
def test_the_true_map_closes_no_loop_wrongly_when_visits_are_where_the_truth_places_them(tour):
    """Loop closures judged from the visits' positions as the truth places them (a turn's two ends one
    visit, at their middle): every join the true map makes is a true join. Judged from the turn ends'
    own poses instead, a turn that drove 4 m puts a join of one true dstate 'farther than the radius'."""
    poses = [(x, y, h) for x, y, h, _ in tour]
    turns = [(k, k + 1) for k in range(len(tour) - 1) if tour[k][3]]
    truth = true_dstates(poses, radius_m=3.0, axis_rad=0.0, together=turns)
    loops = loop_closure(truth, visit_positions(poses, turns), 3.0, [sector_of_truth(d) for d in truth])
    assert loops["precision"] in (None, 1.0)


def test_a_join_of_a_turn_that_drove_on_is_judged_at_the_turns_middle():
    # Visit 0-1 is a turn that drove 4 m (its ends at 0 and 4 m); t3 comes back near its start, facing
    # the way the turn ended: one true dstate with t1, 1.6 m from the turn's middle but 3.5 m from t1.
    poses = [(0.0, 0.0, 0.0), (4.0, 0.0, 1.57), (30.0, 0.0, 1.57), (0.5, 0.5, 1.57)]
    turns = [(0, 1)]
    labels = ["a", "b", "c", "b"]
    truth = true_dstates(poses, radius_m=3.0, axis_rad=0.0, together=turns)
    assert truth[1] == truth[3]
    sectors = [sector_of_truth(d) for d in truth]
    assert loop_closure(labels, visit_positions(poses, turns), 3.0, sectors)["precision"] == 1.0
    assert loop_closure(labels, poses, 3.0, sectors)["precision"] == 0.0  # judged at the turn's end
