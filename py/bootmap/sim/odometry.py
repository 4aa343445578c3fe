"""How far the robot's measured actions are from what it truly did: measured minus true, per action.

The simulator records the true pose at every dstate beside the odometry-measured action that led there,
so the error of each measured turn angle and each travel's heading change can be read off a tableau.
This is what the noise model is judged by (``bench/odometry_bench.py``, ``tests/sim/test_odometry.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..tableau import Tableau
from ..tableau import Travel as TravelAction
from ..tableau import Turn as TurnAction


def _wrap_deg(a: float) -> float:
    """An angle in degrees, wrapped to [-180, 180)."""
    return (a + 180.0) % 360.0 - 180.0


@dataclass(frozen=True)
class ActionErrors:
    """Measured minus true angles of a tableau's actions, in degrees.

    Attributes
    ----------
    turns : ndarray
        One per turn: the odometry's turn angle minus the true change of heading.
    turn_angles : ndarray
        The true turn angles, rounded to whole degrees (so errors can be grouped by kind of turn).
    travels : ndarray
        One per travel: the odometry's heading change minus the true one.
    """

    turns: np.ndarray
    turn_angles: np.ndarray
    travels: np.ndarray


def action_errors(tableau: Tableau) -> ActionErrors:
    """Measured-minus-true angles of every action of a simulated tableau (it needs true poses).

    A measured turn of -98 degrees where the robot truly turned -90 gives -8. The true change is the
    difference of the recorded headings, wrapped; the measured-minus-true difference is wrapped too, so a
    turn-around read as 190 degrees against a true -170 is 0, not 360.

    Examples
    --------
    >>> from bootmap.tableau import Step, Tableau, Turn
    >>> t = Tableau((Step(action=Turn(-98.0), image=None, pose=(0, 0, 0.0)),
    ...              Step(image=None, pose=(0, 0, -math.pi / 2))), "w", {})
    >>> action_errors(t).turns.tolist()
    [-8.0]
    """
    turns, angles, travels = [], [], []
    steps = tableau.steps
    for a, b in zip(steps, steps[1:]):
        if a.pose is None or b.pose is None or a.action is None:
            continue
        true = _wrap_deg(math.degrees(b.pose[2] - a.pose[2]))
        if isinstance(a.action, TurnAction):
            turns.append(_wrap_deg(a.action.angle_deg - true))
            angles.append(round(true))
        elif isinstance(a.action, TravelAction):
            travels.append(_wrap_deg(a.action.heading_change_deg - true))
    return ActionErrors(np.array(turns), np.array(angles), np.array(travels))
