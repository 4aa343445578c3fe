"""Explanations: why two time points are different dstates, or the same one, and which experience
proves it.

The paper resolves the tableau by assuming "dstates with the same view are equal unless they can be
proved different". This module shows that proof. For time points a and b (or two dstates of the
minimal map):

* **different** in every minimal map: the solver is asked to suppose a and b are one dstate
  (``same_asked`` in core/ask.lp) on ever fewer tableau steps, until the steps left are a
  subset-minimal *evidence*: with them alone the supposition has no model, and dropping any one step
  gives it one. Then, on the evidence, the axiom constraints are switched off one at a time to find
  the ones the contradiction needs; for each, the finest map that keeps the others shows where it
  fails and, through the instrumented theory (bootmap.trace), the chain of rule instances - named,
  with file and line - from the tableau steps to the failure.
* **same** in every minimal map: nothing in the experience tells them apart (minimality); the
  explanation says how far their futures agree and which actions, from the tableau's own vocabulary,
  would test them further.
* **undecided**: minimal maps disagree; the explanation lists which of them keep a and b apart.

Because the machinery reads rules from the .lp files, a rule a user adds in a new level file shows up,
by its ``%!`` name, in the proofs it takes part in, with no change to this code.

Example
-------
>>> from bootmap.examples import notched_rectangle
>>> e = Explainer(levels=["causal", "topological"]).explain(notched_rectangle(3), 0, 4)
>>> e.verdict, e.evidence
('different', [0, 1, 2, 3, 4])
"""

from __future__ import annotations

import re
import threading
import time
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Hashable, Sequence

from clingo import String, Symbol

from ..errors import ExplainError, InconsistentTableau, SolveTimeout
from ..tableau import Tableau
from .assertions import Assertion, Conflict, assertion_facts
from .cogmap import CognitiveMap, action_text
from .facts import Excerpts, action_symbol, action_symbols, read_actions, tableau_facts
from .grounding import Classes, Deadline, Grounding, key_with_view, prepass
from .misreads import find_suspects
from .proof import Failure, Names, ProofNode, merged, node, rule_dict
from .resolver import Resolver
from .trace import Derivations, Instrumented, RuleRef
from .vocabulary import FEATURE, FINEST_MAP, MAY_BE, SAME_ASKED, SHOWN_BY_ALL, SUSPECT, action_word

__all__ = ["Explainer", "Explanation", "Failure", "ProofNode"]


@dataclass(frozen=True)
class Explanation:
    """The answer to "are time points a and b the same dstate, and why?"."""

    a: int
    b: int
    names: tuple[str, str]              # their dstates in the (first) minimal map
    verdict: str                        # "different", "same" or "undecided"
    sentence: str
    evidence: list[int] = field(default_factory=list)
    axioms: list[RuleRef] = field(default_factory=list)    # the constraints the contradiction needs
    failures: list[Failure] = field(default_factory=list)
    agree_steps: int = 0                # same: how many steps their futures agree
    suggestion: list[str] = field(default_factory=list)    # same: actions that would test them
    alternatives: list[dict] = field(default_factory=list)  # undecided: the minimal maps and a/b in each
    levels: list[str] = field(default_factory=list)
    total_s: float = 0.0                # seconds to answer
    supposed: str = "same"              # what the proof supposes and refutes: "same" (one dstate) or "apart"

    def rules_cited(self) -> list[str]:
        """Every rule the proof uses, each once, in order of first use."""
        names = [r.name for r in self.axioms]
        for f in self.failures:
            for p in f.premises:
                names += p.rules_cited()
        return list(dict.fromkeys(names))

    def to_dict(self) -> dict:
        return {"a": self.a, "b": self.b, "dstates": list(self.names), "verdict": self.verdict,
                "sentence": self.sentence, "evidence": self.evidence,
                "axioms": [rule_dict(r) for r in self.axioms],
                "failures": [f.to_dict() for f in self.failures], "rules_cited": self.rules_cited(),
                "agree_steps": self.agree_steps, "suggestion": self.suggestion,
                "alternatives": self.alternatives, "levels": self.levels, "found_by": "fewest dstates", "joins": [],
                "supposed": self.supposed, "stats": {"total_s": self.total_s}}

    def to_text(self) -> str:
        out = [f"t{self.a} ({self.names[0]}) vs t{self.b} ({self.names[1]}): {self.verdict}",
               f"levels: {', '.join(self.levels)}", "", self.sentence]
        if self.evidence:
            out += ["", "evidence (these steps alone force it; dropping any one does not): "
                    + ", ".join(f"t{t}" for t in self.evidence)]
        if self.axioms:
            out += ["axioms the contradiction needs: " + ", ".join(r.cite() for r in self.axioms)]
        for f in self.failures:
            out += f.lines(self.a, self.b, self.supposed)
        if self.suggestion:
            out += ["", "experience that would test them:"] + [f"  {s}" for s in self.suggestion]
        for alt in self.alternatives:
            out += [f"minimal map {alt['map']}: t{self.a} is {alt['a']}, t{self.b} is {alt['b']}"
                    + (" (apart)" if alt["apart"] else " (same)")]
        return "\n".join(out)


