"""Control laws: trajectory-following and hill-climbing to distinctive states, and turns.

Each law sees only a :class:`~bootmap.sim.perception.Percept` of the current scan (and, for openings, the
scan itself) and the odometry; never the map or the true pose. A law runs until its state stops changing
- the fixed point of a hill-climbing law, which is a dstate (the paper's "isolated fixed point") - and
then reports the tableau action it performed, measured by odometry.

``Travel`` follows a wall on one side at a set distance (the paper's room circuits) or the middle of a
corridor (hallways), then hill-climbs: to ``stop_distance`` from the wall ahead, or, at a side opening,
to where the opening is symmetric about the robot: the near edge is seen in the scan before the robot
reaches it and carried by odometry, the far edge is seen in the scan; once the opening's width is known
the stop is where the far edge is half of it ahead. ``Turn`` rotates by odometry, corrected by the
walls' direction (or, where odometry is far off, by the walls' directions from scan to scan), and then
hill-climbs to alignment with the walls of the new path. Travel distances are odometry's signed progress:
backing up onto a fixed point the robot overshot counts back.

Every phase is bounded, so every law ends. A law whose hill-climbing has not converged ``SETTLE_BOUND``
control periods into it (noisy readings that never hold the tolerance for two periods in a row, or a
travel whose steering holds it still off its line) settles on filtered readings - the median of the
last few, each carried to the present by odometry - with its tolerances doubled, and doubled again every
``WIDEN_TICKS`` periods; after ``WIDENINGS`` doublings, or ``max_ticks`` periods of the whole law, it
stands where it is. The law's ``bounded`` (the phase) and ``widened`` (the factor; ``inf`` for a law
that stood) say so, and the simulator writes them to the tableau's ``meta["bounded_laws"]``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..tableau import Action
from ..tableau import Travel as TravelAction
from ..tableau import Turn as TurnAction
from ..walls import rotation_candidates, wall_directions
from .perception import Percept, Perception
from .physics import Odometry

NEAR_EDGE_WATCH = 1.0  # m: the end of the wall beside the robot is watched for this far ahead
NEAR_EDGE_SLACK = 0.3  # m: a sighting of the edge further than this from where the side opened is stale
MIN_FAR_EDGE = 0.5  # m: an opening's far edge is first measured when at least this far ahead
BACK_OFF_SLACK = math.radians(1.0)  # a turn's last approach may start this much nearer than its window
QUARTER = math.pi / 2
# A turn's rotation is corrected by wall readings this near the robot's axes: further out (up to the
# percept's 25-degree fold limit) a few chords of corners and door recesses can outvote the walls.
TRACK_LIMIT = math.radians(18)
# Even there, two such readings in a row can be corner chords (a dead end seen 40-50 degrees off its walls):
# a reading is taken only where it differs from odometry's rotation since the last one by less than
# odometry can be off (a turn-rate scale error of a third, and a few degrees besides).
TRACK_GATE = math.radians(8)
TRACK_GATE_SCALE = 0.4
PAIR_GATE = math.radians(3)  # and where it follows from the last scan's reading, by odometry, within this
# Odometry can be off by more than those gates allow (at three times the default noise, a turn rate half as
# fast again as odometry's): the walls' readings are refused, or a stray is taken, and the estimate carries
# the turn to a heading 40-60 degrees off the walls. So the turn is also followed from one scan to the next
# by the directions the walls run in (:mod:`bootmap.walls`, the map's compass): the rotation between two
# consecutive scans is the strongest of those their histograms allow within SCAN_GATE of odometry's step
# (the histograms repeat every quarter turn, and a control period's step is a fraction of one), good to a
# few tenths of a degree. Where the scans' rotation since the turn began and the estimate part by more than
# SCAN_TRUST and SCAN_TRUST_SCALE of the rotation - more than the estimate is off at the default noise, where
# odometry reports the commanded rate before the body reaches it (up to 10 degrees ahead as a turn starts)
# and its scale is a few percent off - the estimate follows the scans for the rest of the turn.
SCAN_GATE = math.radians(20)
SCAN_TRUST, SCAN_TRUST_SCALE = math.radians(12), 0.15
TAKEOVER = TRACK_LIMIT  # a turn's walls take over this far from its target, when they show there
TURN_BOUND = math.radians(30)  # a turn never looks for or aligns with walls further than this from its target
HOLD_TICKS = 10  # control periods an aligning turn waits for walls it lost before it stands where it is
# Every hill-climbing phase is bounded. A law still short of its fixed point SETTLE_BOUND control periods
# into its last phase (a turn aligning, a travel within STOP_ZONE of its stop) settles on filtered
# readings: the median of the last FILTER_LENGTH readings, each carried to the present by odometry's
# motion since (over half a second odometry is off by millimetres and hundredths of a degree), with the
# tolerances doubled, and doubled again every WIDEN_TICKS periods; WIDENINGS doublings on, it stands
# where it is. At the shipped noise hill-climbing takes at most about 70 periods (Taylor Hall's junctions).
SETTLE_BOUND = 100
FILTER_LENGTH = 5
WIDEN_TICKS = 20
WIDENINGS = 4
STOP_ZONE = 0.1  # m: a travel this near its stop is hill-climbing onto it


@dataclass(frozen=True)
class Limits:
    """The robot's motion limits and the control-law gains."""

    v_max: float = 0.9  # m/s
    w_max: float = 2.0  # rad/s
    accel: float = 1.0  # m/s^2, braking profile towards a stop
    w_accel: float = 4.0  # rad/s^2
    k_heading: float = 3.0  # 1/s: turn rate per radian of wall angle
    k_lateral: float = 2.5  # 1/(m s): turn rate per metre off the wall distance or centre line
    k_stop: float = 4.0  # 1/s: final approach gain of the hill-climbing
    k_align: float = 5.0  # 1/s
    stop_tolerance: float = 0.008  # m: the hill-climbing has converged within this
    align_tolerance: float = math.radians(0.6)
    settle_ticks: int = 2  # consecutive converged control periods that make a fixed point


