"""Odometry as a real robot reads it: noise added to a clean tableau's turns and travels (tests, benchmarks)."""

from __future__ import annotations

import numpy as np

from ..tableau import Step, Tableau, Travel, Turn


def with_odometry_noise(tableau: Tableau, turn_sd: float, drift_sd: float, rng: np.random.Generator) -> Tableau:
    """The tableau with every turn off by N(0, ``turn_sd``) degrees and every travel's heading change by
    N(0, ``drift_sd``); views, images and truth as they were.

    >>> from bootmap.examples import notched_rectangle
    >>> t = with_odometry_noise(notched_rectangle(1), 5.0, 2.0, np.random.default_rng(0))
    >>> round(t.steps[0].action.angle_deg, 1), t.steps[0].view
    (-89.4, 'V0')
    """
    steps = []
    for s in tableau.steps:
        a = s.action
        if isinstance(a, Turn):
            a = Turn(a.angle_deg + float(rng.normal(0, turn_sd)))
        elif isinstance(a, Travel):
            a = Travel(a.distance_m, a.heading_change_deg + float(rng.normal(0, drift_sd)))
        steps.append(Step(s.view, a, s.image, s.truth, s.pose))
    return Tableau(tuple(steps), tableau.world, dict(tableau.meta))
