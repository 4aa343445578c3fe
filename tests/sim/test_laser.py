"""The laser: the vectorised sweep caster agrees with pymunk's segment_query_first; the noise is as specified."""

import math

import numpy as np
import pytest

from bootmap.sim.laser import Laser, Scene, SweepCaster, build_space, cast_reference
from bootmap.sim.world import load_world, world_names


def _free_poses(world, rng, n):
    x0, y0, x1, y1 = world.bounds()
    out = []
    while len(out) < n:
        x, y = rng.uniform(x0, x1), rng.uniform(y0, y1)
        if world.in_free_space(np.array([x, y]))[0]:
            out.append((x, y, rng.uniform(-math.pi, math.pi)))
    return out


@pytest.mark.parametrize("name", world_names())
def test_sweep_caster_matches_pymunk_reference_in_every_world(name):
    w = load_world(name)
    scene = Scene.of_world(w)
    space = build_space(scene)
    caster = SweepCaster(w.laser.angles, w.laser.range_max)
    for x, y, th in _free_poses(w, np.random.default_rng(0), 25):
        fast = caster.cast(scene, x, y, th)
        ref = cast_reference(space, w.laser.angles, w.laser.range_max, x, y, th)
        np.testing.assert_allclose(fast, ref, atol=1e-6)


def test_sweep_caster_matches_reference_on_random_clutter():
    rng = np.random.default_rng(7)
    segs = rng.uniform(-5, 5, (100, 4))
    discs = np.column_stack([rng.uniform(-5, 5, (10, 2)), rng.uniform(0.05, 0.5, 10)])
    scene = Scene(segs, discs)
    space = build_space(scene)
    angles = np.linspace(-math.pi / 2, math.pi / 2, 180)
    caster = SweepCaster(angles, 8.0)
    checked = 0
    for _ in range(60):
        x, y = rng.uniform(-6, 6, 2)
        if (np.hypot(discs[:, 0] - x, discs[:, 1] - y) <= discs[:, 2]).any():
            continue  # a sensor inside an obstacle is not a pose the robot can have
        th = rng.uniform(-4, 4)
        np.testing.assert_allclose(caster.cast(scene, x, y, th),
                                   cast_reference(space, angles, 8.0, x, y, th), atol=1e-6)
        checked += 1
    assert checked > 40


def test_beams_follow_ros_conventions():
    """Beam 0 looks right (-90 deg), the last beam left (+90 deg), counter-clockwise in between."""
    w = load_world("notched_rectangle")
    laser = Laser(w.laser)
    r = laser.exact(Scene.of_world(w), (1.0, 1.0, 0.0))  # facing east: right wall 1 m, left wall 2 m
    assert r[0] == pytest.approx(1.0) and r[-1] == pytest.approx(2.0)
    assert w.laser.angles[0] == pytest.approx(-math.pi / 2) and w.laser.angles[-1] == pytest.approx(math.pi / 2)


def test_range_noise_and_dropouts_follow_the_world_parameters():
    w = load_world("notched_rectangle")
    laser = Laser(w.laser)
    scene = Scene.of_world(w)
    rng = np.random.default_rng(3)
    pose = (2.5, 1.5, 0.3)
    exact = laser.exact(scene, pose)
    scans = np.array([laser.scan(scene, pose, rng) for _ in range(400)])
    dropped = scans >= w.laser.range_max
    assert dropped.mean() == pytest.approx(w.laser.dropout, abs=0.001)
    err = (scans - exact)[~dropped]
    assert err.std() == pytest.approx(w.laser.noise_sd, rel=0.05)
    assert abs(err.mean()) < 0.001
