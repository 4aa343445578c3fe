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
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import clingo
from clingo import Function, Number, Symbol

from .cogmap import CognitiveMap, action_text
from .errors import ExplainError, SolveTimeout
from .facts import add_facts, excerpt_facts, quantise, tableau_facts
from .resolver import Resolver
from .tableau import Tableau, Turn
from .trace import Derivations, Instrumented, RuleRef, load_instrumented

# Atoms a proof need not spell out: bookkeeping of the search layout.
_QUIET = {("time", 1), ("dstate", 1), ("cand", 2), ("flip", 2)}
# Tableau facts: where a proof touches the experience.
_OBSERVATIONS = {"view", "turn", "travel", "resume_heading"}


@dataclass
class ProofNode:
    """One atom of a proof and how it holds: by a rule instance (``rule`` and ``premises``), as a
    tableau observation (``step``), or as the supposition or the dstate assignment (``rule`` None)."""

    atom: str
    text: str
    rule: RuleRef | None = None
    step: int | None = None
    premises: list["ProofNode"] = field(default_factory=list)

    def to_dict(self) -> dict:
        out: dict = {"atom": self.atom, "text": self.text}
        if self.rule:
            out["rule"] = _rule_dict(self.rule)
        if self.step is not None:
            out["step"] = self.step
        if self.premises:
            out["premises"] = [p.to_dict() for p in self.premises]
        return out

    def rules_cited(self) -> list[str]:
        names = [self.rule.name] if self.rule else []
        for p in self.premises:
            names += p.rules_cited()
        return names

    def lines(self, indent: int = 0) -> list[str]:
        why = f"   [{self.rule.cite()}]" if self.rule else (f"   [step t{self.step}]" if self.step is not None else "")
        out = ["  " * indent + f"- {self.text}{why}"]
        for p in self.premises:
            out += p.lines(indent + 1)
        return out


@dataclass
class Failure:
    """An axiom the supposition breaks: the rule, the instance where it fails, and why its premises
    hold, in the finest map that keeps every other axiom of the proof."""

    rule: RuleRef
    premises: list[ProofNode]
    merged: list[list[int]]     # time points that map puts together (the supposition and what it forced)

    def to_dict(self) -> dict:
        return {"rule": _rule_dict(self.rule), "premises": [p.to_dict() for p in self.premises],
                "merged": self.merged}


@dataclass
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
    stats: dict = field(default_factory=dict)

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
                "axioms": [_rule_dict(r) for r in self.axioms],
                "failures": [f.to_dict() for f in self.failures], "rules_cited": self.rules_cited(),
                "agree_steps": self.agree_steps, "suggestion": self.suggestion,
                "alternatives": self.alternatives, "levels": self.levels, "stats": self.stats}

    def to_text(self) -> str:
        out = [f"t{self.a} ({self.names[0]}) vs t{self.b} ({self.names[1]}): {self.verdict}",
               f"levels: {', '.join(self.levels)}", "", self.sentence]
        if self.evidence:
            out += ["", "evidence (these steps alone force it; dropping any one does not): "
                    + ", ".join(f"t{t}" for t in self.evidence)]
        if self.axioms:
            out += ["axioms the contradiction needs: " + ", ".join(r.cite() for r in self.axioms)]
        for f in self.failures:
            merged = "; ".join(" = ".join(f"t{t}" for t in group) for group in f.merged)
            out += ["", f"Suppose t{self.a} and t{self.b} are one dstate (which makes {merged}).",
                    f"Then {f.rule.cite()} fails, because:"]
            for p in f.premises:
                out += p.lines(1)
        if self.suggestion:
            out += ["", "experience that would test them:"] + [f"  {s}" for s in self.suggestion]
        for alt in self.alternatives:
            out += [f"minimal map {alt['map']}: t{self.a} is {alt['a']}, t{self.b} is {alt['b']}"
                    + (" (apart)" if alt["apart"] else " (same)")]
        return "\n".join(out)


def _rule_dict(r: RuleRef) -> dict:
    return {"name": r.name, "level": r.level, "file": Path(r.file).name, "line": r.line}


