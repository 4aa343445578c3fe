"""Active exploration: explore until the map is unique and complete, rehearsing whenever maps disagree.

The paper's Figure 1 closes two loops that a fixed policy leaves open: when the experience leaves more
than one minimal map, "the rehearsal procedure proposes an exploratory sequence of actions likely to
produce the relevant experience" (feedback path (a)); and the map is built as the robot goes, not after.
:class:`Active` does both. At every dstate it

1. labels the image it sees with a view (:class:`bootmap.views.OnlineViews`, see below) and appends the
   step to its own tableau;
2. brings its map up to date (:meth:`bootmap.mapping.api.Mapper.stream`: the last map extended by
   determinism where it still stands, else resolved);
3. if the map is not unique, carries out the rehearsal plan (:meth:`bootmap.mapping.api.Mapper.rehearse`:
   the shortest actions whose outcome the minimal maps predict differently), replanning when it is done
   or the map becomes unique;
4. else explores as :class:`~bootmap.sim.policies.Explore` does (every exit of every place, headings at a
   place joined by turns, travelling straight on first at a junction);
5. once every exit is known, joins the paths its map knows one way only: a path of the map whose
   dstates all face one way is a corridor travelled both ways whose two directions no turn-around has
   joined yet (the topological axioms join a path's directions only by a turn-around), so it goes to a
   place on it and turns around there;
6. stops when the map is unique, every exit of every place is known and no path is known one way only,
   or after ``max_steps`` dstates.

Views. The robot sees images, not views. Clustering all images so far (the experiment's k-means) would
relabel earlier steps whenever the clustering moves, and the map of the experience so far would have to
be found again from scratch; it also needs the whole sweep of k at every step. Leader clustering labels
each image once, for good: the first image of a view is its prototype, and an image within 0.4 m (mean
absolute range difference) of a prototype shows that view. At the shipped worlds' dstates that labels
each true dstate with one view and finds the paper's 8 views of Taylor Hall. The policy's tableau holds
the labels without the images, so the resolver takes them as the robot's word (no misread search).

Navigation (which way to a place) uses Explore's dead reckoning on a 90-degree grid; the map decides
everything else. The policy never sees the world or the true pose.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import replace

import numpy as np

from ..mapping.api import Mapper
from ..mapping.cogmap import CognitiveMap
from ..tableau import Step, Tableau
from ..views import OnlineViews
from ..sim.policies import TRAVEL, Decision, Explore, Observation

__all__ = ["Active", "decision_of"]

VIEW_THRESHOLD = 0.4  # metres of mean absolute range difference: one view (see the module docstring)
# The robot commands turns in quarter turns, so it reads its measured turns rounded to them. Learning the
# action types from the angles instead can take two quarter turns among six turn-arounds for one type
# (the plus world: its map then puts the crossing's four dstates on one path).
QUANTUM_DEG = 90


def decision_of(word: str) -> Decision:
    """A rehearsal plan's action as the simulator's decision: ``"travel"``, or ``"turn +90"`` (degrees)."""
    if word == "travel":
        return TRAVEL
    kind, _, degrees = word.partition(" ")
    if kind != "turn" or not degrees:
        raise ValueError(f"not an action the robot can take: {word!r} (expected 'travel' or 'turn <degrees>')")
    return Decision("turn", math.radians(float(degrees)))


class Active(Explore):
    """Active mapping: exploration and rehearsal until the map is unique and complete.

    Parameters
    ----------
    max_steps : int
        Stop after this many dstates whatever the map says.
    view_threshold : float
        Metres of mean absolute range difference within which an image shows a known view.
    max_range : float, optional
        The laser's maximum range (drop-outs read it); the simulation sets it from the world.
    place_tolerance : float
        Metres within which dead reckoning says two dstates are at the same place (navigation only).
    mapper : Mapper, optional
        Finds the maps and plans the rehearsals (default ``Mapper(quantum_deg=90, how="fewest")``: the
        robot turns in quarter turns, and stops at its dstates).
    max_plan : int
        Longest rehearsal plan searched for.

    Attributes
    ----------
    tableau_ : Tableau
        The robot's own experience: views and actions.
    map_ : CognitiveMap
        The map of ``tableau_``, current after every step.
    complete_ : bool
        The policy stopped because the map is unique and complete (not because of ``max_steps``).
    rehearsals_ : int
        Rehearsal plans carried out (begun).
    plans_ : list of tuple
        ``(t, actions)``: each rehearsal plan begun, with the time point it was begun at.
    turnarounds_ : int
        Turn-arounds made to join a path's two directions.
    """

    def __init__(self, max_steps: int = 400, view_threshold: float = VIEW_THRESHOLD, max_range: float | None = None,
                 place_tolerance: float = 2.5, mapper: Mapper | None = None, max_plan: int = 10):
        if not (isinstance(max_steps, int) and max_steps >= 2):
            raise ValueError(f"max_steps must be an integer >= 2, got {max_steps!r}")
        if not view_threshold > 0:
            raise ValueError(f"view_threshold must be > 0 metres, got {view_threshold!r}")
        super().__init__(wander=False, place_tolerance=place_tolerance)
        self.max_steps, self.view_threshold, self.max_range = max_steps, view_threshold, max_range
        self.mapper, self.max_plan = mapper, max_plan

    def reset(self, rng: np.random.Generator) -> None:
        super().reset(rng)
        self.views_ = OnlineViews(self.view_threshold, self.max_range)
        self._mapper = self.mapper or Mapper(quantum_deg=QUANTUM_DEG, how="fewest")
        self.stream_ = self._mapper.stream()
        self.tableau_: Tableau | None = None
        self.map_: CognitiveMap | None = None
        self.complete_ = False
        self.rehearsals_ = 0
        self.plans_: list[tuple[int, list[str]]] = []
        self.turnarounds_ = 0
        self._steps: list[Step] = []
        self._where: list[tuple[int, int]] = []  # (place, heading) by dead reckoning, per time point
        self._plan: deque[Decision] = deque()
        self._joined: set[tuple[int, int]] = set()  # (place, axis) where a turn-around was made to join

    # ------------------------------------------------------------------ the loop
    def decide(self, obs: Observation) -> Decision | None:
        self._update(obs)
        self._observe(obs)
        if len(self._steps) >= self.max_steps:
            return None
        decision = self._asked(self._rehearse(obs) or self._explore())
        if decision is None:
            self.complete_ = self.map_.unique and self.explored_
        return decision

    def _observe(self, obs: Observation) -> None:
        """Append what the robot sees to its tableau and bring the map up to date."""
        if obs.image is None:
            raise ValueError("the active policy needs the image at every dstate (Observation.image)")
        view = self.views_.label(obs.image)
        if self._steps:
            self._steps[-1] = replace(self._steps[-1], action=obs.action)
        self._steps.append(Step(view=view))
        self._where.append((self._here, self._heading))
        self.tableau_ = Tableau(tuple(self._steps), meta={"generator": "bootmap.agent.active"})
        self.map_ = self._mapper.map(self.tableau_, stream=self.stream_)

    # ------------------------------------------------------------------ rehearsal
    def _rehearse(self, obs: Observation) -> Decision | None:
        """The next action of a rehearsal plan while the maps disagree (a new plan when one is done)."""
        if self.map_.unique:
            self._plan.clear()  # what the plan was to tell apart is told apart
            return None
        if not self._plan:
            plan = self._mapper.rehearse(self.tableau_, self.max_plan, cmap=self.map_)
            self._plan = deque(decision_of(a) for a in plan.actions)
            if not self._plan:
                return None
            self.rehearsals_ += 1
            self.plans_.append((len(self._steps) - 1, list(plan.actions)))
            self._intent = None  # exploration picks up afresh after the rehearsal
        decision = self._plan.popleft()
        if decision.kind == "travel" and not obs.front_open:
            self._plan.clear()  # the plan assumed a dstate the robot is not at: replan next time
            return None
        return decision

    # ------------------------------------------------------------------ exploration
    def _explore(self) -> Decision | None:
        here = self.places_[self._here]
        target = self._intent if self._intent is not None else self._choose(here)
        if target is None:
            return self._join_paths()
        return self._turn_to(target)

    def _join_paths(self) -> Decision | None:
        """Towards a turn-around on a path the map knows one way only; None when there is none."""
        tasks = {(p, h) for p, h in self._one_way() if (p, h % 2) not in self._joined}
        if not tasks:
            return None
        for p, h in sorted(tasks):
            if p == self._here and self._heading in (h, (h + 2) % 4):
                self._joined.add((p, h % 2))
                self.turnarounds_ += 1
                return Decision("turn", math.pi)
        for p, h in sorted(tasks):
            if p == self._here:  # at the place, facing across the path: face along it first
                return Decision("turn", math.pi / 2 if (h - self._heading) % 4 == 1 else -math.pi / 2)
        step = self._first_step_to({p for p, _ in tasks})
        return None if step is None else self._turn_to(step)

    def _one_way(self) -> set[tuple[int, int]]:
        """(place, heading) of the time points on paths whose dstates all face one way in the map."""
        dirs: dict[str, set[str]] = {}
        for d, (pa, way) in self.map_.path_of.items():
            dirs.setdefault(pa, set()).add(way)
        one_way = {pa for pa, ways in dirs.items() if len(ways) == 1}
        return {self._where[t] for t, d in enumerate(self.map_.dstate_of)
                if d in self.map_.path_of and self.map_.path_of[d][0] in one_way}

    def _first_step_to(self, targets: set[int]) -> int | None:
        """Breadth-first over travelled edges: the first direction towards the nearest target place."""
        start = self._here
        first: dict[int, int | None] = {start: None}
        queue = deque([start])
        while queue:
            i = queue.popleft()
            if i in targets and i != start:
                return first[i]
            for d, j in sorted(self.places_[i].edges.items()):
                if j not in first:
                    first[j] = d if i == start else first[i]
                    queue.append(j)
        return None