@dataclass(frozen=True)
class StepExplanation:
    """Why the map reads (or does not read) the view seen at one time point as a misread.

    Attributes
    ----------
    t : int
        The time point.
    view, dstate, dstate_view : str
        The view seen at t, the dstate the map puts t at, and that dstate's view.
    misread : bool
        The map takes the view seen at t as a misread.
    cost : int or None
        What that cost (a dstate costs 4), when it is one.
    reason : str or None
        Why the view was suspect before the search, if it was.
    evidence : tuple of str
        What the experience around t showed, side by side.
    dstates, as_seen_lower_bound : int
        Dstates of the map, and dstates proved necessary reading every view as seen.
    """

    t: int
    view: str
    dstate: str
    dstate_view: str
    misread: bool
    cost: int | None
    reason: str | None
    evidence: tuple[str, ...]
    dstates: int
    as_seen_lower_bound: int | None

    def to_dict(self) -> dict:
        return {"t": self.t, "view": self.view, "dstate": self.dstate, "dstate_view": self.dstate_view,
                "misread": self.misread, "cost": self.cost, "reason": self.reason, "evidence": list(self.evidence),
                "dstates": self.dstates, "as_seen_lower_bound": self.as_seen_lower_bound}

    def to_text(self) -> str:
        if self.misread:
            out = [f"t{self.t} saw view {self.view}, but the map puts it at {self.dstate}, whose view is "
                   f"{self.dstate_view}: it takes what was seen as a misread (cost {self.cost}; a dstate costs 4)."]
        else:
            out = [f"t{self.t} saw view {self.view}, and the map reads it as seen: {self.dstate} shows "
                   f"{self.dstate_view}."]
        if self.reason:
            out += [f"The view was suspect: {self.reason}."] + [f"  {e}" for e in self.evidence]
        if self.misread and self.as_seen_lower_bound:
            out.append(f"Reading every view as seen needs at least {self.as_seen_lower_bound} dstates (proved); "
                       f"with its misreads the map has {self.dstates}.")
        elif self.reason:
            out.append("Reading it as a misread would not save dstates enough to pay for it.")
        return "\n".join(out)


