"""A place's local map, rendered as one image all round: what the robot saw while it passed through.

A visit's own scan shows the 180 degrees ahead. The robot came from behind and leaves ahead, and saw the
place from there too: the hybrid SSH (Beeson, Modayil and Kuipers, IJRR 2010) describes a place by its
*local perceptual map*, built from the scans taken while the robot is in it. Here, every scan taken while
the robot's odometry has travelled at most ``reach_m`` from the visit (before it or after it) is moved into
the visit's frame by odometry (dead reckoning is good over a few metres), and its returns are rendered
from the visit's pose as a laser all round would see them: per bearing (``beams`` of them, from -180
degrees), the nearest return. Two visits of one place from opposite directions then show the same walls,
which their 180-degree scans, facing away from each other, do not.

The reach is the place's radius (3 m): the scans taken in the place. Only odometry is read, as recorded;
the log's corrected poses never enter. The images are matched with
:class:`bootmap.scan_match.ScanMatcher` at ``fov_deg=360`` (:func:`bootmap.surfaces.beam_angles`).

Example
-------
A corridor along x, walls at y = +-1, driven from x = 0 to x = 4; each scan sees the walls ahead only.
At x = 2 the local map also shows the wall behind and to the left (bearing 135 degrees, 1.41 m away), which
the scan ahead from x = 0 saw:

>>> import numpy as np
>>> from bootmap.ingest.scans import Scan
>>> a = np.radians(np.arange(-90, 91))
>>> ahead = np.minimum(1 / np.maximum(np.abs(np.sin(a)), 1e-9), 20.0)  # the walls seen from any x
>>> scans = [Scan(float(k), ahead, -np.pi / 2, np.radians(1), 20.0, (x, 0.0, 0.0))
...          for k, x in enumerate(np.arange(0.0, 4.01, 0.25))]
>>> image = local_images(scans, [8], reach_m=2.0)[0]
>>> image.shape, round(float(image[180 + 135]), 2), round(float(image[180 - 135]), 2)
((360,), 1.41, 1.41)
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from ..errors import BadInput
from ..surfaces import returns
from .dstates import odometry_track
from .scans import Scan, between

#: Bearings of a local map's image: one a degree, all round.
LOCAL_BEAMS = 360
#: How far the robot may have travelled from the visit, either way, for a scan to count (m): a place's radius.
LOCAL_REACH_M = 3.0


def local_images(scans: Sequence[Scan], visits: Sequence[int], reach_m: float = LOCAL_REACH_M,
                 beams: int = LOCAL_BEAMS, max_range: float = 20.0) -> np.ndarray:
    """The local map of each visit (an index into ``scans``) as an image all round.

    Parameters
    ----------
    scans : sequence of Scan
        The log's scans in time order, with their odometry.
    visits : sequence of int
        The scans the visits were made at.
    reach_m : float
        Scans taken within this much travel (by odometry, m) before or after a visit make its local map.
    beams : int
        Bearings of the image, ``2 pi / beams`` apart from -pi (:func:`bootmap.surfaces.beam_angles` at 360).
    max_range : float
        Returns at or beyond this range are left out; a bearing with none reads ``max_range``.

    Returns
    -------
    ndarray of shape (len(visits), beams)
    """
    if not reach_m >= 0 or beams < 1:
        raise BadInput(f"a local map needs reach_m >= 0 and beams >= 1, got reach_m={reach_m}, beams={beams}")
    odometry = np.array([s.odometry[:3] for s in scans], dtype=float).reshape(-1, 3)
    travelled, _ = odometry_track(odometry)  # odometry's path length up to each scan
    seen: dict[int, np.ndarray] = {}  # each scan's returns, in its robot's frame
    out = np.full((len(visits), beams), float(max_range))
    for row, k in enumerate(visits):
        lo = int(np.searchsorted(travelled, travelled[k] - reach_m, side="left"))
        hi = int(np.searchsorted(travelled, travelled[k] + reach_m, side="right"))
        parts = []
        for j in range(lo, hi):
            if j not in seen:
                seen[j] = returns(scans[j].ranges, scans[j].angles, min(scans[j].range_max, max_range))
            xy = seen[j]
            if not len(xy):
                continue
            tx, ty, th = between(odometry[k], odometry[j])  # scan j's frame in the visit's
            c, s = math.cos(th), math.sin(th)
            parts.append(np.column_stack([c * xy[:, 0] - s * xy[:, 1] + tx, s * xy[:, 0] + c * xy[:, 1] + ty]))
        if not parts:
            continue
        points = np.vstack(parts)
        rho = np.hypot(points[:, 0], points[:, 1])
        near = rho < max_range
        bearing = np.arctan2(points[near, 1], points[near, 0])
        b = np.rint((bearing + math.pi) / (2 * math.pi) * beams).astype(int) % beams
        np.minimum.at(out[row], b, rho[near])
    return out
