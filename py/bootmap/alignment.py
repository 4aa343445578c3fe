"""Aligning a laser image to a dstate's mean image: taking out the small motion between two stops at one dstate.

A robot that stops at a dstate by its control laws settles within a few centimetres and a degree or so of
the same pose, and its laser image differs from the dstate's other images by that motion as well as by the
sensor's noise. Where two dstates look alike but for a few beams (the paper's notch), a motion of a
centimetre moves a corner across a beam and hides the difference. Aligning each image to a dstate's mean
image takes the motion out:

1. **Reprojection** (:func:`reproject`). An image's returns, moved by a pose of the sensor (x, y metres,
   theta radians, in the robot's frame), read again at the image's own bearings, each bearing's range
   interpolated between the returns on either side of it: the image as the laser would have read it from
   that pose. Beams that read the maximum range move as points at that range, and no range exceeds it.
2. **The mean's sensitivity to the pose** (:class:`Reference`). How each beam of the mean image changes
   with a small move of the sensor: central differences of its reprojection (a Jacobian, beams x 3). A beam
   at a jump in depth (a corner's edge, a doorway) does not change smoothly but by the jump: it is left out
   of the fit, as is a beam that saw nothing.
3. **The fit** (:meth:`Reference.align`). The pose that best explains the image's ranges as the mean's
   moved, by least squares on the beams' range residuals (the mean's Jacobian as the model: the motion is
   millimetres to centimetres, where it is nearly linear), with a prior on the pose (:data:`POSE_PRIOR`: a
   stop's scatter, not another place) so that a direction the walls do not fix (along a corridor) stays
   put. After the first step, the beams more than three robust standard deviations off are left out
   (drop-outs, and the notch itself, which is what must stay visible). Each step ends in a reprojection
   from the pose so far, and the next fits what is left (:data:`ITERATIONS` steps).

Why not ICP (:mod:`bootmap.scan_match`, ``small_gicp``): point-to-point ICP pairs each return with the
nearest return of the other scan, which along a wall lies up to a beam's spacing away (3.5 cm at 2 m), as
large as the motion to be found; matching places metres apart, that does not matter. Here the residuals
are taken along each beam against the mean's own surface, which the mean, an average of many images, draws
with a fraction of one image's noise.
"""

from __future__ import annotations

import math

import numpy as np

from .surfaces import beam_angles

__all__ = ["POSE_PRIOR", "Reference", "reproject"]

#: The standard deviations of the prior on an image's pose relative to a dstate's mean (x, y metres, theta
#: radians): how far a robot's stops at one dstate scatter, a few centimetres and a degree and a half.
POSE_PRIOR = np.array([0.03, 0.03, math.radians(1.5)])

#: A beam whose range differs from a neighbour's by more than this (metres) sits at a jump in depth.
DEPTH_JUMP_M = 0.15

#: Residuals beyond this many robust standard deviations are left out after the first step.
OUTLIER_SD = 3.0

#: Gauss-Newton steps, each ending in a reprojection (with a third, recognition was the same or a point
#: lower: seeds 7200-7202, four times the laser noise, both worlds).
ITERATIONS = 2


def reproject(images, poses, fov_deg: float = 180.0, range_max: float | None = None) -> np.ndarray:
    """Each image as its laser would have read it with the sensor moved by its pose.

    Parameters
    ----------
    images : array-like, shape (n_images, n_beams)
        Ranges (m) at :func:`bootmap.surfaces.beam_angles` bearings.
    poses : array-like, shape (n_images, 3) or (3,)
        The sensor's pose (x, y metres, theta radians) in the frame the image is read again in.
    fov_deg : float
        The images' field of view.
    range_max : float, optional
        No range exceeds it (default: the images' largest).

    Examples
    --------
    A wall 2 m ahead, read again from 0.1 m further back (the image's sensor at x = +0.1 in the new frame):

    >>> ranges = 2.0 / np.cos(beam_angles(5, 90.0))
    >>> reproject([ranges], [0.1, 0.0, 0.0], fov_deg=90.0)[0, 2].round(3)
    np.float64(2.1)
    """
    X = np.atleast_2d(np.asarray(images, dtype=float))
    q = np.broadcast_to(np.asarray(poses, dtype=float), (len(X), 3))
    cap = float(X.max()) if range_max is None else float(range_max)
    angles = beam_angles(X.shape[1], fov_deg)
    a = angles[None, :] + q[:, 2:3]
    # The returns in the frame whose origin the image's sensor sits at pose q in ...
    px, py = q[:, 0:1] + X * np.cos(a), q[:, 1:2] + X * np.sin(a)
    # ... read from that frame's origin: the sensor moved by -q relative to the image's own.
    rr, aa = np.hypot(px, py), np.arctan2(py, px)
    # One interpolation for all images: each image's returns sorted by bearing, padded at both ends with its
    # first and last range (no reading beyond them), and the images laid end to end along the bearing axis,
    # each shifted by a whole lap past the last one's padding.
    order = np.argsort(aa, axis=1, kind="stable")
    aa, rr = np.take_along_axis(aa, order, axis=1), np.take_along_axis(rr, order, axis=1)
    pad = np.pi  # beyond any bearing a pose of a fraction of a turn can move a beam to
    xp = np.hstack([np.full((len(X), 1), -2 * pad), aa, np.full((len(X), 1), 2 * pad)])
    fp = np.hstack([rr[:, :1], rr, rr[:, -1:]])
    lap = 8 * pad * np.arange(len(X))[:, None]
    out = np.interp((angles[None, :] + lap).ravel(), (xp + lap).ravel(), fp.ravel()).reshape(X.shape)
    return np.minimum(out, cap)


