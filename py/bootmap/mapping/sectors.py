"""A log's headings: where the robot faced at each dstate, as the sector of the building it faced.

A robot that stops at its dstates turns on the spot between travels, and each turn's measured angle is
one of a few types (:mod:`.motion`). A log's robot drove on: its dstates are where the heading changed
(:mod:`bootmap.ingest.dstates`), and the angle from one to the next is whatever the drive made of it (a
corner taken as a 146-degree arc, a travel that bends 90 degrees because the turn detector cut it short).
Typed one by one, such angles sum to a heading that wanders off the building's axes, and two visits of
one dstate are left facing "different ways" for the axioms, which forbid their join.

The building says what a heading is: its corridors run along a main axis and across it
(:func:`bootmap.paths.main_axis`, from the robot's own dead-reckoned path: the whole track where a log's
tableau records it, ``meta.odometry.axis_deg``, else the path through its dstates). Each
dstate faces the sector (east, north, west or south of that axis) its heading lies in (the heading odometry
began at plus the actions' measured angles: for a log's own tableau, odometry's heading at each dstate),
and each action's angle is the change of sector, a multiple of 90 degrees (a turn-around is +180). The angles then
add up to the sectors, however the drive bent: the heading the axioms see at a dstate is where odometry
says it faced, never a sum of rounding errors. The truth of a log's dstate is made the same way from the
true poses (:mod:`bootmap.ingest.truth`); what differs is only odometry's drift.

Example
-------
A robot drives east, turns left through an arc of 80 degrees, and later right through 120:

>>> poses = [(0, 0, 0.0), (10, 0, 0.02), (12, 2, 1.42), (12, 12, 1.55), (14, 13, -0.55)]
>>> sector_angles(poses)
[0, 90, 0, -90]
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ..paths import main_axis

#: The building's sectors: four, 90 degrees each, centred on its main axis and across it.
SECTOR_DEG = 90


def sectors(poses: Sequence[Sequence[float]], axis_rad: float | None = None) -> np.ndarray:
    """Each pose's heading sector (0 east of the axis, 1 north, 2 west, 3 south), the headings unwrapped
    first so that a spin is counted, not folded (:func:`sector_angles` wraps the changes again)."""
    p = np.asarray(poses, dtype=float).reshape(-1, 3)
    axis = main_axis(p) if axis_rad is None else axis_rad
    return np.rint(np.unwrap(p[:, 2] - axis) / np.radians(SECTOR_DEG)).astype(int)


def sector_angles(poses: Sequence[Sequence[float]], axis_rad: float | None = None) -> list[int]:
    """The angle of each action between consecutive poses, as the change of sector (degrees: 0, 90,
    -90 or 180)."""
    change = np.diff(sectors(poses, axis_rad)) % (360 // SECTOR_DEG)
    return [int(c * SECTOR_DEG if c * SECTOR_DEG <= 180 else c * SECTOR_DEG - 360) for c in change]
