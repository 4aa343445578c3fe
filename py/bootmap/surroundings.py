"""A place match checked against the places around it: more of the experience at once than one place.

Place recognition by one place's local map (:mod:`bootmap.ingest.local_maps`, matched by
:class:`~bootmap.scan_match.ScanMatcher`) cannot tell look-alikes apart: the junctions of a long corridor, a
stretch of corridor that aligns turned or shifted. A revisit of a place is a revisit of its surroundings
too, wherever both drives saw them. So a match of visit ``j`` onto an earlier visit ``i`` (``j``'s pose in
``i``'s frame, ``T``) is checked where it predicts something else:

1. The places ``offset_m`` before and after ``j`` along its own drive (two place radii: other places, near
   enough for odometry to place them to within centimetres to decimetres) are put into ``i``'s frame by
   ``T`` composed with odometry's motion from ``j`` to them.
2. Each is looked for among the scans of ``i``'s own drive, ``offset_m`` plus a place radius either side of
   it and taken before ``j``: the scan whose odometry puts it nearest the prediction, if within a place
   radius. None there: ``i``'s drive did not pass that way, and that side says nothing.
3. Where one is found, the two places' local maps are aligned from the predicted motion (ICP alone, no
   search: :meth:`~bootmap.scan_match.ScanMatcher.match_prepared`) and scored as a match is.

The verified score is the mean of the match's own score and its surroundings' scores: a look-alike whose
surroundings differ loses, a revisit whose surroundings agree keeps its score. Only each visit's ``top``
likeliest earlier visits are checked (by the scores given), among those odometry says the robot has left
since (a scan between the two lies beyond a place radius of the earlier), as place recognition verifies
what it retrieves; every other pair scores 0. Only the scans' odometry and ranges are read, never their true poses.

Example
-------
A corridor driven twice from its start, a scan every 0.5 m: the second drive's visit at 5 m matched onto
the first's (the ``scores`` given here say the pair alike), and the places 6 m before and after it agree:

>>> import numpy as np
>>> from bootmap.ingest.scans import Scan
>>> from bootmap.scan_match import ScanMatcher
>>> a = np.radians(np.arange(-90, 90))
>>> def scan(k, x):
...     r = np.minimum(1 / np.maximum(np.abs(np.sin(a)), 1e-9), 20.0)
...     return Scan(float(k), r, -np.pi / 2, np.radians(1), 20.0, (x, 0.0, 0.0))
>>> xs = np.r_[np.arange(0, 20, 0.5), np.arange(0, 20, 0.5)]
>>> scans = [scan(k, x) for k, x in enumerate(xs)]
>>> V = SurroundingsCheck(ScanMatcher(fov_deg=360.0)).verify(scans, [10, 50], np.ones((2, 2)))
>>> V.shape, bool(V[1, 0] > 0.5), float(V[0, 1])
((2, 2), True, 0.0)
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from .errors import BadInput
from .ingest.dstates import odometry_track
from .ingest.local_maps import LOCAL_REACH_M, local_images
from .ingest.scans import Scan, between, compose
from .proc import in_processes
from .scan_match import ScanMatcher

__all__ = ["SurroundingsCheck"]

#: How far along the query's drive its surroundings are taken (m): two place radii, other places.
OFFSET_M = 6.0
#: How many of each visit's likeliest earlier visits are checked.
VERIFY_TOP = 3


def _inverse(p) -> tuple[float, float, float]:
    c, s = math.cos(p[2]), math.sin(p[2])
    return -c * p[0] - s * p[1], s * p[0] - c * p[1], -p[2]


class SurroundingsCheck:
    """Place matches verified by their surroundings; see the module docstring for the method.

    Parameters
    ----------
    matcher : ScanMatcher
        Matches the local maps (``fov_deg=360``); its ``place_radius_m`` is the place radius, its
        ``max_range`` the local maps' clip range, its ``n_jobs`` the processes the check runs in.
    offset_m : float
        How far before and after a visit, along its drive, its surroundings are taken (m).
    top : int
        How many of each visit's likeliest earlier visits (by the scores given) are checked.
    reach_m : float
        The local maps' reach (:func:`bootmap.ingest.local_maps.local_images`).
    """

    def __init__(self, matcher: ScanMatcher | None = None, offset_m: float = OFFSET_M, top: int = VERIFY_TOP,
                 reach_m: float = LOCAL_REACH_M):
        self.matcher = matcher if matcher is not None else ScanMatcher(fov_deg=360.0)
        self.offset_m = offset_m
        self.top = top
        self.reach_m = reach_m
        if not offset_m > 0 or top < 1:
            raise BadInput(f"a surroundings check needs offset_m > 0 and top >= 1, got {offset_m} and {top}")

    def verify(self, scans: Sequence[Scan], visits: Sequence[int], scores, allowed=None) -> np.ndarray:
        """The verified scores of each visit's likeliest earlier visits.

        Parameters
        ----------
        scans : sequence of Scan
            The drive's scans in time order, with their odometry.
        visits : sequence of int
            The scans the visits were made at, in time order.
        scores : array-like (n_visits, n_visits)
            How alike the visits are (e.g. :meth:`ScanMatcher.scores` of their local maps); ``scores[j, i]``
            for ``i < j`` is read, and chooses which ``top`` earlier visits of ``j`` are checked.
        allowed : array-like (n_visits, n_visits) of bool, optional
            The pairs that may be one place (``allowed[j, i]``), e.g. within odometry's reach; all when None.

        Returns
        -------
        ndarray (n_visits, n_visits)
            ``V[j, i]`` for ``i < j``: the mean of the match's score and its surroundings' scores, for each
            checked pair; 0 elsewhere.
        """
        n = len(visits)
        S = np.asarray(scores, dtype=float)
        if S.shape != (n, n):
            raise BadInput(f"scores of shape {S.shape} for {n} visits")
        ok = np.ones((n, n), dtype=bool) if allowed is None else np.asarray(allowed, dtype=bool)
        if ok.shape != (n, n):
            raise BadInput(f"allowed of shape {ok.shape} for {n} visits")
        if any(not 0 <= k < len(scans) for k in visits) or list(visits) != sorted(visits):
            raise BadInput(f"visits must be scan indices in time order, within the {len(scans)} scans")
        odometry = np.array([s.odometry[:3] for s in scans], dtype=float).reshape(-1, 3)
        left = self._left(odometry, visits)
        pairs = []
        for j in range(n):
            earlier = [i for i in range(j) if ok[j, i] and S[j, i] > 0 and left[i] < visits[j]]
            earlier.sort(key=lambda i: (-S[j, i], i))
            pairs += [(j, i) for i in earlier[:self.top]]
        V = np.zeros((n, n))
        if pairs:
            values = in_processes(_verified, self.matcher.n_jobs, (self, list(scans), list(visits)), pairs)
            for (j, i), v in zip(pairs, values):
                V[j, i] = v
        return V

    def _left(self, odometry: np.ndarray, visits: Sequence[int]) -> np.ndarray:
        """For each visit, the first scan after it that odometry puts beyond a place radius of it (the robot
        has left its place), or the number of scans."""
        radius = self.matcher.place_radius_m
        out = np.full(len(visits), len(odometry))
        for v, k in enumerate(visits):
            far = np.flatnonzero(np.hypot(*(odometry[k + 1:, :2] - odometry[k, :2]).T) > radius)
            if len(far):
                out[v] = k + 1 + far[0]
        return out


def _verified(check: SurroundingsCheck, scans: list[Scan], visits: list[int], pairs: list) -> list[float]:
    """The verified score of each pair ``(j, i)`` of visits (one process's share)."""
    m = check.matcher
    radius = m.place_radius_m
    odometry = np.array([s.odometry[:3] for s in scans], dtype=float).reshape(-1, 3)
    travelled, _ = odometry_track(odometry)
    prepared: dict[int, object] = {}

    def local(k: int):
        if k not in prepared:
            prepared[k] = m.prepare(local_images(scans, [k], check.reach_m, max_range=m.max_range)[0])
        return prepared[k]

    out = []
    for j, i in pairs:
        kj, ki = visits[j], visits[i]
        match = m.match_prepared(local(ki), local(kj))
        values = [match.score]
        if match.score > 0:
            for off in (-check.offset_m, check.offset_m):
                values += _surrounding(m, local, odometry, travelled, ki, kj, match.transform, off, radius)
        out.append(float(np.mean(values)))
    return out


def _surrounding(m: ScanMatcher, local, odometry, travelled, ki: int, kj: int, T, off: float,
                 radius: float) -> list[float]:
    """The score of the place ``off`` metres along ``kj``'s drive against ``ki``'s drive where the match
    ``T`` (``kj`` in ``ki``'s frame) predicts it: one score, or none where ``ki``'s drive did not pass."""
    target = travelled[kj] + off
    if not travelled[0] <= target <= travelled[-1]:
        return []
    kn = int(np.argmin(np.abs(travelled - target)))
    predicted = compose(T, between(odometry[kj], odometry[kn]))  # that place in ki's frame
    lo = int(np.searchsorted(travelled, travelled[ki] - abs(off) - radius, side="left"))
    hi = min(int(np.searchsorted(travelled, travelled[ki] + abs(off) + radius, side="right")), kj)
    if hi <= lo:
        return []
    there = np.array([between(odometry[ki], odometry[q]) for q in range(lo, hi)])
    gap = np.hypot(there[:, 0] - predicted[0], there[:, 1] - predicted[1])
    q = int(np.argmin(gap))
    if gap[q] > radius:
        return []
    start = compose(_inverse(there[q]), predicted)  # kn's pose in scan lo+q's frame
    return [m.match_prepared(local(lo + q), local(kn), start).score]
