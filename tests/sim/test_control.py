"""Control laws and perception: fixed points that do not depend on the way the robot came.

A dstate's image varies for honest reasons only if the hill-climbing really converges to one fixed point:
these tests hold the pieces that make it so (odometry that counts reversing back, the near edge of an
opening seen before it is passed, a wall angle that door recesses do not tilt).
"""

import math
from collections import defaultdict

import numpy as np
import pytest

from bootmap.sim import run
from bootmap.sim.laser import Scene, SweepCaster
from bootmap.sim.perception import Perception
from bootmap.sim.physics import Odometry
from bootmap.sim.world import LaserSpec

SPEC = LaserSpec(180, -math.pi / 2, math.pi / 2, 8.0, 0.0, 0.0)


def _corridor(opening_at: float | None = None, recess_at: float | None = None) -> Scene:
    """A corridor 2.4 m wide along x (walls y = -1.2 and 1.2), the robot at the origin facing +x; optionally
    a 2.4 m side corridor opening to the left from x = opening_at, and a 0.9 m door recessed 4 cm into the
    right wall from x = recess_at."""
    left = [(-20, 1.2, opening_at, 1.2), (opening_at, 1.2, opening_at, 20),
            (opening_at + 2.4, 20, opening_at + 2.4, 1.2), (opening_at + 2.4, 1.2, 40, 1.2)] \
        if opening_at is not None else [(-20, 1.2, 40, 1.2)]
    if recess_at is None:
        right = [(-20, -1.2, 40, -1.2)]
    else:
        a, b = recess_at, recess_at + 0.9
        right = [(-20, -1.2, a, -1.2), (a, -1.2, a, -1.24), (a, -1.24, b, -1.24), (b, -1.24, b, -1.2),
                 (b, -1.2, 40, -1.2)]
    return Scene(np.array(left + right, dtype=float), np.zeros((0, 3)))


def test_odometry_progress_counts_reversing_back_while_distance_counts_it_forward():
    odo = Odometry()
    odo.advance(1.0, 0.0, 1.0)
    odo.advance(-0.25, 0.0, 1.0)
    assert odo.progress == pytest.approx(0.75) and odo.distance == pytest.approx(1.25)
    assert odo.x == pytest.approx(0.75)


@pytest.mark.parametrize("edge", [0.2, 0.5, 0.9])
def test_near_edge_of_an_opening_ahead_is_seen_before_it_is_passed(edge):
    caster, perception = SweepCaster(SPEC.angles, SPEC.range_max), Perception(SPEC, open_range=3.0)
    ranges = caster.cast(_corridor(opening_at=edge), 0.0, 0.0, 0.0)
    assert perception.near_edge(ranges, +1, depth=1.7) == pytest.approx(edge, abs=0.03)
    assert perception.near_edge(ranges, -1, depth=1.7) > 7.0  # the right wall runs on, out of the laser's reach
    past = caster.cast(_corridor(opening_at=-0.5), 0.0, 0.0, 0.0)  # already level with the opening
    assert math.isnan(perception.near_edge(past, +1, depth=1.7))


@pytest.mark.parametrize("recess_at", [0.6, 1.5, 3.0])
def test_wall_angle_is_not_tilted_by_a_door_recess(recess_at):
    caster, perception = SweepCaster(SPEC.angles, SPEC.range_max), Perception(SPEC, open_range=3.0)
    for heading_deg in (-0.4, 0.0, 0.3):
        ranges = caster.cast(_corridor(recess_at=recess_at), 0.0, 0.0, math.radians(heading_deg))
        # turning by the wall angle aligns the robot with the walls
        assert math.degrees(perception.wall_angle(ranges)) == pytest.approx(-heading_deg, abs=0.02)


def test_every_dstate_of_a_place_is_at_one_fixed_point_whichever_way_the_robot_came():
    # Taylor Hall, 100 dstates: the robot arrives at junctions from up to three directions and turns
    # there; all its stops at a place lie within 2.5 cm of each other (they lay 10-15 cm apart when a
    # stop at an opening was dated by the side beams and odometry counted backing up as progress).
    result = run("taylor_hall", policy="explore", steps=100, seed=1)
    at = defaultdict(list)
    for s in result.tableau.steps:
        at[s.truth.split(":")[0]].append(s.pose[:2])
    assert len(at) == 7
    for place, xy in at.items():
        xy = np.array(xy)
        assert np.abs(xy - np.median(xy, axis=0)).max() < 0.025, place
    assert result.contacts == 0