class Reference:
    """Mean images (a dstate's, or several), ready to align images to.

    Parameters
    ----------
    means : array-like, shape (n_means, n_beams) or (n_beams,)
        The mean images.
    fov_deg : float
    range_max : float
        A beam at this range saw nothing.

    Attributes
    ----------
    means : ndarray, shape (n_means, n_beams)
    jacobian : ndarray, shape (n_means, n_beams, 3)
        Each beam's change of range per unit of the sensor's pose (x, y, theta).
    usable : ndarray of bool, shape (n_means, n_beams)
        Beams that change smoothly with the pose: not at a jump in depth, not at the maximum range.
    """

    def __init__(self, means, fov_deg: float = 180.0, range_max: float = 8.0):
        M = np.atleast_2d(np.asarray(means, dtype=float))
        self.means, self.fov_deg, self.range_max = M, fov_deg, float(range_max)
        step = np.array([0.005, 0.005, 0.003])  # 5 mm, 0.17 degrees
        moves = np.vstack([np.diag(step), -np.diag(step)])  # +x, +y, +theta, then each backwards
        moved = reproject(np.repeat(M, 6, axis=0), np.tile(moves, (len(M), 1)), fov_deg, self.range_max)
        moved = moved.reshape(len(M), 6, -1)
        self.jacobian = ((moved[:, :3] - moved[:, 3:]) / (2 * step[None, :, None])).transpose(0, 2, 1)
        jump = np.abs(np.diff(M, axis=1)) > DEPTH_JUMP_M
        at_jump = np.zeros(M.shape, dtype=bool)
        at_jump[:, 1:] |= jump
        at_jump[:, :-1] |= jump
        self.usable = ~at_jump & (M < self.range_max - 0.05)

    def nearby(self, means, like) -> "Reference":
        """Means each near one of these (``like[i]``: the index of the mean that ``means[i]`` is near, such
        as a dstate's mean with one image fewer), taking that mean's sensitivity to the pose and usable
        beams rather than working them out again."""
        other = object.__new__(Reference)
        other.means = np.atleast_2d(np.asarray(means, dtype=float))
        other.fov_deg, other.range_max = self.fov_deg, self.range_max
        other.jacobian, other.usable = self.jacobian[like], self.usable[like]
        return other

    def align(self, images, to=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The images aligned to the means.

        Parameters
        ----------
        images : array-like, shape (n_images, n_beams)
        to : array-like of int, shape (n_images,), optional
            The mean each image is aligned to (default: the one mean, or image i to mean i).

        Returns
        -------
        aligned : ndarray, shape (n_images, n_beams)
            Each image reprojected from its fitted pose.
        poses : ndarray, shape (n_images, 3)
            The fitted poses (x, y, theta) that move each image onto its mean.
        residual : ndarray, shape (n_images,)
            The root mean square of the aligned image's difference from its mean over the usable beams.
        """
        X = np.atleast_2d(np.asarray(images, dtype=float))
        if to is None:
            to = np.zeros(len(X), dtype=int) if len(self.means) == 1 else np.arange(len(X))
        mean, J, usable = self.means[to], self.jacobian[to], self.usable[to]
        fits = usable.sum(axis=1) >= 3  # else nothing to fit a pose to: the image stays as read
        weights0 = (usable & fits[:, None]).astype(float)
        poses, aligned = np.zeros((len(X), 3)), X
        for step in range(ITERATIONS):
            R = aligned - mean  # aligned = mean moved by -(pose still to fit): R ~ -J that pose
            weights = weights0
            if step:  # without the beams far off: drop-outs, and differences that are not motion
                scale = 1.4826 * _weighted_median_abs(R, weights0) + 1e-6
                weights = weights0 * (np.abs(R) < OUTLIER_SD * scale[:, None])
            poses = poses + _step(J, R, weights, poses)
            aligned = np.where(fits[:, None], reproject(X, poses, self.fov_deg, self.range_max), X)
        on = np.where(usable.any(axis=1)[:, None], usable, True)
        residual = np.sqrt(np.sum(np.where(on, (aligned - mean) ** 2, 0.0), axis=1) / on.sum(axis=1))
        return aligned, poses, residual


def _step(J: np.ndarray, R: np.ndarray, weights: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """The Gauss-Newton step d minimising sum w (r + J d)^2 / s^2 + |(pose + d) / prior|^2, every image at
    once (J per image, s: each image's robust spread of residuals)."""
    s2 = np.maximum((1.4826 * _weighted_median_abs(R, weights)) ** 2, 1e-6)
    prior = 1.0 / POSE_PRIOR ** 2
    H = np.einsum("nb,nbi,nbj->nij", weights, J, J) / s2[:, None, None] + np.diag(prior)
    g = -np.einsum("nb,nbi->ni", weights * R, J) / s2[:, None] - poses * prior
    return np.linalg.solve(H, g[:, :, None])[:, :, 0]


def _weighted_median_abs(R: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Per row, the median absolute value over the beams of weight > 0 (0 where there are none)."""
    on = weights > 0
    ranked = np.sort(np.where(on, np.abs(R), np.inf), axis=1)
    n = on.sum(axis=1)
    rows = np.arange(len(R))
    low, high = ranked[rows, np.maximum(n - 1, 0) // 2], ranked[rows, np.maximum(n, 1) // 2 - (n == 0)]
    return np.where(n > 0, 0.5 * (low + high), 0.0)
