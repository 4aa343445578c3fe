"""The record every log reader yields: one laser scan with the robot's poses when it was taken.

A log is a stream of :class:`Scan` records in time order, whatever its format (g2o, CARMEN, ROS bag):
the ranges and the angles they were read at, the odometry pose (what the robot itself measured, the
only pose the learning may use) and, when the log has one, the true pose (for evaluation only).
:func:`to_image` turns a scan into a tableau image the way the simulator writes one.

Example
-------
>>> s = Scan(0.0, np.array([1.0, 2.0, 60.0]), -np.pi / 2, np.pi / 2, 50.0, (0.0, 0.0, 0.0))
>>> s.angles.round(3).tolist(), to_image(s, beams=3, max_range=20.0)
([-1.571, 0.0, 1.571], (1.0, 2.0, 20.0))
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

Pose = tuple[float, float, float]  # x (m), y (m), heading (rad, counter-clockwise from x)

#: The tableau's image format, as the simulator writes it: 180 beams from -90 to +90 degrees.
IMAGE_BEAMS = 180
IMAGE_ANGLE_MIN = -math.pi / 2
IMAGE_ANGLE_MAX = math.pi / 2


@dataclass(frozen=True, eq=False)
class Scan:
    """One laser scan of a log.

    Parameters
    ----------
    time : float
        Seconds (the log's clock).
    ranges : numpy.ndarray
        Metres, beam ``i`` at angle ``angle_min + i * angle_increment``; a reading at or beyond
        ``range_max`` saw nothing.
    angle_min, angle_increment : float
        Radians, relative to the robot's heading; negative is to the right.
    range_max : float
        The sensor's maximum range, metres.
    odometry : Pose
        The robot's own dead-reckoned pose when the scan was taken.
    truth : Pose, optional
        The log's best estimate of the true pose (optimised, or from a ground-truth topic); never used
        by the learning.
    odometry_gap : str
        Empty where the log holds odometry from the previous scan to this one; else how the gap was read:
        ``"laser"`` (a turn on the spot the two scans' beams show, :func:`turn_in_place`) or ``"still"``
        (no motion: the previous pose carried over).
    """

    time: float
    ranges: np.ndarray
    angle_min: float
    angle_increment: float
    range_max: float
    odometry: Pose
    truth: Pose | None = None
    odometry_gap: str = ""

    @property
    def angles(self) -> np.ndarray:
        return self.angle_min + self.angle_increment * np.arange(len(self.ranges))


def image_angles(beams: int = IMAGE_BEAMS) -> np.ndarray:
    """The beam angles of a tableau image (the simulator's: both ends included)."""
    return np.linspace(IMAGE_ANGLE_MIN, IMAGE_ANGLE_MAX, beams)


def to_image(scan: Scan, beams: int = IMAGE_BEAMS, max_range: float = 20.0) -> tuple[float, ...]:
    """A scan as a tableau image: ``beams`` readings from -90 to +90 degrees, clipped at ``max_range``.

    Each image beam takes the nearest beam of the scan (not an interpolation, which would invent
    points between a near wall and a far one); an image beam outside the scan's field of view, or whose
    reading saw nothing, reads ``max_range``, as the simulated laser's does.
    """
    want = image_angles(beams)
    idx = np.rint((want - scan.angle_min) / scan.angle_increment).astype(int)
    inside = (idx >= 0) & (idx < len(scan.ranges))
    out = np.full(beams, float(max_range))
    ranges = np.asarray(scan.ranges, dtype=float)
    seen = np.where(ranges >= scan.range_max, max_range, ranges)
    out[inside] = np.minimum(seen[idx[inside]], max_range)
    return tuple(np.round(out, 4).tolist())


def wrap(angle: float | np.ndarray) -> float | np.ndarray:
    """An angle (radians) in [-pi, pi)."""
    return (np.asarray(angle) + np.pi) % (2 * np.pi) - np.pi if isinstance(angle, np.ndarray) else \
        (angle + math.pi) % (2 * math.pi) - math.pi


def compose(a: Pose, b: Pose) -> Pose:
    """Pose ``a`` followed by the motion ``b`` expressed in ``a``'s frame (SE(2) composition)."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], wrap(a[2] + b[2]))


def between(a: Pose, b: Pose) -> Pose:
    """The motion from pose ``a`` to pose ``b``, in ``a``'s frame: ``a^-1 (+) b``, so that
    ``compose(a, between(a, b)) == b``."""
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return (c * dx + s * dy, -s * dx + c * dy, wrap(b[2] - a[2]))


#: A turn on the spot is read from two scans' beams only where they agree this well (median, metres: a
#: few times a laser's noise) over at least this much of their view, and no turn this far from it
#: agrees a third as well.
TURN_AGREE_M, TURN_OVERLAP_DEG, TURN_UNIQUE_DEG = 0.05, 60.0, 10.0


def turn_in_place(a: Scan, b: Scan, max_range: float = 20.0) -> float | None:
    """The turn (radians, counter-clockwise) from scan ``a`` to scan ``b`` of a robot that turned on the
    spot between them: the shift of ``b``'s beams that lays them on ``a``'s, where over at least
    :data:`TURN_OVERLAP_DEG` of view they agree to :data:`TURN_AGREE_M` and no shift
    :data:`TURN_UNIQUE_DEG` or more away agrees a third as well; None where no shift does (the robot
    also moved, or the scans are ambiguous, as in a featureless hall).

    >>> ranges = 2.0 + np.sin(np.linspace(0, 7, 361)) + np.linspace(0, 1, 361)
    >>> a = Scan(0.0, ranges[60:301], -np.radians(60), np.radians(0.5), 50.0, (0.0, 0.0, 0.0))
    >>> b = Scan(1.0, ranges[100:341], -np.radians(60), np.radians(0.5), 50.0, (0.0, 0.0, 0.0))
    >>> round(float(np.degrees(turn_in_place(a, b))), 1)   # b's beams see what a's saw 20 degrees left
    20.0
    """
    beams = 361
    step = math.pi / (beams - 1)
    ia, ib = np.array(to_image(a, beams, max_range)), np.array(to_image(b, beams, max_range))
    least = int(math.ceil(math.radians(TURN_OVERLAP_DEG) / step))
    shifts = np.arange(-(beams - least), beams - least + 1)
    agree = np.full(len(shifts), np.inf)
    for n, k in enumerate(shifts):
        x, y = (ia[k:], ib[:beams - k]) if k >= 0 else (ia[:k], ib[-k:])
        seen = (x < max_range) | (y < max_range)  # a direction neither saw anything in says nothing
        if seen.sum() >= least:
            agree[n] = float(np.median(np.abs(x[seen] - y[seen])))
    best = int(np.argmin(agree))
    far = np.abs(shifts - shifts[best]) * step >= math.radians(TURN_UNIQUE_DEG)
    if not np.isfinite(agree[best]) or agree[best] > TURN_AGREE_M or \
            agree[far].min(initial=np.inf) < 3 * max(agree[best], 0.01):
        return None
    # b's beam j sees what a's beam j + k saw: the robot turned k beams to the left.
    return float(shifts[best] * step)
