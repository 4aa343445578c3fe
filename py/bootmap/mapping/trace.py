"""The theory, instrumented so a model says which rule instances hold in it.

Explanations need more than a yes/no from clingo: which axiom failed, for which dstates, and how its
premises were derived. This module loads the axiom files through clingo's AST and adds, beside each
rule, a twin that records it:

* a rule ``H :- B.`` also derives ``_bm_fired(R, H, (B1, ..., Bn))``: rule R derived H from the
  positive atoms B1..Bn of its body;
* an integrity constraint ``:- B.`` of a level file becomes ``:- B, _bm_on(R).`` with ``_bm_on(R)`` an
  external the explainer switches, and also derives ``_bm_violated(R, (B1, ..., Bn))`` whenever its
  body holds, so a model made with R switched off shows where R fails.

R is an index into :attr:`Instrumented.rules`, which names each rule by its ``%!`` label, file and line
(see bootmap.mapping.theory). The core files (the search layout) are loaded as they are: their constraints are
the frame of every question, not axioms under question. Nothing here touches user data: the tableau
still arrives as facts through the backend.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import clingo
from clingo import Number, Symbol, ast

from .theory import Theory, rule_lines

FIRED, VIOLATED, ON = "_bm_fired", "_bm_violated", "_bm_on"


@dataclass(frozen=True)
class RuleRef:
    """One rule of the theory as a proof cites it."""

    name: str          # its %! label, or "unnamed" when it has none
    level: str         # the level (file stem), or "core"
    file: str
    line: int
    constraint: bool   # an integrity constraint (something the axioms forbid)

    def cite(self) -> str:
        return f"{self.name} ({Path(self.file).name}:{self.line})"


@dataclass
class Instrumented:
    """The instrumented theory as loaded into one control; ``rules[R]`` is rule R."""

    rules: list[RuleRef] = field(default_factory=list)

    @property
    def switchable(self) -> list[int]:
        """The constraints an explainer can switch off: those of the levels, not of the core layout."""
        return [i for i, r in enumerate(self.rules) if r.constraint and r.level != "core"]

    def on(self, rule: int) -> Symbol:
        return clingo.Function(ON, [Number(rule)])


def load_instrumented(theory: Theory, ctl: clingo.Control) -> Instrumented:
    """Add the theory to ``ctl`` with its recording twins; declare the ``_bm_on`` externals. The files are
    parsed and twinned once for as long as they are unchanged (an explanation loads the theory into many
    controls); a file edited since is read again."""
    level_of = {str(p): lv for lv, p in theory.levels.items()}
    files = []
    for path in theory.files:
        stat = path.stat()
        files.append((str(path), level_of.get(str(path), "core"), stat.st_mtime_ns, stat.st_size))
    statements, rules = _instrumented(tuple(files))
    with ast.ProgramBuilder(ctl) as builder:
        for stm in statements:
            builder.add(stm)
    out = Instrumented(list(rules))
    if out.switchable:
        ctl.add("base", [], f"#external {ON}(0..{len(out.rules) - 1}).")
    return out


@lru_cache(maxsize=8)
def _instrumented(files: tuple[tuple[str, str, int, int], ...]) -> tuple[tuple, tuple[RuleRef, ...]]:
    """The statements of the instrumented theory and its rules, for these files (path, level, and the
    modification time and size that key the cache)."""
    statements: list = []
    out = Instrumented()
    for key, level, _, _ in files:
        names = rule_lines(Path(key))

        def add(stm, key=key, level=level, names=names):
            switched = False
            if stm.ast_type == ast.ASTType.Rule:
                switched = _add_twin(stm, key, level, names, out, statements.append)
            if not switched:
                statements.append(stm)

        ast.parse_files([key], add)
    return tuple(statements), tuple(out.rules)


def _add_twin(rule, file: str, level: str, names: dict[int, str], out: Instrumented, emit) -> bool:
    """Emit the recording twin of one rule and, for a level's constraint, the rule itself with a switch
    on it (then True: the rule as written must not be added too)."""
    head = rule.head
    constraint = head.ast_type == ast.ASTType.Literal and head.atom.ast_type == ast.ASTType.BooleanConstant
    plain_head = head.ast_type == ast.ASTType.Literal and head.atom.ast_type == ast.ASTType.SymbolicAtom
    if not (constraint or plain_head) or not rule.body:
        return False  # choices, aggregates in the head, facts: nothing to record
    line = rule.location.begin.line
    index = len(out.rules)
    out.rules.append(RuleRef(names.get(line, "unnamed"), level, file, line, constraint))
    loc = rule.location
    body, premises = _named_premises(rule.body, loc)
    rid = ast.SymbolicTerm(loc, Number(index))
    tuple_ = ast.Function(loc, "", premises, 0)
    if constraint:
        args, name = [rid, tuple_], VIOLATED
        if level != "core":
            switch = ast.Literal(loc, ast.Sign.NoSign, ast.SymbolicAtom(ast.Function(loc, ON, [rid], 0)))
            emit(ast.Rule(loc, head, list(rule.body) + [switch]))
    else:
        args, name = [rid, head.atom.symbol, tuple_], FIRED
    twin_head = ast.Literal(loc, ast.Sign.NoSign, ast.SymbolicAtom(ast.Function(loc, name, args, 0)))
    emit(ast.Rule(loc, twin_head, body))
    return constraint and level != "core"


def _named_premises(body, loc) -> tuple[list, list]:
    """The body with anonymous variables in its positive atoms named (so they can be recorded), and
    those atoms as terms."""
    counter = [0]

    class Name(ast.Transformer):
        def visit_Variable(self, v):
            if v.name != "_":
                return v
            counter[0] += 1
            return ast.Variable(v.location, f"BmAnon{counter[0]}")

    new_body, premises = [], []
    for lit in body:
        if (lit.ast_type == ast.ASTType.Literal and lit.sign == ast.Sign.NoSign
                and lit.atom.ast_type == ast.ASTType.SymbolicAtom):
            lit = Name()(lit)
            premises.append(lit.atom.symbol)
        new_body.append(lit)
    return new_body, premises


@dataclass
class Derivations:
    """How each atom of one model was derived: its shallowest recorded rule instance."""

    best: dict[Symbol, tuple[int, tuple[Symbol, ...]]]
    violated: dict[int, list[tuple[Symbol, ...]]]

    @classmethod
    def of(cls, symbols: list[Symbol]) -> "Derivations":
        fired: list[tuple[Symbol, int, tuple[Symbol, ...]]] = []
        violated: dict[int, list[tuple[Symbol, ...]]] = {}
        true = set()
        for s in symbols:
            if s.name == FIRED:
                fired.append((s.arguments[1], s.arguments[0].number, tuple(s.arguments[2].arguments)))
            elif s.name == VIOLATED:
                violated.setdefault(s.arguments[0].number, []).append(tuple(s.arguments[1].arguments))
            elif not s.name.startswith("_bm_"):
                true.add(s)
        return cls(_shallowest(fired, true), violated)


def _shallowest(fired, true: set) -> dict[Symbol, tuple[int, tuple[Symbol, ...]]]:
    """For each derived atom, the instance with the fewest derivation levels under it (so a proof is
    well-founded: no atom is justified by itself through a closure's cycle)."""
    depth = {s: 0 for s in true}
    recorded = {h for h, _, _ in fired}
    for h in recorded:
        depth.pop(h, None)  # derived atoms get their depth from a rule instance
    best: dict[Symbol, tuple[int, tuple[Symbol, ...]]] = {}
    changed = True
    while changed:
        changed = False
        for head, rule, body in fired:
            if all(b in depth for b in body):
                d = 1 + max((depth[b] for b in body), default=0)
                if d < depth.get(head, 1 << 30):
                    depth[head], best[head] = d, (rule, body)
                    changed = True
    return best
