"""Loop closing: a map from the robot's own odometry, checked by every axiom.

The paper's map is the one with the fewest dstates: two time points are one dstate unless the
experience proves them different. That needs views that tell dstates apart. On a real log they barely
do (the Killian log's views are near chance, and most of its dstates are seen once), so the fewest
dstates merge visits the experience merely fails to tell apart, and the search for them does not end.

Here the robot's odometry proposes which visits are one dstate, and the axioms dispose:

1. Every visit starts as a dstate of its own.
2. Two visits facing one way (the metrical level's heading) are proposed as one dstate where
   odometry says so: **near**, within ``radius_m`` plus ``near_share`` of the distance driven between
   them (dead reckoning drifts slowly: a short loop closes tightly); or **retraced**, the robot did the
   same actions (turn types, travel length types) for ``context`` steps before and after them, they
   show one view, and they are within ``radius_m`` plus ``drift_share`` of the distance driven (a long
   loop driven again, whose ends dead reckoning has drifted apart). Longest context first, then
   nearest.
3. A proposal is folded as the causal level demands (the same action from one dstate reaches one
   dstate: merge and fold, as RPNI does); every pair of visits the fold joins must face one way and
   lie within the drift bound, or the proposal is dropped.
4. What is left is checked by clingo with every axiom file (the partition fixed, ``fixed/2``), views
   taken as soft evidence: each dstate shows the view most of its visits show, and the other visits
   are listed as misreads (``suspect_steps``). A proposal the axioms reject is dropped.

The result satisfies every axiom but is not proved minimal (``minimal`` is False): it is the map
odometry supports, not the smallest one the views allow. A tableau whose steps carry ``odometry``
(a log) is dead-reckoned from it; otherwise from its actions (turns on the spot, as the simulator's).

Example
-------
Two laps of a square whose corners look alike: views say nothing, odometry closes the loop.

>>> from bootmap.tableau import Tableau
>>> lap = [{"view": "corner", "action": {"type": "travel", "distance_m": 5}},
...        {"view": "corner", "action": {"type": "turn", "angle_deg": 90}}] * 4
>>> square = Tableau.from_dict({"format": "bootmap.tableau/1", "steps": lap * 2 + [{"view": "corner"}]})
>>> cmap = LoopCloser().resolve(square)
>>> cmap.n_dstates, cmap.n_places, cmap.minimal
(8, 4, False)
"""

from __future__ import annotations

import math
import time
from collections import Counter
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Sequence

import numpy as np
from clingo import Function, Number, Symbol

from ..errors import InconsistentTableau, SolveTimeout
from ..tableau import Tableau, Travel, Turn
from .cogmap import CognitiveMap, SolveStats, Try, build_map
from .facts import action_symbols, passes_through, tableau_facts, travel_lengths, typed_actions
from .grounding import Deadline, Grounding
from .motion import measured_angle
from .resolver import Resolver
from .vocabulary import FIXED

__all__ = ["LoopCloser", "MAPPERS", "dead_reckoning", "mapper_for"]

#: How a map is found: ``auto`` (loop closing where the robot drove through dstates, as a log's tableau
#: says, else the fewest dstates), ``loops`` or ``fewest`` (the paper's, :class:`~.resolver.Resolver`).
MAPPERS = ("auto", "loops", "fewest")


