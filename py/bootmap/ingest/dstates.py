"""Where a hill-climbing control law would have settled: the distinctive states of a recorded run.

A log never stops at dstates: the robot drove on. The SSH defines a dstate as the fixed point of a
control law; the law that ends a travel and starts a turn settles at the end of a corridor, and the one
that starts the next travel settles facing along the new corridor. So a recorded run is cut where its
odometry shows a turn between two travels, and each turn gives two dstates: the last scan before the
heading starts to change, and the first after it has stopped.

How a turn is found (all from odometry, never from the true poses):

1. The heading is unwrapped by summing the wrapped change between consecutive scans, so a spin or a
   wiggle across +-180 degrees adds up correctly.
2. At each scan, the heading change over a window of ``window_m`` metres of travel centred on it; a
   corner whose change is spread over a few metres (a curved loop) still adds up within the window,
   where a scan-to-scan threshold would miss it.
3. Scans whose windowed change is at least ``detect_deg`` form stretches; in each, the turn starts at
   the last scan whose heading is within ``settled_deg`` of the stretch's first heading, and ends at the
   first scan within ``settled_deg`` of its last: that is where the robot was travelling straight.
4. A stretch is a turn if its start and end headings differ by ``turn_deg`` or more (wrapped: a full
   spin on the spot is no turn). Turns less than ``min_travel_m`` apart are one turn.

A curve longer than the window is read short by up to ``2 * settled_deg`` (its ends are taken as
straight).

Passing straight through a junction is a visit too, where asked for (:class:`JunctionDetector`; off by
default): the travel law that follows a corridor would have settled in the middle of a side opening,
so within a travel, a stretch where one side's beams (75-90 degrees off the heading) read further than
``open_m`` over ``min_width_m`` to ``max_width_m`` of travel (a side corridor: wider than a doorway,
narrower than a hall) gives one dstate, at its middle scan. That needs the scan, not odometry alone.

Example
-------
>>> heading = np.radians([0] * 20 + [30, 60] + [90] * 20)   # a corner after 20 scans
>>> distance = np.arange(42) * 0.5
>>> [(t.before, t.after, round(t.angle_deg)) for t in find_turns(distance, heading)]
[(19, 22, 90)]
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .scans import Pose, wrap


@dataclass(frozen=True)
class TurnDetector:
    """The parameters of :func:`find_turns` (see the module docstring).

    Parameters
    ----------
    window_m : float
        Metres of travel over which the heading change is summed, centred on each scan.
    detect_deg : float
        A windowed change of at least this many degrees marks a stretch that may hold a turn.
    turn_deg : float
        The least heading change, start to end of a stretch, that counts as a turn.
    settled_deg : float
        A heading within this of the stretch's first (last) is still (already) travelling straight.
    min_travel_m : float
        Turns closer than this (a travel too short to be one) are joined into one turn.
    """

    window_m: float = 8.0
    detect_deg: float = 20.0
    turn_deg: float = 45.0
    settled_deg: float = 10.0
    min_travel_m: float = 1.0


@dataclass(frozen=True)
class JunctionDetector:
    """The parameters of :func:`find_passes` (see the module docstring).

    Parameters
    ----------
    open_m : float
        A side whose beams read further than this (median) is open.
    min_width_m, max_width_m : float
        An opening is a side corridor when it stays open over this much travel.
    margin_m : float
        A pass this close to either end of its travel is at the turn's place already.
    """

    open_m: float = 4.0
    min_width_m: float = 1.5
    max_width_m: float = 5.0
    margin_m: float = 1.5


@dataclass(frozen=True)
class FoundTurn:
    """A turn between two travels: the scans it starts and ends at, and the heading change (degrees)."""

    before: int
    after: int
    angle_deg: float


def odometry_track(poses: list[Pose] | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cumulative distance travelled (m) and unwrapped heading (rad) at each pose.

    Consecutive heading changes are wrapped before they are summed, so a heading that crosses +-pi, or
    a spin, is not read as a jump of 2 pi.
    """
    p = np.asarray(poses, dtype=float).reshape(-1, 3)
    if not len(p):
        return np.zeros(0), np.zeros(0)
    steps = np.hypot(np.diff(p[:, 0]), np.diff(p[:, 1]))
    distance = np.concatenate([[0.0], np.cumsum(steps)])
    heading = p[0, 2] + np.concatenate([[0.0], np.cumsum(wrap(np.diff(p[:, 2])))])
    return distance, heading


