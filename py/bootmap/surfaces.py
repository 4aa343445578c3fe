"""A laser image's returns as points, and the surfaces they lie on.

An image is the tableau's 180 ranges from -90 to +90 degrees in the robot's frame (or, with a field of view
of 360 degrees, ranges all round, as a place's local map is rendered: :mod:`bootmap.ingest.local_maps`;
:func:`beam_angles`). Its *returns* are the
beams that saw something, as 2-D points; its *surfaces* join consecutive returns close enough to be one
wall and sample them every few centimetres, as an occupancy map would draw them, so that a point of
another scan that falls on the wall between two beams lies on a surface. Shared by scan matching
(:mod:`bootmap.scan_match`, two visits aligned) and the log reader's odometry calibration
(:mod:`bootmap.ingest.calibrate`, two consecutive scans aligned), with what both hand to and take from
ICP (``small_gicp`` works in 3-D): the points at z = 0 (:func:`in_3d`), a plane motion as a 4 x 4
transform (:func:`se2`) and back (:func:`planar`).
"""

from __future__ import annotations

import math

import numpy as np


def beam_angles(n: int, fov_deg: float = 180.0) -> np.ndarray:
    """The bearings (radians, counter-clockwise from the robot's heading) of an image's ``n`` beams: over a
    field of view of 180 degrees (a laser's), ``linspace(-pi/2, pi/2, n)``, both ends included; all round
    (360), ``n`` bearings from -pi, ``2 pi / n`` apart.

    >>> np.degrees(beam_angles(3)).tolist(), np.degrees(beam_angles(4, 360)).tolist()
    ([-90.0, 0.0, 90.0], [-180.0, -90.0, 0.0, 90.0])
    """
    if fov_deg >= 360.0:
        return -math.pi + 2 * math.pi * np.arange(n) / max(n, 1)
    half = math.radians(fov_deg) / 2
    return np.linspace(-half, half, n)


def beam_step(n: int, fov_deg: float = 180.0) -> float:
    """The angle between neighbouring beams (radians)."""
    return 2 * math.pi / max(n, 1) if fov_deg >= 360.0 else math.radians(fov_deg) / max(n - 1, 1)


def image_points(image, max_range: float = 20.0, fov_deg: float = 180.0) -> np.ndarray:
    """The returns of a laser image as 2-D points in the robot's frame.

    Parameters
    ----------
    image : array-like of shape (n_beams,)
        Ranges (m) at :func:`beam_angles` from the robot's heading, counter-clockwise (by default
        ``linspace(-pi/2, pi/2, n_beams)``).
    max_range : float
        The reading that means nothing was seen (m); beams at or beyond it, or not positive, give no point.
    fov_deg : float
        The field of view the beams cover (degrees): 180, or 360 for an image all round.

    Returns
    -------
    ndarray of shape (n_returns, 2)
        The returns in beam order.

    Examples
    --------
    >>> image_points([1.0, 20.0, 2.0]).round(6).tolist()
    [[0.0, -1.0], [0.0, 2.0]]
    """
    r = np.asarray(image, dtype=float).ravel()
    return returns(r, beam_angles(len(r), fov_deg), max_range)


def returns(ranges, angles: np.ndarray, max_range: float = 20.0) -> np.ndarray:
    """The beams at ``angles`` (radians) that saw something nearer than ``max_range`` (finite, positive
    readings), as 2-D points in the sensor's frame."""
    r = np.asarray(ranges, dtype=float).ravel()
    seen = np.isfinite(r) & (r > 0.0) & (r < max_range)
    return np.column_stack([r[seen] * np.cos(angles[seen]), r[seen] * np.sin(angles[seen])])


def surface_points(image, max_range: float = 20.0, resolution_m: float = 0.05, max_incidence_deg: float = 75.0,
                   slack_m: float = 0.10, fov_deg: float = 180.0) -> np.ndarray:
    """The surfaces a laser image saw, sampled every ``resolution_m``: its returns, and points between
    consecutive returns close enough to be one wall.

    Parameters
    ----------
    image : array-like of shape (n_beams,)
        Ranges (m), as for :func:`image_points`.
    max_range : float
        The reading that means nothing was seen (m).
    resolution_m : float
        Spacing of the samples along a surface (m): a map cell.
    max_incidence_deg : float
        Two consecutive returns are one wall when they are no farther apart than a wall seen at this angle
        from its normal spaces them: ``r * beam step / cos(max_incidence_deg)`` at range ``r``.
    slack_m : float
        Added to that gap for the range noise of both returns (m).
    fov_deg : float
        The field of view, as for :func:`image_points` (all round, the last beam neighbours the first).

    Returns
    -------
    ndarray of shape (n_samples, 2)

    Examples
    --------
    A wall face on at 2 m (returns 3.5 cm apart, kept as they are) and a gap where nothing was seen:

    >>> len(surface_points(np.full(180, 2.0))), len(surface_points([2.0, 20.0, 2.0]))
    (180, 2)
    """
    r = np.asarray(image, dtype=float).ravel()
    n = len(r)
    a = beam_angles(n, fov_deg)
    seen = np.isfinite(r) & (r > 0.0) & (r < max_range)
    xy = np.column_stack([r * np.cos(a), r * np.sin(a)])
    if n < 2:
        return xy[seen]
    step = beam_step(n, fov_deg)
    parts = [xy[seen]]
    if fov_deg >= 360.0:  # all round: the last beam and the first are neighbours too
        r, seen, xy = np.append(r, r[0]), np.append(seen, seen[0]), np.vstack([xy, xy[:1]])
    gap = np.linalg.norm(np.diff(xy, axis=0), axis=1)
    reach = np.minimum(r[:-1], r[1:]) * step / math.cos(math.radians(max_incidence_deg)) + slack_m
    joined = seen[:-1] & seen[1:] & (gap <= reach)
    k = np.flatnonzero(joined)
    if len(k):
        # Interior samples of every joined segment: ceil(gap / resolution) - 1 of them, evenly spaced.
        count = np.maximum(np.ceil(gap[k] / resolution_m).astype(int) - 1, 0)
        seg = np.repeat(k, count)
        if len(seg):
            within = np.arange(len(seg)) - np.repeat(np.cumsum(count) - count, count)
            t = (within + 1) / np.repeat(count + 1, count)
            parts.append(xy[seg] + t[:, None] * (xy[seg + 1] - xy[seg]))
    return np.concatenate(parts)


def in_3d(xy: np.ndarray) -> np.ndarray:
    """2-D points as 3-D ones at z = 0.

    >>> in_3d(np.array([[1.0, 2.0]])).tolist()
    [[1.0, 2.0, 0.0]]
    """
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    return np.column_stack([xy, np.zeros(len(xy))])


def se2(x: float, y: float, theta: float) -> np.ndarray:
    """The plane motion (a shift, then a turn of ``theta`` radians) as a 4 x 4 homogeneous transform."""
    T = np.eye(4)
    c, s = math.cos(theta), math.sin(theta)
    T[:2, :2] = [[c, -s], [s, c]]
    T[:2, 3] = x, y
    return T


def planar(T: np.ndarray) -> tuple[float, float, float]:
    """The plane motion of a 4 x 4 transform (its x, y shift and its heading in [-pi, pi)).

    >>> [round(v, 6) for v in planar(se2(1.0, 2.0, 0.5))]
    [1.0, 2.0, 0.5]
    """
    theta = math.atan2(T[1, 0], T[0, 0])
    return float(T[0, 3]), float(T[1, 3]), (theta + math.pi) % (2 * math.pi) - math.pi
