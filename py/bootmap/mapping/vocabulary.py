"""The vocabulary shared by Python and the axioms: every predicate that crosses the boundary, once.

The .lp files in ``asp/`` and the Python that meets them must agree on predicate names and arities. They
are written here, each with its role and, for the ones a proof shows, how it reads to a person. Nothing
else in bootmap names a predicate by a bare string: facts are built by calling a :class:`Predicate`
(``VIEW(3, "V1")`` is the symbol ``view(3, "V1")``), and models are read through one
(``IS.args(symbols)``). :func:`mismatches` compares this table with the signatures clingo's parser
finds in the axiom files, and a test runs it, so renaming a predicate in an .lp file fails a test
instead of a user's explanation.

Roles:

* ``tableau``: facts of the experience, built by :mod:`bootmap.mapping.facts` (the axioms read them);
* ``layout``: facts that lay out one search (core/partition.lp reads them);
* ``question``: facts an explanation adds (core/ask.lp reads them);
* ``assertion``: what a person says about the map (core/assert.lp reads them);
* ``derived``: what the axioms derive, read back by Python or shown in a proof.

Phrases are ``str.format`` patterns over the atom's arguments; ``{P1}`` names argument 1 as a place.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable, Iterator, Sequence

import clingo
from clingo import Function, Number, String, Symbol, ast

#: A fixed quantum in degrees (`--quantum 15`), the independent checker's rounding (tests/support/check.py); the
#: resolver learns the robot's action types instead unless it is given one (see motion.py, motion.quantise).
QUANTUM_DEG = 15.0
#: How many actions ahead the causal level compares what time points saw (``#const future_depth``).
FUTURE_DEPTH = 8
#: The name of that constant in causal.lp.
FUTURE_DEPTH_CONST = "future_depth"
#: What one dstate costs where misreads are priced (``#const dstate_cost`` in core/partition.lp).
DSTATE_COST = 4
DSTATE_COST_CONST = "dstate_cost"
#: The program part of core/prepass.lp, grounded beside ``base`` in the prepass only.
PREPASS_PART = "prepass"


@dataclass(frozen=True)
class Functor:
    """A name and an arity: what builds a symbol (an atom, or a term inside one) and recognises it."""

    name: str
    arity: int

    @property
    def signature(self) -> tuple[str, int]:
        return self.name, self.arity

    def __call__(self, *args: int | str | Symbol) -> Symbol:
        """The symbol with these arguments: ints become numbers, str become clingo *strings* (never
        constants: a user's label is data, not program text)."""
        if len(args) != self.arity:
            raise TypeError(f"{self.name}/{self.arity} takes {self.arity} arguments, got {len(args)}")
        return Function(self.name, [_term(a) for a in args])

    def matches(self, symbol: Symbol) -> bool:
        return symbol.type == clingo.SymbolType.Function and symbol.name == self.name \
            and len(symbol.arguments) == self.arity


@dataclass(frozen=True)
class Predicate(Functor):
    """One predicate of the boundary: name, arity, role, and how an atom of it reads to a person."""

    role: str
    phrase: str | None = None

    def args(self, symbols: Iterable[Symbol]) -> Iterator[Sequence[Symbol]]:
        """The arguments of each atom of this predicate among ``symbols`` (e.g. a model)."""
        for s in symbols:
            if self.matches(s):
                yield s.arguments

    def facts_in(self, control: clingo.Control) -> Iterator[Sequence[Symbol]]:
        """The arguments of each atom of this predicate a grounded control holds as a fact."""
        for sa in control.symbolic_atoms.by_signature(self.name, self.arity):
            if sa.is_fact:
                yield sa.symbol.arguments


@dataclass(frozen=True)
class Term(Functor):
    """A function term the axioms build or read (an argument of a predicate, not an atom), with what it
    means. Python makes and reads these terms only through their :class:`Term` (:data:`TERMS`), and a
    test finds each in the .lp files with this name and arity."""

    meaning: str
    python_only: bool = False  # made by Python alone; the rules take it as any other term


class Atoms:
    """A model's atoms grouped by predicate in one pass (reading a symbol's name and arguments is a call
    into clingo each): ``atoms[IS]`` lists the arguments of every ``is/2`` atom. The models of one search
    share most of their atoms: a ``read`` dict given to each remembers every symbol read (a stream's
    resolve with eleven minimal maps read them in 0.27 s, one at a time)."""

    def __init__(self, symbols: Iterable[Symbol], read: dict[Symbol, tuple] | None = None):
        self._args: dict[tuple[str, int], list[Sequence[Symbol]]] = {}
        for s in symbols:
            known = None if read is None else read.get(s)
            if known is None:
                args = s.arguments
                known = ((s.name, len(args)), args)
                if read is not None:
                    read[s] = known
            self._args.setdefault(known[0], []).append(known[1])

    def __getitem__(self, p: Predicate) -> list[Sequence[Symbol]]:
        return self._args.get(p.signature, [])

    def plus(self, more: dict[Predicate, list[Sequence[Symbol]]]) -> "Atoms":
        """These atoms and more, given by predicate as their arguments (atoms Python knows without reading
        a model)."""
        other = Atoms(())
        other._args = dict(self._args)
        for p, rows in more.items():
            other._args[p.signature] = other._args.get(p.signature, []) + list(rows)
        return other


def _term(x: int | str | Symbol) -> Symbol:
    if isinstance(x, bool):
        raise TypeError("booleans are not terms")
    if isinstance(x, int):
        return Number(x)
    if isinstance(x, str):
        return String(x)
    return x


# --------------------------------------------------------------------------------------------------
# The tableau (causal.lp and metrical.lp read these)
# --------------------------------------------------------------------------------------------------
VIEW = Predicate("view", 2, "tableau", "at t{0} the robot saw view {1}")
TURN = Predicate("turn", 2, "tableau", "at t{0} it turned {1} degrees")
TRAVEL = Predicate("travel", 2, "tableau", "at t{0} it travelled along the path (net heading change {1} degrees)")
LENGTH = Predicate("length", 2, "tableau", "the travel from t{0} was {1} dm long")
RESUME = Predicate("resume", 1, "tableau", "the evidence resumes at t{0} after a gap (headings start afresh)")
PASSES_THROUGH = Predicate("passes_through", 0, "tableau", "the robot drove through dstates without stopping at them")

# --------------------------------------------------------------------------------------------------
# The search layout (core/partition.lp reads these)
# --------------------------------------------------------------------------------------------------
ONE_PER_CLASS = Predicate("one_per_class", 0, "layout")
SLOTS = Predicate("slots", 2, "layout")
PREV_IN_CLASS = Predicate("prev_in_class", 2, "layout")
DSTATE_BOUND = Predicate("dstate_bound", 1, "layout")
MINIMISE_DSTATES = Predicate("minimise_dstates", 0, "layout")
SUSPECT = Predicate("suspect", 2, "layout", "the view seen at t{0} may be a misread (cost {1})")
MAY_BE = Predicate("may_be", 2, "layout")
CLASSES_GIVEN = Predicate("classes_given", 0, "layout", "the class keys are given (worked out from the steps)")
FIXED = Predicate("fixed", 2, "layout", "t{0} is at {1} in the map being checked")

# --------------------------------------------------------------------------------------------------
# Questions (core/ask.lp reads these)
# --------------------------------------------------------------------------------------------------
SAME_ASKED = Predicate("same_asked", 2, "question", "suppose t{0} and t{1} are one dstate")
FINEST_MAP = Predicate("finest_map", 0, "question")

# --------------------------------------------------------------------------------------------------
# A person's assertions (core/assert.lp reads these; bootmap.mapping.assertions builds them)
# --------------------------------------------------------------------------------------------------
ASSERTED_SAME = Predicate("asserted_same", 2, "assertion", "a person says t{0} and t{1} are one dstate")
ASSERTED_APART = Predicate("asserted_apart", 2, "assertion", "a person says t{0} and t{1} are different dstates")
PREFERRED_SAME = Predicate("preferred_same", 3, "assertion",
                           "a person prefers t{0} and t{1} one dstate (keeping them apart costs {2})")
PREFERRED_APART = Predicate("preferred_apart", 3, "assertion",
                            "a person prefers t{0} and t{1} apart (one dstate costs {2})")

# --------------------------------------------------------------------------------------------------
# What the axioms derive: read back by Python, or shown in proofs
# --------------------------------------------------------------------------------------------------
# core/partition.lp
CLASS_KEY = Predicate("class_key", 2, "derived")
SHOWN_BY_ALL = Predicate("shown_by_all", 1, "derived")
# core/prepass.lp, grounded in the prepass only: the features that tell time points of a class apart.
PARTIAL = Predicate("partial", 4, "derived")
VARIES = Predicate("varies", 2, "derived")
TELLING = Predicate("telling", 3, "derived")
CANDIDATE = Predicate("cand", 2, "derived")
MISREAD = Predicate("misread", 1, "derived", "the view seen at t{0} was a misread")
# causal.lp
TIME = Predicate("time", 1, "derived")
IS = Predicate("is", 2, "derived", "t{0} is at {1}")
DSTATE = Predicate("dstate", 1, "derived")
ACTION = Predicate("action", 2, "derived", "from t{0} the robot's action was {1}")
FEATURE = Predicate("feature", 3, "derived", "t{0} shows {1} {2}")
DSTATE_FEATURE = Predicate("dstate_feature", 3, "derived", "{0} shows {1} {2}")
NEXT = Predicate("next", 3, "derived", "{1} at {0} leads to {2}")
VIEW_OF = Predicate("view_of", 2, "derived", "{0} shows view {1}")
# metrical.lp
HEADING = Predicate("heading", 3, "derived", "at t{0} the robot faced {2} degrees (counted from t{1})")
HEADING_OF = Predicate("heading_of", 2, "derived", "{0} faces {1} degrees")
# topological.lp
TURN_LINK = Predicate("turn_link", 3, "derived", "turning {2} degrees at {0} reaches {1}, at the same place")
AROUND = Predicate("around", 2, "derived", "turning around at {0} reaches {1}")
TRAVEL_LINK = Predicate("travel_link", 2, "derived", "travelling on from {0} reaches {1}")
TURN_LINKED = Predicate("turn_linked", 2, "derived", "{0} and {1} are linked by a turn")
FLIP = Predicate("flip", 2, "derived")
SAME_PLACE = Predicate("same_place", 2, "derived", "{0} and {1} are at one place")
PLACE_OF = Predicate("place_of", 2, "derived", "{0} is at {P1}")
SAME_PATH = Predicate("same_path", 3, "derived", "{1} faces along {0}'s path ({2} way)")
PATH_REP = Predicate("path_rep", 2, "derived", "{0}'s path is the path of {1}")
PATH_OF = Predicate("path_of", 3, "derived", "{0} faces {2} along the path of {1}")
AHEAD = Predicate("ahead", 2, "derived", "{P1} lies ahead of {0}")
BEHIND = Predicate("behind", 2, "derived", "{P1} lies behind {0}")
ON_PATH = Predicate("on_path", 2, "derived", "{P1} lies on the path {0} faces")
RIGHT = Predicate("right", 2, "derived", "{P1} lies right of the path {0} faces")
LEFT = Predicate("left", 2, "derived", "{P1} lies left of the path {0} faces")

PREDICATES: tuple[Predicate, ...] = tuple(v for v in list(globals().values()) if isinstance(v, Predicate))
_BY_SIGNATURE = {p.signature: p for p in PREDICATES}

# --------------------------------------------------------------------------------------------------
# Function terms
# --------------------------------------------------------------------------------------------------

CANDIDATE_DSTATE = Term("d", 2, "a candidate dstate: slot I of class K, d(K, I) (core/partition.lp)")
CLASS_KEY_TERM = Term("k", 3, "a class key: value X of grouping feature F, then the rest, k(F, X, Rest) (core/partition.lp)")
NIL = Term("nil", 0, "the end of a class key or of an action sequence")
FIXED_DSTATE = Term("s", 1, "a dstate of a partition being checked, fixed(T, s(N))", python_only=True)
SEQUENCE = Term("c", 2, "a sequence of actions: the first, then the rest, c(A, Rest) (causal.lp's futures)")
AFTER = Term("after", 1, "the feature: what the robot saw after a sequence of actions, after(S) (causal.lp)")
VIEW_FEATURE = Term("view", 0, "the feature: the view seen")
HEADING_FEATURE = Term("heading", 0, "the feature: the heading, counted from t0 (metrical.lp)")
HEADING_SINCE = Term("heading_since", 1, "the feature: the heading counted from where the steps resume after a gap")
LENGTH_FEATURE = Term("length", 0, "the feature: a travel's length type (metrical.lp)")
SAME, OPPOSITE = Term("same", 0, "one way along a path"), Term("opposite", 0, "the other way along a path")
POS, NEG = Term("pos", 0, "the way a path's least dstate faces"), Term("neg", 0, "the other way")
TOLD_APART = Term("told_apart", 2, "the feature: a person's word that T1 and T2 differ, told_apart(T1, T2); "
                                   "T1 shows it with value 1, T2 with value 2 (core/assert.lp)")
TOLD_AFTER = Term("told_after", 2, "the feature: a person's word seen after a sequence of actions, told_after(S, "
                                   "told_apart(T1, T2)) (core/assert.lp)")
BROKEN_SAME = Term("broken_same", 0, "a preference for one dstate, broken (what core/assert.lp's cost counts)")
BROKEN_APART = Term("broken_apart", 0, "a preference for two dstates, broken (what core/assert.lp's cost counts)")
TURN_ACTION = Term("turn", 1, "a turn by its angle type, turn(A) (causal.lp's action/2)")
TRAVEL_ACTION = Term("travel", 0, "a travel, whatever its length (causal.lp's action/2)")
TRAVEL_BY_LENGTH = Term("travel", 1, "a travel by its length type, travel(L), where the robot drove through dstates")
TRAVEL_BENT = Term("travel", 2, "a travel by its length type and its net heading change, travel(L, C), where the "
                                "robot drove through dstates and round a corner on the way")

TERMS: tuple[Term, ...] = tuple(v for v in list(globals().values()) if isinstance(v, Term))

#: Atoms a proof need not spell out: bookkeeping of the search layout.
QUIET = frozenset(p.signature for p in (TIME, DSTATE, CANDIDATE, FLIP))


def predicate(symbol: Symbol) -> Predicate | None:
    """The vocabulary's predicate of an atom, or None (a user's own predicate, or not an atom)."""
    if symbol.type != clingo.SymbolType.Function:
        return None
    return _BY_SIGNATURE.get((symbol.name, len(symbol.arguments)))


# --------------------------------------------------------------------------------------------------
# Actions, as the causal level names them
# --------------------------------------------------------------------------------------------------

def fixed_dstate(n: int) -> Symbol:
    """``s(N)``: the dstate a partition being checked puts a time point at (``fixed(T, s(N))``): any
    numbering of the partition's groups will do."""
    return FIXED_DSTATE(n)


def action_term(kind: str, angle: int, length: int | None = None) -> Symbol:
    """The term causal.lp makes of an action (``turn_action``, ``travel_action``): a turn by its
    quantised angle, ``turn(A)``, or ``travel`` whatever its length and bend; where the robot drove
    through dstates without stopping (``travel_action_passing``), a travel by its length type,
    ``travel(L)``, or by its length type and heading change where it bent round a corner, ``travel(L, C)``."""
    if kind == "turn":
        return TURN_ACTION(angle)
    if length is None:
        return TRAVEL_ACTION()
    return TRAVEL_BY_LENGTH(length) if angle == 0 else TRAVEL_BENT(length, angle)


def action_word(term: Symbol) -> str:
    """An action term as a person reads it: ``turn(-90)`` -> "turn -90", ``travel`` -> "travel"."""
    if TURN_ACTION.matches(term):
        return f"turn {term.arguments[0].number:+d}"
    if TRAVEL_BY_LENGTH.matches(term):
        return f"travel {term.arguments[0].number / 10:g} m"
    if TRAVEL_BENT.matches(term):
        return f"travel {term.arguments[0].number / 10:g} m turning {term.arguments[1].number:+d}"
    return term.name


# --------------------------------------------------------------------------------------------------
# Checking the table against the axiom files
# --------------------------------------------------------------------------------------------------

def signatures(files: Iterable[str | Path], also: Callable[[ast.AST], None] | None = None
               ) -> tuple[set[tuple[str, int]], set[tuple[str, int]], dict[str, str]]:
    """What clingo's parser finds in these files: the predicates in rule heads (defined), anywhere in a
    rule (used), and the ``#const`` declarations (name -> default value). ``also`` is shown every statement
    of the same parse."""
    defined: set[tuple[str, int]] = set()
    used: set[tuple[str, int]] = set()
    constants: dict[str, str] = {}

    def atoms(node, into: set) -> None:
        # Every symbolic atom inside the node, walked directly: an ast.Transformer took a third longer on the
        # stock theory (40 ms against 30), which a process's first resolve pays (Theory.map_levels).
        stack = [node]
        while stack:
            n = stack.pop()
            if n.ast_type == ast.ASTType.SymbolicAtom:
                term = n.symbol
                if term.ast_type == ast.ASTType.UnaryOperation:  # classical negation: -p(X) is of p/1
                    term = term.argument
                if term.ast_type == ast.ASTType.Function:
                    into.add((term.name, len(term.arguments)))
                elif term.ast_type == ast.ASTType.SymbolicTerm and term.symbol.type == clingo.SymbolType.Function:
                    into.add((term.symbol.name, len(term.symbol.arguments)))
                continue
            for key in n.child_keys:
                child = getattr(n, key)
                if isinstance(child, ast.AST):
                    stack.append(child)
                elif child is not None:
                    stack.extend(c for c in child if isinstance(c, ast.AST))

    def statement(stm) -> None:
        if stm.ast_type == ast.ASTType.Rule:
            atoms(stm.head, defined)
            atoms(stm.head, used)
            for lit in stm.body:
                atoms(lit, used)
        elif stm.ast_type == ast.ASTType.Minimize:
            for lit in stm.body:
                atoms(lit, used)
        elif stm.ast_type == ast.ASTType.Definition:
            constants[stm.name] = str(stm.value)
        if also is not None:
            also(stm)

    ast.parse_files([str(f) for f in files], statement)
    return defined, used, constants


def function_terms(files: Iterable[str | Path]) -> set[tuple[str, int]]:
    """Every function term (name, arity) the rules of these files build or match, atoms and ``#const``
    names left out: what :data:`TERMS` names."""
    found: set[tuple[str, int]] = set()

    class Collect(ast.Transformer):
        def visit_SymbolicAtom(self, atom):  # the atom's own name is a predicate: only its arguments
            term = atom.symbol
            if term.ast_type == ast.ASTType.Function:
                for arg in term.arguments:
                    self(arg)
            return atom

        def visit_Function(self, term):
            found.add((term.name, len(term.arguments)))
            for arg in term.arguments:
                self(arg)
            return term

        def visit_SymbolicTerm(self, term):
            if term.symbol.type == clingo.SymbolType.Function:
                found.add((term.symbol.name, len(term.symbol.arguments)))
            return term

    def statement(stm) -> None:
        if stm.ast_type in (ast.ASTType.Rule, ast.ASTType.Minimize):
            Collect()(stm)

    ast.parse_files([str(f) for f in files], statement)
    return found - {(name, 0) for name in signatures(files)[2]}


def term_mismatches(files: Iterable[str | Path]) -> list[str]:
    """How :data:`TERMS` and these axiom files disagree (empty when they agree): a term of the table no
    rule uses (but Python's own), or a term the rules use that the table does not name."""
    found = function_terms(files)
    table = {(t.name, t.arity) for t in TERMS}
    problems = [f"no rule uses the term {t.name}/{t.arity}" for t in TERMS
                if not t.python_only and (t.name, t.arity) not in found]
    problems += [f"the rules use the term {n}/{a}, which the vocabulary does not name" for n, a in sorted(found - table)]
    return problems


def mismatches(files: Iterable[str | Path]) -> list[str]:
    """How the vocabulary and these axiom files disagree (empty when they agree): a predicate Python
    builds that no rule reads, one Python reads that no rule defines, a ``future_depth`` missing or with
    another default than :data:`FUTURE_DEPTH`."""
    defined, used, constants = signatures(files)
    problems = []
    for p in PREDICATES:
        where = defined if p.role == "derived" else used
        if p.signature not in where:
            verb = "defines" if p.role == "derived" else "reads"
            problems.append(f"no rule {verb} {p.name}/{p.arity} ({p.role})")
    for name, value in ((FUTURE_DEPTH_CONST, FUTURE_DEPTH), (DSTATE_COST_CONST, DSTATE_COST)):
        if name not in constants:
            problems.append(f"no #const {name}")
        elif constants[name] != str(value):
            problems.append(f"#const {name} = {constants[name]}, but Python's default is {value}")
    return problems
