"""Odometry as a real robot reads it: noise added to a clean tableau's turns and travels (tests, benchmarks)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from bootmap.tableau import Tableau, Travel, Turn


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
        steps.append(replace(s, action=a))
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
        steps[i] = replace(s, view=str(rng.choice(labels[others], p=p)))
    return Tableau(tuple(steps), tableau.world, dict(tableau.meta)), wrong


def with_mistyped_action(tableau: Tableau, rng: np.random.Generator, off_deg: tuple[float, float] = (47.0, 55.0)
                         ) -> tuple[Tableau, int]:
    """The tableau with one quarter turn, from the middle half of the walk, read ``off_deg`` degrees off
    (drawn uniformly, either way): past the midpoint to the neighbouring grid angle, so that the robot's
    learned types take it for another action (a slipped wheel, a gyro glitch); and its time point.

    >>> from bootmap.examples import notched_rectangle
    >>> t, at = with_mistyped_action(notched_rectangle(4), np.random.default_rng(0))
    >>> at, t.steps[at].action.angle_deg != notched_rectangle(4).steps[at].action.angle_deg
    (20, True)
    """
    turns = [t for t, s in enumerate(tableau.steps) if isinstance(s.action, Turn) and abs(s.action.angle_deg) < 135]
    if not turns:
        raise ValueError("the tableau has no quarter turn to mistype")
    middle = turns[len(turns) // 4: max(len(turns) // 4 + 1, 3 * len(turns) // 4)]
    at = int(rng.choice(middle))
    steps = list(tableau.steps)
    s = steps[at]
    off = float(rng.uniform(*off_deg)) * float(rng.choice([-1.0, 1.0]))
    steps[at] = replace(s, action=Turn(s.action.angle_deg + off))  # type: ignore[union-attr]
    return Tableau(tuple(steps), tableau.world, dict(tableau.meta)), at
