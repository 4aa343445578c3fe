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


def with_misreads(tableau: Tableau, fraction: float, rng: np.random.Generator) -> tuple[Tableau, list[int]]:
    """The tableau with ``fraction`` of its time points (at least one when ``fraction`` > 0) showing a
    view other than their own, as a clustering that misreads an image now and then would label it;
    and the time points misread, in order. The wrong view is another view of the tableau, drawn as often
    as it is seen (a misclustered image lands in a cluster that exists, more likely a big one).

    >>> from bootmap.examples import notched_rectangle
    >>> t, wrong = with_misreads(notched_rectangle(1), 0.2, np.random.default_rng(0))
    >>> len(wrong), all(t.steps[i].view != notched_rectangle(1).steps[i].view for i in wrong)
    (2, True)
    """
    n = len(tableau)
    count = 0 if fraction <= 0 else max(1, int(round(fraction * n)))
    wrong = sorted(int(i) for i in rng.choice(n, size=min(count, n), replace=False))
    views = [s.view for s in tableau.steps]
    labels, counts = np.unique(views, return_counts=True)
    steps = list(tableau.steps)
    for i in wrong:
        others = labels != views[i]
        p = counts[others] / counts[others].sum()
        s = steps[i]
        steps[i] = Step(str(rng.choice(labels[others], p=p)), s.action, s.image, s.truth, s.pose)
    return Tableau(tuple(steps), tableau.world, dict(tableau.meta)), wrong