def find_turns(distance: np.ndarray, heading: np.ndarray, detector: TurnDetector = TurnDetector()) -> list[FoundTurn]:
    """The turns of a run, from its cumulative distance and unwrapped heading (:func:`odometry_track`)."""
    windowed = _windowed_change(distance, heading, detector.window_m)
    marked = np.abs(windowed) >= np.radians(detector.detect_deg)
    turns = [_settle(heading, a, b, np.radians(detector.settled_deg)) for a, b in _runs(marked)]
    turns = _join_close(turns, distance, heading, detector.min_travel_m)
    least = np.radians(detector.turn_deg)
    return [FoundTurn(int(b), int(a), float(np.degrees(wrap(heading[a] - heading[b])))) for b, a in turns
            if abs(wrap(heading[a] - heading[b])) >= least]


def _windowed_change(distance: np.ndarray, heading: np.ndarray, window_m: float) -> np.ndarray:
    """At each scan, the heading change from the first scan within ``window_m / 2`` behind it to the last
    within ``window_m / 2`` ahead (by distance travelled, so a spin on the spot falls in one window)."""
    lo = np.searchsorted(distance, distance - window_m / 2, side="left")
    hi = np.searchsorted(distance, distance + window_m / 2, side="right") - 1
    return heading[hi] - heading[lo]


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Maximal stretches of True, as (first, last) indices."""
    edges = np.diff(np.concatenate([[0], mask.astype(int), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1))


def _settle(heading: np.ndarray, first: int, last: int, settled: float) -> tuple[int, int]:
    """Within a marked stretch, the last scan still on the first heading and the first already on the last."""
    span = heading[first:last + 1]
    left = np.flatnonzero(np.abs(span - span[0]) > settled)
    right = np.flatnonzero(np.abs(span - span[-1]) > settled)
    before = first + max(left[0] - 1, 0) if len(left) else first
    after = first + min(right[-1] + 1, len(span) - 1) if len(right) else last
    return before, max(after, before)


def _join_close(turns: list[tuple[int, int]], distance: np.ndarray, heading: np.ndarray,
                min_travel_m: float) -> list[tuple[int, int]]:
    """Turns separated by less than ``min_travel_m`` of travel (or overlapping) become one."""
    joined: list[tuple[int, int]] = []
    for before, after in turns:
        if joined and distance[before] - distance[joined[-1][1]] < min_travel_m:
            joined[-1] = (joined[-1][0], max(after, joined[-1][1]))
        else:
            joined.append((before, after))
    return joined


def side_ranges(scans) -> tuple[np.ndarray, np.ndarray]:
    """Per scan, the median range of the beams 75-90 degrees to the left, and to the right."""
    left, right = np.empty(len(scans)), np.empty(len(scans))
    for k, scan in enumerate(scans):
        degrees = np.degrees(scan.angles)
        ranges = np.minimum(scan.ranges, scan.range_max)
        left[k] = np.median(ranges[(degrees >= 75) & (degrees <= 90)])
        right[k] = np.median(ranges[(degrees <= -75) & (degrees >= -90)])
    return left, right


def find_passes(left: np.ndarray, right: np.ndarray, distance: np.ndarray, turns: list[FoundTurn],
                detector: JunctionDetector = JunctionDetector()) -> list[int]:
    """The scans where a travel passes straight through a junction (see the module docstring), in
    time order: the middle of each side opening of a side corridor's width, on either side."""
    passes: set[int] = set()
    for turn, following in zip(turns, turns[1:]):
        start, end = turn.after, following.before
        for side in (left, right):
            for first, last in _runs(side[start:end + 1] > detector.open_m):
                width = distance[start + last] - distance[start + first]
                middle = start + (first + last) // 2
                if detector.min_width_m <= width <= detector.max_width_m and \
                        min(distance[middle] - distance[start], distance[end] - distance[middle]) >= detector.margin_m:
                    passes.add(int(middle))
    return _one_per_crossing(sorted(passes), distance, detector.margin_m)


def _one_per_crossing(passes: list[int], distance: np.ndarray, margin_m: float) -> list[int]:
    """Openings on both sides at once (a crossing) are one pass: the first of any within the margin."""
    kept: list[int] = []
    for i in passes:
        if not kept or distance[i] - distance[kept[-1]] >= margin_m:
            kept.append(i)
    return kept


def dstate_scans(turns: list[FoundTurn], passes: list[int] = ()) -> list[int]:
    """The chosen scans, in time order: each turn's start and end, and the junctions passed."""
    return sorted([i for t in turns for i in (t.before, t.after)] + list(passes))
