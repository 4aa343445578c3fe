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
matters and the displacement dead reckoning gives along it (:meth:`Anchoring.rows`, :meth:`Anchoring.way`). Where no join lies between them, or the joins are no shortcut, these are
the drive's own: the metres driven and the difference of the dead-reckoned positions. So a loop closed
early keeps a later revisit of the loop's places within reach, with its position corrected by the
closure, long after the drive alone would have drifted too far to tell.

Only the time points of joined dstates (*hubs*) need the graph's search: a way from any time point
reaches a hub first along the drive, at the hub just before or just after it. The hubs' shortest ways are
found by Dijkstra (scipy's) and their displacements summed down each tree of shortest ways; every other
pair combines its two nearest hubs each side.

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
>>> metres, displacement = a.way(1, 3)
>>> metres, displacement.tolist()
(200.0, [-100.0, 100.0])
>>> metres, displacement = a.way(0, 3)
>>> metres, displacement.tolist()
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

    Only the hubs' ways are kept (their number squared); the ways from other time points are worked out
    for the rows asked (:meth:`rows`, :meth:`way`), so a long drive costs memory by the rows asked at once.
    """

    def __init__(self, along, xy, groups: Sequence[Sequence[int]], jump_m: float):
        self.along = along = np.asarray(along, dtype=float)
        self.xy = xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        self.n = n = len(along)
        if xy.shape != (n, 2):
            raise ValueError(f"{len(xy)} positions for {n} time points")
        if not jump_m > 0:
            raise ValueError(f"a join must count for some drive, got jump_m={jump_m}")
        hubs = sorted({t for g in groups if len(g) > 1 for t in g})
        self.hubs = np.asarray(hubs, dtype=int)
        if not hubs:
            return
        self.H, self.V = self._hub_ways(along, xy, groups, hubs, jump_m)
        # each time point's nearest hub before it and at or after it along the drive (k == -1 or len: none)
        after = np.searchsorted(self.hubs, np.arange(n), side="left")
        self.ends = []
        for k in (after - 1, after):
            ok = (k >= 0) & (k < len(hubs))
            k = np.clip(k, 0, len(hubs) - 1)
            h = self.hubs[k]
            # hub index, metres from t to it, displacement from t to it
            self.ends.append((k, np.where(ok, np.abs(along[h] - along), np.inf), xy[h] - xy))

    def rows(self, rows) -> tuple[np.ndarray, np.ndarray]:
        """The metres of drive whose drift lies between each time point of ``rows`` and every time point
        ``(len(rows), n)``, the joins' lengths included, and where dead reckoning puts the latter from the
        former along that way ``(len(rows), n, 2)`` (a join moves nothing)."""
        rows = np.asarray(rows, dtype=int).reshape(-1)
        driven = np.abs(self.along[None, :] - self.along[rows, None])
        displacement = self.xy[None, :, :] - self.xy[rows, None, :]
        if not len(self.hubs):
            return driven, displacement
        for ki, ci, di in self.ends:
            ki, ci, di = ki[rows], ci[rows], di[rows]
            for kj, cj, dj in self.ends:
                # row -> its hub -> (the hubs' shortest way) -> the column's hub -> the column
                total = ci[:, None] + self.H[ki[:, None], kj[None, :]] + cj[None, :]
                better = total < driven - 1e-9
                if better.any():
                    way = di[:, None, :] + self.V[ki[:, None], kj[None, :]] - dj[None, :, :]
                    driven = np.where(better, total, driven)
                    displacement = np.where(better[..., None], way, displacement)
        return driven, displacement

    def way(self, i: int, j: int) -> tuple[float, np.ndarray]:
        """The metres of drive between i and j and where dead reckoning puts j from i along that way."""
        driven, displacement = self.rows([i])
        return float(driven[0, j]), displacement[0, j]

    @staticmethod
    def _hub_ways(along, xy, groups, hubs, jump_m) -> tuple[np.ndarray, np.ndarray]:
        """Shortest ways among the hubs, over the drive between consecutive hubs and a join between the hubs
        of one dstate (Dijkstra, scipy's), and the displacement along each: summed down each source's tree
        of shortest ways by pointer doubling (log2 of the hubs' number of steps, each over every pair)."""
        # scipy only once loops are closed: loop closing is loaded wherever maps are made (the service's
        # solvers too, whose memory is capped), and scipy costs some 25 MB
        from scipy.sparse import csr_matrix
        from scipy.sparse.csgraph import dijkstra

        k = len(hubs)
        at = np.asarray(hubs)
        group = np.full(len(along), -1)
        for g, members in enumerate(groups):
            if len(members) > 1:
                group[list(members)] = g
        gid = group[at]
        hop = np.diff(along[at])  # the drive between consecutive hubs
        weight = {}
        for a in range(k - 1):
            weight[a, a + 1] = weight[a + 1, a] = hop[a]
        for g in np.unique(gid):
            members = np.flatnonzero(gid == g)
            for a in members:
                for b in members:
                    if a != b and jump_m < weight.get((a, b), np.inf):
                        weight[a, b] = jump_m
        rows, cols = np.array(list(weight)).T if weight else (np.zeros(0, int), np.zeros(0, int))
        # scipy reads a stored zero as no edge: a hop of no drive (a turn's two ends) costs a nanometre
        cost = np.maximum([weight[e] for e in zip(rows, cols)], 1e-9) if weight else np.zeros(0)
        H, parent = dijkstra(csr_matrix((cost, (rows, cols)), shape=(k, k)), return_predecessors=True)
        # each hub's step from its parent on its source's tree: nothing across a join, the drive's else
        root = parent < 0
        parent = np.where(root, np.arange(k)[:, None], parent)
        child = np.broadcast_to(np.arange(k)[None, :], (k, k))
        joined = (gid[parent] == gid[child]) & ((np.abs(parent - child) != 1)
                                                 | (jump_m < np.abs(along[at][parent] - along[at][child])))
        V = np.where((joined | root)[..., None], 0.0, xy[at][child] - xy[at][parent])
        up = parent
        for _ in range(max(1, int(np.ceil(np.log2(max(k, 2))))) + 1):
            V = V + np.take_along_axis(V, up[..., None], axis=1)
            up = np.take_along_axis(up, up, axis=1)
        return H, V
