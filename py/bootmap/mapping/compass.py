"""The walls as a compass: how far each action turned the robot, read from the laser images at its ends.

Odometry reads a turn on the spot to a few degrees on a good robot and to tens of degrees on a poor one
(a turn-around read as 236 degrees); a heading read wrong puts every later time point in the wrong
heading. The laser reads it better. Walls are straight, and the directions the walls run in, as a robot
sees them, turn with the robot: a turn of 90 degrees shifts every wall's direction in the image by -90.
So the rotation between two images is where their histograms of wall directions agree (the angle
histograms of Weiss, Wetzler and von Puttkamer, IROS 1994). The images need not overlap: before and
after a turn-around a 180-degree laser sees disjoint halves of a corridor, but the same walls' direction.

A wall has no sense (a wall running at 10 degrees also runs at 190), and a building's walls repeat their
directions (a rectangular building's every 90 degrees), so the histograms say the rotation only up to
those repeats: they give *candidates*. Odometry chooses among them, as a compass needle is read against a
rough idea of the way one faces:

1. Each image's wall directions: every beam's point with its neighbours lies on a line (the smaller
   spread of the points across it is small), whose direction votes with the length of wall it covers.
2. Each action's candidates: the peaks of the two histograms' circular correlation, each peak being a
   rotation modulo 180 degrees, so each makes two candidates.
3. How far odometry strays, per kind of action: the robust spread of odometry's readings around the
   nearest candidate (learned from the tableau; the robot's own noise, not a setting).
4. Each action's reading: the nearest candidate where it lies within three such spreads of what odometry
   read (*confirmed*), else odometry's own reading. Where a second candidate is nearly as likely given
   odometry's spread (at least :data:`ALTERNATIVE_ODDS` as likely), the action is ambiguous: its reading
   is the nearer candidate, and the other is kept as the angle the action has if odometry misled it. The
   resolver weighs it as it weighs a mistyped action (:mod:`.search.retyping`).
5. For a robot that stops at its dstates, a turn is on the spot, and the beams both images share (none
   for a turn-around) must agree: a candidate they refute is dropped; one they verify is taken, if
   odometry's heavy tails allow it, with the nearer unverifiable candidate as its alternative. Where no
   candidate is left within three spreads, the nearest one the beams leave is read, if the tails allow it.

Images without a laser's geometry (``meta.laser``: ``angle_min``, ``angle_max``, ``range_max``), or
tableaux without images, are read by odometry alone. A log of a robot that drove through its dstates
without stopping (``meta.passes_through``) is not read here: its images at an action's two ends lie
metres apart, around corners, and the walls each sees are not the other's (on the MIT Killian Court log,
reading its actions from the walls put 80.6% of visits in their true dstate, against 88.8% by odometry's
angles); its headings are the building's sectors (:mod:`.sectors`).

Example
-------
>>> import numpy as np
>>> from bootmap.tableau import Step, Tableau, Turn
>>> def corridor(heading_deg):  # a robot 1 m from either wall of a long corridor running east
...     a = np.linspace(-np.pi / 2, np.pi / 2, 180) + np.radians(heading_deg)
...     with np.errstate(divide="ignore"):
...         r = np.abs(1.0 / np.sin(a))
...     return tuple(np.minimum(r, 8.0))
>>> laser = {"angle_min": -np.pi / 2, "angle_max": np.pi / 2, "range_max": 8.0}
>>> steps = [Step(action=Turn(a), image=corridor(h)) for a, h in ((203.0, 0), (-178.0, 180))]
>>> steps.append(Step(image=corridor(0)))
>>> c = WallCompass().fit(Tableau(tuple(steps), "corridor", {"laser": laser}))
>>> [round(x) for x in c.readings_], c.confirmed_
([180, -180], [True, True])
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache, partial
from typing import Callable

import numpy as np

from ..tableau import Action, Tableau, Travel, Turn
# the wall-direction histograms and their rotations (step 1, and step 2's peaks) are the foundation's,
# shared with the simulator's turn law
from ..walls import HALF_WINDOW, MAX_RANGE_SHARE, SMOOTH_DEG, rotation_candidates, wall_directions, wrap_deg
from .motion import measured_angle

#: A reading is confirmed where the nearest candidate lies within this many of odometry's spreads ...
CONFIRM_SDS = 3.0
#: ... and ambiguous where the next candidate is at least this likely, relative to the nearest, given
#: odometry's spread (Gaussian): odometry cannot tell the two apart.
ALTERNATIVE_ODDS = 0.01
#: The least spread odometry is granted (degrees): the laser's own resolution.
MIN_SPREAD_DEG = 1.0
#: Before and after a turn on the spot, two beams looking the same way agree within this many metres plus
#: this share of the range ...
AGREE_M, AGREE_SHARE = 0.1, 0.05
#: ... and a candidate turn is refuted where more than this share of the shared beams that see something
#: disagree (or verified where fewer do), judged on at least this many beams.
REFUTE_SHARE, MIN_SHARED = 0.25, 20


@dataclass(frozen=True)
class Reading:
    """What the walls say about one action."""

    odometry: float                 # what odometry read (a turn's angle, a travel's heading change)
    reading: float                  # what the compass reads: the confirmed candidate, or odometry's reading
    confirmed: bool                 # the walls confirmed a candidate near odometry's reading
    alternative: float | None       # a second candidate odometry cannot tell from the first


class WallCompass:
    """Read each action's change of heading from the wall directions in the images at its ends
    (scikit-learn's estimator contract; module docstring).

    Attributes
    ----------
    readings_ : list of float
        Per action, the angle read: a turn's angle or a travel's heading change, in degrees; odometry's
        own reading where the walls confirm no candidate (or the tableau has no laser images).
    confirmed_ : list of bool
        Per action, whether the walls confirmed the reading.
    alternatives_ : list of float or None
        Per action, a second candidate as likely as :data:`ALTERNATIVE_ODDS` of the first, given odometry.
    spread_deg_ : dict
        Per kind (``"turn"``, ``"travel"``), how far odometry strays from the walls' reading (robust s.d.).
    used_ : bool
        Whether the tableau had laser images to read (else every reading is odometry's).
    """

    def fit(self, tableau: Tableau) -> "WallCompass":
        actions = tableau.actions
        odometry = [measured_angle(a) for a in actions]
        laser = _laser(tableau)
        self.used_ = laser is not None
        self.spread_deg_ = {}
        if laser is None:  # no walls to read: every reading is odometry's own (what _read makes of no candidates)
            out = [Reading(o, o, False, None) for o in odometry]
        else:
            # (each image's walls and each pair's candidates are remembered: a map kept current as steps
            # arrive reads only the new ones)
            lo, hi, rmax = float(laser[0][0]), float(laser[0][-1]), laser[1]
            images = [s.image if isinstance(s.image, tuple) else tuple(s.image) for s in tableau.steps]
            candidates = [_candidates(images[t], images[t + 1], lo, hi, rmax) for t in range(len(actions))]
            kinds = [a.kind for a in actions]
            for kind in ("turn", "travel"):
                off = [_nearest([a for a, _ in c], o)[1] for c, o, k in zip(candidates, odometry, kinds)
                       if k == kind and c]
                if off:
                    self.spread_deg_[kind] = max(MIN_SPREAD_DEG, 1.4826 * float(np.median(off)))
            # A robot that stops at its dstates turns on the spot: the images before and after a turn share
            # the beams that look the same way, and those must agree.
            out = []
            for t, (o, c, k) in enumerate(zip(odometry, candidates, kinds)):
                agrees = partial(overlap_agrees, images[t], images[t + 1], *laser) if k == "turn" else None
                out.append(_read(o, c, self.spread_deg_.get(k, MIN_SPREAD_DEG), agrees))
        self.results_ = out
        self.readings_ = [r.reading for r in out]
        self.confirmed_ = [r.confirmed for r in out]
        self.alternatives_ = [r.alternative for r in out]
        return self

    def actions(self, actions: list[Action]) -> list[Action]:
        """The actions with the compass's readings in place of odometry's angles (lengths unchanged)."""
        out: list[Action] = []
        for a, r in zip(actions, self.readings_):
            out.append(Turn(r) if isinstance(a, Turn) else Travel(a.distance_m, r))  # type: ignore[union-attr]
        return out


def _read(odometry: float, candidates: list[tuple[float, float]], spread: float,
          agrees: Callable[[float], bool | None] | None = None) -> Reading:
    """One action's reading from its candidates (module docstring, steps 4 and 5): each weighed by its
    strength and by how likely odometry's reading makes it (Gaussian, odometry's spread). ``agrees`` (for
    a turn on the spot, :func:`overlap_agrees`) says of a candidate turn whether the beams both images
    share agree (True), disagree (False), or are too few to say (None)."""
    window = CONFIRM_SDS * spread

    def odds(c: float, strength: float) -> float:
        return strength * float(np.exp(-0.5 * ((c - odometry) / spread) ** 2))

    weighed = sorted(((odometry + wrap_deg(c - odometry), w) for c, w in candidates),
                     key=lambda cw: -odds(*cw) if abs(cw[0] - odometry) <= window else abs(cw[0] - odometry))
    if agrees is not None:
        said = {c: agrees(c) for c, _ in weighed}
        weighed = [(c, w) for c, w in weighed if said[c] is not False]  # the shared beams refute it
        verified = sorted((c for c, _ in weighed if said[c]), key=lambda c: abs(c - odometry))
        nearest = min(weighed, key=lambda cw: abs(cw[0] - odometry), default=(math.inf, 0.0))[0]
        if verified and verified[0] == nearest:
            # the shared beams agree with the candidate nearest odometry's reading
            return Reading(odometry, nearest, True, None)
        if verified and _tail_odds(abs(verified[0] - odometry), abs(nearest - odometry), spread) >= ALTERNATIVE_ODDS:
            # the beams verify a candidate odometry cannot rule out, beside a nearer one they cannot check
            # (a spot of like walls can look alike turned by the difference): the verified one, the other
            # kept as its alternative
            return Reading(odometry, verified[0], True, nearest)
    near = [(c, w) for c, w in weighed if abs(c - odometry) <= window]
    if not near:
        # No candidate where odometry usually strays. On the spot, the one the beams leave nearest, if
        # odometry's heavy tails allow it (not to learn types from); else odometry's own reading.
        far = weighed[0][0] if agrees is not None and weighed else None
        if far is not None and _tail_odds(abs(far - odometry), window, spread) >= ALTERNATIVE_ODDS:
            return Reading(odometry, far, False, None)
        return Reading(odometry, odometry, False, None)
    alternative = None
    if len(near) > 1 and odds(*near[1]) >= ALTERNATIVE_ODDS * odds(*near[0]) and \
            abs(wrap_deg(near[1][0] - near[0][0])) > 2 * SMOOTH_DEG:
        alternative = near[1][0]
    return Reading(odometry, near[0][0], True, alternative)


def _tail_odds(far: float, near: float, spread: float) -> float:
    """How likely odometry's reading makes a candidate ``far`` degrees from it, relative to one ``near``
    degrees from it, counting its errors' heavy tails (Laplace, of odometry's spread): a turn's reading
    carries the to-and-fro of the law that ended it, so tens of degrees off happen more often than a
    Gaussian of the same spread allows."""
    return float(np.exp(-(far - near) / spread))


def overlap_agrees(before, after, beam_angles: np.ndarray, range_max: float, turn_deg: float) -> bool | None:
    """Whether two images taken on one spot, before and after a turn of ``turn_deg``, agree where they look
    the same way: True where at most :data:`REFUTE_SHARE` of the shared beams that see something disagree
    (by more than :data:`AGREE_M` plus :data:`AGREE_SHARE` of the range), False where more do, None where
    fewer than :data:`MIN_SHARED` beams are shared (a turn-around of a 180-degree laser shares none)."""
    b, a = np.asarray(before, dtype=float), np.asarray(after, dtype=float)
    # the beam at angle alpha after the turn looks where the beam at alpha + turn looked before it
    source = beam_angles + np.radians(wrap_deg(turn_deg))
    shared = (source >= beam_angles[0]) & (source <= beam_angles[-1])
    far = MAX_RANGE_SHARE * range_max
    rb = np.minimum(np.interp(source[shared], beam_angles, b), far)
    ra = np.minimum(a[shared], far)
    seen = (rb < far) | (ra < far)
    if seen.sum() < MIN_SHARED:
        return None
    disagree = np.abs(rb - ra) > AGREE_M + AGREE_SHARE * np.minimum(rb, ra)
    return bool(disagree[seen].mean() <= REFUTE_SHARE)


def _nearest(candidates: list[float], odometry: float) -> tuple[float, float]:
    """The candidate nearest odometry's reading, unwrapped next to it, and its distance."""
    best = min(candidates, key=lambda c: abs(wrap_deg(c - odometry)))
    near = odometry + wrap_deg(best - odometry)
    return near, abs(near - odometry)


