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
(a log) is dead-reckoned from it; otherwise from its actions (turns on the spot, as the simulator's,
at the learned types' angles). :meth:`LoopCloser.explain` says why two time points are one dstate of
the map (each join, proposed or forced) or not (headings, odometry, the rules that reject joining them,
or no evidence); :func:`mapper_for` picks loop closing for a log's tableau (``passes_through``).

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
from functools import cached_property, partial
from typing import Callable, Sequence

import numpy as np
from clingo import Symbol

from ..errors import InconsistentTableau, SolveTimeout
from ..tableau import Tableau, Travel, Turn
from .cogmap import CognitiveMap, SolveStats, Try, build_map
from .explain import time_points
from .facts import action_symbols, passes_through, tableau_facts, travel_lengths, typed_actions
from .grounding import Deadline, Grounding, check_fixed
from .motion import measured_angle
from .proof import rule_dict
from .resolver import Resolver
from .trace import RuleRef
from .vocabulary import FIXED, VIEW, Predicate, action_word, fixed_dstate

__all__ = ["LoopCloser", "LoopExplanation", "MAPPERS", "closes_loops", "dead_reckoning"]

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

    def explain(self, tableau: Tableau, a, b, deadline: Deadline | None = None) -> "LoopExplanation":
        """Why time points (``t4``, ``4``) or dstates (``S4``) ``a`` and ``b`` are one dstate of the loop-closed
        map, or not: the joins that made them one (each proposed by odometry or forced by determinism), or
        what keeps them apart (odometry, or the axioms that reject the map joining them)."""
        tableau.require_views()
        closing = _Closing(self, tableau, deadline or Deadline.after(self.resolver.time_limit))
        cmap = closing.run()
        x, y = time_points(cmap, a, b)
        return closing.explain(cmap, x, y)


def closes_loops(tableau: Tableau, how: str = "auto") -> bool:
    """Whether the map of ``tableau`` is found by loop closing: ``how`` is ``loops``, or ``auto`` and the
    tableau says the robot drove through dstates without stopping (``passes_through``: a log), whose views
    the fewest dstates cannot rest on."""
    if how not in MAPPERS:
        raise ValueError(f"unknown mapper {how!r}; known: {', '.join(MAPPERS)}")
    return how == "loops" or (how == "auto" and passes_through(tableau))


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
    """One loop closing: the evidence, the partition (with every join undoable) and the last map the axioms
    accepted."""

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
        # What every check of a partition shares: the actions as the axioms see them (not the views)
        self.action_facts = [f for f in tableau_facts(tableau, angles=self.angles) if not VIEW.matches(f)]
        self.made: dict[tuple, Symbol] = {}  # the views' and the partition's facts made so far (_fact)
        self.dstates = _Partition(n)
        self.kinds: dict[tuple[int, int], str] = {}  # each proposal: "near" or "retraced"
        self.refused: tuple[int, int, str] | None = None  # the last pair a fold refused, and why
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
                    self.kinds[i, j] = "near" if near <= 1.0 else "retraced"
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
    def _fold(self, i: int, j: int, why: Join | None = None) -> bool:
        """Join i's and j's dstates and every pair determinism then joins; False if some pair joined would
        face two ways or lie beyond the drift bound (``refused`` says which; the caller undoes the joins
        made)."""
        queue = [why or Join(i, j, "proposed", self.kinds.get((i, j), ""))]
        members = self.dstates.members
        while queue:
            join = queue.pop()
            a, b = self.dstates.root[join.x], self.dstates.root[join.y]
            if a == b:
                continue
            refused = next(((x, y, cause) for x in members[a] for y in members[b]
                            if (cause := self._kept_apart(x, y))), None)
            if refused:
                self.refused = refused
                return False
            a = self.dstates.join(a, b, join)
            led: dict[Symbol, int] = {}
            for t in members[a]:
                action = self.fold_key[t]
                if action is not None:
                    if action in led:
                        queue.append(Join(led[action] + 1, t + 1, "forced", action=action_word(action),
                                          after=(led[action], t)))
                    else:
                        led[action] = t
        return True

    def _kept_apart(self, x: int, y: int) -> str:
        """What keeps visits x and y from being one dstate before any axiom is asked ("" if nothing): they
        face two ways, travel on unequally far (where the robot stopped at every dstate), or lie beyond the
        drift bound."""
        if self.heading[x] != self.heading[y]:
            return f"they face different ways (headings {self.heading[x]} and {self.heading[y]}: metrical level)"
        lx, ly = self.length_of.get(x), self.length_of.get(y)
        if lx is not None and ly is not None and lx != ly:
            return f"the travels from them differ ({lx} and {ly} dm: length_is_feature)"
        if self._apart(x, y, self.closer.drift_share) > 1.0:
            return (f"{self._odometry(x, y)}, more than odometry may drift "
                    f"({self._bound(x, y, self.closer.drift_share):.1f} m)")
        return ""

    def _odometry(self, x: int, y: int) -> str:
        return (f"dead reckoning puts them {float(np.hypot(*(self.xy[x] - self.xy[y]))):.1f} m apart after "
                f"{abs(self.along[y] - self.along[x]):.0f} m driven")

    def _bound(self, x: int, y: int, share: float) -> float:
        return self.closer.radius_m + share * abs(self.along[y] - self.along[x])

    def _evidence(self, x: int, y: int) -> str:
        """The odometry behind a proposal, in words."""
        i, j = min(x, y), max(x, y)
        if self.kinds.get((i, j)) == "retraced":
            return (f"the same {self._agreeing(i, j)} actions around them, one view, and {self._odometry(x, y)} "
                    f"(within {self._bound(x, y, self.closer.drift_share):.1f} m)")
        return f"{self._odometry(x, y)} (within {self._bound(x, y, self.closer.near_share):.1f} m)"

    def _accepted(self) -> bool:
        """Check the partition with every axiom; keep its map if they accept it."""
        found = self._checked(self._partition())
        if found is not None:
            self.best = found
        return found is not None

    def _facts(self, dstate_of: list[int]) -> tuple[list[Symbol], dict[int, str]]:
        """The tableau's facts with the partition fixed, each dstate showing its visits' commonest view (and
        that view, per dstate). Only the views and the partition change from one check to the next."""
        groups: dict[int, list[int]] = {}
        for t, d in enumerate(dstate_of):
            groups.setdefault(d, []).append(t)
        shown = {d: Counter(self.views[t] for t in ts).most_common(1)[0][0] for d, ts in groups.items()}
        views = [self._fact(VIEW, t, shown[d]) for t, d in enumerate(dstate_of)]
        fixed = [self._fact(FIXED, t, d) for t, d in enumerate(dstate_of)]
        return views + self.action_facts + fixed, shown

    def _fact(self, predicate: Predicate, t: int, value: str | int) -> Symbol:
        """``view(t, value)`` or ``fixed(t, s(value))``, each made once: a check repeats most of the last one's
        facts, and every symbol made is a call into clingo."""
        key = (predicate.name, t, value)
        if key not in self.made:
            self.made[key] = predicate(t, value if predicate is VIEW else fixed_dstate(value))
        return self.made[key]

    def _checked(self, dstate_of: list[int]) -> CognitiveMap | None:
        """The map of this partition if every axiom accepts it, each dstate showing its visits' most common
        view (the other visits' views are misreads)."""
        resolver = self.resolver
        self.checks += 1
        facts, shown = self._facts(dstate_of)
        groups = set(dstate_of)
        views = self.views
        models, grounding = check_fixed(resolver.theory, facts, resolver.future_depth, self.deadline)
        self.tries.append(Try(f"{len(groups)} dstates (loop closing)", "sat" if models else
                              ("timeout" if models is None else "unsat"), grounding.ground_s + grounding.solve_s))
        if models is None:
            raise self._timed_out()  # not a rejection: the axioms did not answer in time
        if not models:
            return None
        cmap = build_map(self.tableau, models, True, resolver.theory.levels, self._stats(), minimal=False,
                         action_types=self.action_types)
        misreads = [{"t": t, "observed": views[t], "expected": cmap.views[cmap.dstate_of[t]], "cost": None}
                    for t in range(self.n) if views[t] != shown[dstate_of[t]]]
        return replace(cmap, suspect_steps=misreads, found_by="loop closing")

    def explain(self, cmap: CognitiveMap, a: int, b: int) -> "LoopExplanation":
        """Why a and b are one dstate of ``cmap`` (this closing's map), or not."""
        names = (cmap.dstate_of[a], cmap.dstate_of[b])
        answer = partial(LoopExplanation, a, b, names, levels=list(self.resolver.theory.levels))
        if names[0] == names[1]:
            chain = [j.text(self._evidence) for j in self._chain(a, b)]
            return answer("same", f"t{a} and t{b} are one dstate: loop closing joined them (below) and every "
                                  f"axiom accepts the map.", chain, total_s=time.perf_counter() - self.start)
        sentence, axioms = self._kept_apart_why(a, b)
        return answer("different", sentence, axioms=axioms, total_s=time.perf_counter() - self.start)

    def _chain(self, a: int, b: int) -> list[Join]:
        """The joins that link a to b (a path in the forest of the joins standing)."""
        links: dict[int, list[tuple[int, Join]]] = {}
        for join in self.dstates.reasons():
            links.setdefault(join.x, []).append((join.y, join))
            links.setdefault(join.y, []).append((join.x, join))
        came: dict[int, tuple[int, Join] | None] = {a: None}  # breadth first from a: how each was reached
        frontier = [a]
        while frontier and b not in came:
            reached = []
            for t in frontier:
                for u, join in links.get(t, []):
                    if u not in came:
                        came[u] = (t, join)
                        reached.append(u)
            frontier = reached
        chain, t = [], b
        while came.get(t):
            t, join = came[t]
            chain.append(join)
        return chain[::-1]

    def _kept_apart_why(self, a: int, b: int) -> tuple[str, list[RuleRef]]:
        """What keeps a and b apart, in words, and the constraints joining them would break (if any)."""
        cause = self._kept_apart(a, b)
        if cause:
            return f"t{a} and t{b} are different dstates: {cause}.", []
        mark = self.dstates.mark()
        try:
            if not self._fold(a, b, Join(a, b, "asked")):
                x, y, cause = self.refused
                return (f"t{a} and t{b} are different dstates: making them one makes t{x} and t{y} one (by their "
                        f"dstates, or by determinism), but {cause}."), []
            failing = self._failing_rules(self._partition())
        finally:
            self.dstates.undo(mark)
        if failing:
            return (f"t{a} and t{b} are different dstates: the axioms reject the map that makes them one (with "
                    f"what determinism then joins): it breaks {' and '.join(r.cite() for r in failing)}."), failing
        proposed = self.kinds.get((min(a, b), max(a, b)))
        why = (f"it was proposed ({proposed}) but rejected beside joins made before it" if proposed else
               f"nothing proposed them ({self._odometry(a, b)}: beyond {self._bound(a, b, self.closer.near_share):.1f} "
               f"m for visits proposed as near; {self._agreeing(min(a, b), max(a, b))} actions around them agree, where "
               f"{self.closer.context} and one view propose visits as retraced)")
        return (f"t{a} and t{b} are different dstates only for want of evidence: {why}. Every axiom would accept "
                f"them as one dstate; loop closing joins only what odometry proposes."), []

    def _failing_rules(self, dstate_of: list[int]) -> list[RuleRef]:
        """The constraints this partition breaks: a subset-minimal set that still rules it out (each switched
        off in turn, kept off if the partition stays ruled out); empty if every axiom accepts it."""
        if self._checked(dstate_of) is not None:
            return []
        facts, _ = self._facts(dstate_of)
        traced = Grounding(self.resolver.theory, facts, self.resolver.future_depth, ["1"], instrumented=True).ground()
        rules = traced.rules
        needed = list(rules.switchable)
        for r in list(needed):
            trial = [x for x in needed if x != r]
            result = traced.solve(self.deadline, assumptions=[(rules.on(x), x in trial) for x in rules.switchable])
            if result is None:
                raise self._timed_out()
            if not result.satisfiable:
                needed = trial
        return [rules.rules[r] for r in needed]

    def _stats(self) -> SolveStats:
        return SolveStats(classes=self.n, lower_bound=0, total_s=time.perf_counter() - self.start,
                          bounds=tuple(self.tries[-3:]))

    def _timed_out(self) -> SolveTimeout:
        best = None if self.best is None else replace(self.best, stats=self._stats())
        found = f"best map so far: {best.n_dstates} dstates" if best else "no map found yet"
        limit = self.deadline.limit_s
        return SolveTimeout(f"time limit of {limit:g} s reached while closing loops ({self.checks} partitions "
                            f"checked); {found}", best_map=best, time_limit_s=limit, stage="loop closing")


@dataclass(frozen=True)
class LoopExplanation:
    """The answer to "are time points a and b one dstate of the loop-closed map, and why?"."""

    a: int
    b: int
    names: tuple[str, str]              # their dstates in the map
    verdict: str                        # "same" or "different"
    sentence: str
    joins: list[str] = field(default_factory=list)  # same: the joins that made them one, in order
    axioms: list[RuleRef] = field(default_factory=list)  # different: the constraints joining them breaks
    levels: list[str] = field(default_factory=list)
    total_s: float = 0.0

    def to_dict(self) -> dict:
        # The keys of a minimal map's explanation (:class:`~.explain.Explanation`), those of proofs empty.
        return {"a": self.a, "b": self.b, "dstates": list(self.names), "verdict": self.verdict,
                "sentence": self.sentence, "evidence": [], "axioms": [rule_dict(r) for r in self.axioms],
                "failures": [], "rules_cited": [r.name for r in self.axioms],
                "agree_steps": 0, "suggestion": [], "alternatives": [], "levels": self.levels,
                "found_by": "loop closing", "joins": self.joins, "stats": {"total_s": self.total_s}}

    def to_text(self) -> str:
        out = [f"t{self.a} ({self.names[0]}) vs t{self.b} ({self.names[1]}): {self.verdict} (loop-closed map)",
               f"levels: {', '.join(self.levels)}", "", self.sentence]
        return "\n".join(out + ([""] + [f"  {j}" for j in self.joins] if self.joins else []))


@dataclass(frozen=True)
class Join:
    """Why time points ``x`` and ``y`` were put in one dstate: ``proposed`` by odometry (``kind`` near or
    retraced), or ``forced`` by determinism (``after``: the time points before them, already one dstate,
    took the same ``action``)."""

    x: int
    y: int
    how: str                                 # "proposed" or "forced"
    kind: str = ""                           # proposed: "near" or "retraced"
    action: str = ""                         # forced: the action both took
    after: tuple[int, int] | None = None     # forced: the time points that took it

    def text(self, evidence: Callable[[int, int], str]) -> str:
        if self.how == "proposed":
            return f"t{self.x} = t{self.y}: proposed ({self.kind}): {evidence(self.x, self.y)}"
        u, v = self.after
        return (f"t{self.x} = t{self.y}: forced: t{u} and t{v} are one dstate and both took {self.action} "
                f"(deterministic_action: one action from one dstate reaches one dstate)")


class _Partition:
    """Time points grouped into dstates, with every join undoable (a log of joins, undone last first)."""

    def __init__(self, n: int):
        self.root = list(range(n))  # each time point's dstate, named by one of its time points
        self.members = {t: [t] for t in range(n)}
        self._joins: list[tuple[int, int, int, Join]] = []  # (kept, joined, how many the kept one had, why)

    def join(self, a: int, b: int, why: "Join") -> int:
        """Join dstates a and b (roots) for the reason ``why``; returns the root kept."""
        if len(self.members[a]) < len(self.members[b]):
            a, b = b, a
        self._joins.append((a, b, len(self.members[a]), why))
        for t in self.members[b]:
            self.root[t] = a
        self.members[a] += self.members.pop(b)
        return a

    def mark(self) -> int:
        return len(self._joins)

    def reasons(self) -> list["Join"]:
        """Why each join standing was made, in order."""
        return [why for _, _, _, why in self._joins]

    def undo(self, mark: int) -> None:
        """Undo the joins made since ``mark``."""
        while len(self._joins) > mark:
            a, b, had, _ = self._joins.pop()
            self.members[b] = self.members[a][had:]
            del self.members[a][had:]
            for t in self.members[b]:
                self.root[t] = b