def _fold(angle: float) -> float:
    """An angle folded onto [-45, 45) degrees (the walls' directions are known to a quarter turn)."""
    return (angle + QUARTER / 2) % QUARTER - QUARTER / 2


def _approach_speed(error: float, lim: Limits) -> float:
    """Speed towards a stop ``error`` metres ahead: full speed, then a braking profile, then linear."""
    mag = min(lim.v_max, math.sqrt(2 * lim.accel * abs(error)), lim.k_stop * abs(error))
    return math.copysign(mag, error)


class ControlLaw:
    """Base of the control laws: the fixed-point bookkeeping and the odometry-measured action."""

    timeout = 60.0  # simulated seconds before the simulator declares the robot stuck
    max_ticks = 500  # control periods after which the law stands where it is, whatever its phase

    def __init__(self, lim: Limits):
        self.lim = lim
        self.done = False
        self._calm = 0
        self.start: Odometry | None = None
        self.climbing = 0  # control periods spent in the law's last, hill-climbing phase
        self.bounded: str | None = None  # the phase that reached its bound, if one did
        self.widened = 1.0  # the factor the tolerances were widened by when the law settled
        self._readings: list[tuple[float, float, float, float]] = []  # (error, wall, progress, theta)
        self.ticks = 0  # control periods so far

    def begin(self, odometry: Odometry) -> None:
        self.start = odometry.copy()

    def _settle(self, converged: bool) -> None:
        self._calm = self._calm + 1 if converged else 0
        self.done = self._calm >= self.lim.settle_ticks

    # -- the bound on the hill-climbing phase
    def _climb(self, error: float, wall: float, odo: Odometry, phase: str) -> None:
        """Count a control period of hill-climbing and remember its readings for the filter."""
        self.climbing += 1
        self._readings.append((error, wall, odo.progress, odo.theta))
        del self._readings[:-FILTER_LENGTH]
        if self.climbing > SETTLE_BOUND and self.bounded is None:
            self.bounded = phase

    @property
    def relaxed(self) -> bool:
        """The hill-climbing has passed its bound: settle on filtered readings, with wider tolerances."""
        return self.bounded is not None

    def _widening(self) -> float:
        return 2.0 ** (1 + (self.climbing - SETTLE_BOUND - 1) // WIDEN_TICKS)

    def _expired(self) -> bool:
        """Past the last widening: the fixed point is where the robot stands."""
        return self.climbing > SETTLE_BOUND + WIDENINGS * WIDEN_TICKS

    def _filtered(self, odo: Odometry) -> tuple[float, float]:
        """(error, wall angle): medians of the recent readings, each carried to now by odometry."""
        errors = [e - (odo.progress - p) for e, _, p, _ in self._readings if math.isfinite(e)]
        walls = [w - (odo.theta - t) for _, w, _, t in self._readings if not math.isnan(w)]
        return (float(np.median(errors)) if errors else math.nan,
                float(np.median(walls)) if walls else math.nan)

    def _tick(self, phase: str) -> bool:
        """Count a control period; past ``max_ticks``, end the law where it stands (True)."""
        self.ticks += 1
        if self.ticks >= self.max_ticks:
            self.bounded = self.bounded or phase
            self.widened = math.inf
            self.done = True
        return self.done

    def _settle_relaxed(self, converged: bool) -> None:
        self._settle(converged)
        if self.done:
            self.widened = self._widening()
        elif self._expired():  # the last widening has passed: stand where it is
            self.done = True
            self.widened = math.inf

    def action(self, odometry: Odometry) -> Action:
        raise NotImplementedError


class Travel(ControlLaw):
    """Follow the path ahead, then hill-climb to the next dstate.

    Parameters
    ----------
    lim : Limits
    perception : Perception
        Used for the far edge of a side opening.
    follow : {"left", "right", "centre"}
        Keep ``wall_distance`` from the wall on that side, or the middle of the corridor.
    wall_distance, stop_distance : float
        Metres.
    junctions : bool
        Stop at side openings (hallways); otherwise pass them holding the heading (room circuits).
    """

    timeout = 300.0
    # Past the simulator's own limit: noise near the stop is bounded by the settle rule above, so a travel
    # still going at 300 s is a robot that cannot move as its world file says (far too slow, say), which
    # the simulator reports as stuck rather than stopping it mid-corridor and calling that a dstate.
    max_ticks = 3100

    def __init__(self, lim: Limits, perception: Perception, follow: str, wall_distance: float,
                 stop_distance: float, junctions: bool):
        super().__init__(lim)
        self.perception, self.follow = perception, follow
        self.wall_distance, self.stop_distance, self.junctions = wall_distance, stop_distance, junctions
        self._armed = {+1: False, -1: False}
        self._opened_at: dict[int, float] = {}
        self._edge_ahead: dict[int, float] = {}  # odometry distance where the wall on a side is seen to end
        self._width: dict[int, float] = {}  # width of an opening, from its near edge to its far edge
        self._held = {+1: wall_distance, -1: wall_distance}

    def step(self, p: Percept, ranges: np.ndarray, odo: Odometry) -> tuple[float, float]:
        if self._tick("travel"):
            return 0.0, 0.0
        lim = self.lim
        phi = 0.0 if math.isnan(p.wall_angle) else p.wall_angle
        travelled = odo.progress - self.start.progress  # signed: backing up to the fixed point counts back
        self._track_openings(p, ranges, travelled)
        omega = lim.k_heading * phi + lim.k_lateral * self._lateral_error(p)
        omega = max(-lim.w_max, min(lim.w_max, omega))
        error = self._stop_error(p, ranges, travelled)
        if abs(error) < STOP_ZONE or self.climbing:
            self._climb(error, p.wall_angle, odo, "stop")
        if self.relaxed:
            # Standing at its stop the robot cannot move sideways: the lateral term is dropped (with it,
            # a heading error and a lateral one that cancel hold the robot short of alignment for ever).
            error, phi = self._filtered(odo)
            phi = 0.0 if math.isnan(phi) else phi
            error = error if math.isfinite(error) else 0.0
            widen = self._widening()
            omega = max(-lim.w_max, min(lim.w_max, lim.k_heading * phi))
            self._settle_relaxed(abs(error) < widen * lim.stop_tolerance and
                                 abs(phi) < widen * 2 * lim.align_tolerance)
            if self.done:
                return 0.0, 0.0
            return _approach_speed(error, lim), omega
        v = _approach_speed(error, lim) if math.isfinite(error) else lim.v_max
        converged = abs(error) < lim.stop_tolerance and abs(phi) < 2 * lim.align_tolerance
        self._settle(converged)
        if self.done:
            return 0.0, 0.0
        # Turning hard at full speed swings the robot off its line: slow down while correcting.
        v *= max(0.3, 1.0 - abs(omega) / lim.w_max)
        return v, omega

    def _track_openings(self, p: Percept, ranges: np.ndarray, travelled: float) -> None:
        """Openings present where the travel starts belong to the place being left: ignore them until
        the side closes. A side that opens afterwards is a new opening, noted with the distance at which
        its near edge was passed.

        The side beams only notice the opening once the robot is level with its edge, up to one control
        period (a tenth of a metre at full speed) late. So while the wall beside the robot is closed, the
        scan ahead is watched for where that wall ends; the edge seen last, carried by odometry, dates
        the opening more precisely than the moment the side beams opened.
        """
        for side, is_open, dist in ((+1, p.left_open, p.left), (-1, p.right_open, p.right)):
            if not is_open:
                self._armed[side] = True
                self._opened_at.pop(side, None)
                self._width.pop(side, None)
                if math.isfinite(dist):
                    self._held[side] = dist
                    if self.junctions:
                        ahead = self.perception.near_edge(ranges, side, dist + 0.5)
                        if 0.0 <= ahead < NEAR_EDGE_WATCH:
                            self._edge_ahead[side] = travelled + ahead
                        elif ahead >= NEAR_EDGE_WATCH:
                            self._edge_ahead.pop(side, None)
            elif self._armed[side] and side not in self._opened_at:
                seen = self._edge_ahead.pop(side, None)
                recent = seen is not None and abs(seen - travelled) < NEAR_EDGE_SLACK
                self._opened_at[side] = seen if recent else travelled

    def _lateral_error(self, p: Percept) -> float:
        """Positive when the robot should turn left to get back onto its line."""
        left, right = p.left, p.right  # inf where the side is open
        if self.follow == "left":
            return left - self.wall_distance if math.isfinite(left) else 0.0
        if self.follow == "right":
            return self.wall_distance - right if math.isfinite(right) else 0.0
        if math.isfinite(left) and math.isfinite(right):
            return 0.5 * (left - right)
        if math.isfinite(right):  # one wall left: hold the distance it had before the opening
            return self._held[-1] - right
        if math.isfinite(left):
            return left - self._held[+1]
        return 0.0

    def _stop_error(self, p: Percept, ranges: np.ndarray, travelled: float) -> float:
        """Signed distance to the dstate ahead: the midpoint of a side opening, or the stop before the
        wall ahead; ``inf`` while neither is in sight.

        The opening's width is measured once, when its far edge first comes into view: the far edge's
        distance ahead plus the distance travelled since the near edge (a short stretch of odometry).
        From then on the hill-climbing needs only the scan: the midpoint is where the far edge is half
        the width ahead, so the fixed point does not depend on odometry drift or on which way the robot
        came.
        """
        front = p.front - self.stop_distance if p.front < self.perception.range_max * 0.98 else math.inf
        if not self.junctions or not self._opened_at:
            return front
        errors = []
        for side, opened in self._opened_at.items():
            depth = self._held[side] + 0.5
            far = min(p.front, self.perception.far_edge(ranges, side, depth))
            width = self._width.get(side)
            if width is None:
                # the far edge is only measured once the beams beside the robot have left the near one
                if not math.isfinite(far) or far < MIN_FAR_EDGE:
                    continue
                width = self._width[side] = far + (travelled - opened)
            errors.append(far - 0.5 * width)
        return min(errors + [front])

    def action(self, odometry: Odometry) -> Action:
        dist = odometry.progress - self.start.progress
        dtheta = math.degrees(odometry.theta - self.start.theta)
        return TravelAction(round(max(dist, 1e-3), 4), round(dtheta, 3))


class Turn(ControlLaw):
    """Turn in place by ``angle`` (radians, positive left): rotate to near the new heading, then
    hill-climb to alignment with the walls of the new path.

    The rotation is measured by odometry and corrected by the walls. Walls in buildings meet at right
    angles, so the percept's wall angle says the robot's heading to within a quarter turn; while the walls
    are read reliably (within ``TRACK_LIMIT`` of the axes, following from the last scan's reading by
    odometry's step within ``PAIR_GATE``, and from the last reliable one within ``TRACK_GATE``, each
    plus ``TRACK_GATE_SCALE`` of the rotation odometry measured), the change of the wall angle since the
    last such reading is the rotation since then, and odometry only says which quarter turn it is in (it
    is never 45 degrees off over the 50-odd degrees between two reliable readings). Odometry alone carries
    the estimate across the gaps, and decides it where no wall is seen at all. A turn-rate scale error
    that leaves odometry 50 degrees off on a turn-around (2-3 standard deviations at twice the default
    noise, docs/noise.md) therefore does not move where the turn ends; a law that trusted odometry to
    within a fixed search range instead turned to and fro between the range and odometry's target for
    ever (``stuck: turn did not reach a dstate``). Further off still (at three times the default noise the
    turn rate can be half as fast again as odometry's), the gates refuse the walls' readings, or let a
    stray through, and the estimate would carry the turn 40-60 degrees past the walls, where none shows
    within ``TURN_BOUND`` of the target and the estimate settles it diagonally. So the turn is also
    followed scan to scan by the histograms of the directions the walls run in (``SCAN_GATE``), which
    see every wall in view whatever its angle; where they part from the estimate by more than it can be
    off at the default noise (``SCAN_TRUST``), the estimate follows them for the rest of the turn. (Short
    of that they are only a check: at the default noise the law turns as by odometry and the walls.)

    Phases, each ending, so that every turn ends:

    * ``rotate``: towards the angle by the estimate, until the walls show the target's axis within
      ``TAKEOVER``, or it is within ``align_window`` of the angle;
    * ``align``: the hill-climbing on the walls. The last approach always starts ``align_window`` short
      of the walls, by the walls: a robot that the rotation brought closer, or past them, first backs off
      to there. The hill-climbing stops as soon as the walls are within tolerance, so where in the
      tolerance it stops depends on the way it came; if that way varied with the odometry error, so
      would the heading at the dstate and its image (a turn approached from 5 or from 15 degrees out
      stops up to a degree apart, which splits a view). Walls lost for a scan (drop-outs): hold still;
      lost for ``HOLD_TICKS``, the fixed point is where the robot stands. Walls that lead further than
      ``TURN_BOUND`` from the target are not the new path's: the estimate settles the turn;
    * ``search``: within the window no wall is seen (a crossing, or walls further off the axes than the
      percept folds): turn on past the target, up to ``TURN_BOUND``, until walls show;
    * ``return``: none showed: back to the target by the estimate, and settle there (the turn is the
      estimate's alone, that is odometry's where no wall is seen), unless walls show within the window:
      then they take over;
    * ``final``: the walls led too far: the estimate settles the turn at the target.

    ``align``, ``return`` and ``final`` are hill-climbing and bounded as every law's is (the module's
    docstring): past ``SETTLE_BOUND`` control periods they settle on the median of the last readings, each
    carried to the present by odometry, with widening tolerances; and the turn ends after ``max_ticks``.

    Parameters
    ----------
    lim : Limits
    angle : float
        Radians, positive left.
    align_window : float
        Radians of turn still to go (by the estimate) where alignment with the walls takes over, and how
        far short of the walls the last approach starts.
    perception : Perception, optional
        The laser's geometry (beam angles, maximum range), for the walls' directions in each scan; without
        it the turn is followed by odometry and the percept's wall angle alone.

    Attributes
    ----------
    turned : float
        The rotation so far by the estimate, radians.
    scanned : float
        The rotation so far by the walls' directions, scan to scan, radians.
    scanning : bool
        The estimate has parted from the scans by more than ``SCAN_TRUST`` and follows them.
    phase : str
        One of the phases above.
    """

    timeout = 30.0
    max_ticks = 250  # 25 s at 10 Hz: a turn-around takes two

    def __init__(self, lim: Limits, angle: float, align_window: float = math.radians(12),
                 perception: Perception | None = None):
        super().__init__(lim)
        self.angle, self.align_window = angle, align_window
        self.perception = perception  # its laser's geometry, for the wall directions; None: odometry alone
        self.direction = math.copysign(1.0, angle)
        self.phase = "rotate"
        self.turned = 0.0
        self.approaching = False  # the last approach, from align_window short of the walls, has begun
        self._odometry_theta = 0.0
        self._anchor: tuple[float, float] | None = None  # (wall angle, turned) at the last reliable reading
        self.scanned = 0.0  # the rotation so far by the walls' directions, scan to scan
        self.scanning = False  # the estimate follows the scans (odometry has been found too far off)
        self._directions: np.ndarray | None = None  # the last scan's histogram of wall directions
        self._previous = math.nan  # the last scan's wall angle, if within TRACK_LIMIT
        self._lost = 0  # control periods the walls have been lost while aligning

    def begin(self, odometry: Odometry) -> None:
        super().begin(odometry)
        self._odometry_theta = odometry.theta

    @property
    def aligning(self) -> bool:
        """The walls have taken over from the estimate."""
        return self.phase == "align"

    def _scan_step(self, ranges: np.ndarray, step: float) -> float:
        """The rotation since the last scan by the walls' directions: of the rotations the two scans'
        histograms allow, the strongest within ``SCAN_GATE`` of odometry's ``step``; odometry's step where
        they allow none there (no wall seen in one of them)."""
        directions = wall_directions(ranges, self.perception.angles, self.perception.range_max)
        before, self._directions = self._directions, directions
        if before is None:
            return step
        near = [(strength, math.radians(c) + round((step - math.radians(c)) / (2 * math.pi)) * 2 * math.pi)
                for c, strength in rotation_candidates(before, directions)]
        near = [(strength, c) for strength, c in near if abs(c - step) <= SCAN_GATE]
        return max(near)[1] if near else step

    def _track(self, wall: float, ranges: np.ndarray, odo: Odometry) -> None:
        """Advance the rotation estimate by odometry, then correct it by a reliable wall reading; once the
        scans show the estimate further off than odometry can be, follow the scans instead."""
        step = odo.theta - self._odometry_theta
        self._odometry_theta = odo.theta
        if self.perception is not None:
            self.scanned += self._scan_step(ranges, step)
            if self.scanning or \
                    abs(self.scanned - self.turned - step) > SCAN_TRUST + SCAN_TRUST_SCALE * abs(self.scanned):
                self.scanning = True
                self.turned = self.scanned
                return
        self.turned += step
        if math.isnan(wall) or abs(wall) > TRACK_LIMIT:
            self._previous = math.nan
            return
        previous, self._previous = self._previous, wall
        if self._anchor is not None:
            # walls are seen as walls from one scan to the next: a reading that does not follow from the
            # last one by odometry's step is a stray (corner chords, 35-55 degrees off the walls)
            if math.isnan(previous) or \
                    abs(_fold(previous - wall - step)) > PAIR_GATE + TRACK_GATE_SCALE * abs(step):
                return
            wall_then, turned_then = self._anchor
            by_odometry = self.turned - turned_then
            by_walls = wall_then - wall  # the walls turn the other way in the robot's frame
            quarters = round((by_odometry - by_walls) / QUARTER)
            by_walls += quarters * QUARTER
            if abs(by_walls - by_odometry) > TRACK_GATE + TRACK_GATE_SCALE * abs(by_odometry):
                return  # more than odometry can be off: chords of a corner, not the walls
            self.turned = turned_then + by_walls
        self._anchor = (wall, self.turned)

    def step(self, p: Percept, ranges: np.ndarray, odo: Odometry) -> tuple[float, float]:
        if self._tick(self.phase):
            return 0.0, 0.0
        self._track(p.wall_angle, ranges, odo)
        remaining = self.angle - self.turned
        # The percept folds the walls onto the nearest axis; the estimate says which axis is the target's.
        wall = p.wall_angle
        if not math.isnan(wall):
            wall += round((remaining - wall) / QUARTER) * QUARTER
        if self.phase == "align" and abs(remaining) > TURN_BOUND:
            self.phase = "final"
        # The walls take over as soon as they show the target's axis (TAKEOVER ahead, by the estimate):
        # at the window the rotation's momentum has carried the robot a few degrees nearer than the
        # estimate, and nearly every last approach would begin by backing off against that momentum
        # (which scatters the final heading by a third more).
        if self.phase == "rotate" and not math.isnan(wall) and abs(remaining) <= TAKEOVER:
            self.phase = "align"
        if self.phase in ("rotate", "return") and abs(remaining) <= self.align_window:
            if not math.isnan(wall):
                self.phase = "align"
            elif self.phase == "rotate":
                self.phase = "search"
        if self.phase == "search":
            if not math.isnan(wall) and abs(wall) <= TURN_BOUND:
                self.phase = "align"
            else:
                # turn on past the target, at most at the speed of the last approach, until walls show;
                # slowing into the bound so as not to pass it
                gap = TURN_BOUND + remaining * self.direction
                if gap < BACK_OFF_SLACK:
                    self.phase = "return"
                else:
                    self._settle(False)
                    return 0.0, self.direction * self.lim.k_align * min(self.align_window, gap)
        if self.phase == "align":
            self._climb(math.nan, wall, odo, "align")
            return self._align(wall, odo)
        settle = self.phase in ("return", "final")
        if settle:
            self._climb(remaining, math.nan, odo, self.phase)
        return self._rotate(remaining, settle)

    def _rotate(self, remaining: float, settle: bool) -> tuple[float, float]:
        lim = self.lim
        mag = min(lim.w_max, math.sqrt(2 * lim.w_accel * abs(remaining)), lim.k_align * abs(remaining))
        if settle and self.relaxed:  # the estimate has kept moving (walls correcting it): widen
            self._settle_relaxed(abs(remaining) < self._widening() * lim.align_tolerance)
        else:
            self._settle(settle and abs(remaining) < lim.align_tolerance)
        return 0.0, (0.0 if self.done else math.copysign(mag, remaining))

    def _align(self, wall: float, odo: Odometry) -> tuple[float, float]:
        lim = self.lim
        if self.relaxed:
            # past the bound: hill-climb and settle on the filtered wall angle, tolerance widening
            _, wall = self._filtered(odo)
            if math.isnan(wall):
                self._settle_relaxed(False)
                return 0.0, 0.0
            widen = self._widening()
            self._settle_relaxed(abs(wall) < widen * lim.align_tolerance)
            return 0.0, (0.0 if self.done else max(-lim.w_max, min(lim.w_max, lim.k_align * wall)))
        if math.isnan(wall):  # the walls lost (drop-outs): hold still, and stand here if they stay lost
            self._lost += 1
            self._settle(False)
            self.done = self._lost >= HOLD_TICKS
            return 0.0, 0.0
        self._lost = 0
        # short of the walls (in the turn's direction) by the window, less a degree of slack: approach
        self.approaching = self.approaching or wall * self.direction >= self.align_window - BACK_OFF_SLACK
        target = 0.0 if self.approaching else self.direction * self.align_window
        self._settle(self.approaching and abs(wall) < lim.align_tolerance)
        return 0.0, (0.0 if self.done else max(-lim.w_max, min(lim.w_max, lim.k_align * (wall - target))))

    def action(self, odometry: Odometry) -> Action:
        """The turn as the robot measured it: odometry's rotation; or, where the turn was followed by the
        scans because odometry was found further off than it can be (``scanning``), the scans' rotation,
        which is what the robot then knows it turned."""
        turned = self.scanned if self.scanning else odometry.theta - self.start.theta
        return TurnAction(round(math.degrees(turned), 3))
