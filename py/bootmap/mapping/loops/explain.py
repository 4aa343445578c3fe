"""Why two time points are one dstate of the loop-closed map, or not.

One dstate: the joins that made them one, each proposed by odometry (near, or retraced) or forced by
determinism, with the evidence for each. Different dstates: what keeps them apart before any axiom is
asked (headings, the travels from them, odometry), or what joining them would make one that may not be,
or the axioms that reject the map joining them (a subset-minimal set of constraints, cited by name and
line), or else that nothing proposed them: loop closing joins only what odometry proposes.

Where the tableau carries laser images and says what laser took them (a log's, ``meta.laser``), each join
proposed by odometry, and each pair kept apart by odometry or for want of evidence, also shows how alike the two scans
are once aligned (:class:`bootmap.scan_match.ScanMatcher`): what the laser says of the join, beside what
odometry and the axioms say. Loop closing does not weigh it (a scan matches look-alike places too).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from functools import partial
from typing import TYPE_CHECKING, Callable

from ...scan_match import ScanMatcher
from ...tableau import Tableau
from ..cogmap import CognitiveMap
from ..grounding import Grounding
from ..proof import rule_dict
from ..trace import RuleRef

if TYPE_CHECKING:
    from .closing import Closing


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
        # The keys of a minimal map's explanation (:class:`~bootmap.mapping.explain.Explanation`), those of
        # proofs empty.
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
    retraced) or by the laser's place match (recognised), or ``forced`` by determinism (``after``: the time
    points before them, already one dstate, took the same ``action``)."""

    x: int
    y: int
    how: str                                 # "proposed" or "forced"
    kind: str = ""                           # proposed: "near", "retraced" or "recognised"
    action: str = ""                         # forced: the action both took
    after: tuple[int, int] | None = None     # forced: the time points that took it
    person: bool = False                     # made on a person's word (asserted, preferred) or forced by one

    def text(self, evidence: Callable[[int, int], str]) -> str:
        if self.how == "asserted":
            return f"t{self.x} = t{self.y}: a person said they are one dstate"
        if self.how == "proposed":
            return f"t{self.x} = t{self.y}: proposed ({self.kind}): {evidence(self.x, self.y)}"
        u, v = self.after
        return (f"t{self.x} = t{self.y}: forced: t{u} and t{v} are one dstate and both took {self.action} "
                f"(deterministic_action: one action from one dstate reaches one dstate)")


def explain(closing: Closing, cmap: CognitiveMap, a: int, b: int) -> LoopExplanation:
    """Why a and b are one dstate of ``cmap`` (the map ``closing`` found), or not."""
    return _Explaining(closing).explain(cmap, a, b)


def why_apart(closing: Closing, a: int, b: int) -> tuple[str, list[RuleRef]]:
    """What keeps a and b apart in ``closing``'s partition as it stands, in words, and the constraints
    joining them would break (if any)."""
    return _Explaining(closing)._kept_apart_why(a, b)


def failing_rules(closing: Closing, dstate_of: list[int]) -> list[RuleRef]:
    """The constraints a partition breaks (a subset-minimal set; empty if every axiom accepts it)."""
    return _Explaining(closing)._failing_rules(dstate_of)


def scan_evidence(tableau: Tableau, x: int, y: int) -> str | None:
    """How alike the laser images at time points ``x`` and ``y`` are once aligned, in words: the scan
    match's score (the share of both scans' returns the other confirms, less those it refutes) and how far
    apart the alignment puts the two robots. None where
    either has no image or the tableau does not say what laser took them (``meta.laser``: its range and a
    field of view symmetric about the heading)."""
    laser = tableau.meta.get("laser") or {}
    a, b = tableau.steps[x].image, tableau.steps[y].image
    try:
        low, high, reach = float(laser["angle_min"]), float(laser["angle_max"]), float(laser["range_max"])
    except (KeyError, TypeError, ValueError):
        return None
    if a is None or b is None or len(a) != len(b) or not math.isclose(low, -high) or reach <= 0:
        return None
    match = ScanMatcher(max_range=reach, fov_deg=math.degrees(high - low)).match(a, b)
    explained, returns = sum(match.inliers), sum(match.points)
    apart = math.hypot(match.transform[0], match.transform[1])
    return (f"their scans, aligned, score {match.score:.2f} (scan match: {explained} of {returns} returns "
            f"confirmed, {sum(match.refuted)} refuted; taken {apart:.1f} m apart)")


