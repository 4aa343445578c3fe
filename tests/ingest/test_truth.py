"""Truth from poses: places, the building's axis, true dstates, corners and their recall."""

import numpy as np
import pytest

from bootmap.ingest.dstates import find_turns, odometry_track
from bootmap.ingest.truth import corner_recall, corners_in_poses, main_axis, place_labels, true_dstates


def test_places_join_poses_within_the_radius_and_turn_ends():
    poses = [(0, 0, 0), (2, 0, 0), (4, 0, 0), (20, 0, 0), (25, 0, 0), (0.5, 0.5, 0)]
    assert place_labels(poses, radius_m=3.0) == [0, 0, 0, 1, 2, 0]  # 0-2-4 chain; 20 and 25 apart
    assert place_labels(poses, radius_m=3.0, together=[(3, 4)]) == [0, 0, 0, 1, 1, 0]
    assert place_labels(poses, radius_m=1.0) == [0, 1, 2, 3, 4, 0]


def test_a_travel_never_joins_its_two_ends_into_one_place():
    # Turns 3-6 m apart chain into one place by the radius; but the robot travelled from one to the other,
    # and a travel always leaves its place (the SSH): the chain breaks at its longest link.
    poses = [(0, 0, 0), (2.5, 0, 0), (5.5, 0, 0), (0.4, 0.2, 0)]
    assert place_labels(poses, radius_m=3.0) == [0, 0, 0, 0]
    assert place_labels(poses, radius_m=3.0, apart=[(0, 2)]) == [0, 0, 1, 0]
    assert place_labels(poses, radius_m=3.0, apart=[(0, 1)]) == [0, 1, 1, 0]
    # a turn's two ends stay together whatever the radius says
    assert place_labels(poses, radius_m=1.0, together=[(0, 2)], apart=[(1, 2)]) == [0, 1, 0, 0]


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