@dataclass(frozen=True)
class Explainer:
    """Explain pairs of time points of a tableau. Its settings are fixed when it is made; each question
    gets its own deadline.

    Parameters
    ----------
    axioms, levels, quantum_deg, time_limit
        As for :class:`bootmap.mapping.resolver.Resolver` (the levels are the axiom families in play).
    max_window : int
        The proof is looked for in windows of steps around a and b, doubling up to this many steps
        on each side.

    Attributes
    ----------
    resolver : Resolver
        The resolver whose minimal maps the explanations are about.
    """

    axioms: str | Path | None = None
    levels: Sequence[str] | None = None
    quantum_deg: float | None = None
    time_limit: float | None = 60.0
    max_window: int = 32
    resolver: Resolver = field(init=False, repr=False, compare=False)
    maps: "_Memo" = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "resolver", Resolver(self.axioms, self.levels, self.quantum_deg, self.time_limit))
        object.__setattr__(self, "maps", _Memo(size=4))

    def minimal_map(self, tableau: Tableau, deadline: Deadline) -> CognitiveMap:
        """The minimal map the questions are about, resolved once per experience (views and actions):
        a person asking about several pairs of one tableau (the viewer's clicks) waits for the resolver
        only the first time."""
        return self.maps.get(_experience(tableau), lambda: self.resolver.resolve(tableau, deadline))

    def remember(self, tableau: Tableau, cmap: CognitiveMap) -> None:
        """Take ``cmap`` as the minimal map of ``tableau`` (resolved elsewhere with this explainer's
        settings), so that questions about it need not resolve it again."""
        self.maps.get(_experience(tableau), lambda: cmap)

    def explain(self, tableau: Tableau, a: int | str, b: int | str, deadline: Deadline | None = None,
                assertions: Sequence[Assertion] = ()) -> Explanation:
        """Explain whether ``a`` and ``b`` (time points, ``"t4"``, or dstate names such as ``"S4"``) are
        one dstate, by ``deadline`` (default: ``time_limit`` from now); with a person's ``assertions``, in
        the map that honours them, whose proofs may cite them as evidence. Raises :class:`ExplainError`
        for names the map does not have, :class:`SolveTimeout` when out of time."""
        start = time.perf_counter()
        deadline = deadline or Deadline.after(self.time_limit)
        if assertions:
            facts = tuple(assertion_facts(assertions))
            cmap = self.maps.get((_experience(tableau), facts),
                                 lambda: self.resolver.resolve(tableau, deadline, assertions))
        else:
            cmap = self.minimal_map(tableau, deadline)
        q = _Question(self, tableau, deadline, cmap)
        q.assume(assertions, pin=False)
        a, b = time_points(cmap, a, b)
        maps = [cmap.dstate_of] + cmap.alternatives
        apart = [m[a] != m[b] for m in maps]
        names = (cmap.dstate_of[a], cmap.dstate_of[b])
        if all(apart):
            answer = q.prove(cmap, a, b, names)
        elif not any(apart):
            answer = _same(tableau, cmap, a, b, q.angles)
        else:
            answer = {"verdict": "undecided",
                      "alternatives": [{"map": i + 1, "a": m[a], "b": m[b], "apart": m[a] != m[b]}
                                       for i, m in enumerate(maps)],
                      "sentence": f"The minimal maps disagree: {sum(apart)} of {len(maps)} keep t{a} and t{b} "
                                  "apart. More experience is needed to decide."}
        return Explanation(a, b, names, levels=list(self.resolver.theory.levels),
                           total_s=round(time.perf_counter() - start, 4), **answer)

    def explain_step(self, tableau: Tableau, t: int | str, deadline: Deadline | None = None) -> StepExplanation:
        """Why the map reads the view seen at ``t`` as seen, or as a misread."""
        cmap = self.minimal_map(tableau, deadline or Deadline.after(self.time_limit))
        t, _ = time_points(cmap, t, t)
        angles, _ = read_actions(tableau, self.quantum_deg)
        actions = action_symbols(tableau, angles)
        suspect = {s.t: s for s in find_suspects(tableau.views, actions)}.get(t)
        taken = {s["t"]: s for s in cmap.suspect_steps}.get(t)
        d = cmap.dstate_of[t]
        return StepExplanation(t, tableau.steps[t].view, d, cmap.views[d], taken is not None,
                               taken and taken["cost"], suspect and suspect.reason,
                               suspect.evidence if suspect else (), cmap.n_dstates, cmap.stats.as_seen_lower_bound)

    def conflict(self, tableau: Tableau, assertions: Sequence[Assertion], deadline: Deadline | None = None,
                 cmap: CognitiveMap | None = None, local: bool = False) -> Conflict | None:
        """Why no map honours a person's hard ``assertions`` (None if some map does): a subset-minimal set
        of them that no map honours (deletion: each dropped in turn stays dropped if the rest still
        clash), and the proof that a ``same`` of that set cannot hold beside the others, as
        :meth:`explain` proves two time points different: the fewest steps, the axioms, the chain of rule
        instances. ``cmap`` is the map made without the assertions (default: resolved here).

        With ``local``, only clashes that the steps around each ``same`` show (up to ``max_window`` on
        either side, beside the other assertions) are looked for: a few small groundings, where the
        whole experience with every partition allowed may be far beyond the deadline. None then says
        only that no clash is that near."""
        start = time.perf_counter()
        deadline = deadline or Deadline.after(self.time_limit)
        cmap = cmap or self.minimal_map(tableau, deadline)
        q = _Question(self, tableau, deadline, cmap)
        clash = [x for x in assertions if not x.soft]

        def clashes(xs: Sequence[Assertion]) -> bool:
            # The map made without them is a map of the experience: where it honours them all, so does
            # some map, and no search need say so.
            if all(x.holds_in(cmap) for x in xs):
                return False
            return q.clash_nearby(xs) if local else not q.can_hold(xs)

        if not clashes(clash):
            return None
        for x in list(clash):
            trial = [y for y in clash if y is not x]
            if clashes(trial):
                clash = trial
        # The proof is of a "same" where there is one; else of an "apart": the axioms can make two time
        # points one dstate (two dstates of one place facing one way along one path are one), and a person
        # who says they differ clashes with them.
        proved = next((x for x in clash if x.kind == "same" and q.clash_nearby(clash, x)), None) or \
            next((x for x in clash if x.kind == "same"), None) or clash[0]
        q.assume([x for x in clash if x is not proved])
        names = (cmap.dstate_of[proved.a], cmap.dstate_of[proved.b])
        answer = q.prove(cmap, proved.a, proved.b, names, proved.kind)
        explanation = Explanation(proved.a, proved.b, names, levels=list(self.resolver.theory.levels),
                                  total_s=round(time.perf_counter() - start, 4), supposed=proved.kind, **answer)
        return Conflict([proved] + [x for x in clash if x is not proved], explanation,
                        list(self.resolver.theory.levels))

    def can_be_same(self, tableau: Tableau, a: int, b: int, keep: Sequence[int] | None = None,
                    deadline: Deadline | None = None) -> bool:
        """Can time points a and b be one dstate in some map of these steps (default: all) that
        satisfies the axioms, however many dstates it needs?"""
        return _Question(self, tableau, deadline or Deadline.after(self.time_limit)).can_be_same(a, b, keep)

    def can_be_apart(self, tableau: Tableau, a: int, b: int, keep: Sequence[int] | None = None,
                     deadline: Deadline | None = None) -> bool:
        """Can time points a and b be two dstates in some map of these steps (default: all) that satisfies
        the axioms? (Not always: two dstates of one place facing one way along one path are one.)"""
        return _Question(self, tableau, deadline or Deadline.after(self.time_limit)).can_be(a, b, keep, "apart")

    def minimal_evidence(self, tableau: Tableau, a: int, b: int, keep: Sequence[int],
                         deadline: Deadline | None = None) -> list[int]:
        """Drop steps one at a time (farthest from a and b first) while a and b still cannot be one
        dstate: what is left is subset-minimal evidence."""
        return _Question(self, tableau, deadline or Deadline.after(self.time_limit)).minimal_evidence(a, b, keep)