class _Explaining:
    """One explanation, read off a finished loop closing: its joins, and what it refuses or the axioms
    reject when asked to join two time points (every join made for the question is undone)."""

    def __init__(self, closing: Closing):
        self.closing = closing

    def _scans(self, x: int, y: int) -> str:
        """The scan match of x and y, as a clause to add ("" where the tableau has no laser images)."""
        said = scan_evidence(self.closing.tableau, x, y)
        return f"; {said}" if said else ""

    def explain(self, cmap: CognitiveMap, a: int, b: int) -> LoopExplanation:
        """Why a and b are one dstate of ``cmap`` (this closing's map), or not."""
        closing = self.closing
        names = (cmap.dstate_of[a], cmap.dstate_of[b])
        answer = partial(LoopExplanation, a, b, names, levels=list(closing.resolver.theory.levels))
        if names[0] == names[1]:
            chain = [j.text(self._evidence) for j in self._chain(a, b)]
            return answer("same", f"t{a} and t{b} are one dstate: loop closing joined them (below) and every "
                                  f"axiom accepts the map.", chain, total_s=time.perf_counter() - closing.start)
        sentence, axioms = self._kept_apart_why(a, b)
        return answer("different", sentence, axioms=axioms, total_s=time.perf_counter() - closing.start)

    def _evidence(self, x: int, y: int) -> str:
        """The odometry behind a proposal, in words."""
        closing, closer = self.closing, self.closing.closer
        i, j = min(x, y), max(x, y)
        odometry = closing.odometry(x, y, as_proposed=True)
        bound = partial(closing.drift_bound, x, y, as_proposed=True)
        if closing.kinds.get((i, j)) == "preferred":
            return f"a person prefers them one dstate ({odometry})"
        if closing.kinds.get((i, j)) == "recognised":
            return (f"{self._matched(i, j)}, and {odometry} (within "
                    f"{bound(closer.drift_share):.1f} m){self._scans(x, y)}")
        if closing.kinds.get((i, j)) == "retraced":
            return (f"the same {closing.agreeing(i, j)} actions around them, one view, and {odometry} "
                    f"(within {bound(closer.drift_share):.1f} m){self._scans(x, y)}")
        return f"{odometry} (within {bound(closer.near_share):.1f} m){self._scans(x, y)}"

    def _matched(self, i: int, j: int) -> str:
        """What the tableau's place match says of i and j (i < j), in words ("" where it has none)."""
        score = self.closing.matches.get((i, j))
        if score is None:
            return ""
        return (f"the laser matches their places, verified by the places around them, with score {score:.2f} "
                f"(loop closing proposes {self.closing.closer.match_score:g} or more)")

    def _chain(self, a: int, b: int) -> list[Join]:
        """The joins that link a to b (a path in the forest of the joins standing)."""
        links: dict[int, list[tuple[int, Join]]] = {}
        for join in self.closing.dstates.reasons():
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
        closing, closer = self.closing, self.closing.closer
        cause = closing.kept_apart(a, b)
        if cause:
            # Kept apart by odometry alone, the laser may say otherwise (a drifted revisit): show it.
            laser = self._scans(a, b) if cause.startswith(closing.odometry(a, b)) else ""
            return f"t{a} and t{b} are different dstates: {cause}{laser}.", []
        proposed = closing.kinds.get((min(a, b), max(a, b)))
        mark = closing.dstates.mark()
        try:
            if not closing.fold(a, b, Join(a, b, "asked", proposed or "")):
                x, y, cause = closing.refused
                return (f"t{a} and t{b} are different dstates: making them one makes t{x} and t{y} one (by their "
                        f"dstates, or by determinism), but {cause}."), []
            failing = self._failing_rules(closing.partition())
        finally:
            closing.dstates.undo(mark)
        if failing:
            return (f"t{a} and t{b} are different dstates: the axioms reject the map that makes them one (with "
                    f"what determinism then joins): it breaks {' and '.join(r.cite() for r in failing)}."), failing
        i, j = min(a, b), max(a, b)
        matched, elsewhere = self._matched(i, j), closing.elsewhere(i, j)
        if not proposed and elsewhere and (closing.near(i, j) or closing.retraced(i, j)):
            said = (f"{closing.odometry(a, b)} (within {closing.drift_bound(a, b, closer.near_share):.1f} m, near)"
                    if closing.near(i, j) else
                    f"the same {closing.agreeing(i, j)} actions around them, one view, and {closing.odometry(a, b)} "
                    f"(within {closing.drift_bound(a, b, closer.drift_share):.1f} m, retraced)")
            why = (f"{said}, but the laser matches t{j}'s place, verified by the places around it, with "
                   f"{', '.join(f't{x}' for x in elsewhere)}, not with t{i}'s: odometry alone proposes no "
                   f"visits the laser places elsewhere")
        else:
            why = (f"it was proposed ({proposed}) but rejected beside joins made before it" if proposed else
                   f"nothing proposed them ({closing.odometry(a, b)}: beyond "
                   f"{closing.drift_bound(a, b, closer.near_share):.1f} m for visits proposed as near; "
                   f"{closing.agreeing(i, j)} actions around them agree, where "
                   f"{closer.context} and one view propose visits as retraced; "
                   f"{matched or 'the tableau has no place match of them'})")
        return (f"t{a} and t{b} are different dstates only for want of evidence: {why}{self._scans(a, b)}. Every "
                f"axiom would accept them as one dstate; loop closing joins only what odometry or the laser's "
                f"place matches propose."), []

    def _failing_rules(self, dstate_of: list[int]) -> list[RuleRef]:
        """The constraints this partition breaks: a subset-minimal set that still rules it out (each switched
        off in turn, kept off if the partition stays ruled out); empty if every axiom accepts it."""
        closing = self.closing
        if closing.checked(dstate_of) is not None:
            return []
        facts, _ = closing.facts_of(dstate_of)
        resolver = closing.resolver
        traced = Grounding(resolver.theory, facts, resolver.future_depth, ["1"], instrumented=True).ground()
        rules = traced.rules
        needed = list(rules.switchable)
        for r in list(needed):
            trial = [x for x in needed if x != r]
            result = traced.solve(closing.deadline, assumptions=[(rules.on(x), x in trial) for x in rules.switchable])
            if result is None:
                raise closing.timed_out()
            if not result.satisfiable:
                needed = trial
        return [rules.rules[r] for r in needed]
