"""What the control laws perceive: a few features computed from one laser scan, nothing else.

The features are the ones a wall-following, corridor-following robot needs: the range straight ahead,
the perpendicular distance to the wall on each side, whether a side is open (a doorway or side corridor),
and the angle of the walls in the robot's frame. Walls are found without a map: short straight runs of
scan points give local wall directions; folded onto a 90-degree grid (walls in buildings meet at right
angles) their robust mean says how far the robot is turned from the walls around it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .world import LaserSpec

HALF_WINDOW = 3  # scan points either side of the centre of a straight-run window
MAX_SAG = 0.025  # m: a window with a point further than this from its chord is not straight
AGREE = math.radians(1.5)  # chords within this of the weighted median direction are averaged
FOLD_LIMIT = math.radians(25)  # wall directions further from the robot's axes than this are ignored
MAX_CHORD = 1.0  # m: longer chords span too much (they bridge gaps and corners)
NOMINAL_NOISE = 0.01  # m: the range noise HALF_WINDOW, MAX_SAG and MAX_CHORD are set for


@dataclass(frozen=True)
class Percept:
    """Features of one scan. Distances in metres, angles in radians (counter-clockwise positive).

    Attributes
    ----------
    front : float
        Median range of the beams straight ahead.
    left, right : float
        Perpendicular distance to the wall on that side; ``inf`` when the side is open or the
        sector beside the robot looks into an opening.
    left_open, right_open : bool
        The beams across that side reach beyond ``open_range``: a side corridor or doorway.
    wall_angle : float
        Direction of the surrounding walls in the robot frame, folded to the nearest axis; ``nan``
        when no straight wall is seen. Turning by ``+wall_angle`` aligns the robot with them.
    """

    front: float
    left: float
    right: float
    left_open: bool
    right_open: bool
    wall_angle: float


class Perception:
    """Compute :class:`Percept` features from scans of one laser.

    Parameters
    ----------
    laser : LaserSpec
        Beam angles and maximum range.
    open_range : float
        A side whose beams read further than this is open.

    Examples
    --------
    >>> from bootmap.sim.world import LaserSpec
    >>> spec = LaserSpec(180, -math.pi / 2, math.pi / 2, 8.0, 0.0, 0.0)
    >>> a = spec.angles  # a corridor 2 m wide, robot in the middle, aligned
    >>> ranges = np.minimum(1.0 / np.abs(np.sin(a) + 1e-12), 8.0)
    >>> p = Perception(spec, open_range=3.0)(ranges)
    >>> round(p.left, 3), round(p.right, 3), p.left_open, round(abs(p.wall_angle), 3)
    (1.0, 1.0, False, 0.0)
    """

    def __init__(self, laser: LaserSpec, open_range: float):
        self.range_max = laser.range_max
        self.open_range = open_range
        # Noisier ranges need longer runs: a chord's direction error is the range noise over its length,
        # so the window and the straightness test grow with the noise beyond the shipped 1 cm.
        self.noise_scale = max(1.0, laser.noise_sd / NOMINAL_NOISE)
        self.half_window = int(round(HALF_WINDOW * self.noise_scale))
        self.max_sag = MAX_SAG * self.noise_scale
        self.max_chord = MAX_CHORD * self.noise_scale
        a = laser.angles
        self.angles, self.cos, self.sin = a, np.cos(a), np.sin(a)
        deg = np.degrees(a)
        self.front_idx = np.flatnonzero(np.abs(deg) <= 2.6)
        self.left_idx = np.flatnonzero((deg >= 75) & (deg <= 90.01))
        self.right_idx = np.flatnonzero((deg <= -75) & (deg >= -90.01))
        self.left_edge_idx = np.flatnonzero(deg >= 87.5)  # openings are judged right beside the robot
        self.right_edge_idx = np.flatnonzero(deg <= -87.5)
        # far_edge scans from the side beam towards the front
        self.left_sweep = np.flatnonzero((deg > 0) & (deg <= 90.01))[::-1]
        self.right_sweep = np.flatnonzero((deg < 0) & (deg >= -90.01))

    def __call__(self, ranges: np.ndarray) -> Percept:
        phi = self.wall_angle(ranges)
        phi0 = 0.0 if math.isnan(phi) else phi
        left_open = _median(ranges[self.left_edge_idx]) > self.open_range
        right_open = _median(ranges[self.right_edge_idx]) > self.open_range
        left = math.inf if left_open else self._side(ranges, self.left_idx, phi0, +1)
        right = math.inf if right_open else self._side(ranges, self.right_idx, phi0, -1)
        return Percept(_median(ranges[self.front_idx]), left, right, left_open, right_open, phi)

    def _side(self, ranges: np.ndarray, idx: np.ndarray, phi: float, side: int) -> float:
        """Perpendicular distance to the wall on one side; ``inf`` when the sector beside the robot
        already looks into an opening (its edge beams may not have reached it yet)."""
        d = _median(side * ranges[idx] * np.sin(self.angles[idx] - phi))
        return d if d <= self.open_range else math.inf

    def wall_angle(self, ranges: np.ndarray) -> float:
        """Robust direction of the straight walls in view, folded onto the robot's axes; nan if none."""
        x, y = ranges * self.cos, ranges * self.sin
        k = self.half_window
        cx, cy = x[2 * k:] - x[:-2 * k], y[2 * k:] - y[:-2 * k]
        length = np.hypot(cx, cy)
        # A window is straight when every point in it lies within MAX_SAG of its chord: testing the middle
        # point alone passes a window with a step at one end (a door recess, a locker), whose chord is
        # then tilted by several degrees.
        n = len(ranges) - 2 * k
        cross = np.zeros(n)
        for j in range(1, 2 * k):
            mx, my = x[j:j + n] - x[:n], y[j:j + n] - y[:n]
            np.maximum(cross, np.abs(cx * my - cy * mx), out=cross)
        with np.errstate(divide="ignore", invalid="ignore"):
            sag = cross / length
        ok = (sag < self.max_sag) & (length > 0.05) & (length < self.max_chord)
        ok &= (ranges[2 * k:] < self.range_max * 0.98) & (ranges[:-2 * k] < self.range_max * 0.98)
        if ok.sum() < 4:
            return math.nan
        folded = (np.arctan2(cy[ok], cx[ok]) + math.pi / 4) % (math.pi / 2) - math.pi / 4
        w = length[ok] ** 2  # a longer chord gives its direction more precisely
        w[np.abs(folded) > FOLD_LIMIT] = 0.0
        if w.sum() <= 0:
            return math.nan
        # Robust mean: the weighted median direction, then the weighted mean of the chords that agree
        # with it (the edge of a door recess or of clutter tilts a few chords; they do not pull).
        order = np.argsort(folded)
        cumulative = np.cumsum(w[order])
        first = float(folded[order][np.searchsorted(cumulative, 0.5 * cumulative[-1])])
        w[np.abs(folded - first) > AGREE] = 0.0
        total = w.sum()
        return first if total <= 0 else float(np.dot(folded, w) / total)

    def near_edge(self, ranges: np.ndarray, side: int, depth: float) -> float:
        """Distance ahead to where the wall on ``side`` ends (the near edge of an opening not reached yet).

        Sweeping from the side beam towards the front, the beams hit the wall beside the robot (within
        ``depth`` of its axis) until two beams in a row reach beyond it (two, so that a drop-out is not
        taken for an opening). The wall ends between the last beam on it and the first beyond: the
        estimate is the middle of the two beams' crossings of the wall's line, within half a beam's
        spacing of the edge (a couple of centimetres a metre ahead). A wall that runs on out of the
        laser's reach ends there, as far as the scan can tell; ``inf`` if no beam on that side leaves the
        wall, nan if the side beam itself already looks into an opening.
        """
        idx = self.left_sweep if side > 0 else self.right_sweep
        r = ranges[idx]
        s, c = np.abs(self.sin[idx]), self.cos[idx]
        beyond = (r * s > depth) | (r >= self.range_max * 0.98)
        if beyond[0]:
            return math.nan
        two = np.flatnonzero(beyond[1:-1] & beyond[2:]) + 1
        if not len(two):
            return math.inf
        i = two[0]
        wall = r[i - 1] * s[i - 1]  # the wall's distance from the axis, seen by the last beam on it
        return float(0.5 * (r[i - 1] * c[i - 1] + wall * c[i] / max(s[i], 1e-9)))

    def far_edge(self, ranges: np.ndarray, side: int, depth: float) -> float:
        """Distance ahead to the far edge of the opening on ``side`` (+1 left, -1 right).

        Sweeping from the side beam towards the front, the first beam that stays within ``depth`` of
        the robot's axis has left the opening: it hits the opening's far wall or the corridor wall
        beyond, and its forward coordinate is where the opening ends. ``inf`` if no beam does.
        """
        idx = self.left_sweep if side > 0 else self.right_sweep
        r = ranges[idx]
        lateral = np.abs(r * self.sin[idx])
        hit = np.flatnonzero((lateral < depth) & (r < self.range_max * 0.98))
        if not len(hit):
            return math.inf
        i = idx[hit[0]]
        return float(ranges[i] * self.cos[i])


def _median(v: np.ndarray) -> float:
    """Median of a short array (sorting a handful of values beats np.median's overhead)."""
    s = np.sort(v)
    n = len(s)
    return float(s[n // 2]) if n % 2 else float(0.5 * (s[n // 2 - 1] + s[n // 2]))
