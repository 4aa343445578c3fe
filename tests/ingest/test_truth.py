"""Truth from poses: places, the building's axis, true dstates, corners and their recall."""

import numpy as np
import pytest

from bootmap.ingest.dstates import find_turns, odometry_track
from bootmap.ingest.truth import corner_recall, corners_in_poses, main_axis, place_labels, true_dstates


def test_a_place_is_visits_all_within_the_radius_of_each_other_and_a_turn_is_one_visit():
    poses = [(0, 0, 0), (2, 0, 0), (4, 0, 0), (20, 0, 0), (25, 0, 0), (0.5, 0.5, 0)]
    # 0-2-4 would chain, but 0 and 4 lie 4 m apart: no place is wider than the radius
    labels = place_labels(poses, radius_m=3.0)
    assert labels[0] == labels[5] and labels[0] != labels[2] and len({labels[3], labels[4], labels[0]}) == 3
    # a turn's two ends are one visit, at the middle of them (22.5, 0), whatever their distance
    assert place_labels(poses, radius_m=3.0, together=[(3, 4)])[3:5] == [2, 2]
    assert place_labels(poses, radius_m=1.0) == [0, 1, 2, 3, 4, 0]


def test_no_two_poses_of_a_place_lie_farther_apart_than_the_radius_unless_one_turn_joins_them():
    rng = np.random.default_rng(4)
    for _ in range(20):
        xy = rng.uniform(0, 15, (40, 2))
        poses = [(x, y, 0.0) for x, y in xy]
        turns = [(k, k + 1) for k in range(0, 40, 2) if rng.random() < 0.3]
        labels = place_labels(poses, radius_m=3.0, together=turns)
        middle = {}
        for a, b in turns:
            middle[a] = middle[b] = (xy[a] + xy[b]) / 2
        at = np.array([middle.get(i, xy[i]) for i in range(40)])
        for i in range(40):
            for j in range(i + 1, 40):
                if labels[i] == labels[j]:
                    assert np.hypot(*(at[i] - at[j])) <= 3.0 + 1e-9


def test_a_travel_never_joins_its_two_ends_into_one_place():
    # Turns 2.5 m apart would be one place by the radius; but the robot travelled from one to the other,
    # and a travel always leaves its place (the SSH).
    poses = [(0, 0, 0), (2.5, 0, 0), (5.5, 0, 0), (0.4, 0.2, 0)]
    assert place_labels(poses, radius_m=3.0) == [0, 0, 1, 0]
    assert place_labels(poses, radius_m=3.0, apart=[(0, 1)]) == [0, 1, 1, 0]  # 2.5 and 5.5: 3 m apart
    labels = place_labels(poses, radius_m=3.0, apart=[(1, 3)])
    assert labels[1] != labels[3] and labels[0] == labels[3]


def test_the_axis_is_the_corridors_direction_modulo_90():
    angle = np.radians(30)
    legs = [(0, 0), (10, 0), (10, 10), (-5, 10)]  # corridors along x and y, then rotated by 30 degrees
    rot = [(x * np.cos(angle) - y * np.sin(angle), x * np.sin(angle) + y * np.cos(angle), 0.0) for x, y in legs]
    assert np.degrees(main_axis(rot)) == pytest.approx(30)
    # Headings sectored in the building's frame: 30 degrees is its east, 120 its north.
    poses = [(0, 0, np.radians(30)), (0, 0.1, np.radians(125)), (50, 0, np.radians(-150))]
    assert true_dstates(poses, axis_rad=angle) == ["P0:E", "P0:N", "P1:W"]


def test_corners_come_from_positions_not_headings():
    path = [(x, 0.0, 9.9) for x in np.arange(0, 10, 0.5)] + [(10.0, y, 9.9) for y in np.arange(0, 10, 0.5)]
    (corner,) = corners_in_poses(path)
    assert corner.angle_deg == pytest.approx(90) and path[corner.scan][:2] == (10.0, 0.0)


def test_the_excerpt_turns_cover_its_corners_with_true_angles(excerpt_scans):
    truth = [s.truth for s in excerpt_scans]
    turns = find_turns(*odometry_track([s.odometry for s in excerpt_scans]))
    corners = corners_in_poses(truth)
    assert len(corners) == 8
    recall = corner_recall(turns, truth, corners)
    assert (recall.recall, recall.precision) == (1.0, 1.0)
    assert max(np.abs(recall.angle_errors_deg)) < 1.0  # odometry is good locally: the probe's 0.6 deg
    assert np.degrees(main_axis(truth)) == pytest.approx(-30.4, abs=0.1)


def test_a_missed_corner_lowers_recall(excerpt_scans):
    truth = [s.truth for s in excerpt_scans]
    turns = find_turns(*odometry_track([s.odometry for s in excerpt_scans]))
    recall = corner_recall(turns[1:], truth, corners_in_poses(truth))
    assert (recall.found, recall.corners) == (7, 8)