@dataclass
class Explainer:
    """Explain pairs of time points of a tableau.

    Parameters
    ----------
    axioms, levels, quantum_deg, time_limit
        As for :class:`bootmap.resolver.Resolver` (the levels are the axiom families in play).
    max_window : int
        The proof is looked for in windows of steps around a and b, doubling up to this many steps
        on each side.
    """

    axioms: str | Path | None = None
    levels: Sequence[str] | None = None
    quantum_deg: float = 15.0
    time_limit: float | None = 60.0
    max_window: int = 32
    resolver: Resolver = field(init=False, repr=False)
    _deadline: float | None = field(default=None, init=False, repr=False)
    _cached: tuple[Tableau, list[Symbol]] | None = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        self.resolver = Resolver(self.axioms, self.levels, self.quantum_deg, self.time_limit)

    def explain(self, tableau: Tableau, a: int | str, b: int | str) -> Explanation:
        """Explain whether ``a`` and ``b`` (time points, ``"t4"``, or dstate names such as ``"S4"``) are
        one dstate. Raises :class:`ExplainError` for names the map does not have."""
        start = time.perf_counter()
        self._deadline = None if self.time_limit is None else start + self.time_limit
        cmap = self.resolver.resolve(tableau)
        a, b = _time_points(cmap, a, b)
        maps = [cmap.dstate_of] + cmap.alternatives
        apart = [m[a] != m[b] for m in maps]
        e = Explanation(a, b, (cmap.dstate_of[a], cmap.dstate_of[b]), "", "",
                        levels=list(self.resolver.theory.levels))
        if all(apart):
            self._prove_apart(tableau, cmap, e)
        elif not any(apart):
            self._same(tableau, cmap, e)
        else:
            e.verdict = "undecided"
            e.alternatives = [{"map": i + 1, "a": m[a], "b": m[b], "apart": m[a] != m[b]} for i, m in enumerate(maps)]
            e.sentence = (f"The minimal maps disagree: {sum(apart)} of {len(maps)} keep t{a} and t{b} apart. "
                          "More experience is needed to decide.")
        e.stats["total_s"] = round(time.perf_counter() - start, 4)
        return e

    # ---------------------------------------------------------------------------------------------
    # Different: evidence, the axioms it needs, and where each fails
    # ---------------------------------------------------------------------------------------------

    def _prove_apart(self, tableau: Tableau, cmap: CognitiveMap, e: Explanation) -> None:
        e.verdict = "different"
        window = self._window(tableau, e.a, e.b)
        if window is None:
            e.sentence = (f"Every minimal map keeps t{e.a} ({e.names[0]}) and t{e.b} ({e.names[1]}) apart, but "
                          f"no contradiction follows from the {2 * self.max_window} steps around them: "
                          "merging them would cost more dstates elsewhere (minimality), not break an axiom.")
            return
        e.evidence = self.minimal_evidence(tableau, e.a, e.b, window)
        e.axioms, e.failures = self._failures(tableau, cmap, e.a, e.b, e.evidence)
        e.sentence = _sentence(e, tableau)

    def _window(self, tableau: Tableau, a: int, b: int) -> list[int] | None:
        """The fewest steps around a and b (doubling) in which a and b cannot be one dstate."""
        n, w = len(tableau), 0
        while True:
            keep = sorted({t for c in (a, b) for t in range(max(0, c - w), min(n, c + w + 1))}
                          | (set(range(min(a, b), max(a, b) + 1)) if abs(a - b) <= 2 * w + 4 else set()))
            if not self.can_be_same(tableau, a, b, keep):
                return keep
            if w >= self.max_window or len(keep) == n:
                return None
            w = max(1, 2 * w)

    def minimal_evidence(self, tableau: Tableau, a: int, b: int, keep: Sequence[int]) -> list[int]:
        """Drop steps one at a time (farthest from a and b first) while a and b still cannot be one
        dstate: what is left is subset-minimal evidence."""
        kept = list(keep)
        for t in sorted(kept, key=lambda t: -min(abs(t - a), abs(t - b))):
            if t in (a, b):
                continue
            trial = [s for s in kept if s != t]
            if not self.can_be_same(tableau, a, b, trial):
                kept = trial
        return kept

    def can_be_same(self, tableau: Tableau, a: int, b: int, keep: Sequence[int] | None = None) -> bool:
        """Can time points a and b be one dstate in some map of these steps (default: all) that
        satisfies the axioms, however many dstates it needs?"""
        keep = list(range(len(tableau))) if keep is None else sorted(keep)
        facts = self._asked(tableau, a, b, keep)
        if facts is None:
            return False
        ctl = self.resolver._control(facts, self.resolver.future_depth)
        ctl.ground([("base", [])])
        return bool(_solve_within(ctl, self._deadline, []).satisfiable)

    def _asked(self, tableau: Tableau, a: int, b: int, keep: list[int]) -> list[Symbol] | None:
        """The kept steps' facts, supposing a and b are one dstate, with every partition of each class
        allowed (as many dstates as time points), so "cannot be one dstate" means in no map at all.
        None when a and b are not even in one class (they differ in a feature every time point shows,
        e.g. the view)."""
        facts = excerpt_facts(self._facts(tableau), keep)
        classes = self.resolver.classes(self.resolver.ground_prepass(facts, self.resolver.future_depth), keep)
        if None in classes.keys or classes.of_time[keep.index(a)] != classes.of_time[keep.index(b)]:
            return None
        return facts + classes.facts(len(keep)) + [Function("same_asked", [Number(a), Number(b)])]

    def _facts(self, tableau: Tableau) -> list[Symbol]:
        """The tableau's facts, built once for all the excerpts one explanation tries."""
        if self._cached is None or self._cached[0] is not tableau:
            self._cached = (tableau, tableau_facts(tableau, self.quantum_deg))
        return self._cached[1]

    def _traced(self, facts: list[Symbol]) -> tuple[clingo.Control, Instrumented]:
        """The instrumented theory (bootmap.trace) grounded with these facts, its switches free so that
        each solve's assumptions set them."""
        ctl = clingo.Control(["--warn=none", "-c", f"future_depth={self.resolver.future_depth}"])
        inst = load_instrumented(self.resolver.theory, ctl)
        add_facts(ctl, facts)
        ctl.ground([("base", [])])
        for r in inst.switchable:
            ctl.assign_external(inst.on(r), None)
        return ctl, inst

    def _failures(self, tableau, cmap, a, b, evidence) -> tuple[list[RuleRef], list[Failure]]:
        asked = self._asked(tableau, a, b, evidence)
        if asked is None:
            return self._feature_failure(tableau, cmap, a, b, evidence)
        ctl, inst = self._traced(asked + [Function("finest_map")])
        needed = _needed_constraints(ctl, inst, self._deadline)
        failures = []
        for r in needed:
            model = _finest_model(ctl, inst, [x for x in needed if x != r], self._deadline)
            if model is None:
                continue
            derivations = Derivations.of(model)
            instance = sorted(derivations.violated.get(r, []))[0]
            names = _Names.of(model, cmap, (a, b))
            shown: set = set()
            premises = [_node(p, derivations, inst, names, shown) for p in instance]
            failures.append(Failure(inst.rules[r], premises, _merged(model)))
        return [inst.rules[r] for r in needed], failures

    def _feature_failure(self, tableau, cmap, a, b, evidence) -> tuple[list[RuleRef], list[Failure]]:
        """a and b differ in a feature every time point shows: no supposition needed, the features'
        own derivations are the proof."""
        ctl, inst = self._traced(excerpt_facts(self._facts(tableau), evidence))
        symbols = [sa.symbol for sa in ctl.symbolic_atoms if sa.is_fact]
        derivations = Derivations.of(symbols)
        mine = {t: {(s.arguments[1], s.arguments[2]) for s in symbols
                    if s.name == "feature" and s.arguments[0].number == t} for t in (a, b)}
        grouping = {s.arguments[0] for s in symbols if s.name == "shown_by_all"}
        clash = sorted(((f, x, y) for f, x in mine[a] for g, y in mine[b] if f == g and f in grouping and x != y),
                       key=lambda c: (str(c[0]) != "view", str(c)))  # the view first: the paper's own reason
        rule = _rule_named(inst, "one_value_per_feature")
        names = _Names({}, {}, (a, b))
        premises = []
        for f, x, y in clash[:1]:
            for t, v in ((a, x), (b, y)):
                atom = Function("feature", [Number(t), f, v])
                premises.append(_node(atom, derivations, inst, names, set()))
        return ([rule] if rule else []), ([Failure(rule, premises, [[a, b]])] if rule else [])

    # ---------------------------------------------------------------------------------------------
    # Same: minimality, how far the futures agree, what would test them
    # ---------------------------------------------------------------------------------------------

    def _same(self, tableau: Tableau, cmap: CognitiveMap, e: Explanation) -> None:
        e.verdict = "same"
        a, b = sorted((e.a, e.b))
        e.agree_steps = _agreeing_steps(tableau, a, b, self.quantum_deg)
        e.suggestion = _suggest(tableau, cmap, a, b, e.agree_steps, self.quantum_deg)
        d = cmap.dstate_of[a]
        e.sentence = (f"t{a} and t{b} are both {d} in every minimal map: nothing in the experience proves them "
                      f"different, so by minimality they are one dstate (same view "
                      f"{cmap.views.get(d)!r}; what followed them agrees for {e.agree_steps} step(s)).")


