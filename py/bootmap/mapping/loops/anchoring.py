"""Dead reckoning re-anchored where loops are closed: the drive and the joins made as one graph.

Loop closing bounds how far apart dead reckoning may put two visits of one place by the metres driven
between them (a place radius plus a share of them: odometry drifts as it goes). Once a loop is closed,
two visits are linked twice: along the drive, and through the join, where the robot was at one place both
times. A pose graph weighs both; here, as the bound is worst-case, the tighter way counts:

- the drive's hops between consecutive time points, each as long as the metres driven, moving the robot as
  odometry says;
- each join of two time points (one dstate), as long as the drive whose drift is a place radius
  (``radius_m / share``: the two visits may lie a radius apart), moving it nowhere.

Between two time points, the shortest way through that graph gives the metres of drive whose drift
matters (:attr:`Anchoring.driven`) and the displacement dead reckoning gives along it
(:attr:`Anchoring.displacement`). Where no join lies between them, or the joins are no shortcut, these are
the drive's own: the metres driven and the difference of the dead-reckoned positions. So a loop closed
early keeps a later revisit of the loop's places within reach, with its position corrected by the
closure, long after the drive alone would have drifted too far to tell.

Only the time points of joined dstates (*hubs*) need the graph's search: a way from any time point
reaches a hub first along the drive, at the hub just before or just after it. The hubs' shortest ways are
found by Floyd-Warshall carrying the displacement along; every other pair combines its two nearest hubs
each side.

Example
-------
A loop of 400 m closed where it began (t0 = t4, a join counting for 50 m of drive). From t0, t3 is 300 m
on along the drive but 150 m through the join, and dead reckoning's 3 m of drift round the loop is gone
from where it puts t3; between t1 and t3 the drive (200 m) is shorter than the way through the join
(250 m), and stays:

>>> import numpy as np
>>> along = np.array([0.0, 100, 200, 300, 400])
>>> xy = np.array([[0, 0], [100, 0], [100, 100], [0, 100], [0, 3.0]])
>>> a = Anchoring(along, xy, [[0, 4]], jump_m=50.0)
>>> float(a.driven[1, 3]), a.displacement[1, 3].tolist()
(200.0, [-100.0, 100.0])
>>> float(a.driven[0, 3]), a.displacement[0, 3].tolist()
(150.0, [0.0, 97.0])
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

__all__ = ["Anchoring"]


class Anchoring:
    """The shortest ways between time points through the drive and the joins made.

    Parameters
    ----------
    along : array (n,)
        The metres driven by each time point (non-decreasing).
    xy : array (n, 2)
        Each time point's dead-reckoned position.
    groups : sequence of sequences of int
        The joined dstates: each the time points loop closing made one dstate (a group of one is no join).
    jump_m : float
        How long a join counts, in metres of drive: a place radius over the drift per metre.

    Attributes
    ----------
    driven : ndarray (n, n)
        The metres of drive whose drift lies between each two time points, the joins' lengths included.
    displacement : ndarray (n, n, 2)
        ``displacement[i, j]``: where dead reckoning puts j from i along that way (a join moves nothing).
    """

    def __init__(self, along, xy, groups: Sequence[Sequence[int]], jump_m: float):
        along = np.asarray(along, dtype=float)
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        n = len(along)
        if xy.shape != (n, 2):
            raise ValueError(f"{len(xy)} positions for {n} time points")
        if not jump_m > 0:
            raise ValueError(f"a join must count for some drive, got jump_m={jump_m}")
        self.driven = np.abs(along[None, :] - along[:, None])
        self.displacement = xy[None, :, :] - xy[:, None, :]
        hubs = sorted({t for g in groups if len(g) > 1 for t in g})
        if not hubs:
            return
        H, V = self._hub_ways(along, xy, groups, hubs, jump_m)
        # each time point's nearest hub before and after it along the drive (or none: -1)
        hub_at = np.asarray(hubs)
        after = np.searchsorted(hub_at, np.arange(n), side="left")  # first hub at or after t
        ends = []  # the hub before t, and the hub at or after it
        for k in (after - 1, after):
            ok = (k >= 0) & (k < len(hubs))
            k = np.clip(k, 0, len(hubs) - 1)
            h = hub_at[k]
            cost = np.where(ok, np.abs(along[h] - along), np.inf)
            ends.append((k, cost, xy[h] - xy))  # hub index, metres from t to it, displacement from t to it
        for ki, ci, di in ends:
            for kj, cj, dj in ends:
                # t_i -> its hub -> (hubs' shortest way) -> t_j's hub -> t_j
                total = ci[:, None] + H[ki[:, None], kj[None, :]] + cj[None, :]
                better = total < self.driven - 1e-9
                if better.any():
                    way = di[:, None, :] + V[ki[:, None], kj[None, :]] - dj[None, :, :]
                    self.driven = np.where(better, total, self.driven)
                    self.displacement = np.where(better[..., None], way, self.displacement)

    @staticmethod
    def _hub_ways(along, xy, groups, hubs, jump_m) -> tuple[np.ndarray, np.ndarray]:
        """Shortest ways among the hubs (Floyd-Warshall, displacements carried along): the drive between
        consecutive hubs, and a join between the hubs of one dstate."""
        k = len(hubs)
        index = {t: i for i, t in enumerate(hubs)}
        at = np.asarray(hubs)
        H = np.abs(along[at][None, :] - along[at][:, None])
        H = np.where(np.abs(np.arange(k)[None, :] - np.arange(k)[:, None]) <= 1, H, np.inf)
        V = xy[at][None, :, :] - xy[at][:, None, :]
        for g in groups:
            members = [index[t] for t in g if t in index]
            for a in members:
                for b in members:
                    if a != b and jump_m < H[a, b]:
                        H[a, b] = jump_m
                        V[a, b] = 0.0
        for m in range(k):
            via = H[:, m, None] + H[None, m, :]
            better = via < H - 1e-9
            if better.any():
                H = np.where(better, via, H)
                V = np.where(better[..., None], V[:, m, None, :] + V[None, m, :, :], V)
        return H, V
