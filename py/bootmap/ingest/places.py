"""Places from the building, not from the drive: where a scan shows a junction, a corner or a room.

A log was not driven by the SSH control laws, so a turn seen in odometry is not reproducible: the robot
turns at a junction on one visit and drives straight through it on the next, and dstates chosen at
turns then exist on one visit and not on the other. The hybrid SSH (Beeson, Modayil and Kuipers, IJRR
2010) finds places from the laser's local structure instead: a place is where the free space around
the robot opens onto more than one way on (its *gateways*), so every pass through it is a visit, with
the same local description each time, whichever way the robot drives.

One scan (a front laser, 180 degrees) gives the gateways ahead and to the sides; the way the robot came
is always one more, behind it:

- an **opening** is a run of beams that see nothing within ``open_m`` (wider than a corridor is, so a
  corridor's own walls never open);
- it is a **gateway** when the obstacles flanking the run are at least ``gateway_m`` apart: wider than
  a door (0.8-1.0 m), as narrow as a corridor (building codes ask 1.1 m or more), so that where
  corridors and halls meet is a place and every office door along a corridor is not;
- a scan is on a **path** when its only gateway lies within ``ahead_deg`` of straight ahead: the
  corridor goes on and nothing else leaves it. Any other scan is at a **place**: a junction (two or more
  gateways), a corner (one gateway to a side: the way ahead is closed), a room (gateways all round), or
  a dead end (none).

Consecutive place scans make one **visit**; visits less than ``min_path_m`` of travel apart are one (a
place's radius: a junction whose side opening is lost for a scan or two is still one place). A visit
whose odometry turns by ``turn_deg`` or more from its first scan to its last holds a turn: its two
dstates are the scan it arrives at and the scan it leaves from. Otherwise the robot passed through, and
the visit's dstate is its middle scan.

Every parameter is a fact about buildings and lasers, set once, never fitted to a log.

Example
-------
A corridor 2 m wide seen along its axis has one gateway ahead (a path); where a side corridor opens to
the left, the scan has two (a place):

>>> angles = np.linspace(-np.pi / 2, np.pi / 2, 181)
>>> corridor = np.minimum(1.0 / np.maximum(np.abs(np.sin(angles)), 1e-9), 50.0)
>>> local_topology(corridor, angles, 50.0)
'path'
>>> junction = np.where(angles > np.radians(60), 50.0, corridor)
>>> [round(g.direction_deg) for g in gateways(junction, angles, 50.0)], local_topology(junction, angles, 50.0)
([0, 75], 'place')
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .scans import Scan, wrap

PATH, PLACE = "path", "place"


@dataclass(frozen=True)
class PlaceDetector:
    """Where a log's places are (see the module docstring).

    Parameters
    ----------
    open_m : float
        A direction is open when the laser sees nothing within this many metres: more than a corridor's
        width (1.5-2.5 m in most buildings), so a corridor's walls seen sideways never open.
    gateway_m : float
        An opening is a gateway when its flanking obstacles are at least this far apart: wider than a
        door, as narrow as a corridor.
    ahead_deg : float
        A single gateway within this of straight ahead is the path going on (a corridor's far end seen
        from anywhere along it lies well within it).
    min_path_m : float
        Visits closer than this (metres of travel) are one: a place's radius (the truth's, 3 m), so that
        one junction seen, lost and seen again over a few metres is one visit, and two places are never
        closer than a place is wide.
    turn_deg : float
        A visit whose heading changes this much holds a turn (the SSH's turns are between paths; the
        smallest angle between two corridors of a building is about 45 degrees).
    """

    open_m: float = 3.0
    gateway_m: float = 1.2
    ahead_deg: float = 35.0
    min_path_m: float = 3.0
    turn_deg: float = 45.0


@dataclass(frozen=True)
class Gateway:
    """A way on from the robot's pose: its direction (degrees, left positive) and width (metres)."""

    direction_deg: float
    width_m: float


