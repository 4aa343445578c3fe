"""The noise model of a real robot's odometry: turns measured several degrees off, dstates unmoved.

Real pymunk runs of the notched rectangle (a few circuits per seed, about 0.4 s each): the measured
actions must be off by what a real robot's are, the true stops at dstates must not be (the control laws
stop by the laser), and the same seed must give the same run.
"""

import math

import numpy as np
import pytest

from bootmap.sim import run
from bootmap.sim.control import Limits, Turn
from bootmap.sim.odometry import action_errors
from bootmap.sim.perception import Percept
from bootmap.sim.physics import Odometry, Wander
from bootmap.sim.world import MotionNoise, load_world

SEEDS = (1, 2, 3)
QUIET = {"motion_noise.slip_v": 0.0, "motion_noise.slip_omega": 0.0, "motion_noise.turn_scale": 0.0,
         "motion_noise.drift_deg_s": 0.0}


def _errors(settings=None, circuits=8):
    world = load_world("notched_rectangle", settings)
    runs = [run(world, circuits=circuits, seed=s) for s in SEEDS]
    errors = [action_errors(r.tableau) for r in runs]
    return runs, np.concatenate([e.turns for e in errors]), np.concatenate([e.travels for e in errors])


@pytest.fixture(scope="module")
def default_noise():
    return _errors()


def test_turns_are_measured_several_degrees_off_as_on_a_real_robot(default_noise):
    _, turns, travels = default_noise
    assert len(turns) == 3 * 32
    rms = float(np.sqrt(np.mean(turns ** 2)))
    # 90-degree turns: a scale error of 5% (s.d.) is 4.5 degrees, plus white slip and drift
    assert 3.5 < rms < 8.0, rms
    assert np.percentile(np.abs(turns), 90) > 5.0  # one turn in ten off by more than 5 degrees
    assert np.abs(turns).max() < 25.0  # within what turning to the walls recovers (tests/sim/test_turn.py: far more)
    assert abs(float(np.mean(turns))) < 2.0  # no bias in the mean over many turns
    # travels in a 5 m room take a few seconds: the heading drifts by a degree or so
    assert 0.2 < float(np.sqrt(np.mean(travels ** 2))) < 3.0


def test_without_motion_noise_the_measured_turns_are_the_true_ones():
    _, turns, travels = _errors(QUIET, circuits=2)
    assert np.abs(turns).max() < 1.0 and np.abs(travels).max() < 0.5


def test_odometry_error_does_not_move_the_dstates(default_noise):
    runs, _, _ = default_noise
    for r in runs:
        steps = r.tableau.steps
        assert r.contacts == 0 and len({s.truth for s in steps}) == 8 and "?" not in {s.truth for s in steps}
        for truth in {s.truth for s in steps}:
            poses = np.array([s.pose for s in steps if s.truth == truth])
            off = np.hypot(*(poses[:, :2] - np.median(poses[:, :2], axis=0)).T)
            heading = np.angle(np.exp(1j * (poses[:, 2] - poses[0, 2])))
            # the paper world settles within 2 cm (stop_tolerance) and 0.6 degrees
            assert off.max() < 0.05, (truth, off.max())
            assert np.degrees(np.abs(heading)).max() < 1.5, truth


def test_same_seed_same_noise_and_another_seed_differs():
    world = load_world("notched_rectangle")
    a, b, c = (run(world, circuits=1, seed=s) for s in (4, 4, 5))
    assert a.tableau.dumps() == b.tableau.dumps()
    assert np.array_equal(a.trajectory, b.trajectory)
    assert [s.action for s in a.tableau.steps] != [s.action for s in c.tableau.steps]


def test_wander_holds_its_spread_and_forgets_at_its_correlation_time():
    w = Wander(0.05, 5.0, 0.1, np.random.default_rng(7))
    xs = np.array([w.step() for _ in range(50_000)])
    assert xs.std() == pytest.approx(0.05, rel=0.1)
    lag = 50  # 5 s at 0.1 s
    assert np.corrcoef(xs[:-lag], xs[lag:])[0, 1] == pytest.approx(math.exp(-1), abs=0.1)
    assert Wander(0.0, 5.0, 0.1, np.random.default_rng(7)).step() == 0.0


def test_motion_noise_defaults_are_a_real_robots():
    d = MotionNoise()
    assert d.slip_v >= 3 * 0.02 and d.slip_omega >= 3 * 0.02  # at least three times the old default
    assert d.turn_scale > 0 and d.drift_deg_s > 0


def _percept(wall_angle: float) -> Percept:
    return Percept(front=2.0, left=1.0, right=1.0, left_open=False, right_open=False, wall_angle=wall_angle)


def test_a_turn_aligned_with_the_walls_does_not_turn_away_when_odometry_disagrees():
    law = Turn(Limits(), math.pi / 2)
    law.begin(Odometry())
    near = Odometry(theta=math.radians(85))  # 5 degrees to go by odometry: the walls take over ...
    assert law.step(_percept(math.radians(3)), np.zeros(180), near)[1] < 0  # ... backing off to 12 short
    assert law.step(_percept(math.radians(12)), np.zeros(180), near)[1] > 0  # then the last approach
    # Odometry now says 20 degrees to go (it slipped), but the robot is aligned with the walls: it stays.
    behind = Odometry(theta=math.radians(70))
    for _ in range(3):
        v, omega = law.step(_percept(0.0), np.zeros(180), behind)
        assert (v, omega) == (0.0, 0.0)
    assert law.done
