"""Paths in the plane: a robot's drawn track thinned to what a picture needs.

:func:`simplify` is the Ramer-Douglas-Peucker simplification: the fewest of a path's points that keep
every point within a tolerance of the drawn line. The simulator and the log reader both record a
robot's true path in a tableau's ``meta`` this way, so that a long run stays small enough to post to the
service (its ``meta`` limit) and to draw.

:func:`main_axis` is a building's main axis from a path through it: the direction its corridors run
(modulo 90 degrees), which both a log's truth (heading sectors of the true poses) and the map of a log
(heading sectors of the odometry, :func:`bootmap.mapping.sectors.sector_angles`) are aligned to.

Example
-------
>>> xy = np.array([(0, 0), (1, 0.01), (2, 0), (2, 1), (2, 2)], dtype=float)
>>> simplify(xy, 0.05).tolist()
[0, 2, 4]
"""

from __future__ import annotations

import numpy as np


def simplify(xy: np.ndarray, tolerance_m: float) -> np.ndarray:
    """Indices of the Ramer-Douglas-Peucker simplification of a path (first and last kept; a path of
    fewer than three points is all kept)."""
    if len(xy) < 3:
        return np.arange(len(xy))
    keep = np.zeros(len(xy), dtype=bool)
    keep[[0, -1]] = True
    stack = [(0, len(xy) - 1)]
    while stack:  # iterative: a 4,000-point path would overflow Python's recursion
        a, b = stack.pop()
        if b - a < 2:
            continue
        offset = _distance_to_segment(xy[a + 1:b], xy[a], xy[b])
        k = int(np.argmax(offset))
        if offset[k] > tolerance_m:
            keep[a + 1 + k] = True
            stack += [(a, a + 1 + k), (a + 1 + k, b)]
    return np.flatnonzero(keep)


def _distance_to_segment(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    span = float(ab @ ab)
    t = np.zeros(len(points)) if span == 0 else np.clip((points - a) @ ab / span, 0.0, 1.0)
    return np.hypot(*(points - a - t[:, None] * ab).T)


def main_axis(poses, tolerance_m: float = 1.0) -> float:
    """The building's main axis (radians, in [-pi/4, pi/4)): the mean direction of the path's straight
    legs modulo 90 degrees, each leg weighted by its length."""
    xy = np.asarray(poses, dtype=float).reshape(-1, 3)[:, :2]
    legs = np.diff(xy[simplify(xy, tolerance_m)], axis=0)
    length = np.hypot(legs[:, 0], legs[:, 1])
    direction = np.arctan2(legs[:, 1], legs[:, 0])
    # Directions four times over: corridors at 0, 90, 180 and 270 degrees all point the same way.
    mean = np.arctan2((length * np.sin(4 * direction)).sum(), (length * np.cos(4 * direction)).sum())
    return float((mean / 4 + np.pi / 4 + np.pi) % (2 * np.pi) - np.pi - np.pi / 4) if length.sum() else 0.0
