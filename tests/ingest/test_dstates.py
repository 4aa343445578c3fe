"""Where a control law would have settled: turns found in odometry, synthetic runs and the Killian excerpt."""

import numpy as np
import pytest

from bootmap.ingest.dstates import TurnDetector, dstate_scans, find_turns, odometry_track


def _run(headings_deg, step_m=0.5):
    """Poses driving ``step_m`` between headings: a run as odometry would read it."""
    theta = np.radians(headings_deg)
    xy = np.cumsum(np.column_stack([np.cos(theta), np.sin(theta)]) * step_m, axis=0)
    return np.column_stack([xy, theta])


def _turns(poses, **kw):
    return find_turns(*odometry_track(poses), TurnDetector(**kw))


def test_a_sharp_corner_is_one_turn_between_its_travels():
    (turn,) = _turns(_run([0] * 30 + [45] + [90] * 30))
    assert (turn.before, turn.after, round(turn.angle_deg)) == (29, 31, 90)


def test_a_gradual_corner_needs_the_window():
    # 90 degrees spread over 10 m (3 degrees every 0.5 m): never 20 degrees within 2 m.
    poses = _run([0] * 40 + list(np.arange(3, 90, 3)) + [90] * 40)
    assert _turns(poses, window_m=2.0) == []
    (turn,) = _turns(poses, window_m=6.0)
    assert 66 <= turn.angle_deg <= 90  # read short by up to twice settled_deg: its ends look straight


def test_headings_across_pi_are_unwrapped_before_summing():
    (turn,) = _turns(_run([170] * 30 + [-170] * 0 + [-100] * 30))  # 170 -> 260 (= -100): a left turn of 90
    assert round(turn.angle_deg) == 90


def test_a_spin_on_the_spot_is_no_turn_and_a_wiggle_neither():
    spin = np.array([(0.5 * i, 0.0, 0.0) for i in range(20)] + [(10.0, 0.0, np.radians(a)) for a in range(0, 360, 30)]
                    + [(10.0 + 0.5 * i, 0.0, 0.0) for i in range(20)])
    assert _turns(spin) == []
    assert _turns(_run([0] * 20 + [15, 25, 15] + [0] * 20)) == []


def test_two_turns_with_no_travel_between_are_one_u_turn():
    (turn,) = _turns(_run([0] * 30 + [90, 180] + [180] * 30))
    assert abs(turn.angle_deg) == pytest.approx(180)


def test_the_excerpt_has_eight_turns_and_sixteen_dstates(excerpt_scans):
    turns = find_turns(*odometry_track([s.odometry for s in excerpt_scans]))
    assert [(t.before, t.after) for t in turns] == [(18, 25), (113, 117), (132, 148), (163, 170), (206, 214),
                                                   (236, 244), (321, 324), (341, 350)]
    assert [round(t.angle_deg) for t in turns] == [-89, -80, 77, 100, 80, 84, -83, 87]
    assert dstate_scans(turns)[:4] == [18, 25, 113, 117]


def _corridor_with_junctions():
    """40 m of travel between two turns (a scan every 0.25 m), walls 1 m off on both sides, and: a side
    corridor 2.5 m wide on the left at 10 m, a crossing (both sides open) at 20 m, a doorway 0.5 m wide on
    the right at 27 m, a hall 8 m long on the right from 30 m, and a side corridor 1 m before the travel
    ends (at the turn's place already)."""
    from bootmap.ingest.dstates import FoundTurn

    distance = np.arange(161) * 0.25
    left, right = np.ones(161), np.ones(161)
    open_at = lambda lo, hi: (distance >= lo) & (distance <= hi)
    left[open_at(9.0, 11.5)] = 10.0
    left[open_at(19.0, 21.5)] = right[open_at(19.0, 21.5)] = 10.0
    right[open_at(27.0, 27.5)] = 10.0
    right[open_at(30.0, 38.0)] = 10.0
    left[open_at(38.5, 40.0)] = 10.0
    turns = [FoundTurn(0, 0, 90.0), FoundTurn(160, 160, 90.0)]
    return left, right, distance, turns


def test_a_travel_passing_a_side_corridor_or_a_crossing_visits_it_once():
    from bootmap.ingest.dstates import JunctionDetector, find_passes

    left, right, distance, turns = _corridor_with_junctions()
    passes = find_passes(left, right, distance, turns, JunctionDetector())
    # the side corridor's middle, the crossing's once; no doorway, no hall, nothing at the turn's place
    assert [distance[i] for i in passes] == pytest.approx([10.25, 20.25])
    assert dstate_scans(turns, passes) == [0, 0, passes[0], passes[1], 160, 160]
    # a wider doorway limit lets the doorway in; a narrower corridor limit loses the side corridor
    assert len(find_passes(left, right, distance, turns, JunctionDetector(min_width_m=0.5))) == 3
    assert len(find_passes(left, right, distance, turns, JunctionDetector(max_width_m=2.0))) == 0