# -------------------------------------------------------------------------------------------------
# Solving on the instrumented theory
# -------------------------------------------------------------------------------------------------

def _solve_within(ctl: clingo.Control, deadline: float | None, assumptions, on_model=None) -> clingo.SolveResult:
    """Solve, giving up at the deadline with SolveTimeout (grounding, done before, cannot be cut short)."""
    remaining = None if deadline is None else max(0.0, deadline - time.perf_counter())
    with ctl.solve(assumptions=assumptions, on_model=on_model, async_=True) as handle:
        if not handle.wait(remaining):
            handle.cancel()
            raise SolveTimeout("time limit reached while explaining; try a larger --time-limit or fewer levels")
        return handle.get()


def _switches(inst: Instrumented, on: Sequence[int]) -> list[tuple[Symbol, bool]]:
    on_set = set(on)
    return [(inst.on(r), r in on_set) for r in inst.switchable]


def _needed_constraints(ctl: clingo.Control, inst: Instrumented, deadline: float | None) -> list[int]:
    """A subset-minimal set of the levels' constraints that still rules the supposition out (deletion:
    switch each off in turn and keep it off if the contradiction stands). No optimising here."""
    ctl.configuration.solve.opt_mode = "ignore"
    needed = list(inst.switchable)
    for r in list(needed):
        trial = [x for x in needed if x != r]
        if not _solve_within(ctl, deadline, _switches(inst, trial)).satisfiable:
            needed = trial
    return needed


