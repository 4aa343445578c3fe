"""Motion primitives: the robot's few action types, learned from the angles it measured.

A physical robot's odometry reads a right turn as -87, -93 or -98 degrees. Rounding each measurement to
a fixed quantum (15 degrees) turns -98 into -105, and every heading after it is wrong. The paper's
bootstrap learning has the robot learn its own primitives; this module does so for actions, as views
are learned for images:

1. The measured angles of each action kind (turn angles; travels' net heading changes) are clustered
   in one dimension: sorted on the circle, they are split wherever neighbours are more than 10 degrees
   apart (what a robot may misread a primitive by), and each angle then joins the type whose mean is
   nearest (k-means steps). (The paper's measure M, which picks the number of views, is nearly flat in
   one dimension when clusters are cut at the widest gaps: it cannot tell noise from types here.)
2. Each type's mean is snapped to the coarsest angular grid (180, 90, 45, 15, 5 or 1 degrees) near
   which every common type of the tableau lies (within three of its spreads, or 10 degrees for a tight
   type, and less than a third of a step), so that a loop of four right turns still closes on 360
   however the robot misreads them; types that snap to one angle are one type. A type of one or two
   stray readings does not choose the grid (it is as likely a misread as a primitive): it snaps onto it.

The axioms then see each action's type angle (``turn(T, -90)``), as if the robot had turned exactly.
Clean experience, whose angles are exact multiples of the grid, gets exactly its own angles.

Clean or noisy is decided at the readings' resolution, never by whether numbers repeat alone: a log
records distances to the centimetre and angles to a tenth of a degree, so noisy readings of one corridor
repeat (3.95 m, 3.96 m, ... 4.06 m, each several times). The resolution is a fact about the sensor: given
(``meta.resolution`` of the tableau), or read from the readings (:func:`reading_step`): the coarsest
decimal step they all lie on, or a multiple of it where the readings show one (an encoder or a log that
records 5 cm or half degrees: every reading a multiple of it, and distinct readings one such step apart
again and again, as noise spreads a primitive over neighbouring steps). Readings are exact when values
repeat and no two distinct values are neighbouring steps of that resolution (:func:`exact_readings`):
noise, at any resolution, spreads one primitive over neighbouring steps; exact experience reads each
primitive as one value.

Example
-------
>>> from bootmap.tableau import Travel, Turn
>>> m = MotionPrimitives().fit([Turn(-87.0), Travel(4.0, 1.5), Turn(-98.0), Travel(2.0, -2.0), Turn(178.0)])
>>> m.angles_, m.grid_deg_
([-90, 0, -90, 0, 180], 90)
>>> [f"{t.kind} {t.angle:+d}" for t in m.types_]
['turn -90', 'turn +180', 'travel +0']
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..tableau import Action, Turn

#: Candidate grids, coarsest first; each divides the one before, so a finer grid keeps every coarser angle.
GRIDS = (180, 90, 45, 15, 5, 1)
#: How far a robot's odometry may read a primitive off its true angle, consistently (gyro scale, slip):
#: a tight type this near a grid angle is that angle; one farther is a primitive of its own (a 30-degree
#: bend stays 30).
BIAS_DEG = 10.0
#: A type that sets the grid accounts for at least this share of its kind's actions (and three of them) ...
MIN_SHARE = 0.05
#: Readings whose types spread less than this many degrees are as good as exact (every type is kept) ...
EXACT_DEG = 0.5
#: ... and a type read the same, within this many degrees, at least twice sets the grid however few its
#: readings (noise of a degree or more cannot do that; two turn-arounds of a real robot read at +163.0
#: and +163.6 among eighteen at -174 +- 5 are chance, and must not make every heading its own).
SAME_DEG = 0.05
#: A gyro or a wheelbase read a little wrong scales every turn alike: a robot's odometry may read its turns
#: up to this share long or short (real logs: 6% short). Where its turn types fit no grid as read, the
#: scale that makes them fit the coarsest grid is taken out (a turn-around read 190.8 degrees, 10.8 from
#: 180, beside right turns read -95.4: every turn read 6% long). Scales are tried every SCALE_STEP, for
#: noisy turns only (exact ones are what they say) and grids of SCALED_GRID degrees or more (right angles
#: and diagonals: with many fine types some scale fits a fine grid by chance).
MAX_SCALE, SCALE_STEP, SCALED_GRID = 0.10, 0.002, 45
#: A type of at most this many readings within this many spreads of a type three times its size is
#: that type's tail (a real robot's turn-arounds are read from +167 to +222).
TAIL, TAIL_SDS = 3, 4.0
#: ... but a type of three readings or more this many spreads from every other is a primitive, however
#: small its share (a bend seen seldom, far from any other type).
FAR_SDS = 6.0


#: Resolutions a log may record readings at, coarsest first: a whole unit (metre, degree) to a millionth.
STEPS = tuple(10.0 ** -k for k in range(7))
#: A reading within this share of a step of a whole multiple lies on that step (floating point's own error).
ON_STEP = 1e-6
#: Readings lie on a step when this share of them do: a reading or two typed in by hand, or merged from
#: another source, do not make a log's readings continuous (continuous readings lie on a step by chance
#: about once in a million).
ON_STEP_SHARE = 0.95
#: Readings on a decimal step lie on a coarser grid, a multiple of it (5 cm, half a degree), where they are
#: all multiples of it and at least this many pairs of distinct readings lie one grid step apart: what
#: noise does at that resolution. One pair does not show a grid (exact lengths of 2.0 and 2.2 m are on a
#: 20 cm grid by chance) ...
GRID_EVIDENCE = 2
#: ... nor does a grid coarser than this share of the readings' typical size: half the widest misreading
#: of a travel's length the typing puts down to noise (:data:`LENGTH_RATIO`). Noise of a few per cent
#: spreads a primitive over neighbouring steps of a finer grid (travels of 2 m read to 20 cm: 1.8, 2.0 and
#: 2.2 m); exact travels of 4, 6, 8 and 10 m are primitives on a 2 m grid, not noisy readings of it ...
GRID_SHARE = 0.125
#: ... or, for angles, this many degrees (half the bias a robot may misread a primitive by: exact turns
#: of 15 degrees and their multiples stay primitives).
ANGLE_GRID_DEG = 5.0
#: Distinct readings this close (a share of the readings' typical size; for angles, degrees) are never two
#: primitives: where :data:`GRID_EVIDENCE` pairs of them are, the readings are noisy, whatever step they
#: are printed at. An encoder's tick of 0.123 mm printed to the micrometre, or centimetres converted to
#: feet, puts a corridor's readings 3 or 4 printed steps apart, never on neighbouring ones.
NEAR_SHARE, NEAR_DEG = 0.01, 1.0


@dataclass(frozen=True)
class ActionType:
    """One motion primitive: its kind, the angle the axioms see, and what the robot measured for it, at
    the resolution its readings were recorded at."""

    kind: str                   # "turn" or "travel"
    angle: int                  # degrees, in (-180, 180]
    count: int                  # actions of this type
    mean_deg: float             # their measured mean (circular)
    sd_deg: float               # and spread
    resolution_deg: float = 0.0  # the step the angles of its kind were recorded at (0: continuous)
    exact: bool = True          # its kind's readings are exact primitives (else noisy readings, clustered)
    from_walls: int = 0         # of its actions, those whose angle the laser's walls read (mapping.compass)

    def to_dict(self) -> dict:
        return {"kind": self.kind, "angle_deg": self.angle, "count": self.count,
                "measured_mean_deg": round(self.mean_deg, 2), "measured_sd_deg": round(self.sd_deg, 2),
                "resolution_deg": self.resolution_deg, "exact": self.exact, "read_from_walls": self.from_walls}

    def __str__(self) -> str:
        return f"{self.kind} {self.angle:+d} ({self.count}x, measured {self.mean_deg:+.1f} +- {self.sd_deg:.1f})"


@dataclass(frozen=True)
class LengthType:
    """One length of travel: the label the axioms see (decimetres) and what odometry measured for it."""

    length_dm: int              # the label: the type's mean length in decimetres
    count: int                  # travels of this length
    mean_m: float               # their measured mean
    sd_m: float                 # and spread
    resolution_m: float = 0.0   # the step the distances were recorded at (0: continuous)
    exact: bool = True          # the distances are exact (else noisy readings, clustered)

    def to_dict(self) -> dict:
        return {"length_dm": self.length_dm, "count": self.count, "measured_mean_m": round(self.mean_m, 3),
                "measured_sd_m": round(self.sd_m, 3), "resolution_m": self.resolution_m, "exact": self.exact}

    def __str__(self) -> str:
        return f"{self.length_dm / 10:g} m ({self.count}x, measured {self.mean_m:.2f} +- {self.sd_m:.2f})"


def reading_step(values: Sequence[float], widest: float | None = None) -> float:
    """The resolution the readings were recorded at, as they show it: the coarsest decimal step
    (:data:`STEPS`) that the readings are whole multiples of (:data:`ON_STEP_SHARE` of them), or the
    coarser grid they show on it (:func:`_grid`: a step at most ``widest``, by default at most
    :data:`GRID_SHARE` of the readings it lies between); 0.0 where there is none (continuous).

    >>> reading_step([3.95, 4.06, 12.1]), reading_step([-90.0, 91.3]), reading_step([2.0312345678])
    (0.01, 0.1, 0.0)
    >>> reading_step([7.9, 7.95, 8.0, 8.05, 8.1, 7.95, 8.0, 16.05, 15.9])  # recorded at 5 cm
    0.05
    >>> reading_step([2.0, 2.2, 2.0, 2.2]), reading_step([4.0, 5.0, 6.0, 7.0, 5.0])  # exact: no grid shown
    (0.1, 1.0)
    """
    v = np.asarray(values, dtype=float)
    for step in STEPS:
        q = v / step
        if np.mean(np.abs(q - np.round(q)) < ON_STEP) >= ON_STEP_SHARE:
            return step * _grid(np.round(q).astype(np.int64), None if widest is None else widest / step)
    return 0.0


def _grid(units: np.ndarray, widest: float | None) -> int:
    """The multiple of their step that readings (``units``: whole multiples of it) show as their grid: the
    smallest gap between distinct readings, where :data:`GRID_EVIDENCE` pairs of distinct readings lie that
    far apart, each gap at most ``widest`` (by default :data:`GRID_SHARE` of the longer reading beside it),
    and :data:`ON_STEP_SHARE` of the readings are multiples of it; else 1."""
    distinct = np.unique(units)
    if distinct.size < GRID_EVIDENCE + 1:
        return 1
    gaps = np.diff(distinct)
    g = int(gaps.min())
    limit = GRID_SHARE * np.maximum(np.abs(distinct[:-1]), np.abs(distinct[1:])) if widest is None else widest
    if g <= 1 or int(((gaps == g) & (g <= limit + ON_STEP)).sum()) < GRID_EVIDENCE:
        return 1
    return g if np.mean(units % g == 0) >= ON_STEP_SHARE else 1


def exact_readings(values: Sequence[float], step: float, period: float | None = None,
                   near: float | None = None) -> bool:
    """Whether readings recorded at ``step`` (0: continuous) are exact, each value a primitive read without
    noise: values repeat (noise at a fine resolution never does), no two distinct values are
    neighbouring steps (noise at a coarse one spreads a primitive over neighbouring steps: a corridor read
    3.95, 3.96, ... 4.06 m), and no :data:`GRID_EVIDENCE` pairs of distinct values lie within ``near`` of
    each other (by default :data:`NEAR_SHARE` of their typical size: noise on a grid the printed step does
    not divide). Angles wrap at ``period``.

    >>> exact_readings([2.0, 2.2, 2.0, 2.2], 0.1), exact_readings([3.95, 3.96, 3.95, 4.06, 3.96, 4.05], 0.01)
    (True, False)
    >>> exact_readings([4.0312, 3.9871, 4.0102], 0.0)
    False
    >>> exact_readings([6.53, 6.56, 6.53, 6.59, 6.56, 6.63, 6.59], 0.01)  # 2 m read to the cm, in feet
    False
    """
    v = np.asarray(values, dtype=float)
    if v.size == 0:
        return True
    unit = step or ON_STEP  # continuous readings: equal within ON_STEP
    units = np.unique(np.round(v / unit))
    if len(units) > len(v) / 2:
        return False
    if len(units) < 2:
        return True
    gaps = np.diff(units)
    if period is not None:
        gaps = np.append(gaps, units[0] + round(period / unit) - units[-1])
    if near is None:
        near = NEAR_SHARE * float(np.median(np.abs(v)))
    if int(((gaps > 0) & (gaps * unit <= near)).sum()) >= GRID_EVIDENCE:
        return False
    return step == 0 or bool(gaps.min() > 1)


def resolution_of(tableau_meta: dict, field: str) -> float | None:
    """The resolution a tableau states for its readings (``meta.resolution.distance_m`` or ``.angle_deg``),
    or None where it states none (it is then read from the readings)."""
    given = (tableau_meta.get("resolution") or {}).get(field)
    return None if given is None else float(given)


class MotionPrimitives:
    """Learn the action types of a sequence of actions (scikit-learn's estimator contract).

    Parameters
    ----------
    grids : sequence of int
        Candidate grids in degrees, coarsest first, each a divisor of the one before.
    resolution_deg : float, optional
        The step the angles were recorded at (0: continuous); by default read from the readings of each
        kind (:func:`reading_step`).
    exact_deg : float
        Readings whose types spread less than this are taken as exact: every type is kept, however few
        its readings (:data:`EXACT_DEG`; 0 for readings that are precise but not exact, as a laser's,
        among which a reading or two of their own are strays, not primitives).

    Attributes
    ----------
    types_ : list of ActionType
        The types found, turns first, by angle.
    angles_ : list of int
        The type angle of each action, in order.
    grid_deg_ : int
        The grid the type angles lie on.
    turn_scale_ : float
        How much longer than the type angles the turns were read (1.0: as read; :data:`MAX_SCALE`).
    resolution_ : dict
        Per kind, the step its angles were recorded at (given, or read from them).
    exact_ : dict
        Per kind, whether its readings are exact primitives (:func:`exact_readings`).
    """

    def __init__(self, grids: Sequence[int] = GRIDS, resolution_deg: float | None = None, exact_deg: float = EXACT_DEG):
        self.grids = grids
        self.resolution_deg = resolution_deg
        self.exact_deg = exact_deg

    def fit(self, actions: Sequence[Action], trusted: Sequence[bool] | None = None) -> "MotionPrimitives":
        """Learn the types of ``actions``. Where ``trusted`` is given, the types and their grid are learned
        from the trusted readings of each kind (those a better sensor confirmed, :mod:`.compass`) and every
        other reading takes the grid angle nearest it: a reading the sensor could not confirm is as likely
        a misread as a primitive, and cannot make a type of its own."""
        is_turn, read = _readings(actions)
        kinds = np.where(is_turn, "turn", "travel")
        measured = _wrap(read)
        sure = np.ones(len(read), dtype=bool) if trusted is None else np.asarray(trusted, dtype=bool)
        self.resolution_, self.exact_ = {}, {}
        clusters: list[tuple[str, np.ndarray]] = []  # (kind, indices into actions)
        for kind in ("turn", "travel"):
            idx = np.flatnonzero(kinds == kind)
            if idx.size and sure[idx].any():
                idx = idx[sure[idx]]
            if idx.size:
                self.resolution_[kind], self.exact_[kind] = _as_recorded(read[idx], self.resolution_deg)
                clusters += [(kind, idx[members]) for members in _cluster(measured[idx], self.exact_[kind])]
        means = [_circular_mean(measured[i]) for _, i in clusters]
        spreads = [_circular_sd(measured[i], m) for m, (_, i) in zip(means, clusters)]
        # A type seen once or twice is as likely a misread as a primitive: the grid is set by the types
        # that account for more (when there are any), and a stray reading snaps onto it like the others.
        common, few = [], []  # (mean, spread, is a turn); (mean, is a turn)
        for kind in ("turn", "travel"):
            mine = [(m, sd, len(i)) for m, sd, (k, i) in zip(means, spreads, clusters) if k == kind]
            total = sum(n for _, _, n in mine)
            # How far this kind's readings stray from their types: the noise every type of it shares.
            pooled = float(np.sqrt(sum(n * sd * sd for _, sd, n in mine) / total)) if total else 0.0
            # Readings without noise (a hand-written or simulated tableau) are all primitives.
            same = self.resolution_.get(kind, 0.0) < SAME_DEG  # can two readings agree by more than chance?
            keep = [(m, pooled) for i, (m, sd, n) in enumerate(mine)
                    if n >= max(3, MIN_SHARE * total) or (n >= 2 and sd < SAME_DEG and same) or pooled < self.exact_deg
                    or (n >= 3 and _apart(m, [o for j, (o, _, _) in enumerate(mine) if j != i], pooled))]
            common += [(m, sd, kind == "turn") for m, sd in (keep or [(m, pooled) for m, _, _ in mine])]
            # A few readings (a tail, at most TAIL) set the grid only where no grid angle is near them:
            # three turn-arounds read at -153 beside eighteen at +175 +- 8 are a tail of 180, not a
            # primitive that makes every heading its own; a bend read at 45 three times is a primitive.
            few += [(m, kind == "turn") for m, sd, n in mine
                    if n <= TAIL and (m, pooled) in keep and pooled >= self.exact_deg]
        few_means = {m for m, _ in few}
        self.grid_deg_, self.turn_scale_ = _coarsest_grid([t for t in common if t[0] not in few_means], self.grids,
                                                           few, scaled=not self.exact_.get("turn", True))
        grid, scale = self.grid_deg_, self.turn_scale_
        snapped = [quantise(_as_if(m, k == "turn", scale, grid), grid) for m, (k, _) in zip(means, clusters)]
        angles = np.zeros(len(read), dtype=int)
        typed = np.zeros(len(read), dtype=bool)
        for (_, idx), angle in zip(clusters, snapped):
            angles[idx], typed[idx] = angle, True
        for i in np.flatnonzero(~typed):  # the untrusted: each reading onto the grid angle nearest it
            angles[i] = quantise(_as_if(float(measured[i]), bool(is_turn[i]), scale, grid), grid)
        self.angles_ = angles.tolist()
        self.types_ = _types(is_turn, read, angles, self.resolution_, self.exact_)
        return self


def _apart(mean: float, others: Sequence[float], pooled: float) -> bool:
    """A type of a few readings lies further from every other type of its kind than noise can carry a
    reading (``FAR_SDS`` of the kind's spreads, and twice the bias): a primitive seen seldom, not strays.
    A 45-degree bend read five times among 168 travels at 0 and +-90 (sd 4) is 11 spreads from any; three
    turn-arounds read at -153 beside +175 +- 8 are 4."""
    reach = max(2 * BIAS_DEG, FAR_SDS * pooled)
    return all(_between(mean, o) > reach for o in others)


def measured_angle(action: Action) -> float:
    """What odometry measured: a turn's angle, or a travel's net heading change."""
    return action.angle_deg if isinstance(action, Turn) else action.heading_change_deg


def action_types(actions: Sequence[Action], angles: Sequence[int], resolution_deg: float | None = None
                 ) -> list[ActionType]:
    """The types of these actions given the angle each was read as (learned, or rounded to a quantum):
    turns first, by angle, each with its kind's resolution (given, or read from the readings)."""
    is_turn, read = _readings(actions)
    resolution, exact = {}, {}
    for kind, mine in (("turn", is_turn), ("travel", ~is_turn)):
        if mine.any():
            resolution[kind], exact[kind] = _as_recorded(read[mine], resolution_deg)
    return _types(is_turn, read, np.asarray(angles, dtype=int), resolution, exact)


def turns_exact(actions: Sequence[Action], resolution_deg: float | None = None) -> bool:
    """Whether the turns among ``actions`` are read exactly (:func:`exact_readings` at their resolution, given
    or read from them); True where there are none."""
    is_turn, read = _readings(actions)
    return not is_turn.any() or _as_recorded(read[is_turn], resolution_deg)[1]


def _as_recorded(read: np.ndarray, resolution_deg: float | None) -> tuple[float, bool]:
    """One kind's angles as recorded: the step they were recorded at (given, or read from them), and
    whether they are exact at it (:func:`exact_readings`, on the circle)."""
    step = reading_step(read, widest=ANGLE_GRID_DEG) if resolution_deg is None else resolution_deg
    return step, exact_readings(_wrap(read), step, period=360.0, near=NEAR_DEG)


def _readings(actions: Sequence[Action]) -> tuple[np.ndarray, np.ndarray]:
    """Which actions are turns, and what odometry measured for each (:func:`measured_angle`)."""
    is_turn = np.fromiter((isinstance(a, Turn) for a in actions), dtype=bool, count=len(actions))
    read = np.fromiter((measured_angle(a) for a in actions), dtype=float, count=len(actions))
    return is_turn, read


def _types(is_turn: np.ndarray, read: np.ndarray, angles: np.ndarray, resolution: dict, exact: dict
           ) -> list[ActionType]:
    """The action types, turns first, by angle: each with its count, measured mean and spread, and its
    kind's resolution and exactness."""
    out = []
    for kind, mine in (("turn", is_turn), ("travel", ~is_turn)):
        for angle in np.unique(angles[mine]):
            v = _wrap(read[mine & (angles == angle)])
            out.append(ActionType(kind, int(angle), len(v), _circular_mean(v), _circular_sd(v, int(angle)),
                                  resolution.get(kind, 0.0), exact.get(kind, True)))
    return out


def _wrap(a: np.ndarray) -> np.ndarray:
    """Angles into (-180, 180]."""
    w = (a + 180.0) % 360.0 - 180.0
    return np.where(w == -180.0, 180.0, w)


def _cluster(values: np.ndarray, exact: bool) -> list[np.ndarray]:
    """The angles split wherever neighbours (sorted, on the circle) are more than :data:`BIAS_DEG`
    apart (exact readings: wherever they differ), then each moved to the type whose mean is nearest."""
    order = np.argsort(values)
    v = values[order]
    # Start the circle at its widest empty arc, so that a type around 180 (turn-arounds read as 178 and
    # -179) is not cut in two.
    gaps = np.append(np.diff(v), v[0] + 360.0 - v[-1])  # the last one wraps around
    start = (int(np.argmax(gaps)) + 1) % len(v)
    order = np.concatenate([order[start:], order[:start]])
    v = np.concatenate([v[start:], v[:start] + 360.0])
    # Exact readings are as many types as values.
    splits = np.flatnonzero(np.diff(v) > (EXACT_DEG if exact else BIAS_DEG)) + 1
    parts = np.split(np.arange(len(v)), splits)
    # A gap that noise opened inside one type: neighbours less than twice the bias apart, one of them
    # spread over more than a quarter of the distance, are one type (exact angles 15 apart stay two).
    merged = [parts[0]]
    for p in parts[1:]:
        last = merged[-1]
        if _one_type(v[last], v[p]):
            merged[-1] = np.concatenate([last, p])
        else:
            merged.append(p)
    refined = _refined(values, [order[p] for p in _tails_joined(v, merged)])
    # The k-means steps can cut the same gap open again: a stray reading beyond a type's tail gathers
    # the tail around itself (travels read -23, -12.7, -10.7, -9.6 and -9.1 beside fifty at 0 +- 3.5
    # made a type of their own at -13, and a 15-degree grid for every heading). Neighbours that are
    # one type by the rule above are joined again.
    return _rejoined(values, refined)


def _one_type(a: np.ndarray, b: np.ndarray) -> bool:
    """Two neighbouring groups of readings (unwrapped, ``b`` after ``a``) are one type: less than twice
    the bias apart, and one of them spread over more than a quarter of the distance."""
    apart = b.mean() - a.mean()
    return apart < 2 * BIAS_DEG and max(a.std(), b.std()) > apart / 4


def _rejoined(values: np.ndarray, clusters: list[np.ndarray]) -> list[np.ndarray]:
    """Neighbouring clusters (by circular mean) that :func:`_one_type` calls one type, joined."""
    clusters = sorted(clusters, key=lambda c: _circular_mean(values[c]))
    joined = True
    while joined and len(clusters) > 1:
        joined = False
        for i in range(len(clusters)):
            a, b = clusters[i - 1], clusters[i]  # i = 0 pairs the last cluster with the first, across +-180
            ma, mb = _circular_mean(values[a]), _circular_mean(values[b])
            va = ma + _wrap(values[a] - ma)
            vb = ma + (mb - ma) % 360.0 + _wrap(values[b] - mb)  # b after a, going round the circle
            if _one_type(va, vb):
                clusters[i - 1] = np.sort(np.concatenate([a, b]))
                del clusters[i]
                joined = True
                break
    return clusters


def _tails_joined(v: np.ndarray, parts: list[np.ndarray]) -> list[np.ndarray]:
    """A few readings (at most ``TAIL``) just past a type many times their number, within
    ``TAIL_SDS`` of its spreads, are that type's tail, not a primitive of their own (turn-arounds read
    at +198, +207 and +222 beside nineteen read at +181 +- 8)."""
    out = list(parts)
    changed = True
    while changed:
        changed = False
        for i, p in enumerate(out):
            if len(p) > TAIL:
                continue
            for j in (i - 1, i + 1):
                if 0 <= j < len(out) and len(out[j]) >= 3 * len(p):
                    big = v[out[j]]
                    if abs(v[p].mean() - big.mean()) <= TAIL_SDS * max(big.std(), 1.0):
                        out[j] = np.sort(np.concatenate([out[j], p]))
                        del out[i]
                        changed = True
                        break
            if changed:
                break
    return out


def _refined(values: np.ndarray, clusters: list[np.ndarray]) -> list[np.ndarray]:
    """Each angle to the type whose mean is nearest on the circle, until nothing moves (k-means, started
    from the gap split: a far outlier of one type can sit across a gap nearer another type's tail)."""
    labels = np.empty(len(values), dtype=int)
    for c, idx in enumerate(clusters):
        labels[idx] = c
    for _ in range(20):
        means = np.array([_circular_mean(values[labels == c]) for c in range(len(clusters))])
        nearest = np.argmin(np.abs(_wrap(values[:, None] - means[None, :])), axis=1)
        if np.array_equal(nearest, labels) or len(np.unique(nearest)) < len(clusters):
            break
        labels = nearest
    return [np.flatnonzero(labels == c) for c in range(len(clusters))]


def _between(a: float, b: float) -> float:
    """Degrees between two angles, the short way round the circle."""
    return abs(float(_wrap(np.array([a - b]))[0]))


def _circular_mean(a: np.ndarray) -> float:
    r = np.radians(a)
    return float(_wrap(np.array([np.degrees(np.arctan2(np.sin(r).mean(), np.cos(r).mean()))]))[0])


def _circular_sd(a: np.ndarray, centre: float) -> float:
    return float(np.sqrt(np.mean(_wrap(a - centre) ** 2)))


def _coarsest_grid(types: Sequence[tuple[float, float, bool]], grids: Sequence[int],
                   few: Sequence[tuple[float, bool]] = (), scaled: bool = True) -> tuple[int, float]:
    """The coarsest grid near every type (mean, spread, whether a turn), and the turns' scale: each mean
    within three spreads (sd, the noise of its kind), or :data:`BIAS_DEG` for tight readings, of a grid
    angle, and less than a third of a step away; the means of types of a ``few`` readings only less than a
    third of a step away. Turns are taken as read where that fits some grid as coarse as any scale would,
    else (where ``scaled``: noisy turns) read up to :data:`MAX_SCALE` long or short, at the scale that
    fits the coarsest grid (of :data:`SCALED_GRID` degrees or more) best: the least squared offsets."""
    def fits(q: int, scale: float) -> float | None:
        """The squared offsets of the types from the grid ``q``, turns as if read ``scale`` long; None
        where one lies too far."""
        total = 0.0
        for m, sd, turn in types:
            off = _off_grid(_as_if(m, turn, scale, q), q)
            if off >= min(q / 3, max(3 * sd, BIAS_DEG)):
                return None
            total += off * off
        if any(_off_grid(_as_if(m, turn, scale, q), q) >= q / 3 for m, turn in few):
            return None
        return total

    scales = np.arange(1.0 - MAX_SCALE, 1.0 + MAX_SCALE + SCALE_STEP / 2, SCALE_STEP)
    turning = scaled and any(turn and abs(m) > BIAS_DEG for m, _, turn in types)
    for q in grids:
        if fits(q, 1.0) is not None:
            return q, 1.0
        if turning and q >= SCALED_GRID:
            fitted = [(total, abs(s - 1.0), float(s)) for s in scales if (total := fits(q, float(s))) is not None]
            if fitted:
                return q, round(min(fitted)[2], 3)
    return grids[-1], 1.0


def _as_if(angle: float, turn: bool, scale: float, grid: int) -> float:
    """A measured angle as if the robot had read it ``scale`` long (turns only): of the angle and its turn
    the other way round the circle, whichever lies nearer the grid once scaled (a turn-around read 190.8
    degrees is recorded as -169.2)."""
    if not turn or scale == 1.0:
        return angle
    candidates = (angle / scale, (angle - 360.0 if angle > 0 else angle + 360.0) / scale)
    return min(candidates, key=lambda a: _off_grid(a, grid))


def _off_grid(angle: float, grid: int) -> float:
    """How far an angle lies from the nearest angle of the grid (degrees, on the circle)."""
    return _between(angle, quantise(angle, grid))


def quantise(angle_deg: float, quantum_deg: float) -> int:
    """Round an angle to the quantum and wrap it into (-180, 180]; -180 becomes 180 (turn-around).
    Noise beyond half a quantum rounds to the neighbouring angle (-98 is not a right turn at 15 degrees).

    >>> quantise(-97, 15), quantise(-98, 15), quantise(-180, 15), quantise(7.4, 15), quantise(7.6, 15)
    (-90, -105, 180, 0, 15)
    """
    q = round(angle_deg / quantum_deg) * quantum_deg
    a = int(round(((q + 180.0) % 360.0) - 180.0))
    return 180 if a == -180 else a


#: Two travels whose distances differ by more than this factor are of different lengths (odometry reads a
#: travel's length to a few per cent; where the robot stops varies by a few centimetres).
LENGTH_RATIO = 1.25
#: ... but for this share of a type's readings at either end. A corridor driven hundreds of times is read
#: over a wider span than one driven a few times (318 travels of 2 m read with 3% error: 1.77-2.23 m, 26%);
#: its extremes split off as types of their own made them other actions, and forced dstates apart that
#: are one.
LENGTH_TAIL = 0.025
#: Readings that look exact may still be noisy where the resolution is coarser than the noise: most
#: readings of a corridor land on one value, a few on the next step (a 4 m travel read to 20 cm: 4.0 m
#: thirteen times, 4.2 m three times; a 2 m one read to 25 cm: 2.0 m a hundred times, 2.25 m six). Where
#: the resolution is read from the readings, a length within :data:`GRID_SHARE` of one read this many
#: times as often is that length, as a stray turn reading snaps onto its type; two exact lengths read
#: alike often stay two (2.0 and 2.2 m, twice each), and a tableau that states its resolution keeps
#: every exact length.
STRAY_ODDS = 3


def length_types(distances: Sequence[float], resolution_m: float | None = None) -> list[int]:
    """The length type of each travel, in decimetres (the mean of its type): travels are sorted by length
    and split wherever the next is more than :data:`LENGTH_RATIO` times longer, and a group whose
    longest is still more than that times its shortest (travels of every length, chained by small steps,
    as a log's are; the :data:`LENGTH_TAIL` at either end not counted) is split again at its widest step
    until none is; exact lengths (clean experience, :func:`exact_readings` at the distances' resolution,
    given or read) are each a type.

    >>> length_types([4.02, 1.98, 3.95, 2.03, 12.1, 4.0])
    [40, 20, 40, 20, 121, 40]
    >>> length_types([2.0, 2.2, 2.0, 2.2])
    [20, 22, 20, 22]
    >>> length_types([3.95, 3.96, 4.06, 3.95, 4.05, 3.96])  # one corridor, read to the centimetre
    [40, 40, 40, 40, 40, 40]
    >>> length_types([1.0, 1.2, 1.4, 1.7, 2.0, 2.4])  # no step of 25%, yet 2.4 m is no 1 m travel
    [10, 13, 13, 18, 18, 24]
    >>> length_types([4.0] * 13 + [4.2] * 3 + [2.0] * 4)[-8:]  # 4 m read to 20 cm: 4.2 is 4.0 misread
    [40, 40, 40, 40, 20, 20, 20, 20]
    """
    return LengthTypes(resolution_m).fit(distances).labels_


class LengthTypes:
    """Learn the lengths of a robot's travels (scikit-learn's estimator contract): :func:`length_types`.

    Parameters
    ----------
    resolution_m : float, optional
        The step the distances were recorded at (0: continuous); by default read from them
        (:func:`reading_step`).
    noisy : bool
        The same odometry read its turns with noise (:func:`turns_exact`): then it read the distances
        with noise too, however exact they look (at a resolution coarser than the noise most readings
        of a corridor fall on one value, and a few on the next: 4.0 m eleven times, 4.25 m five).

    Attributes
    ----------
    labels_ : list of int
        Each travel's length type, in decimetres.
    types_ : list of LengthType
        The types found, shortest first.
    resolution_m_ : float
        The resolution used.
    exact_ : bool
        Whether the distances were taken as exact (each value its own type).
    """

    def __init__(self, resolution_m: float | None = None, noisy: bool = False):
        self.resolution_m = resolution_m
        self.noisy = noisy

    def fit(self, distances: Sequence[float]) -> "LengthTypes":
        d = np.asarray(distances, dtype=float)
        self.resolution_m_ = (reading_step(d) if d.size else 0.0) if self.resolution_m is None else self.resolution_m
        self.exact_ = not self.noisy and exact_readings(d, self.resolution_m_)
        self.labels_, self.types_ = [], []
        if d.size == 0:
            return self
        order = np.argsort(d)
        v = np.log(np.maximum(d[order], 1e-3))
        if self.exact_:
            splits = np.flatnonzero(np.diff(v) > 1e-6) + 1
        else:
            # neighbours split where the longer is LENGTH_RATIO times the shorter, each taken half a step
            # of the resolution towards the other (readings 1.5 and 2.0 m to 50 cm may be one travel)
            sorted_d = d[order]
            spans = _log_span(sorted_d[:-1], sorted_d[1:], self.resolution_m_)
            splits = np.flatnonzero(spans > np.log(LENGTH_RATIO)) + 1
        out = np.empty(len(d), dtype=int)
        parts = np.split(order, splits)
        if not self.exact_:
            parts = [p for part in parts for p in _within_ratio(part, d, np.log(LENGTH_RATIO), self.resolution_m_)]
        elif self.resolution_m is None:  # exact as they look: a few may be noise at a coarse resolution
            parts = _strays_joined(parts, d)
        for part in parts:
            mine = d[part]
            out[part] = label = int(round(float(mine.mean()) * 10))
            self.types_.append(LengthType(label, len(mine), float(mine.mean()), float(mine.std()),
                                          self.resolution_m_, self.exact_))
        self.labels_ = out.tolist()
        return self


def _strays_joined(parts: list[np.ndarray], d: np.ndarray) -> list[np.ndarray]:
    """Exact lengths (``parts``: indices into ``d``, one value each, shortest first), each joined to the
    nearest within :data:`GRID_SHARE` of it read :data:`STRAY_ODDS` times as often (noise at a coarse
    resolution), if any."""
    value = [float(d[p[0]]) for p in parts]
    into = list(range(len(parts)))
    for i, p in enumerate(parts):
        near = [j for j, q in enumerate(parts) if len(q) >= STRAY_ODDS * len(p)
                and abs(value[j] - value[i]) <= GRID_SHARE * value[j]]
        if near:
            into[i] = min(near, key=lambda j: abs(value[j] - value[i]))
    joined: dict[int, list[np.ndarray]] = {}
    for i, p in enumerate(parts):
        joined.setdefault(into[i], []).append(p)
    return [np.concatenate(joined[k]) for k in sorted(joined)]


def _log_span(shorter, longer, resolution: float):
    """How many times longer ``longer`` is than ``shorter`` (log; arrays alike), each reading taken half a
    step of its ``resolution`` towards the other (either may lie half a step from what was driven); at most
    0 where they are within a step."""
    return np.log(np.maximum(longer - resolution / 2, 1e-3)) - np.log(np.maximum(shorter + resolution / 2, 1e-3))


def _within_ratio(part: np.ndarray, d: np.ndarray, log_ratio: float, resolution: float = 0.0) -> list[np.ndarray]:
    """``part`` (indices into ``d``, sorted by length) split at its widest steps (in log length) until
    no piece's longest is more than ``exp(log_ratio)`` times its shortest, but for the
    :data:`LENGTH_TAIL` of its readings at either end, and for the ``resolution`` each was recorded at
    (a 2 m travel read to 25 cm as 1.75, 2.0 and 2.25 m: each may have been half a step nearer)."""
    lengths = d[part]
    tail = int(len(lengths) * LENGTH_TAIL)
    if len(part) < 2 or _log_span(lengths[tail], lengths[-1 - tail], resolution) <= log_ratio:
        return [part]
    cut = int(np.argmax(np.diff(np.log(np.maximum(lengths, 1e-3))))) + 1
    return (_within_ratio(part[:cut], d, log_ratio, resolution)
            + _within_ratio(part[cut:], d, log_ratio, resolution))


# -------------------------------------------------------------------------------------------------
# Mistyped actions: readings far from their type, which the resolver may retype at a cost
# -------------------------------------------------------------------------------------------------

#: A reading is far from its type when it lies this many robust spreads of its kind off the type's angle
#: (the spread of the readings around their types, from their median: the few far readings do not inflate
#: it) ...
TYPE_SDS = 3.0
#: ... and at least this share of a grid step (a quarter: nearer the midpoint to the next grid angle than
#: its own angle is to the midpoint's other side). A robot whose turns read within 10 degrees (sd) of 90
#: has a reading 30 off about once in 400; Killian's 45- and 60-degree corners read 30-45 off.
TYPE_STEP_SHARE = 0.25


@dataclass(frozen=True)
class TypeSuspect:
    """An action whose reading lies far from its type's angle: it may be of the neighbouring type.

    Attributes
    ----------
    t : int
        The time point the action starts from.
    kind : str
        ``"turn"`` or ``"travel"``.
    measured : float
        What odometry read (degrees).
    angle : int
        The angle of the type it was learned as.
    alternative : int
        The other grid angle nearest the reading: what the action is if it was mistyped.
    """

    t: int
    kind: str
    measured: float
    angle: int
    alternative: int

    def to_dict(self, cost: int | None = None) -> dict:
        return {"t": self.t, "kind": self.kind, "measured_deg": round(self.measured, 2),
                "learned_deg": self.angle, "abduced_deg": self.alternative, "cost": cost}


def type_suspects(actions: Sequence[Action], angles: Sequence[int], grid_deg: int) -> list[TypeSuspect]:
    """The actions whose reading lies far from the angle of their type (:data:`TYPE_SDS`,
    :data:`TYPE_STEP_SHARE`), in order, each with the other grid angle nearest its reading.

    Clean experience (readings on their types) has none; a robot's noise within its types' spread has
    next to none.

    >>> from bootmap.tableau import Travel
    >>> acts = [Turn(-90.0 + d) for d in (1, -2, 0.5, 3, -1, 2, -3, 0)] + [Turn(-139.0), Travel(3.0, 0.0)]
    >>> [(s.t, s.angle, s.alternative) for s in type_suspects(acts, [-90] * 8 + [180, 0], 90)]
    [(8, 180, -90)]
    """
    is_turn, measured = _readings(actions)
    kinds = np.where(is_turn, "turn", "travel")
    off = np.abs(_wrap(measured - np.asarray(angles, dtype=float)))
    out = []
    for kind in ("turn", "travel"):
        idx = np.flatnonzero(kinds == kind)
        if idx.size == 0:
            continue
        spread = 1.4826 * float(np.median(off[idx]))  # the robust sd of readings about their types
        far = max(TYPE_SDS * spread, TYPE_STEP_SHARE * grid_deg)
        for i in idx[off[idx] > far]:
            out.append(TypeSuspect(int(i), kind, float(measured[i]), int(angles[i]),
                                   _neighbour_angle(float(measured[i]), int(angles[i]), grid_deg)))
    return sorted(out, key=lambda s: s.t)


def _neighbour_angle(reading: float, angle: int, grid_deg: int) -> int:
    """Of the two grid angles either side of the reading, the one that is not ``angle`` (the nearer one
    if neither is)."""
    low = float(np.floor(reading / grid_deg) * grid_deg)
    pair = [quantise(low, grid_deg), quantise(low + grid_deg, grid_deg)]
    others = [a for a in pair if a != angle]
    if len(others) == 2:
        others.sort(key=lambda a: _between(reading, a))
    return others[0]
