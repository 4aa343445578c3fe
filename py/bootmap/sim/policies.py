"""Exploration policies: which action to take at each dstate, from the robot's own experience only.

A policy is told what the robot perceives at the dstate it has reached and the action (measured by
odometry) that brought it there; it answers with the next action - travel along the path ahead, or turn
- or None to stop. It never sees the world's map or the true pose.

* :class:`Circuits` - the paper's circuits of a room: follow the wall on one side, and at each corner
  turn away from it (clockwise circuits keep the wall on the left and turn right).
* :class:`RandomWalk` - at every place, travel on, or turn towards an open side or back and travel,
  uniformly at random (the baseline an active explorer must beat).
* :class:`Explore` - a systematic hallway explorer: it takes every unexplored path direction at every
  place and turns around at dead ends, then walks back to the nearest place with an untried direction.
  Places are told apart by dead reckoning on a 90-degree grid (a turn counts as the quarter turns it was
  asked for, since every turn ends aligned with the walls there; travels add their odometry distance),
  so a place it comes back to is recognised by where it is, not by what it looks like.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from ..tableau import Action
from ..tableau import Travel as TravelAction
from ..tableau import Turn as TurnAction
from .perception import Percept

HEADINGS = np.array([[1, 0], [0, 1], [-1, 0], [0, -1]], dtype=float)  # quarter turns, counter-clockwise


@dataclass(frozen=True)
class Decision:
    """The next action: ``"travel"``, or ``"turn"`` by ``angle`` radians (positive left)."""

    kind: str
    angle: float = 0.0


TRAVEL = Decision("travel")


@dataclass(frozen=True)
class Observation:
    """What a policy is told at a dstate: the percept of its image, the action that led there, and the
    image itself (the laser scan; None where a caller has only the percept)."""

    percept: Percept
    action: Action | None
    front_open: bool
    image: np.ndarray | None = None


class Circuits:
    """The paper's circuits of a room.

    Parameters
    ----------
    direction : {"cw", "ccw"}
        Clockwise circuits follow the wall on the left and turn right at corners; counter-clockwise
        the mirror image.
    """

    junctions = False

    def __init__(self, direction: str = "cw"):
        if direction not in ("cw", "ccw"):
            raise ValueError(f"direction must be 'cw' or 'ccw', got {direction!r}")
        self.direction = direction

    @property
    def follow(self) -> str:
        return "left" if self.direction == "cw" else "right"

    def reset(self, rng: np.random.Generator) -> None:
        pass

    def decide(self, obs: Observation) -> Decision:
        if isinstance(obs.action, TurnAction):
            return TRAVEL
        return Decision("turn", -math.pi / 2 if self.direction == "cw" else math.pi / 2)


class RandomWalk:
    """A random walk of a hallway network: at every place, one of the directions open there - the path
    ahead, a side opening, or back the way it came - chosen uniformly by the simulation's generator, then
    a travel that way (a turn is always followed by a travel). It never stops by itself: give the run a
    number of steps.

    Parameters
    ----------
    turn_around : bool
        Count going back among the choices (always taken where nothing else is open).
    """

    junctions = True
    follow = "centre"

    def __init__(self, turn_around: bool = True):
        self.turn_around = turn_around

    def reset(self, rng: np.random.Generator) -> None:
        self.rng = rng

    def decide(self, obs: Observation) -> Decision:
        if isinstance(obs.action, TurnAction):
            return TRAVEL  # the direction was chosen before the turn
        p = obs.percept
        moves = ([TRAVEL] if obs.front_open else []) + \
            ([Decision("turn", math.pi / 2)] if p.left_open else []) + \
            ([Decision("turn", -math.pi / 2)] if p.right_open else [])
        if self.turn_around or not moves:
            moves.append(Decision("turn", math.pi))
        return moves[int(self.rng.integers(len(moves)))]


@dataclass
class _Place:
    position: np.ndarray
    exits: set[int] = field(default_factory=set)  # absolute quarter-turn directions with an open path
    edges: dict[int, int] = field(default_factory=dict)  # direction -> place reached that way
    tried: set[int] = field(default_factory=set)  # directions the robot has set out in from here
    # Headings joined by turns made here (union-find over quarter turns). The SSH's places are dstates
    # linked by turns, so a place is only known as one place once a turn links every exit's heading.
    linked: dict[int, int] = field(default_factory=lambda: {d: d for d in range(4)})

    @property
    def untried(self) -> set[int]:
        return self.exits - self.tried

    def find(self, d: int) -> int:
        while self.linked[d] != d:
            d = self.linked[d]
        return d

    def link(self, a: int, b: int) -> None:
        self.linked[self.find(a)] = self.find(b)

    @property
    def unlinked(self) -> bool:
        """Some exits' headings are not yet joined by turns made here."""
        return len({self.find(d) for d in self.exits}) > 1

    @property
    def unfinished(self) -> bool:
        return bool(self.untried) or self.unlinked


