"""Loop closing itself: odometry proposes which visits are one dstate, each proposal is folded as the
causal level demands, and every axiom checks the partition (the steps in :mod:`bootmap.mapping.loops`).
:class:`Closing` keeps the partition with every join undoable and why each join was made
(:class:`~.explain.Join`), which :mod:`.explain` reads to say why two time points are one dstate or not.
"""

from __future__ import annotations

import itertools
import math
import time
from collections import Counter
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Sequence

import numpy as np
from clingo import Symbol

from ...errors import InconsistentTableau, SolveTimeout
from ...tableau import Tableau, Travel, Turn
from ..assertions import Assertion, Conflict, assertion_facts, hard
from ..cogmap import CognitiveMap, SolveStats, Try, build_map
from ..explain import time_points
from ..facts import action_symbols, passes_through, tableau_facts, travel_length_types, typed_actions
from ..grounding import Deadline, check_fixed
from ..motion import measured_angle
from ..resolver import Resolver
from ..vocabulary import FIXED, VIEW, Predicate, action_word, fixed_dstate
from .anchoring import Anchoring
from .explain import Join, LoopExplanation, explain, failing_rules as _failing_rules, why_apart

#: How a map is found: ``auto`` (loop closing where the robot drove through dstates, as a log's tableau
#: says, else the fewest dstates), ``loops`` or ``fewest`` (the paper's,
#: :class:`~bootmap.mapping.resolver.Resolver`).
MAPPERS = ("auto", "loops", "fewest")

#: Rows of the re-anchored ways worked out at once when looking for fresh pairs, and the most cells
#: (rows x time points) kept for the pairs asked after (memory: a few tens of MB).
_ROWS = 256
_KEPT_CELLS = 2 ** 22