@dataclass(frozen=True)
class Visit:
    """A visit to a place: the scans it spans (inclusive) and odometry's heading change across it (degrees)."""

    first: int
    last: int
    angle_deg: float

    def dstates(self, turn_deg: float) -> tuple[int, ...]:
        """The visit's dstates: where it arrives and where it leaves if it holds a turn, else its middle."""
        if abs(self.angle_deg) >= turn_deg and self.last > self.first:
            return (self.first, self.last)
        return ((self.first + self.last) // 2,)


def gateways(ranges: np.ndarray, angles: np.ndarray, range_max: float,
             detector: PlaceDetector = PlaceDetector()) -> list[Gateway]:
    """The gateways of one scan (``ranges`` at ``angles``, radians; a reading at ``range_max`` saw nothing)."""
    ranges = np.asarray(ranges, dtype=float)
    seen = ranges < range_max
    far = np.where(seen, ranges, np.inf)
    opened = far > detector.open_m
    edges = np.diff(np.concatenate([[0], opened.astype(int), [0]]))
    found = []
    for first, last in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1):
        width = _gap(far, angles, first, last, detector.open_m)
        if width >= detector.gateway_m:
            found.append(Gateway(math.degrees((angles[first] + angles[last]) / 2), width))
    return found


def _gap(far: np.ndarray, angles: np.ndarray, first: int, last: int, open_m: float) -> float:
    """How wide the open run ``first..last`` is: the distance between the obstacles flanking it. Where
    the run reaches the edge of the field of view (an opening beside the robot), its far side is out of
    view: the part in view is the flanking obstacle's distance from the edge beam, and a robot in the
    middle of an opening sees half of it, so that part counts twice (a door beside the robot stays a
    door, a side corridor's mouth a gateway)."""
    before, after = first - 1, last + 1
    if before < 0 and after >= len(far):
        return math.inf  # open all round: a hall
    if before >= 0 and after < len(far):
        p = far[before] * np.array([math.cos(angles[before]), math.sin(angles[before])])
        q = far[after] * np.array([math.cos(angles[after]), math.sin(angles[after])])
        return float(np.hypot(*(p - q)))
    flank, edge = (after, 0) if before < 0 else (before, len(far) - 1)
    apart = abs(angles[flank] - angles[edge])
    return 2.0 * float(far[flank] * (math.sin(apart) if apart < math.pi / 2 else 1.0))


def local_topology(ranges: np.ndarray, angles: np.ndarray, range_max: float,
                   detector: PlaceDetector = PlaceDetector()) -> str:
    """``"path"`` where the scan's only gateway is straight ahead, else ``"place"``."""
    found = gateways(ranges, angles, range_max, detector)
    if len(found) == 1 and abs(found[0].direction_deg) <= detector.ahead_deg:
        return PATH
    return PLACE


def scan_topology(scan: Scan, detector: PlaceDetector = PlaceDetector()) -> str:
    """:func:`local_topology` of a log's scan."""
    return local_topology(scan.ranges, scan.angles, scan.range_max, detector)


def find_visits(scans: list[Scan], distance: np.ndarray, heading: np.ndarray,
                detector: PlaceDetector = PlaceDetector()) -> list[Visit]:
    """The visits to places of a run, in time order, from its scans, cumulative distance and unwrapped
    odometry heading (:func:`~bootmap.ingest.dstates.odometry_track`)."""
    at_place = np.array([scan_topology(s, detector) == PLACE for s in scans])
    edges = np.diff(np.concatenate([[0], at_place.astype(int), [0]]))
    runs: list[list[int]] = []
    for first, last in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1):
        if runs and distance[first] - distance[runs[-1][1]] < detector.min_path_m:
            runs[-1][1] = int(last)
        else:
            runs.append([int(first), int(last)])
    return [Visit(a, b, float(np.degrees(wrap(heading[b] - heading[a])))) for a, b in runs]