def _experience(tableau: Tableau) -> tuple:
    """What a map depends on: views, actions, and images (their margins price misreads)."""
    return tuple((s.view, s.action, s.image) for s in tableau.steps)


class _Memo:
    """The last few values made, by key (thread-safe; a value is made outside the lock, so two threads
    asking at once may both make it, which is harmless)."""

    def __init__(self, size: int):
        self.size, self._items, self._lock = size, OrderedDict(), threading.Lock()

    def get(self, key: Hashable, make: Callable[[], CognitiveMap]) -> CognitiveMap:
        with self._lock:
            if key in self._items:
                self._items.move_to_end(key)
                return self._items[key]
        value = make()
        with self._lock:
            self._items[key] = value
            while len(self._items) > self.size:
                self._items.popitem(last=False)
        return value


class _Question:
    """One explanation under way: the tableau's facts (built once for every excerpt tried) and the deadline."""

    def __init__(self, explainer: Explainer, tableau: Tableau, deadline: Deadline,
                 cmap: CognitiveMap | None = None):
        self.explainer, self.tableau, self.deadline = explainer, tableau, deadline
        self.theory = explainer.resolver.theory
        self.depth = explainer.resolver.future_depth
        self.angles, _ = read_actions(tableau, explainer.quantum_deg)
        for step in (cmap.retyped_steps if cmap is not None else ()):
            self.angles[step["t"]] = step["abduced_deg"]  # the map's evidence: actions as it typed them
        self.facts = tableau_facts(tableau, angles=self.angles)
        self.excerpt = Excerpts(self.facts)
        self.misreads = self.misread_facts(cmap) if cmap is not None and cmap.suspect_steps else {}
        self.assumed: list[Assertion] = []  # a person's assertions the question takes as given
        self.pinned: set[int] = set()       # time points part of every excerpt
        # Each answer of can_be_same, by the pair, the steps kept and the assertions assumed: a clash is
        # looked for, its assertions pared down, then proved, and each asks of the same windows again.
        self.answers: dict[tuple, bool] = {}

    def assume(self, assertions: Sequence[Assertion], pin: bool = True) -> None:
        """Take these assertions as given: with ``pin``, in every excerpt tried (their time points always
        kept: a clash's proof must use them); else as evidence like any step, in the excerpts that keep
        both their time points."""
        self.assumed = list(assertions)
        self.pinned = {t for x in assertions for t in x.pair} if pin else set()

    def assumed_in(self, keep: Sequence[int]) -> list[Symbol]:
        """The assumed assertions an excerpt keeping ``keep`` holds, as facts."""
        return assertion_facts(self._assumed_within(keep))

    def _assumed_within(self, keep: Sequence[int]) -> list[Assertion]:
        """The assumed assertions whose two time points the excerpt keeping ``keep`` holds."""
        kept = set(keep)
        return [x for x in self.assumed if x.a in kept and x.b in kept]

    def clash_nearby(self, assertions: Sequence[Assertion], only: Assertion | None = None) -> bool:
        """Whether the steps around some ``same`` of these assertions (or around ``only``) show it cannot
        hold beside the others (:meth:`window`)."""
        for x in assertions:
            if x.kind != "same" or (only is not None and x is not only):
                continue
            self.assume([y for y in assertions if y is not x])
            try:
                if self.window(x.a, x.b) is not None:
                    return True
            finally:
                self.assume([])
        return False

    def can_hold(self, assertions: Sequence[Assertion]) -> bool:
        """Can every one of these assertions hold in some map of the whole experience that satisfies the
        axioms, however many dstates it needs?"""
        keep = list(range(len(self.tableau)))
        facts, classes = self.with_misreads(self.facts + assertion_facts(assertions), keep)
        if None in classes.keys or any(x.kind == "same" and not classes.same_class(x.a, x.b) for x in assertions):
            return False
        grounding = Grounding(self.theory, facts + classes.layout(len(keep)), self.depth, ["1"]).ground()
        return bool(self._solve(grounding).satisfiable)

    @staticmethod
    def misread_facts(cmap: CognitiveMap) -> dict[int, tuple[Symbol, Symbol]]:
        """Per time point the map takes as a misread: its cost and the view the map expects there. The
        proofs then argue from the experience as the map reads it (a misread may sit at a dstate of its
        expected view), not as seen."""
        return {s["t"]: (SUSPECT(s["t"], s["cost"]), String(s["expected"])) for s in cmap.suspect_steps}

    def with_misreads(self, facts: list[Symbol], keep: Sequence[int]) -> tuple[list[Symbol], Classes]:
        """The kept steps' facts with the map's misreads among them, and the excerpt's classes: each
        misread may be at a dstate of the class its expected view makes (the class keys of this excerpt:
        its headings are its own)."""
        taken = [t for t in keep if t in self.misreads]
        facts = facts + [self.misreads[t][0] for t in taken]
        classes = prepass(self.theory, facts, self.depth).classes(keep)
        key_of = dict(zip(classes.times, (classes.keys[c] for c in classes.of_time)))
        return facts + [MAY_BE(t, key_with_view(key_of[t], self.misreads[t][1]))
                        for t in taken if key_of[t] is not None], classes

    # ---------------------------------------------------------------------------------------------
    # Different: evidence, the axioms it needs, and where each fails
    # ---------------------------------------------------------------------------------------------

    def prove(self, cmap: CognitiveMap, a: int, b: int, names: tuple[str, str], kind: str = "same") -> dict:
        """The fields of an explanation that refutes a supposition: that a and b are one dstate (``same``:
        a "different" verdict) or that they are two (``apart``: a "same" one); the minimal evidence, the
        axioms it needs, where each fails."""
        verdict = "different" if kind == "same" else "same"
        window = self.window(a, b, kind)
        if window is None:
            if kind != "same":
                return {"verdict": verdict, "sentence":
                        f"No map of the experience keeps t{a} ({names[0]}) and t{b} ({names[1]}) apart, but no "
                        f"contradiction follows from the {2 * self.explainer.max_window} steps around them."}
            return {"verdict": verdict, "sentence":
                    f"Every minimal map keeps t{a} ({names[0]}) and t{b} ({names[1]}) apart, but no contradiction "
                    f"follows from the {2 * self.explainer.max_window} steps around them: merging them would cost "
                    "more dstates elsewhere (minimality), not break an axiom."}
        evidence = self.minimal_evidence(a, b, window, kind)
        axioms, failures = self.failures(cmap, a, b, evidence, kind)
        return {"verdict": verdict, "evidence": evidence, "axioms": axioms, "failures": failures,
                "sentence": _sentence(a, b, names, evidence, failures, self.tableau, kind)}

    def window(self, a: int, b: int, kind: str = "same") -> list[int] | None:
        """The fewest steps around a and b (doubling) in which the supposition (``kind``: a and b one
        dstate, or two) holds in no map."""
        n, w = len(self.tableau), 0
        while True:
            keep = sorted({t for c in (a, b) for t in range(max(0, c - w), min(n, c + w + 1))}
                          | (set(range(min(a, b), max(a, b) + 1)) if abs(a - b) <= 2 * w + 4 else set())
                          | self.pinned)
            if not self.can_be(a, b, keep, kind):
                return keep
            if w >= self.explainer.max_window or len(keep) == n:
                return None
            w = max(1, 2 * w)

    def minimal_evidence(self, a: int, b: int, keep: Sequence[int], kind: str = "same") -> list[int]:
        kept = list(keep)
        for t in sorted(kept, key=lambda t: -min(abs(t - a), abs(t - b))):
            if t in (a, b) or t in self.pinned:
                continue
            trial = [s for s in kept if s != t]
            if not self.can_be(a, b, trial, kind):
                kept = trial
        return kept

    def can_be_same(self, a: int, b: int, keep: Sequence[int] | None = None) -> bool:
        return self.can_be(a, b, keep, "same")

    def can_be(self, a: int, b: int, keep: Sequence[int] | None = None, kind: str = "same") -> bool:
        """Whether some map of the kept steps (default: all) that satisfies the axioms has a and b one
        dstate (``kind`` ``same``) or two (``apart``), however many dstates it needs."""
        keep = list(range(len(self.tableau))) if keep is None else sorted(keep)
        key = (kind, a, b, tuple(keep), tuple(self._assumed_within(keep)))
        if key not in self.answers:
            facts = self.asked(a, b, keep, kind)
            self.answers[key] = facts is not None and bool(
                self._solve(Grounding(self.theory, facts, self.depth).ground()).satisfiable)
        return self.answers[key]

    def asked(self, a: int, b: int, keep: list[int], kind: str = "same") -> list[Symbol] | None:
        """The kept steps' facts, supposing a and b are one dstate (``kind`` ``same``; None when they are not
        even in one class: they differ in a feature every time point shows, e.g. the view) or two
        (``apart``: a person's apart of them), with every partition of each class allowed (as many dstates
        as time points), so that "cannot" means in no map at all."""
        # (an apart is a feature of its two time points: the classes are those it makes)
        supposed = [] if kind == "same" else assertion_facts([Assertion("apart", a, b)])
        facts, classes = self.with_misreads(self.excerpt(keep) + self.assumed_in(keep) + supposed, keep)
        if None in classes.keys:
            return None
        if kind != "same":
            return facts + classes.layout(len(keep))
        if not classes.same_class(a, b):
            return None
        return facts + classes.layout(len(keep)) + [SAME_ASKED(a, b)]

    def failures(self, cmap: CognitiveMap, a: int, b: int, evidence: list[int],
                 kind: str = "same") -> tuple[list[RuleRef], list[Failure]]:
        asked = self.asked(a, b, evidence, kind)
        if asked is None:
            return self.feature_failure(a, b, evidence)
        traced = Grounding(self.theory, asked + [FINEST_MAP()], self.depth, instrumented=True).ground()
        inst = traced.rules
        needed = self.needed_constraints(traced)
        out = []
        for r in needed:
            model = self.finest_model(traced, [x for x in needed if x != r])
            if model is None:
                continue
            derivations = Derivations.of(model)
            instance = sorted(derivations.violated.get(r, []))[0]
            names = Names.of(model, cmap, (a, b))
            shown: set = set()
            premises = [node(p, derivations, inst, names, shown) for p in instance]
            out.append(Failure(inst.rules[r], premises, merged(model)))
        return [inst.rules[r] for r in needed], out

    def feature_failure(self, a: int, b: int, evidence: list[int]) -> tuple[list[RuleRef], list[Failure]]:
        """a and b differ in a feature every time point shows: no supposition needed, the features'
        own derivations are the proof."""
        facts = self.excerpt(evidence) + self.assumed_in(evidence)
        if any(t in self.misreads for t in evidence):  # else no prepass is needed: nothing to add
            facts, _ = self.with_misreads(facts, evidence)
        traced = Grounding(self.theory, facts, self.depth, instrumented=True).ground()
        inst = traced.rules
        symbols = [sa.symbol for sa in traced.control.symbolic_atoms if sa.is_fact]
        derivations = Derivations.of(symbols)
        mine = {t: {(f, x) for s, f, x in FEATURE.args(symbols) if s.number == t} for t in (a, b)}
        grouping = {args[0] for args in SHOWN_BY_ALL.args(symbols)}
        clash = sorted(((f, x, y) for f, x in mine[a] for g, y in mine[b] if f == g and f in grouping and x != y),
                       key=lambda c: (str(c[0]) != "view", str(c)))  # the view first: the paper's own reason
        rule = _rule_named(inst, "one_value_per_feature")
        names = Names({}, {}, (a, b))
        premises = []
        for f, x, y in clash[:1]:
            for t, v in ((a, x), (b, y)):
                premises.append(node(FEATURE(t, f, v), derivations, inst, names, set()))
        return ([rule] if rule else []), ([Failure(rule, premises, [[a, b]])] if rule else [])

    # ---------------------------------------------------------------------------------------------
    # Solving on the instrumented theory
    # ---------------------------------------------------------------------------------------------

    def _solve(self, grounding: Grounding, assumptions=(), on_model=None):
        """Solve, giving up at the deadline with SolveTimeout (grounding, done before, cannot be cut short)."""
        result = grounding.solve(self.deadline, on_model, assumptions)
        if result is None:
            limit = self.deadline.limit_s
            raise SolveTimeout(f"time limit of {limit:g} s reached while explaining; try a larger --time-limit or "
                               "fewer levels", time_limit_s=limit, stage="explaining")
        return result

    def needed_constraints(self, traced: Grounding) -> list[int]:
        """A subset-minimal set of the levels' constraints that still rules the supposition out (deletion:
        switch each off in turn and keep it off if the contradiction stands). No optimising here."""
        traced.control.configuration.solve.opt_mode = "ignore"
        needed = list(traced.rules.switchable)
        for r in list(needed):
            trial = [x for x in needed if x != r]
            if not self._solve(traced, _switches(traced.rules, trial)).satisfiable:
                needed = trial
        return needed

    def finest_model(self, traced: Grounding, on: Sequence[int]) -> list[Symbol] | None:
        """The map with the most dstates that keeps the constraints ``on`` (and the supposition): only the
        merges they force. All its atoms."""
        traced.control.configuration.solve.opt_mode = "opt"
        best: list[list[Symbol]] = []
        self._solve(traced, _switches(traced.rules, on), lambda m: best.append(m.symbols(atoms=True)))
        return best[-1] if best else None


