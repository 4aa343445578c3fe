"""Odometry as a real robot reads it: noise added to a clean tableau's turns and travels, recorded at a
log's resolution (tests, benchmarks)."""

from __future__ import annotations

from dataclasses import dataclass, replace
from decimal import Decimal

import numpy as np

from bootmap.tableau import Tableau, Travel, Turn


@dataclass(frozen=True)
class Rounding:
    """The resolution a robot's log records odometry at."""

    distance_m: float
    angle_deg: float


#: As real logs and tableaux record readings: distances to the centimetre, angles to a tenth of a degree.
LOGGED = Rounding(0.01, 0.1)
#: Both ways a test family reads its noisy tableaux (``pytest.mark.parametrize("rounding", ROUNDINGS)``).
ROUNDINGS = (LOGGED, None)


def rounded(tableau: Tableau, rounding: Rounding | None = LOGGED) -> Tableau:
    """The tableau with every reading recorded at ``rounding`` (None: as it is).

    >>> from bootmap.tableau import Step
    >>> t = rounded(Tableau((Step("A", Travel(3.956, -0.27)), Step("B", Turn(-91.349)), Step("A"))))
    >>> t.actions
    [Travel(distance_m=3.96, heading_change_deg=-0.3), Turn(angle_deg=-91.3)]
    """
    if rounding is None:
        return tableau
    steps = []
    for s in tableau.steps:
        a = s.action
        if isinstance(a, Turn):
            a = Turn(_on(a.angle_deg, rounding.angle_deg))
        elif isinstance(a, Travel):
            a = Travel(_on(a.distance_m, rounding.distance_m), _on(a.heading_change_deg, rounding.angle_deg))
        steps.append(replace(s, action=a))
    return Tableau(tuple(steps), tableau.world, dict(tableau.meta))


def _on(value: float, step: float) -> float:
    """The value as a log prints it at this step (3.956 at 0.01 is 3.96, not 3.9600000000000004; 3.77 at
    0.25 is 3.75)."""
    decimals = max(0, -Decimal(repr(step)).as_tuple().exponent)
    return round(round(value / step) * step, decimals)


def with_odometry_noise(tableau: Tableau, turn_sd: float, drift_sd: float, rng: np.random.Generator,
                        distance_sd: float = 0.0, rounding: Rounding | None = LOGGED) -> Tableau:
    """The tableau with every turn off by N(0, ``turn_sd``) degrees, every travel's heading change by
    N(0, ``drift_sd``) and its distance by a share N(0, ``distance_sd``) of itself, recorded at
    ``rounding`` (a log's, by default; None: unrounded); views, images and truth as they were.

    >>> from bootmap.examples import notched_rectangle
    >>> t = with_odometry_noise(notched_rectangle(1), 5.0, 2.0, np.random.default_rng(0))
    >>> t.steps[0].action.angle_deg, t.steps[0].view
    (-89.4, 'V0')
    """
    steps = []
    for s in tableau.steps:
        a = s.action
        if isinstance(a, Turn):
            a = Turn(a.angle_deg + float(rng.normal(0, turn_sd)))
        elif isinstance(a, Travel):
            heading = a.heading_change_deg + float(rng.normal(0, drift_sd))
            distance = a.distance_m * (1.0 + float(rng.normal(0, distance_sd))) if distance_sd else a.distance_m
            a = Travel(distance, heading)
        steps.append(replace(s, action=a))
    return rounded(Tableau(tuple(steps), tableau.world, dict(tableau.meta)), rounding)


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


def with_mistyped_action(tableau: Tableau, rng: np.random.Generator, off_deg: tuple[float, float] = (47.0, 55.0),
                         rounding: Rounding | None = LOGGED) -> tuple[Tableau, int]:
    """The tableau with one quarter turn, from the middle half of the walk, read ``off_deg`` degrees off
    (drawn uniformly, either way): past the midpoint to the neighbouring grid angle, so that the robot's
    learned types take it for another action (a slipped wheel, a gyro glitch), recorded at ``rounding``;
    and its time point.

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
    angle = s.action.angle_deg + off  # type: ignore[union-attr]
    steps[at] = replace(s, action=Turn(angle if rounding is None else _on(angle, rounding.angle_deg)))
    return Tableau(tuple(steps), tableau.world, dict(tableau.meta)), at