class Explore:
    """Systematic exploration of a hallway network, then (if asked for more steps) a random walk.

    Parameters
    ----------
    wander : bool
        After every direction of every place is explored, keep going at random (never turning back
        except at dead ends) instead of stopping.
    place_tolerance : float
        Metres within which dead reckoning says two dstates are at the same place.

    Attributes
    ----------
    places_ : list
        The places found, with their exits and the edges travelled, in the explorer's own frame.
    explored_ : bool
        The robot has set out along every exit of every known place, so every path segment has been
        travelled both ways (and every dead end turned around at), and at every place turns have
        joined the headings of all its exits (so the map can tell it is one place).
    """

    junctions = True
    follow = "centre"

    def __init__(self, wander: bool = False, place_tolerance: float = 2.5):
        self.wander, self.place_tolerance = wander, place_tolerance

    def reset(self, rng: np.random.Generator) -> None:
        self.rng = rng
        self.places_: list[_Place] = []
        self.explored_ = False
        self._heading = 0  # quarter turns from the heading at the start
        self._position = np.zeros(2)
        self._here: int | None = None
        self._intent: int | None = None
        self._turning: int | None = None  # quarter turns (left) of the turn just asked for

    def decide(self, obs: Observation) -> Decision | None:
        self._update(obs)
        here = self.places_[self._here]
        target = self._intent if self._intent is not None else self._choose(here)
        if target is None:
            return None
        return self._asked(self._turn_to(target))

    def _asked(self, decision: Decision | None) -> Decision | None:
        """Remember the quarter turns of a turn asked for (dead reckoning counts them, not odometry's)."""
        if decision is not None and decision.kind == "turn":
            self._turning = round(decision.angle / (math.pi / 2))
        return decision

    def _turn_to(self, target: int) -> Decision:
        """Travel if facing ``target`` (a quarter-turn direction), else turn to it and travel next."""
        rel = (target - self._heading) % 4
        if rel == 0:
            self._intent = None
            return TRAVEL
        self._intent = target
        return Decision("turn", {1: math.pi / 2, 2: math.pi, 3: -math.pi / 2}[rel])

    # ------------------------------------------------------------------ dead reckoning and places
    def _update(self, obs: Observation) -> None:
        arrived_from = None
        if isinstance(obs.action, TurnAction):
            # The turn law ends aligned with the walls at the quarter turn it was asked for, whatever
            # odometry read (a turn-around read at 230 degrees still faces back down the corridor):
            # the heading follows the turn asked for. Odometry rounds it only where none was asked.
            before = self._heading
            quarters = self._turning if self._turning is not None else round(obs.action.angle_deg / 90.0)
            self._turning = None
            self._heading = (self._heading + quarters) % 4
            self.places_[self._here].link(before, self._heading)
        else:  # a travel (or the first dstate, reached by travelling from the start pose)
            if isinstance(obs.action, TravelAction):
                self._position = self._position + obs.action.distance_m * HEADINGS[self._heading]
            arrived_from = self._here
            self._here = self._locate()
        place = self.places_[self._here]
        h = self._heading
        p = obs.percept
        seen = {h: obs.front_open, (h + 1) % 4: p.left_open, (h - 1) % 4: p.right_open}
        place.exits |= {d for d, is_open in seen.items() if is_open}
        if not isinstance(obs.action, TurnAction):
            place.exits.add((h + 2) % 4)  # the way it came is a path
        if arrived_from is not None:
            self.places_[arrived_from].edges[h] = self._here
            self.places_[arrived_from].tried.add(h)
            place.edges[(h + 2) % 4] = arrived_from  # known, but not yet travelled this way
        self.explored_ = not any(pl.unfinished for pl in self.places_)

    def _locate(self) -> int:
        for i, pl in enumerate(self.places_):
            if np.hypot(*(pl.position - self._position)) < self.place_tolerance:
                return i
        self.places_.append(_Place(self._position.copy()))
        return len(self.places_) - 1

    # ------------------------------------------------------------------ choices
    def _choose(self, here: _Place) -> int | None:
        h = self._heading
        untried = [d for d in (h, (h + 1) % 4, (h - 1) % 4, (h + 2) % 4) if d in here.untried]
        if untried:
            return untried[0]
        if here.unlinked:
            # Turn towards an exit no turn here has joined to this heading yet; turning around first,
            # since only a turn-around tells the map that both ways along a path are one path.
            return next(d for d in ((h + 2) % 4, (h + 1) % 4, (h - 1) % 4)
                        if d in here.exits and here.find(d) != here.find(h))
        step = self._first_step_to_untried()
        if step is not None:
            return step
        if not self.wander:
            return None
        onward = sorted(here.exits - {(h + 2) % 4}) or sorted(here.exits)
        return int(self.rng.choice(onward)) if onward else None

    def _first_step_to_untried(self) -> int | None:
        """Breadth-first over travelled edges to the nearest place with an untried exit."""
        start = self._here
        first: dict[int, int | None] = {start: None}
        queue = deque([start])
        while queue:
            i = queue.popleft()
            pl = self.places_[i]
            if i != start and pl.unfinished:
                return first[i]
            for d, j in sorted(pl.edges.items()):
                if j not in first:
                    first[j] = d if i == start else first[i]
                    queue.append(j)
        return None