def _switches(inst: Instrumented, on: Sequence[int]) -> list[tuple[Symbol, bool]]:
    on_set = set(on)
    return [(inst.on(r), r in on_set) for r in inst.switchable]


def _rule_named(inst: Instrumented, name: str) -> RuleRef | None:
    return next((r for r in inst.rules if r.name == name), None)


def _sentence(a: int, b: int, names: tuple[str, str], evidence: list[int], failures: list[Failure],
              tableau: Tableau, kind: str = "same") -> str:
    """One paragraph for a person: what breaks if a and b are one dstate (or, ``kind`` ``apart``, two),
    and on which steps."""
    head = f"t{a} ({names[0]}) and t{b} ({names[1]}) cannot be {'one dstate' if kind == 'same' else 'different dstates'}"
    if not failures:
        return head + "."
    f = failures[0]
    because = " and ".join(p.text for p in f.premises)
    told = "; ".join(_step_text(tableau, t, t == evidence[-1] or t + 1 not in evidence) for t in evidence)
    return f"{head}: if they were, {because} - which {f.rule.name} forbids. The experience that shows it: {told}."


def _step_text(tableau: Tableau, t: int, last: bool) -> str:
    """A step of the evidence: its view and, unless the next step is not evidence, its action."""
    act = "" if last else action_text(tableau.steps[t].action)
    return f"t{t} view {tableau.steps[t].view}" + (f", {act}" if act else "")