@dataclass(frozen=True)
class LoopCloser:
    """Maps from odometry-proposed merges that every axiom accepts (see the module's docstring).

    Parameters
    ----------
    resolver : Resolver, optional
        Its axioms, action typing (``quantum_deg``), ``time_limit`` and ``future_depth`` are used.
    radius_m : float
        Visits whose dead-reckoned positions lie this close may be one place: the odometry's
        resolution at a dstate (a robot that turns while driving ends a turn 2-4 m on).
    near_share : float
        Dead reckoning's drift per metre driven, for visits proposed because they are near.
    drift_share : float
        The most it may drift per metre driven between any two visits of one dstate.
    context : int
        Agreeing actions, before and after two visits, that propose them as one dstate retraced.
    """

    resolver: Resolver = field(default_factory=Resolver)
    radius_m: float = 3.0
    near_share: float = 0.01
    drift_share: float = 0.05
    context: int = 3

    def resolve(self, tableau: Tableau, deadline: Deadline | None = None) -> CognitiveMap:
        """The loop-closed map of ``tableau`` by ``deadline`` (default: the resolver's time limit).

        Raises
        ------
        InconsistentTableau
            No partition loop closing reaches satisfies the axioms.
        SolveTimeout
            Out of time; ``best_map`` is the last map the axioms accepted, if any.
        """
        tableau.require_views()
        return _Closing(self, tableau, deadline or Deadline.after(self.resolver.time_limit)).run()


def mapper_for(tableau: Tableau, resolver: Resolver, how: str = "auto") -> "Resolver | LoopCloser":
    """What finds the map of ``tableau``: ``resolver`` itself (the fewest dstates), or a :class:`LoopCloser`
    around it. ``auto`` closes loops where the tableau says the robot drove through dstates without
    stopping (``passes_through``: a log), whose views the fewest dstates cannot rest on."""
    if how not in MAPPERS:
        raise ValueError(f"unknown mapper {how!r}; known: {', '.join(MAPPERS)}")
    if how == "loops" or (how == "auto" and passes_through(tableau)):
        return LoopCloser(resolver)
    return resolver