def _finest_model(ctl: clingo.Control, inst: Instrumented, on: Sequence[int],
                  deadline: float | None) -> list[Symbol] | None:
    """The map with the most dstates that keeps the constraints ``on`` (and the supposition): only the
    merges they force. All its atoms."""
    ctl.configuration.solve.opt_mode = "opt"
    best: list[list[Symbol]] = []
    _solve_within(ctl, deadline, _switches(inst, on), lambda m: best.append(m.symbols(atoms=True)))
    return best[-1] if best else None


def _rule_named(inst: Instrumented, name: str) -> RuleRef | None:
    return next((r for r in inst.rules if r.name == name), None)


# -------------------------------------------------------------------------------------------------
# Reading a model as a proof
# -------------------------------------------------------------------------------------------------

def _members(model: list[Symbol]) -> dict[Symbol, list[int]]:
    out: dict[Symbol, list[int]] = {}
    for s in model:
        if s.name == "is" and len(s.arguments) == 2:
            out.setdefault(s.arguments[1], []).append(s.arguments[0].number)
    return {d: sorted(ts) for d, ts in out.items()}


def _merged(model: list[Symbol]) -> list[list[int]]:
    return sorted(ts for ts in _members(model).values() if len(ts) > 1)


@dataclass
class _Names:
    """How a proof names the dstates and places of its map: by the minimal map's names of their time
    points, so S0=S4 is the dstate the supposition makes of S0 and S4, and P0=P2 such a place."""

    dstates: dict[Symbol, str]
    places: dict[Symbol, str]
    asked: tuple[int, int]

    @classmethod
    def of(cls, model: list[Symbol], cmap: CognitiveMap, asked: tuple[int, int]) -> "_Names":
        members = _members(model)
        dstates = {d: "=".join(dict.fromkeys(cmap.dstate_of[t] for t in ts)) for d, ts in members.items()}
        at: dict[Symbol, list[int]] = {}
        for s in model:
            if s.name == "place_of" and len(s.arguments) == 2:
                at.setdefault(s.arguments[1], []).extend(members.get(s.arguments[0], []))
        places = {}
        for p, ts in at.items():
            named = [cmap.place_of.get(cmap.dstate_of[t]) for t in sorted(ts)]
            if all(named):
                places[p] = "=".join(dict.fromkeys(named))  # type: ignore[arg-type]
        return cls(dstates, places, asked)

    def place(self, term: Symbol) -> str:
        return self.places.get(term) or f"the place of {_name(term, self.dstates)}"


