"""Truth from a log's poses: places, true dstates and corners, measured from the data, not from us.

A log has no world file to say where its places are, only the true (optimised) pose of every scan.

- **Places**: visits whose true positions all lie within ``radius_m`` of each other are one place (complete
  linkage), every visit to a corner; the two dstates of a turn are one visit, at the middle of its ends
  (a turn never leaves its place, though a robot that turns while driving ends it 2-4 m on).
- **True dstates**: a place and a heading sector, the sectors aligned to the building's main axis (the
  dominant direction of the corridors, found from the true path), named as the simulator names them
  (``P3:N``).
- **Corners**: where the true path bends (a Ramer-Douglas-Peucker simplification of the positions,
  bends closer than ``merge_m`` summed), ``turn_deg`` or more. They come from the positions alone, so
  they check the odometry's turn detector rather than repeat it.

Example
-------
>>> poses = [(0, 0, 0), (0.5, 0, 0), (10, 0, 1.57), (10, 0.5, 1.57), (10, 10, 1.57)]
>>> place_labels(poses, radius_m=3.0)
[0, 0, 1, 1, 2]
>>> true_dstates(poses, radius_m=3.0, axis_rad=0.0)
['P0:E', 'P0:E', 'P1:N', 'P1:N', 'P2:N']
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .dstates import FoundTurn, odometry_track
from ..paths import main_axis, simplify
from .scans import Pose, wrap

SECTORS = "ENWS"  # as bootmap.sim.world.heading_sector names them, here in the building's frame


def place_labels(poses: list[Pose] | np.ndarray, radius_m: float = 3.0,
                 together: list[tuple[int, int]] = (), apart: list[tuple[int, int]] = ()) -> list[int]:
    """A place index per pose: a place is a group of *visits* whose positions all lie within ``radius_m`` of
    each other (complete linkage: no chain of visits along a corridor makes one place of it, and two
    visits of one place are never more than ``radius_m`` apart, the distance loop closures are judged
    by). A visit is a pose, or the poses ``together`` joins (a turn's two ends: a turn never leaves its
    place, though a robot that turns while driving ends it 2-4 m on), at the middle of their positions.
    A pair in ``apart`` (a travel's two ends: a travel always leaves its place) is never in one place.
    Places are numbered in the order they are first visited.

    >>> place_labels([(0, 0, 0), (1, 0, 0), (3.5, 0, 0), (20, 0, 0), (0.5, 0, 0)], radius_m=3.0)
    [0, 0, 1, 2, 0]
    >>> place_labels([(0, 0, 0), (4, 0, 0), (2, 0.5, 0)], radius_m=3.0, together=[(0, 1)])
    [0, 0, 0]
    """
    from scipy.cluster.hierarchy import fcluster, linkage
    from scipy.spatial.distance import pdist, squareform

    groups, middles = _visits(poses, together)
    visit_of = {i: v for v, members in enumerate(groups) for i in members}
    n = len(visit_of)
    if len(groups) < 2:
        return [0] * n
    distance = squareform(pdist(middles))
    far = 2.0 * radius_m + float(distance.max())  # beyond any place: complete linkage never joins them
    for a, b in apart:
        i, j = visit_of[a], visit_of[b]
        if i != j:
            distance[i, j] = distance[j, i] = far
    clusters = fcluster(linkage(squareform(distance), method="complete"), t=radius_m, criterion="distance")
    first_seen: dict[int, int] = {}
    return [first_seen.setdefault(int(clusters[visit_of[i]]), len(first_seen)) for i in range(n)]


def visit_positions(poses: list[Pose] | np.ndarray, together: list[tuple[int, int]] = ()) -> np.ndarray:
    """Where each pose's visit is, as the truth places it (:func:`place_labels`): the middle of the
    positions of the poses ``together`` joins with it (a turn's two ends), else its own position. Loop
    closures and place recognition judge distances between visits from these, so that two poses of one
    true place are never judged farther apart than the place's radius.

    >>> visit_positions([(0, 0, 0), (4, 0, 0), (9, 0, 0)], together=[(0, 1)]).tolist()
    [[2.0, 0.0], [2.0, 0.0], [9.0, 0.0]]
    """
    groups, middles = _visits(poses, together)
    out = np.zeros((sum(map(len, groups)), 2))
    for members, middle in zip(groups, middles):
        out[members] = middle
    return out


def _visits(poses, together) -> tuple[list[list[int]], np.ndarray]:
    """The visits (groups of poses ``together`` joins, in order of their first pose) and their middles."""
    from scipy.cluster.hierarchy import DisjointSet

    xy = np.asarray(poses, dtype=float).reshape(-1, 3)[:, :2]
    turns = DisjointSet(range(len(xy)))
    for a, b in together:
        turns.merge(a, b)
    groups = sorted((sorted(members) for members in turns.subsets()), key=lambda members: members[0])
    return groups, np.array([xy[members].mean(axis=0) for members in groups]).reshape(-1, 2)


def true_dstates(poses: list[Pose] | np.ndarray, radius_m: float = 3.0, axis_rad: float | None = None,
                 together: list[tuple[int, int]] = (), apart: list[tuple[int, int]] = ()) -> list[str]:
    """The true dstate of each pose: its place (:func:`place_labels`) and its heading's sector in the
    building's frame."""
    p = np.asarray(poses, dtype=float).reshape(-1, 3)
    axis = main_axis(p) if axis_rad is None else axis_rad
    return [f"P{place}:{sector_name(heading, axis)}"
            for place, heading in zip(place_labels(p, radius_m, together, apart), p[:, 2])]


def sector_name(heading_rad: float, axis_rad: float) -> str:
    """The heading's sector (``E``, ``N``, ``W``, ``S``) in the building's frame."""
    return SECTORS[int(np.rint(wrap(heading_rad - axis_rad) / (np.pi / 2))) % 4]


@dataclass(frozen=True)
class Corner:
    """A bend of the true path: the scan at its apex and the change of direction (degrees)."""

    scan: int
    angle_deg: float


def corners_in_poses(poses: list[Pose] | np.ndarray, turn_deg: float = 45.0, tolerance_m: float = 0.5,
                     merge_m: float = 3.0) -> list[Corner]:
    """The corners the true path turns, from positions only (never the odometry, never the headings)."""
    xy = np.asarray(poses, dtype=float).reshape(-1, 3)[:, :2]
    keep = simplify(xy, tolerance_m)
    legs = np.diff(xy[keep], axis=0)
    length = np.hypot(legs[:, 0], legs[:, 1])
    bends = wrap(np.diff(np.arctan2(legs[:, 1], legs[:, 0])))
    corners, k = [], 0
    while k < len(bends):
        # A curve is several small bends joined by short legs: sum them into one corner.
        end = k
        while end + 1 < len(bends) and length[end + 1] < merge_m:
            end += 1
        total = float(np.degrees(wrap(bends[k:end + 1].sum())))  # a loop on the spot ends where it began
        if abs(total) >= turn_deg:
            corners.append(Corner(int(keep[(k + end) // 2 + 1]), total))
        k = end + 1
    return corners


@dataclass(frozen=True)
class CornerRecall:
    """How the odometry's turns compare with the corners seen in the true poses."""

    corners: int
    found: int
    turns: int
    turns_at_corners: int
    angle_errors_deg: list[float]

    @property
    def recall(self) -> float:
        return self.found / self.corners if self.corners else 1.0

    @property
    def precision(self) -> float:
        return self.turns_at_corners / self.turns if self.turns else 1.0

    def to_dict(self) -> dict:
        errors = np.abs(self.angle_errors_deg) if self.angle_errors_deg else np.zeros(0)
        return {"corners": self.corners, "found": self.found, "recall": self.recall, "turns": self.turns,
                "turns_at_corners": self.turns_at_corners, "precision": self.precision,
                "angle_error_deg_median": float(np.median(errors)) if len(errors) else None,
                "angle_error_deg_max": float(errors.max()) if len(errors) else None,
                "angles_within_10_deg": float((errors <= 10).mean()) if len(errors) else None}


def corner_recall(turns: list[FoundTurn], truth: list[Pose] | np.ndarray, corners: list[Corner],
                  match_m: float = 3.0) -> CornerRecall:
    """Which corners a found turn covers: the corner's apex lies within ``match_m`` metres of travel of
    the turn's stretch. Each turn's angle is compared with the true heading change over its stretch."""
    distance, heading = odometry_track(truth)
    near = [[abs(distance[c.scan] - np.clip(distance[c.scan], distance[t.before], distance[t.after])) <= match_m
             for t in turns] for c in corners]
    found = sum(any(row) for row in near)
    at_corners = sum(any(row[j] for row in near) for j in range(len(turns)))
    errors = [float(np.degrees(wrap(np.radians(t.angle_deg) - (heading[t.after] - heading[t.before]))))
              for t in turns]
    return CornerRecall(len(corners), found, len(turns), at_corners, errors)
