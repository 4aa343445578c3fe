"""Proofs as a person reads them: a model of the instrumented theory turned into a tree of sentences.

The explainer (:mod:`.explain`) finds *which* steps and axioms make two time points different; this
module says *how*: from a model of the instrumented theory (:mod:`.trace`) it builds, for the atom where
an axiom fails, the chain of rule instances that derived it, each cited by its ``%!`` name, file and
line, down to the tableau's steps. Atoms read through the vocabulary's phrases
(:mod:`.vocabulary`); a user's own predicate reads as its atom, with dstates and places named as the map
names them.
"""

from __future__ import annotations

import re
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import clingo
from clingo import Symbol

from .cogmap import CognitiveMap
from .trace import Derivations, Instrumented, RuleRef
from .vocabulary import (DSTATE_FEATURE, FEATURE, IS, PLACE_OF, QUIET, SEQUENCE, TOLD_AFTER, TOLD_APART, TURN_ACTION,
                         action_word, predicate)


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
            out["rule"] = rule_dict(self.rule)
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
        return {"rule": rule_dict(self.rule), "premises": [p.to_dict() for p in self.premises],
                "merged": self.merged}

    def lines(self, a: int, b: int, supposed: str = "same") -> list[str]:
        """The failure as text: what is supposed of time points a and b (``same``: one dstate; ``apart``:
        two), the axiom that then fails, and why its premises hold."""
        groups = "; ".join(" = ".join(f"t{t}" for t in group) for group in self.merged)
        two = "one dstate" if supposed == "same" else "different dstates"
        out = ["", f"Suppose t{a} and t{b} are {two}{f' (which makes {groups})' if groups else ''}.",
               f"Then {self.rule.cite()} fails, because:"]
        for p in self.premises:
            out += p.lines(1)
        return out


def rule_dict(r: RuleRef) -> dict:
    return {"name": r.name, "level": r.level, "file": Path(r.file).name, "line": r.line}


# -------------------------------------------------------------------------------------------------
# Reading a model
# -------------------------------------------------------------------------------------------------

def members(model: list[Symbol]) -> dict[Symbol, list[int]]:
    """Each dstate term of a model and the time points at it."""
    out: dict[Symbol, list[int]] = {}
    for t, d in IS.args(model):
        out.setdefault(d, []).append(t.number)
    return {d: sorted(ts) for d, ts in out.items()}


def merged(model: list[Symbol]) -> list[list[int]]:
    """The groups of time points a model puts at one dstate."""
    return sorted(ts for ts in members(model).values() if len(ts) > 1)


@dataclass
class Names:
    """How a proof names the dstates and places of its map: by the minimal map's names of their time
    points, so S0=S4 is the dstate the supposition makes of S0 and S4, and P0=P2 such a place."""

    dstates: dict[Symbol, str]
    places: dict[Symbol, str]
    asked: tuple[int, int]

    @classmethod
    def of(cls, model: list[Symbol], cmap: CognitiveMap, asked: tuple[int, int]) -> "Names":
        at_dstate = members(model)
        dstates = {d: "=".join(dict.fromkeys(cmap.dstate_of[t] for t in ts)) for d, ts in at_dstate.items()}
        # A supposition that splits one of the map's dstates (a person's apart) makes two of one name: each
        # is named by its first time point as well.
        twice = {n for n, k in Counter(dstates.values()).items() if k > 1}
        dstates = {d: f"{n} (t{min(at_dstate[d])})" if n in twice else n for d, n in dstates.items()}
        at: dict[Symbol, list[int]] = {}
        for d, p in PLACE_OF.args(model):
            at.setdefault(p, []).extend(at_dstate.get(d, []))
        places = {}
        for p, ts in at.items():
            named = [cmap.place_of.get(cmap.dstate_of[t]) for t in sorted(ts)]
            if all(named):
                places[p] = "=".join(dict.fromkeys(named))  # type: ignore[arg-type]
        return cls(dstates, places, asked)

    def term(self, term: Symbol) -> str:
        """A term as a person reads it: a dstate by its map name, a view label quoted, an action in words."""
        if term in self.dstates:
            return self.dstates[term]
        if term.type == clingo.SymbolType.String:
            return repr(term.string)
        if TURN_ACTION.matches(term):
            return action_word(term)
        return str(term)

    def place(self, term: Symbol) -> str:
        return self.places.get(term) or f"the place of {self.term(term)}"

    def atom(self, atom: Symbol) -> str:
        """The atom itself, its dstates named."""
        if atom.type != clingo.SymbolType.Function or not atom.arguments:
            return str(atom)
        return f"{atom.name}({', '.join(self.term(x) for x in atom.arguments)})"

    def _told(self, at_time: bool, args: Sequence[Symbol]) -> str:
        """A person's word as a feature (core/assert.lp): ``told_apart(T1, T2)`` shows 1 at T1 and 2 at T2;
        ``told_after(S, told_apart(T1, T2))`` shows it at the time point the actions S started from."""
        feature, value = args[1], args[2].number
        actions = []
        if TOLD_AFTER.matches(feature):
            sequence, feature = feature.arguments
            while SEQUENCE.matches(sequence):
                actions.append(action_word(sequence.arguments[0]))
                sequence = sequence.arguments[1]
        ends = [x.number for x in feature.arguments]
        mine, other = (ends[0], ends[1]) if value == 1 else (ends[1], ends[0])
        where = f"t{args[0].number}" if at_time else self.term(args[0])
        if not actions:
            return (f"a person told t{mine} apart from t{other}" if at_time else
                    f"{where} holds t{mine}, which a person told apart from t{other}")
        return f"{', then '.join(actions)} from {where} reached t{mine}, which a person told apart from t{other}"

    def phrase(self, atom: Symbol) -> str:
        """The atom as a sentence, by the vocabulary's phrase; a user's own predicate as its atom."""
        p = predicate(atom)
        if p is None or p.phrase is None:
            return self.atom(atom)
        args = atom.arguments
        if p in (FEATURE, DSTATE_FEATURE) and (TOLD_APART.matches(args[1]) or TOLD_AFTER.matches(args[1])):
            return self._told(p is FEATURE, args)
        return re.sub(r"\{(P?)(\d)\}", lambda m: (self.place(args[int(m[2])]) if m[1] else self.term(args[int(m[2])])),
                      p.phrase)


def node(atom: Symbol, derivations: Derivations, inst: Instrumented, names: Names, shown: set) -> ProofNode:
    """The proof of one atom: its rule instance and, once per atom, the proofs of its premises."""
    text = names.phrase(atom)
    p = predicate(atom)
    if p is not None and p.role == "tableau":
        return ProofNode(str(atom), text, step=atom.arguments[0].number)
    how = derivations.best.get(atom)
    label = names.atom(atom)
    if how is None:
        if IS.matches(atom) and atom.arguments[0].number in names.asked:
            text += " (the supposition)"
        return ProofNode(label, text)
    rule, body = how
    out = ProofNode(label, text, rule=inst.rules[rule])
    if atom in shown:
        out.text += " (shown above)"
        return out
    shown.add(atom)
    out.premises = [node(b, derivations, inst, names, shown) for b in body
                    if (b.name, len(b.arguments)) not in QUIET]
    return out