@dataclass(frozen=True)
class LoopCloser:
    """Maps from odometry-proposed merges that every axiom accepts (see :mod:`bootmap.mapping.loops`).

    Parameters
    ----------
    resolver : Resolver, optional
        Its axioms, action typing (``quantum_deg``), ``time_limit`` and ``future_depth`` are used.
    radius_m : float
        Visits whose dead-reckoned positions lie this close may be one place: the odometry's
        resolution at a dstate (a robot that turns while driving ends a turn 2-4 m on).
    near_share : float
        Dead reckoning's drift per metre driven, for visits proposed because they are near. Re-anchored
        where loops closed, a join counts as ``radius_m / near_share`` metres of drive (:mod:`.anchoring`).
    drift_share : float
        The most it may drift per metre driven between any two visits of one dstate.
    context : int
        Agreeing actions, before and after two visits, that propose them as one dstate retraced.
    match_score : float
        A place match the tableau carries (``meta.place_matches``: the laser's, verified by the places
        around it) at least this strong proposes its two visits as one dstate, *recognised*, within the
        drift bound. Along the drives of six real logs, the best earlier matches scoring 0.7 or more were
        the true place on 88-100% of the visits (docs/results/real_logs.md); the axioms judge the rest.
    """

    resolver: Resolver = field(default_factory=Resolver)
    radius_m: float = 3.0
    near_share: float = 0.01
    drift_share: float = 0.05
    context: int = 3
    match_score: float = 0.7

    def resolve(self, tableau: Tableau, deadline: Deadline | None = None,
                assertions: Sequence[Assertion] = (), prior: Sequence[str] | None = None) -> CognitiveMap:
        """The loop-closed map of ``tableau`` by ``deadline`` (default: the resolver's time limit). A person's
        ``assertions`` (time points): each hard ``same`` is joined first, with what determinism then joins,
        whatever odometry's drift (the person knows where the robot was); each ``apart`` refuses every join
        that would make the two one. A soft ``same`` is the first proposal, kept where the axioms accept it;
        a soft ``apart`` refuses odometry's proposals as a hard one does (loop closing weighs no costs).
        ``prior``, the dstate of each time point in the map made without the assertions, is what the joins
        fall back on where the proposals all at once are refused beside them: its joins kept where they
        still fold and the axioms accept them, before odometry's proposals one at a time.

        Raises
        ------
        InconsistentTableau
            No partition loop closing reaches satisfies the axioms.
        SolveTimeout
            Out of time; ``best_map`` is the last map the axioms accepted, if any.
        """
        tableau.require_views()
        return Closing(self, tableau, deadline or Deadline.after(self.resolver.time_limit), assertions).run(prior)

    def conflict(self, tableau: Tableau, assertions: Sequence[Assertion], before: CognitiveMap,
                 deadline: Deadline) -> Conflict:
        """Why no loop-closed map honours the hard ``assertions``: a subset-minimal set of them that loop
        closing cannot join (each dropped in turn stays dropped if the rest still clash), and why the first
        ``same`` of it cannot be joined beside the others (headings, what determinism joins, or the axioms
        that reject the map, by name and line)."""
        start = time.perf_counter()
        clash = hard(assertions)
        for x in list(clash):
            trial = [y for y in clash if y is not x]
            if trial and not self._holds(tableau, trial, deadline):
                clash = trial
        same = next((x for x in clash if x.kind == "same"), None)
        if same is None:  # an apart refuses joins the axioms need
            return self._apart_conflict(tableau, clash, before, deadline, start)
        others = [x for x in clash if x is not same]
        closing = Closing(self, tableau, deadline, others)
        closing.asserted()
        closing.odometry_bound = False
        names = (before.dstate_of[same.a], before.dstate_of[same.b])
        sentence, axioms = why_apart(closing, same.a, same.b)
        levels = list(self.resolver.theory.levels)
        explanation = LoopExplanation(same.a, same.b, names, "different", sentence, axioms=axioms, levels=levels,
                                      total_s=time.perf_counter() - start)
        return Conflict([same] + others, explanation, levels)

    def _apart_conflict(self, tableau: Tableau, clash: list[Assertion], before: CognitiveMap, deadline: Deadline,
                        start: float) -> Conflict:
        """Why loop closing finds no map with these assertions, all of them ``apart``: the first refuses the
        joins that would make its two time points one, and the axioms reject the partition loop closing
        starts from without them (every visit a dstate of its own, but the joins a person made), by name
        and line: two dstates may be what the axioms make one (one place, one path, facing one way)."""
        apart, others = clash[0], clash[1:]
        closing = Closing(self, tableau, deadline, others)
        closing.asserted()
        failing = _failing_rules(closing, closing.partition())
        names = (before.dstate_of[apart.a], before.dstate_of[apart.b])
        breaks = f": it breaks {' and '.join(r.cite() for r in failing)}" if failing else ""
        sentence = (f"t{apart.a} ({names[0]}) and t{apart.b} ({names[1]}) cannot be different dstates of a "
                    f"loop-closed map: loop closing refuses every join that makes them one, and the axioms reject "
                    f"the partition it starts from without them{breaks}.")
        levels = list(self.resolver.theory.levels)
        explanation = LoopExplanation(apart.a, apart.b, names, "same", sentence, axioms=failing, levels=levels,
                                      total_s=time.perf_counter() - start)
        return Conflict(list(clash), explanation, levels)

    def _holds(self, tableau: Tableau, assertions: Sequence[Assertion], deadline: Deadline) -> bool:
        """Whether loop closing finds a map with these assertions."""
        try:
            Closing(self, tableau, deadline, assertions).run()
        except InconsistentTableau:
            return False
        return True

    def explain(self, tableau: Tableau, a, b, deadline: Deadline | None = None,
                assertions: Sequence[Assertion] = ()) -> LoopExplanation:
        """Why time points (``t4``, ``4``) or dstates (``S4``) ``a`` and ``b`` are one dstate of the loop-closed
        map, or not: the joins that made them one (each proposed by odometry or forced by determinism), or
        what keeps them apart (odometry, or the axioms that reject the map joining them)."""
        tableau.require_views()
        closing = Closing(self, tableau, deadline or Deadline.after(self.resolver.time_limit), assertions)
        cmap = closing.run()
        x, y = time_points(cmap, a, b)
        return explain(closing, cmap, x, y)


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
    types' angles, :func:`~bootmap.mapping.facts.typed_actions`, which odometry's drift on straight travels
    does not bend), else the measured ones."""
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


class Closing:
    """One loop closing: the evidence, the partition (with every join undoable) and the last map the axioms
    accepted."""

    def __init__(self, closer: LoopCloser, tableau: Tableau, deadline: Deadline,
                 assertions: Sequence[Assertion] = ()):
        self.closer, self.tableau, self.deadline = closer, tableau, deadline
        self.resolver = closer.resolver
        self.start = time.perf_counter()
        self.n = n = len(tableau)
        self.angles, self.action_types, _ = typed_actions(tableau, self.resolver.quantum_deg)
        actions = action_symbols(tableau, self.angles)
        lengths, self.length_types = travel_length_types(tableau)
        # what the causal level folds on (its action names), and what a retraced context compares
        self.fold_key: list[Symbol | None] = actions + [None] * (n - len(actions))
        self.context_key = [(a, lengths.get(t)) for t, a in enumerate(actions)]
        # a robot that stopped at every dstate travels on from one dstate always as far (metrical.lp)
        self.length_of = {} if passes_through(tableau) else lengths
        self.heading = np.concatenate([[0], np.cumsum(self.angles)]).astype(int) % 360
        self.xy, self.along = dead_reckoning(tableau, self.angles)
        self.views = tableau.views
        self.matches = tableau.place_matches()  # what the laser says of pairs of visits
        # What every check of a partition shares: the actions as the axioms see them (not the views)
        self.action_facts = [f for f in tableau_facts(tableau, angles=self.angles, lengths=lengths)
                             if not VIEW.matches(f)]
        # A person's word: joins to make first, joins to refuse (.assertions); the axioms check it too
        self.asserted_same = [x.pair for x in assertions if x.kind == "same" and not x.soft]
        self.preferred_same = [x.pair for x in assertions if x.kind == "same" and x.soft]
        self.told_apart = {x.pair for x in assertions if x.kind == "apart"}
        self.action_facts += assertion_facts([x for x in assertions if not x.soft])
        self.odometry_bound = True  # whether dead reckoning's drift bound keeps visits apart
        self.made: dict[tuple, Symbol] = {}  # the views' and the partition's facts made so far (_fact)
        self.dstates = _Partition(n)
        self.kinds: dict[tuple[int, int], str] = {}  # each proposal: "near", "retraced" or "recognised"
        self.refused: tuple[int, int, str] | None = None  # the last pair a fold refused, and why
        self.best: CognitiveMap | None = None
        self.tries: list[Try] = []
        self.checks = 0
        # dead reckoning re-anchored at the joins made (None: the drive's own), and the odometry each
        # proposal was made on (gap, metres of drive, re-anchored), as explanations quote it
        self.anchoring: Anchoring | None = None
        self._rows: dict[int, tuple[np.ndarray, np.ndarray]] = {}  # its rows worked out so far (_way)
        self.figures: dict[tuple[int, int], tuple[float, float, bool]] = {}

    # ------------------------------------------------------------------------------------------
    def run(self, prior: Sequence[str] | None = None) -> CognitiveMap:
        # Every proposal at once first: the topological level may reject a partition on the way to one it
        # accepts (two dstates of one place facing one way, until their other dstates are joined too).
        if self.deadline.passed():
            raise self.timed_out()
        if not self.asserted():
            raise InconsistentTableau("no map found by loop closing with the assertions: the joins a person "
                                      "asserted cannot be made", levels=tuple(self.resolver.theory.levels))
        # A person's joins stay whatever follows; the axioms judge the partitions made with them (the
        # topological level may refuse them alone, until the proposals join what they imply).
        base = self.dstates.mark()
        proposals = self.preferred + self.proposals
        self._fold_all(proposals)
        if not self._accepted():
            # Else one proposal at a time, each kept only where the axioms accept the partition it makes;
            # with a person's joins, after the joins of the map made without them, where those still stand.
            self.dstates.undo(base)
            if not (prior is not None and self.asserted_same and self._kept(prior)):
                self.dstates.undo(base)
                self._accepted()
            for i, j in proposals:
                if self.deadline.passed():
                    raise self.timed_out()
                if self.dstates.root[i] == self.dstates.root[j]:
                    continue
                before = self.dstates.mark()
                if not (self.fold(i, j) and self._accepted()):
                    self.dstates.undo(before)
        if self.best is not None and self.closer.near_share > 0:  # with no drift allowed, a join counts for none
            self.close_again()
        if self.best is None:
            raise InconsistentTableau("no map found by loop closing: no partition it reached satisfies the axioms",
                                      levels=tuple(self.resolver.theory.levels))
        return replace(self.best, stats=self._stats())

    def close_again(self) -> None:
        """Loop closing again with dead reckoning re-anchored at the joins made (:mod:`.anchoring`), as a
        pose graph corrects a drive where its loops close: the pairs that become near, retraced or recognised
        are proposed (those proposed before are not asked again), each kept where the fold and the axioms
        accept it; until a round joins nothing."""
        while True:
            self.reanchor()
            made = False
            for i, j in self._propose(fresh=True):
                if self.deadline.passed():
                    raise self.timed_out()
                if self.dstates.root[i] == self.dstates.root[j]:
                    continue
                before = self.dstates.mark()
                if self.fold(i, j) and self._accepted():
                    made = True
                else:
                    self.dstates.undo(before)
            if not made:
                return

    def reanchor(self) -> None:
        """Re-anchor dead reckoning at the joins standing: a join counts as the drive over which a near pair
        may drift a place radius."""
        members = self.dstates.members
        groups = [members[r] for r in members if len(members[r]) > 1]
        self.anchoring = Anchoring(self.along, self.xy, groups, self.closer.radius_m / self.closer.near_share)
        self._rows = {}

    def _kept(self, prior: Sequence[str]) -> bool:
        """Fold the joins of a map made before (each dstate's visits, in order), dropping those refused;
        whether the axioms accept the partition then."""
        first: dict[str, int] = {}
        joins = []
        for t, d in enumerate(prior):
            if d in first:
                joins.append((first[d], t))
            else:
                first[d] = t
        self._fold_all(joins)
        return self._accepted()

    def asserted(self) -> bool:
        """Make the joins a person asserted, with what determinism then joins, whatever odometry's drift;
        False if some join they make is refused (``refused`` says which)."""
        self.odometry_bound = False
        try:
            for a, b in self.asserted_same:
                if self.dstates.root[a] != self.dstates.root[b] and \
                        not self.fold(a, b, Join(a, b, "asserted", person=True)):
                    return False
        finally:
            self.odometry_bound = True
        return True

    @cached_property
    def preferred(self) -> list[tuple[int, int]]:
        """A person's soft ``same``: proposals before odometry's, joined whatever its drift."""
        for pair in self.preferred_same:
            self.kinds[pair] = "preferred"
        return list(self.preferred_same)

    def _fold_all(self, proposals: list[tuple[int, int]]) -> None:
        """Fold each proposal in turn, dropping those the fold refuses."""
        for i, j in proposals:
            if self.dstates.root[i] != self.dstates.root[j]:
                before = self.dstates.mark()
                if not self.fold(i, j):
                    self.dstates.undo(before)

    def partition(self) -> list[int]:
        """Each time point's dstate as it stands, named by one of its time points."""
        return list(self.dstates.root)

    @cached_property
    def proposals(self) -> list[tuple[int, int]]:
        """Pairs of visits odometry proposes as one dstate, strongest first (longest context, nearest), then
        the laser's."""
        return self._propose()

    def _propose(self, fresh: bool = False) -> list[tuple[int, int]]:
        """The proposals on dead reckoning as it stands (re-anchored or not); with ``fresh``, only pairs not
        proposed before and not one dstate already."""
        ranked = []
        for i, j in (self._fresh_pairs() if fresh else itertools.combinations(range(self.n), 2)):
            if self.heading[i] != self.heading[j]:
                continue
            near = self.near(i, j)
            agree = self.agreeing(i, j)
            retraced = self.retraced(i, j, agree)
            if (near or retraced) and self.elsewhere(i, j):
                continue  # the laser places j elsewhere: odometry alone does not propose them
            if near or retraced:
                # nearest in metres, as the truth's places are drawn (not as a share of the drift allowed:
                # that ranks a pair far apart after a long drive before a close pair after a short one)
                ranked.append((-agree, self.gap(i, j), i, j))
                self.kinds[i, j] = "near" if near else "retraced"
                self._note(i, j)
        ranked.sort()
        return [(i, j) for _, _, i, j in ranked] + self.recognised()

    def _fresh_pairs(self) -> list[tuple[int, int]]:
        """The pairs not proposed before, in two dstates, facing one way and within the drift bound as dead
        reckoning stands (re-anchored): all that odometry may propose now, found at once."""
        off = self.middle - self.xy  # each visit's middle from its time point
        root = np.asarray(self.dstates.root)
        pairs = []
        for start in range(0, self.n, _ROWS):  # a block of rows at a time: memory by the block, not n squared
            rows = np.arange(start, min(start + _ROWS, self.n))
            driven, displacement = self.anchoring.rows(rows)
            if (len(self._rows) + len(rows)) * self.n <= _KEPT_CELLS:
                self._rows.update({int(i): (driven[[r]], displacement[[r]]) for r, i in enumerate(rows)})
            gaps = np.hypot(*np.moveaxis(displacement + off[None, :, :] - off[rows, None, :], -1, 0))
            within = ((gaps <= self.closer.radius_m + self.closer.drift_share * driven + 1e-9)
                      & (self.heading[rows, None] == self.heading[None, :]) & (root[rows, None] != root[None, :])
                      & (rows[:, None] < np.arange(self.n)[None, :]))
            pairs += [(int(rows[r]), int(j)) for r, j in np.argwhere(within) if (rows[r], j) not in self.kinds]
        return pairs

    def _note(self, i: int, j: int) -> None:
        """Keep the odometry a proposal was made on, for explanations."""
        self.figures[i, j] = (self.gap(i, j), self.driven(i, j), self.reanchored(i, j))

    def recognised(self) -> list[tuple[int, int]]:
        """Pairs of visits the laser proposes as one dstate, after odometry's (strongest match first): a place
        match of at least ``match_score``, facing one way, within the drift bound, not proposed by odometry,
        and one place once their scans are put together (:meth:`turn_offset`)."""
        ranked = []
        root = self.dstates.root
        for (i, j), score in self.matches.items():
            if score >= self.closer.match_score and (i, j) not in self.kinds and root[i] != root[j] \
                    and self.heading[i] == self.heading[j] and self._apart(i, j, self.closer.drift_share) <= 1.0 \
                    and self.turn_offset(i, j) <= self.closer.radius_m:
                ranked.append((-score, i, j))
                self.kinds[i, j] = "recognised"
                self._note(i, j)
        ranked.sort()
        return [(i, j) for _, i, j in ranked]

    def elsewhere(self, i: int, j: int) -> list[int]:
        """The earlier visits the laser matched j's place with, where none of them is i's place (i, or the
        other end of i's turn; j's place likewise): the likeliest earlier places of j, verified by the places
        around them, and i not among them. Empty where the laser confirms i or says nothing of j (no match of
        j's place with an earlier visit: the laser was not asked, or found nothing it could verify)."""
        if not self.matches:
            return []
        there = self.turn_ends[j]
        named = {a for b in there for a in self.earlier_matches.get(b, ()) if a < min(there)}
        return [] if named & set(self.turn_ends[i]) else sorted(named)

    @cached_property
    def earlier_matches(self) -> dict[int, set[int]]:
        """Each time point with the earlier ones the laser matched its place with."""
        out: dict[int, set[int]] = {}
        for a, b in self.matches:
            out.setdefault(b, set()).add(a)
        return out

    def turn_offset(self, i: int, j: int) -> float:
        """How far apart the visits of i and j lie where their scans coincide (metres): a place match puts the
        scans together, but a visit is the middle of its turn (:meth:`gap`), metres from either end where the
        robot turned while driving. Each middle's offset from its scan is odometry's over a few metres; the
        frame's drift between the two visits is not corrected (visits facing one way)."""
        here = self.middle[i] - self.xy[i]
        there = self.middle[j] - self.xy[j]
        return float(np.hypot(*(there - here)))

    def retraced(self, i: int, j: int, agree: int | None = None) -> bool:
        """Whether odometry proposes i and j as one dstate retraced: ``context`` actions around them agree,
        they show one view (a retraced pair's odometry is loose: its views must agree as well) and lie within
        the drift bound."""
        agree = self.agreeing(i, j) if agree is None else agree
        return (agree >= self.closer.context and self.views[i] == self.views[j]
                and self._apart(i, j, self.closer.drift_share) <= 1.0)

    def near(self, i: int, j: int) -> bool:
        """Whether dead reckoning puts i and j near enough to be proposed as one dstate on its word alone."""
        return self._apart(i, j, self.closer.near_share) <= 1.0

    def _apart(self, i: int, j: int, share: float) -> float:
        """How far apart dead reckoning puts i and j, as a share of what it may drift between them."""
        gap = self.gap(i, j)
        return gap / (self.closer.radius_m + share * self.driven(i, j))

    def driven(self, i: int, j: int) -> float:
        """The metres of drive whose drift lies between i and j: those driven, or once dead reckoning is
        re-anchored, the shortest way through the drive and the joins made (:mod:`.anchoring`)."""
        if self.anchoring is None:
            return abs(float(self.along[j] - self.along[i]))
        return self._way(i, j)[0]

    def reanchored(self, i: int, j: int) -> bool:
        """Whether dead reckoning between i and j goes through a join made (a shorter way than the drive)."""
        return self.anchoring is not None and self.driven(i, j) < abs(float(self.along[j] - self.along[i])) - 1e-6

    @cached_property
    def turn_ends(self) -> list[tuple[int, ...]]:
        """Each time point with the other end of the turn it starts or ends: a turn never leaves its place,
        though a robot that turns while driving ends it metres on."""
        steps = self.tableau.steps
        ends = [[t] for t in range(self.n)]
        for t, step in enumerate(steps[:-1]):
            if isinstance(step.action, Turn):
                ends[t].append(t + 1)
                ends[t + 1].append(t)
        return [tuple(e) for e in ends]

    def gap(self, i: int, j: int) -> float:
        """How far apart dead reckoning puts the places of i and j (metres): the middles of the turns they
        belong to (a visit is where its turn is; its ends lie metres apart when the robot turned while
        driving)."""
        if self.anchoring is None:
            return float(np.hypot(*(self.middle[i] - self.middle[j])))
        # re-anchored: the way from i's time point to j's (the earlier first: where two ways tie, one answer),
        # and each middle's offset from its time point
        i, j = min(i, j), max(i, j)
        way = self._way(i, j)[1] + (self.middle[j] - self.xy[j]) - (self.middle[i] - self.xy[i])
        return float(np.hypot(*way))

    def _way(self, i: int, j: int) -> tuple[float, np.ndarray]:
        """The re-anchored way from i to j (metres of drive, displacement), from i's row, kept while the
        anchoring stands (the rows asked are few: the proposals' and their dstates' visits)."""
        if i not in self._rows:
            if (len(self._rows) + 1) * self.n > _KEPT_CELLS:
                self._rows.clear()
            self._rows[i] = self.anchoring.rows([i])
        driven, displacement = self._rows[i]
        return float(driven[0, j]), displacement[0, j]

    @cached_property
    def middle(self) -> np.ndarray:
        """Each time point's visit, dead-reckoned: the middle of the ends of the turn it belongs to."""
        return np.array([self.xy[list(ends)].mean(axis=0) for ends in self.turn_ends])

    def agreeing(self, i: int, j: int) -> int:
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
    def fold(self, i: int, j: int, why: Join | None = None) -> bool:
        """Join i's and j's dstates and every pair determinism then joins; False if some pair joined would
        face two ways or lie beyond the drift bound (``refused`` says which; the caller undoes the joins
        made)."""
        kind = self.kinds.get((i, j), "")
        queue = [why or Join(i, j, "proposed", kind, person=kind == "preferred")]
        members = self.dstates.members
        while queue:
            join = queue.pop()
            a, b = self.dstates.root[join.x], self.dstates.root[join.y]
            if a == b:
                continue
            # A near proposal joins visits odometry puts in one place: so must it put every pair of visits it
            # makes one dstate (as the truth's places are made: complete linkage), not only the pair proposed;
            # but not in a dstate a person made, whose visits odometry need not put together (_vouched)
            near = join.kind == "near" and not self._vouched(a, b)
            share = self.closer.near_share if near else None
            refused = next(((x, y, cause) for x in members[a] for y in members[b]
                            if (cause := self.kept_apart(x, y, share))), None)
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
                                          after=(led[action], t), person=join.person))
                    else:
                        led[action] = t
        return True

    def _vouched(self, a: int, b: int) -> bool:
        """Whether dstate a or b (roots) holds a join a person made (or one it forced): its visits are one
        place on their word, whatever odometry says."""
        root = self.dstates.root
        return any(j.person and root[j.x] in (a, b) for j in self.dstates.reasons())

    def kept_apart(self, x: int, y: int, share: float | None = None) -> str:
        """What keeps visits x and y from being one dstate before any axiom is asked ("" if nothing): they
        face two ways, travel on unequally far (where the robot stopped at every dstate), or lie beyond the
        drift bound (``share`` of the distance driven between them: by default ``drift_share``; a near
        proposal's joins, ``near_share``), or a person said they differ."""
        if (min(x, y), max(x, y)) in self.told_apart:
            return "a person said they are different dstates"
        if self.heading[x] != self.heading[y]:
            return f"they face different ways (headings {self.heading[x]} and {self.heading[y]}: metrical level)"
        lx, ly = self.length_of.get(x), self.length_of.get(y)
        if lx is not None and ly is not None and lx != ly:
            return f"the travels from them differ ({lx} and {ly} dm: length_is_feature)"
        near = share is not None
        share = self.closer.drift_share if share is None else share
        if self.odometry_bound and self.kinds.get((min(x, y), max(x, y))) != "preferred" \
                and self._apart(x, y, share) > 1.0:
            allowed = "a near proposal allows" if near else "odometry may drift"
            return f"{self.odometry(x, y)}, more than {allowed} ({self.drift_bound(x, y, share):.1f} m)"
        return ""

    def odometry(self, x: int, y: int, as_proposed: bool = False) -> str:
        """How far apart dead reckoning puts x and y, in words (``as_proposed``: as it stood when they were
        proposed, where they were)."""
        gap, driven, anchored = self._figures(x, y, as_proposed)
        if anchored:
            return (f"dead reckoning re-anchored at the loops closed puts them {gap:.1f} m apart, {driven:.0f} m of "
                    f"drive between them that way, not the {abs(self.along[y] - self.along[x]):.0f} m driven")
        return f"dead reckoning puts them {gap:.1f} m apart after {driven:.0f} m driven"

    def drift_bound(self, x: int, y: int, share: float, as_proposed: bool = False) -> float:
        """The metres dead reckoning may put x and y apart, drifting ``share`` per metre of drive between them."""
        return self.closer.radius_m + share * self._figures(x, y, as_proposed)[1]

    def _figures(self, x: int, y: int, as_proposed: bool = False) -> tuple[float, float, bool]:
        """The gap, the metres of drive between x and y and whether re-anchored: as now, or ``as_proposed``
        (as they stood when the pair was proposed, where it was)."""
        i, j = min(x, y), max(x, y)
        if as_proposed and (i, j) in self.figures:
            return self.figures[i, j]
        return self.gap(i, j), self.driven(i, j), self.reanchored(i, j)

    def _accepted(self) -> bool:
        """Check the partition with every axiom; keep its map if they accept it."""
        found = self.checked(self.partition())
        if found is not None:
            self.best = found
        return found is not None

    def facts_of(self, dstate_of: list[int]) -> tuple[list[Symbol], dict[int, str]]:
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

    def checked(self, dstate_of: list[int]) -> CognitiveMap | None:
        """The map of this partition if every axiom accepts it, each dstate showing its visits' most common
        view (the other visits' views are misreads)."""
        resolver = self.resolver
        self.checks += 1
        facts, shown = self.facts_of(dstate_of)
        groups = set(dstate_of)
        views = self.views
        models, grounding = check_fixed(resolver.theory, facts, resolver.future_depth, self.deadline)
        self.tries.append(Try(f"{len(groups)} dstates (loop closing)", "sat" if models else
                              ("timeout" if models is None else "unsat"), grounding.ground_s + grounding.solve_s))
        if models is None:
            raise self.timed_out()  # not a rejection: the axioms did not answer in time
        if not models:
            return None
        cmap = build_map(self.tableau, models, True, resolver.theory.levels, self._stats(), minimal=False,
                         action_types=self.action_types, length_types=self.length_types)
        misreads = [{"t": t, "observed": views[t], "expected": cmap.views[cmap.dstate_of[t]], "cost": None}
                    for t in range(self.n) if views[t] != shown[dstate_of[t]]]
        return replace(cmap, suspect_steps=misreads, found_by="loop closing")

    def _stats(self) -> SolveStats:
        return SolveStats(classes=self.n, lower_bound=0, total_s=time.perf_counter() - self.start,
                          bounds=tuple(self.tries[-3:]))

    def timed_out(self) -> SolveTimeout:
        """Out of time: the error carries the last map the axioms accepted, if any."""
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