def _node(atom: Symbol, derivations: Derivations, inst: Instrumented, names: _Names, shown: set) -> ProofNode:
    """The proof of one atom: its rule instance and, once per atom, the proofs of its premises."""
    text = _phrase(atom, names)
    if atom.name in _OBSERVATIONS:
        return ProofNode(str(atom), text, step=atom.arguments[0].number)
    how = derivations.best.get(atom)
    label = _atom_text(atom, names.dstates)
    if how is None:
        if atom.name == "is" and atom.arguments[0].number in names.asked:
            text += " (the supposition)"
        return ProofNode(label, text)
    rule, body = how
    node = ProofNode(label, text, rule=inst.rules[rule])
    if atom in shown:
        node.text += " (shown above)"
        return node
    shown.add(atom)
    node.premises = [_node(p, derivations, inst, names, shown) for p in body
                     if (p.name, len(p.arguments)) not in _QUIET]
    return node


def _name(term: Symbol, names: dict) -> str:
    if term in names:
        return names[term]
    if term.type == clingo.SymbolType.String:
        return repr(term.string)
    return str(term)


def _atom_text(atom: Symbol, names: dict) -> str:
    if atom.type != clingo.SymbolType.Function or not atom.arguments:
        return str(atom)
    return f"{atom.name}({', '.join(_name(x, names) for x in atom.arguments)})"


# How the axioms' own predicates read to a person; anything else (a user's own) reads as its atom.
_PHRASES = {
    ("view", 2): "at t{0} the robot saw view {1}",
    ("turn", 2): "at t{0} it turned {1} degrees",
    ("travel", 2): "at t{0} it travelled along the path",
    ("is", 2): "t{0} is at {1}",
    ("action", 2): "from t{0} the robot's action was {1}",
    ("next", 3): "{1} at {0} leads to {2}",
    ("feature", 3): "t{0} shows {1} {2}",
    ("dstate_feature", 3): "{0} shows {1} {2}",
    ("heading", 2): "at t{0} the robot faced {1} degrees",
    ("resume_heading", 2): "at t{0} odometry read a heading of {1} degrees",
    ("turn_link", 3): "turning {2} degrees at {0} reaches {1}, at the same place",
    ("around", 2): "turning around at {0} reaches {1}",
    ("travel_link", 2): "travelling on from {0} reaches {1}",
    ("turn_linked", 2): "{0} and {1} are linked by a turn",
    ("same_place", 2): "{0} and {1} are at one place",
    ("place_of", 2): "{0} is at {P1}",
    ("same_path", 3): "{1} faces along {0}'s path ({2} way)",
    ("path_rep", 2): "{0}'s path is the path of {1}",
    ("ahead", 2): "{P1} lies ahead of {0}",
    ("behind", 2): "{P1} lies behind {0}",
    ("on_path", 2): "{P1} lies on the path {0} faces",
    ("right", 2): "{P1} lies right of the path {0} faces",
    ("left", 2): "{P1} lies left of the path {0} faces",
}