def _laser(tableau: Tableau) -> tuple[np.ndarray, float] | None:
    """The beams' angles and the laser's maximum range, where the tableau has images, says its laser's
    geometry (``meta.laser``) and the robot stopped at its dstates, else None."""
    laser = tableau.meta.get("laser")
    steps = tableau.steps
    if not isinstance(laser, dict) or not steps or any(s.image is None for s in steps) or \
            tableau.meta.get("passes_through", False):
        return None
    try:
        lo, hi, rmax = float(laser["angle_min"]), float(laser["angle_max"]), float(laser["range_max"])
    except (KeyError, TypeError, ValueError):
        return None
    beams = len(steps[0].image)
    if beams < 2 * HALF_WINDOW + 1 or any(len(s.image) != beams for s in steps) or not hi > lo:
        return None
    return np.linspace(lo, hi, beams), rmax


#: How many images' walls, and pairs' candidates, are remembered.
REMEMBERED = 16384


@lru_cache(maxsize=REMEMBERED)
def _walls(image: tuple, lo: float, hi: float, range_max: float) -> np.ndarray:
    return wall_directions(image, np.linspace(lo, hi, len(image)), range_max)


@lru_cache(maxsize=REMEMBERED)
def _candidates(before: tuple, after: tuple, lo: float, hi: float, range_max: float) -> list[tuple[float, float]]:
    return rotation_candidates(_walls(before, lo, hi, range_max), _walls(after, lo, hi, range_max))
