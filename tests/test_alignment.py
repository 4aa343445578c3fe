"""Aligning a laser image to a dstate's mean: reprojection and the fitted pose, on the simulator's own laser."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bootmap.alignment import POSE_PRIOR, Reference, reproject
from bootmap.sim.laser import Laser, Scene
from bootmap.sim.world import load_world

WORLD = load_world("notched_rectangle", {"laser.noise_sd": 0.0, "laser.dropout": 0.0})
SCENE, LASER = Scene.of_world(WORLD), Laser(WORLD.laser)
STOP = (4.5, 0.5, math.radians(-90.0))  # the south-east corner's stop, facing the notch's wall


def moved(pose, dx, dy, dtheta):
    """``pose`` moved by (dx, dy) in its own frame and turned by dtheta."""
    x, y, t = pose
    return (x + dx * math.cos(t) - dy * math.sin(t), y + dx * math.sin(t) + dy * math.cos(t), t + dtheta)


@settings(max_examples=50, deadline=None)
@given(seed=st.integers(0, 2**31), n_beams=st.integers(8, 181))
def test_reprojecting_from_the_same_pose_changes_nothing(seed, n_beams):
    rng = np.random.default_rng(seed)
    image = np.clip(2.0 + np.cumsum(0.05 * rng.standard_normal(n_beams)), 0.2, 8.0)
    assert np.allclose(reproject([image], [0.0, 0.0, 0.0], range_max=8.0)[0], image)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31), n_images=st.integers(2, 6))
def test_images_reprojected_together_are_each_as_reprojected_alone(seed, n_images):
    # All images go through one interpolation: no image's returns may leak into another's.
    rng = np.random.default_rng(seed)
    images = np.clip(2.0 + np.cumsum(0.3 * rng.standard_normal((n_images, 60)), axis=1), 0.1, 8.0)
    poses = np.c_[0.1 * rng.standard_normal((n_images, 2)), 0.2 * rng.standard_normal(n_images)]
    together = reproject(images, poses, range_max=8.0)
    for i in range(n_images):
        assert np.allclose(together[i], reproject(images[i], poses[i], range_max=8.0)[0], rtol=0, atol=1e-9)


def test_reprojecting_reads_the_walls_as_the_laser_would_from_the_moved_pose():
    # The laser's exact image from the stop, reprojected as from a pose 3 cm back and 1 degree turned, is the
    # laser's exact image from there, but where a corner's edge falls between beams.
    here = LASER.exact(SCENE, STOP)
    there = moved(STOP, -0.03, 0.01, math.radians(1.0))
    # The image's sensor sits at the inverse motion in the frame of the moved pose.
    c, s = math.cos(-math.radians(1.0)), math.sin(-math.radians(1.0))
    inverse = (c * 0.03 - s * -0.01, s * 0.03 + c * -0.01, -math.radians(1.0))
    again = reproject([here], inverse, range_max=WORLD.laser.range_max)[0]
    truth = LASER.exact(SCENE, there)
    off = np.abs(again - truth)
    assert np.median(off) < 1e-3 and np.mean(off < 0.01) > 0.95, off.max()


@pytest.mark.parametrize("dx, dy, dtheta_deg", [(0.02, 0.0, 0.0), (0.0, -0.015, 0.0), (0.0, 0.0, 0.8),
                                                (-0.01, 0.02, -0.6)])
def test_an_image_from_a_nearby_stop_is_aligned_back_onto_the_mean(dx, dy, dtheta_deg):
    # A dstate's mean image (the laser's exact image at its stop) and noisy images from stops a little off it:
    # the fitted pose is the stop's offset, and the aligned images lie on the mean but for the noise.
    rng = np.random.default_rng(0)
    reference = Reference(LASER.exact(SCENE, STOP), range_max=WORLD.laser.range_max)
    pose = moved(STOP, dx, dy, math.radians(dtheta_deg))
    images = np.array([LASER.exact(SCENE, pose) + 0.01 * rng.standard_normal(180) for _ in range(5)])
    aligned, poses, residual = reference.align(images)
    expected = np.array([dx, dy, math.radians(dtheta_deg)])  # the image's sensor, in the stop's frame
    assert np.allclose(poses[:, :2], expected[:2], atol=0.004), poses
    assert np.allclose(poses[:, 2], expected[2], atol=math.radians(0.1)), np.degrees(poses[:, 2])
    u = reference.usable[0]
    before = np.sqrt(np.mean((images[:, u] - reference.means[0, u]) ** 2, axis=1))
    assert np.all(residual < 0.015) and np.all(residual < before), (residual, before)


def test_the_prior_holds_a_pose_the_walls_do_not_fix():
    # Facing down a long corridor past the laser's reach, a move along it changes no beam: the fit keeps the
    # pose where the prior puts it rather than anywhere.
    walls = np.full(180, 8.0)
    angles = np.linspace(-np.pi / 2, np.pi / 2, 180)
    side = np.abs(np.sin(angles)) > 0.2
    walls[side] = np.minimum(1.0 / np.abs(np.sin(angles[side])), 8.0)  # two walls 1 m either side
    reference = Reference(walls, range_max=8.0)
    _, poses, _ = reference.align([walls + 0.01 * np.random.default_rng(1).standard_normal(180)])
    assert abs(poses[0, 0]) < POSE_PRIOR[0]  # along the corridor: no evidence, stays near 0


def test_an_image_with_nothing_to_fit_is_kept_as_read():
    reference = Reference(np.full(30, 8.0), range_max=8.0)  # nothing in reach
    image = np.full((1, 30), 8.0)
    aligned, poses, _ = reference.align(image)
    assert np.array_equal(aligned, image) and not poses.any()
