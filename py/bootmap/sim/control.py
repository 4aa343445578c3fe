"""Control laws: trajectory-following and hill-climbing to distinctive states, and turns.

Each law sees only a :class:`~bootmap.sim.perception.Percept` of the current scan (and, for openings, the
scan itself) and the odometry; never the map or the true pose. A law runs until its state stops changing
- the fixed point of a hill-climbing law, which is a dstate (the paper's "isolated fixed point") - and
then reports the tableau action it performed, measured by odometry.

``Travel`` follows a wall on one side at a set distance (the paper's room circuits) or the middle of a
corridor (hallways), then hill-climbs: to ``stop_distance`` from the wall ahead, or, at a side opening,
to where the opening is symmetric about the robot: the near edge is seen in the scan before the robot
reaches it and carried by odometry, the far edge is seen in the scan; once the opening's width is known
the stop is where the far edge is half of it ahead. ``Turn`` rotates by odometry and then hill-climbs
to alignment with the walls of the new path. Travel distances are odometry's signed progress: backing
up onto a fixed point the robot overshot counts back.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..tableau import Action
from ..tableau import Travel as TravelAction
from ..tableau import Turn as TurnAction
from .perception import Percept, Perception
from .physics import Odometry

NEAR_EDGE_WATCH = 1.0  # m: the end of the wall beside the robot is watched for this far ahead
NEAR_EDGE_SLACK = 0.3  # m: a sighting of the edge further than this from where the side opened is stale
MIN_FAR_EDGE = 0.5  # m: an opening's far edge is first measured when at least this far ahead
BACK_OFF_SLACK = math.radians(1.0)  # a turn's last approach may start this much nearer than its window
SEARCH_LIMIT = math.radians(40)  # a turn looks for walls this far past its odometry angle before giving up


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


def _approach_speed(error: float, lim: Limits) -> float:
    """Speed towards a stop ``error`` metres ahead: full speed, then a braking profile, then linear."""
    mag = min(lim.v_max, math.sqrt(2 * lim.accel * abs(error)), lim.k_stop * abs(error))
    return math.copysign(mag, error)


class ControlLaw:
    """Base of the control laws: the fixed-point bookkeeping and the odometry-measured action."""

    timeout = 60.0  # simulated seconds before the robot counts as stuck

    def __init__(self, lim: Limits):
        self.lim = lim
        self.done = False
        self._calm = 0
        self.start: Odometry | None = None

    def begin(self, odometry: Odometry) -> None:
        self.start = odometry.copy()

    def _settle(self, converged: bool) -> None:
        self._calm = self._calm + 1 if converged else 0
        self.done = self._calm >= self.lim.settle_ticks

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
        lim = self.lim
        phi = 0.0 if math.isnan(p.wall_angle) else p.wall_angle
        travelled = odo.progress - self.start.progress  # signed: backing up to the fixed point counts back
        self._track_openings(p, ranges, travelled)
        omega = lim.k_heading * phi + lim.k_lateral * self._lateral_error(p)
        omega = max(-lim.w_max, min(lim.w_max, omega))
        error = self._stop_error(p, ranges, travelled)
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
    """Turn in place by ``angle`` (radians, positive left) by odometry, then hill-climb to alignment
    with the walls of the new path.

    Odometry only has to bring the robot near the new heading: once within ``align_window`` of it by
    odometry, with walls in sight, the law aligns with the walls and never goes back to odometry (the
    robot is where the walls say; a slipping odometry that still reads the turn as unfinished must not
    turn it away again). Until the walls are in sight, odometry turns on, to the whole angle, and on
    beyond it by up to ``SEARCH_LIMIT`` while no wall shows: a robot that turned short (its turn starts
    a control period late, and slips) may be more than 25 degrees off the walls, where the percept does
    not see them as walls.

    The last approach always starts ``align_window`` short of the walls, by the walls: a robot that
    odometry brought closer, or past them, first backs off to there. The hill-climbing stops as soon as
    the walls are within tolerance, so where in the tolerance it stops depends on the way it came; if
    that way varied with the odometry error, so would the heading at the dstate and its image (a turn
    approached from 5 or from 15 degrees out stops up to a degree apart, which splits a view).

    Parameters
    ----------
    lim : Limits
    angle : float
        Radians, positive left.
    align_window : float
        Radians of odometry-measured turn still to go where alignment with the walls takes over, and
        how far short of the walls the last approach starts.
    """

    timeout = 30.0

    def __init__(self, lim: Limits, angle: float, align_window: float = math.radians(12)):
        super().__init__(lim)
        self.angle, self.align_window = angle, align_window
        self.direction = math.copysign(1.0, angle)
        self.aligning = False  # the walls have taken over from odometry
        self.approaching = False  # the last approach, from align_window short of the walls, has begun

    def step(self, p: Percept, ranges: np.ndarray, odo: Odometry) -> tuple[float, float]:
        lim = self.lim
        remaining = self.angle - (odo.theta - self.start.theta)
        # the walls take over within the window (or once they have): before, odometry turns
        wall = p.wall_angle if self.aligning or abs(remaining) <= self.align_window else math.nan
        if not self.aligning and wall * self.direction < -self.align_window:
            # Walls that say the robot turned too far by more than the window: a robot that starts its
            # turn late and slips turns short, not long, so this is the fold of walls far ahead
            # (a 45-degree reading folds to -45) or corner chords; turn on until the walls are clear.
            wall = math.nan
        if math.isnan(wall) and self.aligning:  # the walls lost for a scan (drop-outs): hold still
            self._settle(False)
            return 0.0, 0.0
        if math.isnan(wall) and -SEARCH_LIMIT < remaining * self.direction <= self.align_window:
            # Odometry says nearly there, yet no wall is within 25 degrees of the axes: the robot has
            # turned short (a turn starts a tick late and slips), so it turns on until the walls show.
            self._settle(False)
            return 0.0, self.direction * lim.k_align * self.align_window
        if math.isnan(wall):  # no walls to align with at all: the turn is odometry's alone
            mag = min(lim.w_max, math.sqrt(2 * lim.w_accel * abs(remaining)), lim.k_align * abs(remaining))
            self._settle(abs(remaining) < lim.align_tolerance)
            return 0.0, (0.0 if self.done else math.copysign(mag, remaining))
        self.aligning = True
        # short of the walls (in the turn's direction) by the window, less a degree of slack: approach
        self.approaching = self.approaching or wall * self.direction >= self.align_window - BACK_OFF_SLACK
        target = 0.0 if self.approaching else self.direction * self.align_window
        self._settle(self.approaching and abs(wall) < lim.align_tolerance)
        return 0.0, (0.0 if self.done else max(-lim.w_max, min(lim.w_max, lim.k_align * (wall - target))))

    def action(self, odometry: Odometry) -> Action:
        return TurnAction(round(math.degrees(odometry.theta - self.start.theta), 3))
