"""A person's word about the map: two time points are one dstate (``same``, a manual loop closure) or
not (``apart``, a closure refused).

An assertion is one more fact for the axioms (core/assert.lp): a hard one must hold, a soft one is kept
unless breaking it saves more than its cost (a dstate costs :data:`~.vocabulary.DSTATE_COST`). The
resolver then finds the fewest dstates that honour them; where the hard ones contradict the experience
(or each other) the answer is the conflict, not an empty map: :class:`Conflict`, a minimal set of the
assertions with the steps and axioms that clash with them (:meth:`.explain.Explainer.conflict`).

Assertions are data, never program text: time points reach clingo as numbers through the vocabulary.
The file a person writes (``bootmap map run.json --assert notes.json``)::

    {"format": "bootmap.assertions/1",
     "assertions": [{"same": ["t3", "t45"]},
                    {"apart": [12, 80], "soft": true, "cost": 6, "note": "two doors alike"}]}

A time point is ``t3`` or ``3``; a dstate name (``S4``) stands for its first visit in the map made
without the assertions (:func:`resolve_names`).

Example
-------
>>> a = parse_assertions([{"same": ["t0", "t4"]}, {"apart": [1, 5], "soft": True}], n_steps=8)
>>> [str(x) for x in a]
['same(t0, t4)', 'apart(t1, t5) soft, cost 5']
>>> a[0].fact()
Function('asserted_same', [Number(0), Number(4)], True)
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

from clingo import Symbol

from ..errors import AssertionsError
from .vocabulary import ASSERTED_APART, ASSERTED_SAME, DSTATE_COST, PREFERRED_APART, PREFERRED_SAME

from .diff import MapDiff

if TYPE_CHECKING:
    from .cogmap import CognitiveMap

__all__ = ["Assertion", "AssertedMap", "Conflict", "FORMAT", "KINDS", "SOFT_COST", "parse_assertions", "load_assertions",
           "assertion_facts", "resolve_names", "hard"]

FORMAT = "bootmap.assertions/1"
KINDS = ("same", "apart")
#: What breaking a soft assertion costs unless it says: one dstate and a little more, so a soft assertion
#: is kept wherever it costs at most one extra dstate.
SOFT_COST = DSTATE_COST + 1
#: The most a soft assertion may cost (above it, say it hard).
MAX_COST = 1000
_KEYS = {"same", "apart", "soft", "cost", "note", "by", "at", "id"}
_POINT = re.compile(r"t?(\d+)")
_DSTATE = re.compile(r"S\d+")


@dataclass(frozen=True)
class Assertion:
    """``same`` or ``apart`` of time points ``a`` < ``b`` (or of dstates by name, ``"S4"``, until
    :func:`resolve_names`); soft ones with the cost of breaking them. ``note``, ``by`` and ``at`` (who
    said it and when) and ``id`` (the service's) are kept with it and never reach the solver."""

    kind: str
    a: int | str
    b: int | str
    soft: bool = False
    cost: int = SOFT_COST
    note: str | None = None
    by: str | None = None
    at: str | None = None
    id: int | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise AssertionsError(f"unknown kind {self.kind!r}; known: {', '.join(KINDS)}")
        if isinstance(self.a, int) and isinstance(self.b, int) and self.a > self.b:
            a, b = self.b, self.a
            object.__setattr__(self, "a", a)
            object.__setattr__(self, "b", b)

    @property
    def pair(self) -> tuple[int, int]:
        return self.a, self.b  # type: ignore[return-value]

    @property
    def names_dstates(self) -> bool:
        return isinstance(self.a, str) or isinstance(self.b, str)

    def fact(self) -> Symbol:
        """The assertion as core/assert.lp reads it."""
        if self.names_dstates:
            raise ValueError(f"{self} names dstates: resolve_names first")
        if self.soft:
            return (PREFERRED_SAME if self.kind == "same" else PREFERRED_APART)(self.a, self.b, self.cost)
        return (ASSERTED_SAME if self.kind == "same" else ASSERTED_APART)(self.a, self.b)

    def holds_in(self, cmap: CognitiveMap) -> bool:
        """Whether the map does what the assertion says."""
        return cmap.same(self.a, self.b) == (self.kind == "same")  # type: ignore[arg-type]

    def __str__(self) -> str:
        return f"{self.kind}({_name(self.a)}, {_name(self.b)})" + (f" soft, cost {self.cost}" if self.soft else "")

    def to_dict(self) -> dict:
        out: dict[str, Any] = {self.kind: [_name(self.a), _name(self.b)]}
        if self.soft:
            out.update(soft=True, cost=self.cost)
        out.update({k: v for k, v in (("note", self.note), ("by", self.by), ("at", self.at), ("id", self.id))
                    if v is not None})
        return out


def _name(x: int | str) -> str:
    return f"t{x}" if isinstance(x, int) else x


def assertion_facts(assertions: Sequence[Assertion]) -> list[Symbol]:
    """The assertions as facts, each pair once per kind and hardness."""
    return list(dict.fromkeys(a.fact() for a in assertions))


def parse_assertions(data: Any, n_steps: int | None = None, source: str | None = None) -> list[Assertion]:
    """Assertions from JSON data: ``{"format": ..., "assertions": [...]}`` or the list alone. Each entry
    names one kind with two time points; ``n_steps`` (the tableau's length) checks they exist. Dstate
    names are kept as names for :func:`resolve_names`. Errors name ``source`` (a file) and the field."""
    where = f"{source}: assertions" if source else "assertions"
    if isinstance(data, dict):
        unknown = sorted(set(data) - {"format", "assertions"})
        if unknown:
            raise AssertionsError(f"unknown key {unknown[0]!r}; an assertions file has 'format' and 'assertions'",
                                  source or "")
        if data.get("format", FORMAT) != FORMAT:
            raise AssertionsError(f"format {data.get('format')!r} is not {FORMAT!r}",
                                  f"{source}: format" if source else "format")
        if "assertions" not in data:
            raise AssertionsError("missing 'assertions' (a list)", source or "")
        data = data["assertions"]
    if not isinstance(data, list):
        raise AssertionsError(f"expected a list of assertions, got {_kind(data)}", where)
    return [_one(entry, n_steps, f"{where}[{i}]") for i, entry in enumerate(data)]


def _one(entry: Any, n_steps: int | None, where: str) -> Assertion:
    if not isinstance(entry, dict):
        raise AssertionsError(f"expected an object such as {{\"same\": [\"t3\", \"t45\"]}}, got {_kind(entry)}",
                              where)
    unknown = sorted(set(entry) - _KEYS)
    if unknown:
        raise AssertionsError(f"unknown key {unknown[0]!r}; known: {', '.join(sorted(_KEYS))}", where)
    kinds = [k for k in KINDS if k in entry]
    if len(kinds) != 1:
        raise AssertionsError("say exactly one of 'same' or 'apart', with two time points", where)
    kind = kinds[0]
    pair = entry[kind]
    if not isinstance(pair, list) or len(pair) != 2:
        raise AssertionsError(f"expected two time points such as [\"t3\", \"t45\"], got {json.dumps(pair)}",
                              f"{where}.{kind}")
    a, b = (_point(x, n_steps, f"{where}.{kind}[{i}]") for i, x in enumerate(pair))
    if a == b:
        raise AssertionsError(f"t{a} is always its own dstate: " + (
            "it cannot be apart from itself" if kind == "apart" else "saying so adds nothing"), f"{where}.{kind}")
    soft = entry.get("soft", False)
    if not isinstance(soft, bool):
        raise AssertionsError(f"expected true or false, got {json.dumps(soft)}", f"{where}.soft")
    cost = entry.get("cost", SOFT_COST)
    if "cost" in entry and not soft:
        raise AssertionsError("a cost is for a soft assertion (add \"soft\": true)", f"{where}.cost")
    if isinstance(cost, bool) or not isinstance(cost, int) or not 1 <= cost <= MAX_COST:
        raise AssertionsError(f"expected a whole number from 1 to {MAX_COST} (a dstate costs {DSTATE_COST}), "
                              f"got {json.dumps(cost)}", f"{where}.cost")
    texts = {}
    for key in ("note", "by", "at"):
        value = entry.get(key)
        if value is not None and not isinstance(value, str):
            raise AssertionsError(f"expected text, got {_kind(value)}", f"{where}.{key}")
        texts[key] = value
    ident = entry.get("id")
    if ident is not None and (isinstance(ident, bool) or not isinstance(ident, int)):
        raise AssertionsError(f"expected a whole number, got {json.dumps(ident)}", f"{where}.id")
    return Assertion(kind, a, b, soft, cost, id=ident, **texts)


def _point(x: Any, n_steps: int | None, where: str) -> int | str:
    """A time point (``t3`` or 3), or a dstate's name (resolved against a map later)."""
    if isinstance(x, bool) or not isinstance(x, (int, str)):
        raise AssertionsError(f"expected a time point (t3 or 3) or a dstate (S4), got {_kind(x)}", where)
    if isinstance(x, str):
        text = x.strip()
        if _DSTATE.fullmatch(text):
            return text
        m = _POINT.fullmatch(text)
        if not m:
            raise AssertionsError(f"{x!r} is neither a time point (t3 or 3) nor a dstate (S4)", where)
        x = int(m.group(1))
    if x < 0 or (n_steps is not None and x >= n_steps):
        span = f"t0..t{n_steps - 1}" if n_steps else "no time points"
        raise AssertionsError(f"time point t{x} is not in the tableau (it has {span})", where)
    return x


def _kind(x: Any) -> str:
    return {dict: "an object", list: "a list", str: "text", bool: "true/false", type(None): "null"}.get(
        type(x), "a number")


def load_assertions(path: str | Path, n_steps: int | None = None) -> list[Assertion]:
    """Read an assertions file; errors name the file, and the line where JSON breaks or the field."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as e:
        raise AssertionsError(f"cannot read: {e.strerror}", str(path)) from None
    except UnicodeDecodeError:
        raise AssertionsError("not UTF-8 text (JSON is)", str(path)) from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as e:
        raise AssertionsError(f"not JSON: {e.msg} at line {e.lineno} column {e.colno}", str(path)) from None
    return parse_assertions(data, n_steps, source=str(path))


def resolve_names(assertions: Sequence[Assertion], cmap: CognitiveMap, source: str | None = None) -> list[Assertion]:
    """The assertions with every dstate name replaced by its first visit in ``cmap`` (the map made
    without them). Errors name ``source`` (a file) and the field."""
    where = f"{source}: assertions" if source else "assertions"
    out = []
    for i, x in enumerate(assertions):
        if not x.names_dstates:
            out.append(x)
            continue
        ends = []
        for value in (x.a, x.b):
            if isinstance(value, str):
                if value not in cmap.views:
                    raise AssertionsError(f"the map has no dstate {value} (it has {', '.join(cmap.views)})",
                                          f"{where}[{i}].{x.kind}")
                value = cmap.dstate_of.index(value)
            ends.append(value)
        if ends[0] == ends[1]:
            raise AssertionsError(f"both ends are {cmap.dstate_of[ends[0]]}: " + (
                "it cannot be apart from itself" if x.kind == "apart" else "saying so adds nothing"),
                f"{where}[{i}].{x.kind}")
        out.append(replace(x, a=min(ends), b=max(ends)))
    return out


@dataclass(frozen=True)
class Conflict:
    """Assertions no map can honour, with why: a subset-minimal set of them (dropping any one leaves a
    map), and the proof, as :class:`~.explain.Explanation` gives it, that the first ``same`` of them
    cannot hold with the others: the steps of experience and the axioms (file:line) it needs."""

    assertions: list[Assertion]
    explanation: Any  # an explain.Explanation, or a loop-closed map's loops.LoopExplanation
    levels: list[str] = field(default_factory=list)

    @property
    def sentence(self) -> str:
        said = " and ".join(str(a) for a in self.assertions)
        one = len(self.assertions) == 1
        head = (f"The assertion {said} contradicts the experience" if one else
                f"The assertions {said} cannot all hold")
        return f"{head}: {self.explanation.sentence}"

    def to_dict(self) -> dict:
        return {"assertions": [a.to_dict() for a in self.assertions], "sentence": self.sentence,
                "explanation": self.explanation.to_dict(), "levels": self.levels}

    def to_text(self) -> str:
        out = ["no map honours the assertions: they clash with the experience"
               + ("" if len(self.assertions) == 1 else " and with each other"),
               "the clashing assertions (dropping any one leaves a map): "
               + "; ".join(str(a) for a in self.assertions), "", self.sentence]
        e = self.explanation
        if getattr(e, "evidence", None):
            out += ["", "evidence (these steps force it; dropping any one does not): "
                    + ", ".join(f"t{t}" for t in e.evidence)]
        if e.axioms:
            out += ["axioms the clash needs: " + ", ".join(r.cite() for r in e.axioms)]
        for f in getattr(e, "failures", ()):  # (a loop-closed map's explanation has none)
            out += f.lines(e.a, e.b, e.supposed)
        return "\n".join(out)


@dataclass(frozen=True)
class AssertedMap:
    """What a person's assertions made of a map: the map before them, and either the map after them with
    what changed (``diff``) or, where no map honours them, the ``conflict``.

    Attributes
    ----------
    before : CognitiveMap
        The map of the experience alone.
    assertions : list of Assertion
        The assertions, dstate names resolved to time points of ``before``.
    after : CognitiveMap or None
        The map that honours them (None on a conflict).
    diff : MapDiff or None
        What changed from ``before`` to ``after``.
    conflict : Conflict or None
        Why no map honours them.
    """

    before: CognitiveMap
    assertions: list[Assertion]
    after: CognitiveMap | None = None
    diff: MapDiff | None = None
    conflict: Conflict | None = None

    @property
    def broken(self) -> list[Assertion]:
        """The soft assertions the map did not keep (breaking them saved more than they cost)."""
        return [x for x in self.assertions if self.after is not None and not x.holds_in(self.after)]

    def to_dict(self) -> dict:
        out = self.after.to_dict() if self.after is not None else {}
        out["assertions"] = [dict(x.to_dict(), held=self.after is not None and x.holds_in(self.after))
                             for x in self.assertions]
        out["diff"] = self.diff.to_dict() if self.diff is not None else None
        out["conflict"] = self.conflict.to_dict() if self.conflict is not None else None
        return out

    def to_text(self) -> str:
        said = "assertions: " + "; ".join(str(x) for x in self.assertions)
        if self.conflict is not None:
            return "\n".join([said, "", self.conflict.to_text()])
        broken = self.broken
        out = [said + (f" (not kept, as breaking them saves more than they cost: "
                       f"{'; '.join(str(x) for x in broken)})" if broken else " (all kept)")]
        if self.diff is not None:
            out.append(self.diff.to_text())
        return "\n".join(out)


def without(assertions: Sequence[Assertion], drop: Assertion) -> list[Assertion]:
    """The assertions but one (by identity of kind, pair and hardness)."""
    key = (drop.kind, drop.pair, drop.soft)
    return [a for a in assertions if (a.kind, a.pair, a.soft) != key]


def hard(assertions: Sequence[Assertion]) -> list[Assertion]:
    return [a for a in assertions if not a.soft]