def dead_reckoning(tableau: Tableau, angles: Sequence[int] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Each time point's dead-reckoned position ``(n, 2)`` and the distance driven to it ``(n,)``: from
    the steps' ``odometry`` where every step has one, else from the actions: a turn on the spot, a travel
    along the heading halfway through its bend. ``angles`` are the actions' angles to use (the learned
    types' angles, :func:`~.facts.typed_actions`, which odometry's drift on straight travels does not
    bend), else the measured ones."""
    steps = tableau.steps
    if all(s.odometry is not None for s in steps):
        xy = np.array([s.odometry[:2] for s in steps], dtype=float)
        hops = np.hypot(*np.diff(xy, axis=0).T) if len(xy) > 1 else np.zeros(0)
        driven = [max(h, s.action.distance_m if isinstance(s.action, Travel) else 0.0)
                  for h, s in zip(hops, steps)]
        return xy, np.concatenate([[0.0], np.cumsum(driven)])
    xy, along = np.zeros((len(steps), 2)), np.zeros(len(steps))
    heading = 0.0
    for t, s in enumerate(steps[:-1]):
        angle = math.radians(measured_angle(s.action) if angles is None else angles[t])
        if isinstance(s.action, Turn):
            xy[t + 1], along[t + 1] = xy[t], along[t]
        else:
            mid = heading + angle / 2
            xy[t + 1] = xy[t] + s.action.distance_m * np.array([math.cos(mid), math.sin(mid)])
            along[t + 1] = along[t] + s.action.distance_m
        heading += angle
    return xy, along


class _Closing:
    """One loop closing: the evidence, the partition (union-find) and the last map the axioms accepted."""

    def __init__(self, closer: LoopCloser, tableau: Tableau, deadline: Deadline):
        self.closer, self.tableau, self.deadline = closer, tableau, deadline
        self.resolver = closer.resolver
        self.start = time.perf_counter()
        self.n = n = len(tableau)
        self.angles, self.action_types, _ = typed_actions(tableau, self.resolver.quantum_deg)
        actions = action_symbols(tableau, self.angles)
        lengths = travel_lengths(tableau)
        # what the causal level folds on (its action names), and what a retraced context compares
        self.fold_key: list[Symbol | None] = actions + [None] * (n - len(actions))
        self.context_key = [(a, lengths.get(t)) for t, a in enumerate(actions)]
        # a robot that stopped at every dstate travels on from one dstate always as far (metrical.lp)
        self.length_of = {} if passes_through(tableau) else lengths
        self.heading = np.concatenate([[0], np.cumsum(self.angles)]).astype(int) % 360
        self.xy, self.along = dead_reckoning(tableau, self.angles)
        self.views = tableau.views
        self.dstates = _Partition(n)
        self.best: CognitiveMap | None = None
        self.tries: list[Try] = []
        self.checks = 0

    # ------------------------------------------------------------------------------------------
    def run(self) -> CognitiveMap:
        # Every proposal at once first: the topological level may reject a partition on the way to one it
        # accepts (two dstates of one place facing one way, until their other dstates are joined too).
        if self.deadline.passed():
            raise self._timed_out()
        self._fold_all(self.proposals)
        if not self._accepted():
            # Else one proposal at a time, each kept only where the axioms accept the partition it makes.
            self.dstates.undo(0)
            self._accepted()
            for i, j in self.proposals:
                if self.deadline.passed():
                    raise self._timed_out()
                if self.dstates.root[i] == self.dstates.root[j]:
                    continue
                before = self.dstates.mark()
                if not (self._fold(i, j) and self._accepted()):
                    self.dstates.undo(before)
        if self.best is None:
            raise InconsistentTableau("no map found by loop closing: no partition it reached satisfies the axioms",
                                      levels=tuple(self.resolver.theory.levels))
        return replace(self.best, stats=self._stats())

    def _fold_all(self, proposals: list[tuple[int, int]]) -> None:
        """Fold each proposal in turn, dropping those the fold refuses."""
        for i, j in proposals:
            if self.dstates.root[i] != self.dstates.root[j]:
                before = self.dstates.mark()
                if not self._fold(i, j):
                    self.dstates.undo(before)

    def _partition(self) -> list[int]:
        return list(self.dstates.root)

    @cached_property
    def proposals(self) -> list[tuple[int, int]]:
        """Pairs of visits odometry proposes as one dstate, strongest first (longest context, nearest)."""
        ranked = []
        for i in range(self.n):
            for j in range(i + 1, self.n):
                if self.heading[i] != self.heading[j]:
                    continue
                near = self._apart(i, j, self.closer.near_share)
                agree = self._agreeing(i, j)
                # a retraced pair's odometry is loose: it needs its views to agree as well
                retraced = (agree >= self.closer.context and self.views[i] == self.views[j]
                            and self._apart(i, j, self.closer.drift_share) <= 1.0)
                if near <= 1.0 or retraced:
                    ranked.append((-agree, near, i, j))
        ranked.sort()
        return [(i, j) for _, _, i, j in ranked]

    def _apart(self, i: int, j: int, share: float) -> float:
        """How far apart dead reckoning puts i and j, as a share of what it may drift between them."""
        gap = float(np.hypot(*(self.xy[i] - self.xy[j])))
        return gap / (self.closer.radius_m + share * abs(self.along[j] - self.along[i]))

    def _agreeing(self, i: int, j: int) -> int:
        """How many actions agree in a row after i and j, plus before them."""
        key, last = self.context_key, len(self.context_key)
        after = 0
        while j + after < last and key[i + after] == key[j + after]:
            after += 1
        before = 0
        while i - 1 - before >= 0 and key[i - 1 - before] == key[j - 1 - before]:
            before += 1
        return after + before

    # ------------------------------------------------------------------------------------------
    def _fold(self, i: int, j: int) -> bool:
        """Join i's and j's dstates and every pair determinism then joins; False if some pair joined would
        face two ways or lie beyond the drift bound (the caller undoes the joins made)."""
        queue = [(i, j)]
        members = self.dstates.members
        while queue:
            a, b = (self.dstates.root[x] for x in queue.pop())
            if a == b:
                continue
            if not all(self._may_join(x, y) for x in members[a] for y in members[b]):
                return False
            a = self.dstates.join(a, b)
            led: dict[Symbol, int] = {}
            for t in members[a]:
                action = self.fold_key[t]
                if action is not None:
                    if action in led:
                        queue.append((led[action], t + 1))
                    else:
                        led[action] = t + 1
        return True

    def _may_join(self, x: int, y: int) -> bool:
        """Whether visits x and y may be one dstate: they face one way, travel on equally far (where the
        robot stopped at every dstate) and lie within the drift bound."""
        lx, ly = self.length_of.get(x), self.length_of.get(y)
        return (self.heading[x] == self.heading[y] and (lx is None or ly is None or lx == ly)
                and self._apart(x, y, self.closer.drift_share) <= 1.0)

    def _accepted(self) -> bool:
        """Check the partition with every axiom; keep its map if they accept it."""
        found = self._checked(self._partition())
        if found is not None:
            self.best = found
        return found is not None

    def _checked(self, dstate_of: list[int]) -> CognitiveMap | None:
        """The map of this partition if every axiom accepts it, each dstate showing its visits' most common
        view (the other visits' views are misreads)."""
        self.checks += 1
        groups: dict[int, list[int]] = {}
        for t, d in enumerate(dstate_of):
            groups.setdefault(d, []).append(t)
        views = self.views
        shown = {d: Counter(views[t] for t in ts).most_common(1)[0][0] for d, ts in groups.items()}
        as_shown = self.tableau.with_views([shown[d] for d in dstate_of])
        fixed = [FIXED(t, Function("s", [Number(d)])) for t, d in enumerate(dstate_of)]
        grounding = Grounding(self.resolver.theory, tableau_facts(as_shown, angles=self.angles) + fixed,
                              self.resolver.future_depth, ["1"]).ground()
        models: list[list[Symbol]] = []
        result = grounding.solve(self.deadline, lambda m: models.append(m.symbols(shown=True)))
        self.tries.append(Try(f"{len(groups)} dstates (loop closing)", "sat" if models else
                              ("timeout" if result is None else "unsat"), grounding.ground_s + grounding.solve_s))
        if result is None:
            raise self._timed_out()  # not a rejection: the axioms did not answer in time
        if not models:
            return None
        cmap = build_map(self.tableau, models, True, self.resolver.theory.levels, self._stats(), minimal=False,
                         action_types=self.action_types)
        misreads = [{"t": t, "observed": views[t], "expected": cmap.views[cmap.dstate_of[t]], "cost": None}
                    for t in range(self.n) if views[t] != shown[dstate_of[t]]]
        return replace(cmap, suspect_steps=misreads, found_by="loop closing")

    def _stats(self) -> SolveStats:
        return SolveStats(classes=self.n, lower_bound=0, total_s=time.perf_counter() - self.start,
                          bounds=tuple(self.tries[-3:]))

    def _timed_out(self) -> SolveTimeout:
        best = None if self.best is None else replace(self.best, stats=self._stats())
        found = f"best map so far: {best.n_dstates} dstates" if best else "no map found yet"
        limit = self.deadline.limit_s
        return SolveTimeout(f"time limit of {limit:g} s reached while closing loops ({self.checks} partitions "
                            f"checked); {found}", best_map=best, time_limit_s=limit, stage="loop closing")


class _Partition:
    """Time points grouped into dstates, with every join undoable (a log of joins, undone last first)."""

    def __init__(self, n: int):
        self.root = list(range(n))  # each time point's dstate, named by one of its time points
        self.members = {t: [t] for t in range(n)}
        self._joins: list[tuple[int, int, int]] = []  # (kept, joined, how many the kept one had)

    def join(self, a: int, b: int) -> int:
        """Join dstates a and b (roots); returns the root kept."""
        if len(self.members[a]) < len(self.members[b]):
            a, b = b, a
        self._joins.append((a, b, len(self.members[a])))
        for t in self.members[b]:
            self.root[t] = a
        self.members[a] += self.members.pop(b)
        return a

    def mark(self) -> int:
        return len(self._joins)

    def undo(self, mark: int) -> None:
        """Undo the joins made since ``mark``."""
        while len(self._joins) > mark:
            a, b, had = self._joins.pop()
            self.members[b] = self.members[a][had:]
            del self.members[a][had:]
            for t in self.members[b]:
                self.root[t] = b