def _phrase(atom: Symbol, names: "_Names") -> str:
    pattern = _PHRASES.get((atom.name, len(atom.arguments))) if atom.type == clingo.SymbolType.Function else None
    if pattern is None:
        return _atom_text(atom, names.dstates)
    args = atom.arguments
    return re.sub(r"\{(P?)(\d)\}", lambda m: (names.place(args[int(m[2])]) if m[1]
                                          else _name(args[int(m[2])], names.dstates)), pattern)


def _sentence(e: Explanation, tableau: Tableau) -> str:
    """One paragraph for a person: what breaks if a and b are one dstate, and on which steps."""
    head = f"t{e.a} ({e.names[0]}) and t{e.b} ({e.names[1]}) cannot be one dstate"
    if not e.failures:
        return head + "."
    f = e.failures[0]
    because = " and ".join(p.text for p in f.premises)
    told = "; ".join(_step_text(tableau, t, t == e.evidence[-1] or t + 1 not in e.evidence) for t in e.evidence)
    return f"{head}: if they were, {because} - which {f.rule.name} forbids. The experience that shows it: {told}."


def _step_text(tableau: Tableau, t: int, last: bool) -> str:
    """A step of the evidence: its view and, unless the next step is not evidence, its action."""
    act = "" if last else action_text(tableau.steps[t].action)
    return f"t{t} view {tableau.steps[t].view}" + (f", {act}" if act else "")


# -------------------------------------------------------------------------------------------------
# Same: agreement and suggestions
# -------------------------------------------------------------------------------------------------

def _agreeing_steps(tableau: Tableau, a: int, b: int, quantum_deg: float) -> int:
    """How many steps after a and after b the robot did the same (as the causal level names actions)
    and then saw the same view."""
    n, k = len(tableau), 0
    while b + k + 1 < n and _action(tableau, a + k, quantum_deg) == _action(tableau, b + k, quantum_deg) \
            and tableau.steps[a + k + 1].view == tableau.steps[b + k + 1].view:
        k += 1
    return k


def _action(tableau: Tableau, t: int, quantum_deg: float) -> str | None:
    """The action from t as the causal level tells actions apart: a turn by its quantised angle, or a
    travel (its distance does not matter)."""
    a = tableau.steps[t].action
    if a is None:
        return None
    return f"turn {quantise(a.angle_deg, quantum_deg):+d}" if isinstance(a, Turn) else "travel"


def _suggest(tableau: Tableau, cmap: CognitiveMap, a: int, b: int, agree: int, quantum_deg: float) -> list[str]:
    """Experience that would test whether a and b are one dstate. If the robot did different things
    after them, repeat at b's dstate what it did after a; otherwise try, at their dstate, an action of
    the tableau's own vocabulary never taken there."""
    n = len(tableau)
    after_a, after_b = _action(tableau, a + agree, quantum_deg), (
        _action(tableau, b + agree, quantum_deg) if b + agree < n else None)
    d = cmap.dstate_of[a]
    if after_a and after_b and after_a != after_b:
        seq = [_action(tableau, a + i, quantum_deg) for i in range(agree + 1)]
        return [f"when at {d} again, do what followed t{a}: {', then '.join(seq)} (t{b} was followed by "
                f"{after_b} instead): the same views again would confirm one dstate, others would prove two"]
    vocabulary = dict.fromkeys(_action(tableau, t, quantum_deg) for t in range(n - 1))
    taken = {_action(tableau, t, quantum_deg) for t in range(n - 1) if cmap.dstate_of[t] == d}
    return [f"when at {d} again: {x} (never done at {d} so far; if t{a} and t{b} were different dstates, "
            "what follows could show it)" for x in vocabulary if x not in taken]


def _time_points(cmap: CognitiveMap, a, b) -> tuple[int, int]:
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