# -------------------------------------------------------------------------------------------------
# Same: minimality, how far the futures agree, what would test them
# -------------------------------------------------------------------------------------------------

def _same(tableau: Tableau, cmap: CognitiveMap, a: int, b: int, angles: list[int]) -> dict:
    """The fields of a "same" explanation."""
    a, b = sorted((a, b))
    agree = _agreeing_steps(tableau, a, b, angles)
    d = cmap.dstate_of[a]
    return {"verdict": "same", "agree_steps": agree, "suggestion": _suggest(tableau, cmap, a, b, agree, angles),
            "sentence": f"t{a} and t{b} are both {d} in every minimal map: nothing in the experience proves them "
                        f"different, so by minimality they are one dstate (same view {cmap.views.get(d)!r}; what "
                        f"followed them agrees for {agree} step(s))."}


def _agreeing_steps(tableau: Tableau, a: int, b: int, angles: list[int]) -> int:
    """How many steps after a and after b the robot did the same (as the causal level names actions)
    and then saw the same view."""
    n, k = len(tableau), 0
    while b + k + 1 < n and _action(tableau, a + k, angles) == _action(tableau, b + k, angles) \
            and tableau.steps[a + k + 1].view == tableau.steps[b + k + 1].view:
        k += 1
    return k


def _action(tableau: Tableau, t: int, angles: list[int]) -> str | None:
    """The action from t as the causal level tells actions apart (a turn by its type's angle, or a
    travel whatever its distance), in words."""
    term = action_symbol(tableau.steps[t].action, angles[t] if t < len(angles) else 0)
    return None if term is None else action_word(term)


def _suggest(tableau: Tableau, cmap: CognitiveMap, a: int, b: int, agree: int, angles: list[int]) -> list[str]:
    """Experience that would test whether a and b are one dstate. If the robot did different things
    after them, repeat at b's dstate what it did after a; otherwise try, at their dstate, an action of
    the tableau's own vocabulary never taken there."""
    n = len(tableau)
    after_a, after_b = _action(tableau, a + agree, angles), (
        _action(tableau, b + agree, angles) if b + agree < n else None)
    d = cmap.dstate_of[a]
    if after_a and after_b and after_a != after_b:
        seq = [_action(tableau, a + i, angles) for i in range(agree + 1)]
        return [f"when at {d} again, do what followed t{a}: {', then '.join(seq)} (t{b} was followed by "
                f"{after_b} instead): the same views again would confirm one dstate, others would prove two"]
    vocabulary = dict.fromkeys(_action(tableau, t, angles) for t in range(n - 1))
    taken = {_action(tableau, t, angles) for t in range(n - 1) if cmap.dstate_of[t] == d}
    return [f"when at {d} again: {x} (never done at {d} so far; if t{a} and t{b} were different dstates, "
            "what follows could show it)" for x in vocabulary if x not in taken]


def time_points(cmap: CognitiveMap, a, b) -> tuple[int, int]:
    """Time points for the question: numbers and ``tN`` name time points; dstate names (``S4``) the
    closest pair of their visits."""
    n = len(cmap.dstate_of)

    def visits(x) -> list[int]:
        text = str(x).strip()
        if re.fullmatch(r"t?\d+", text):
            t = int(text.lstrip("t"))
            if not 0 <= t < n:
                raise ExplainError(f"time point {text} is not in the tableau (it has t0..t{n - 1})")
            return [t]
        found = [t for t, d in enumerate(cmap.dstate_of) if d == text]
        if not found:
            raise ExplainError(f"{text!r} is neither a time point (t0..t{n - 1}) nor a dstate of the map "
                               f"({', '.join(dict.fromkeys(cmap.dstate_of))})")
        return found

    pairs = [(abs(x - y), x, y) for x in visits(a) for y in visits(b) if x != y] or \
        [(0, x, x) for x in visits(a)]
    _, x, y = min(pairs)
    return x, y
