"""One grounding of the theory: the only place bootmap builds a clingo control, grounds and solves.

A :class:`Grounding` holds the theory (plain, or instrumented for explanations, see :mod:`.trace`), a
tableau's facts and the layout of one search, looking ``future_depth`` actions ahead. It grounds once
and solves until a :class:`Deadline`. What the theory derives for certain before any search (the
*prepass*) is read here too: the :class:`Classes` of time points and their proved lower bounds.

The resolver (:mod:`.resolver`) chooses which groundings to make; the explainer (:mod:`.explain`)
asks its questions through the same class.
"""

from __future__ import annotations

import time
from collections import ChainMap, defaultdict
from dataclasses import dataclass
from typing import Callable, Collection, Sequence

import clingo
from clingo import Function, Symbol

from .facts import add_facts
from .theory import Theory
from .trace import Instrumented, load_instrumented
from .vocabulary import CLASS_KEY, DSTATE_BOUND, FEATURE, FUTURE_DEPTH_CONST, PREV_IN_CLASS, SHOWN_BY_ALL, SLOTS


@dataclass(frozen=True)
class Deadline:
    """When a solve must be over (``at``, on ``time.perf_counter``'s clock), and the limit the caller
    set, which messages name. ``Deadline.after(None)`` never comes."""

    at: float | None
    limit_s: float | None

    @classmethod
    def after(cls, seconds: float | None) -> "Deadline":
        return cls(None if seconds is None else time.perf_counter() + seconds, seconds)

    def remaining(self) -> float | None:
        return None if self.at is None else max(0.0, self.at - time.perf_counter())

    def passed(self) -> bool:
        return self.at is not None and time.perf_counter() >= self.at

    def share(self, fraction: float, at_most_s: float) -> "Deadline":
        """A deadline for part of the work: ``fraction`` of the time left, at most ``at_most_s`` seconds
        (the limit messages name stays the caller's)."""
        left = self.remaining()
        span = at_most_s if left is None else min(at_most_s, fraction * left)
        return Deadline(time.perf_counter() + span, self.limit_s)


class Grounding:
    """The theory and a set of facts in one clingo control.

    Parameters
    ----------
    theory : Theory
        The axiom files to load.
    facts : list of Symbol
        The tableau's facts, the search layout, a question.
    future_depth : int
        The ``future_depth`` constant of causal.lp: how many actions ahead time points are compared.
    options : sequence of str
        clingo options (number of models, optimisation mode).
    instrumented : bool
        Load the theory with its recording twins (:mod:`.trace`): each model then says which rule
        instances hold, and the levels' constraints can be switched off (``rules.switchable``).
    """

    def __init__(self, theory: Theory, facts: Sequence[Symbol], future_depth: int, options: Sequence[str] = (),
                 instrumented: bool = False):
        self.control = clingo.Control(["--warn=none", "-c", f"{FUTURE_DEPTH_CONST}={int(future_depth)}", *options])
        self.rules: Instrumented | None = load_instrumented(theory, self.control) if instrumented else None
        if self.rules is None:
            theory.load_into(self.control)
        add_facts(self.control, facts)
        self.ground_s = 0.0
        self.solve_s = 0.0

    def ground(self) -> "Grounding":
        """Ground (clingo cannot interrupt this: callers check their deadline before). An instrumented
        theory's switches are left free, so that each solve's assumptions set them."""
        t0 = time.perf_counter()
        self.control.ground([("base", [])])
        if self.rules is not None:
            for r in self.rules.switchable:
                self.control.assign_external(self.rules.on(r), None)
        self.ground_s += time.perf_counter() - t0
        return self

    def solve(self, deadline: Deadline, on_model: Callable[[clingo.Model], None] | None = None,
              assumptions: Sequence = ()) -> clingo.SolveResult | None:
        """Solve until done or the deadline: clingo's result, or None when the deadline came first."""
        t0 = time.perf_counter()
        with self.control.solve(assumptions=list(assumptions), on_model=on_model, async_=True) as handle:
            finished = handle.wait(deadline.remaining())
            if not finished:
                handle.cancel()
            result = handle.get()
        self.solve_s += time.perf_counter() - t0
        return result if finished else None

    # ---------------------------------------------------------------------------------------------
    # The prepass: what the theory derives from the tableau alone
    # ---------------------------------------------------------------------------------------------

    def classes(self, times: Sequence[int]) -> "Classes":
        """Group time points by the class key the theory derived for each (``class_key/2``)."""
        key_of = {t.number: key for t, key in CLASS_KEY.facts_in(self.control)}
        ids: dict[Symbol | None, int] = {}
        keys, of_time, sizes, prev, last = [], [], [], [], {}
        for t in times:
            key = key_of.get(t)
            c = ids.setdefault(key, len(ids))
            if c == len(sizes):
                keys.append(key)
                sizes.append(0)
            sizes[c] += 1
            of_time.append(c)
            prev.append(last.get(c))
            last[c] = t
        return Classes(keys, list(times), of_time, sizes, prev, [1] * len(sizes))

    def lower_bounds(self, classes: "Classes", leave_out: Collection[int] = ()) -> list[int]:
        """Per class, a set of time points that pairwise disagree on a feature only some of them show
        (e.g. the view seen after the same actions): no two of them can share a dstate. Time points
        ``left_out`` (suspect views, which may be at a dstate of another class) are not counted."""
        partial = self._partial_features(classes.times)
        return [apart_clique(ts, partial) for ts in _members(classes, leave_out)]

    def loners(self, classes: "Classes") -> list[int]:
        """Time points that disagree with every other time point of their class: read as seen, each is
        a dstate of its own."""
        partial = self._partial_features(classes.times)
        return sorted(t for ts in _members(classes) if len(ts) > 1 for t in ts
                      if all(_apart(partial[t], partial[m]) for m in ts if m != t))

    def inflators(self, classes: "Classes", leave_out: Collection[int] = ()) -> list[int]:
        """Time points whose view, as the time points before them saw it later, raises the lower bounds
        of those time points' classes: without that view (as if it were a misread), fewer dstates are
        proved. A misread no rule suspected shows so: the time points before it saw another view, at
        its distance, than their class-mates did. Time points ``left_out`` are suspects already."""
        partial, seen_from = self._partial_features(classes.times, sources=True)
        members = _members(classes, leave_out)
        lower = [apart_clique(ts, partial) for ts in members]
        class_of = dict(zip(classes.times, classes.of_time))
        found = []
        for u, seers in sorted(seen_from.items()):
            if u in leave_out:
                continue
            # What the time points before u show, but for the views they saw at u.
            without = {t: {k: v for k, v in partial[t].items() if k not in seers[t]} for t in seers}
            features = ChainMap(without, partial)
            affected = {class_of[t] for t in seers if t not in leave_out}
            if any(apart_clique(members[c], features) < lower[c] for c in affected):
                found.append(u)
        return found

    def _partial_features(self, times: Sequence[int], sources: bool = False):
        """Each time point's features that only some time points show, as small ints (comparing clingo
        symbols costs a C call each). With ``sources``, also the time point each view seen later was
        seen at (``after(S)`` of causal.lp is seen len(S) actions on): that time point -> {time point
        before it: the features it shows from there}."""
        grouping = {args[0] for args in SHOWN_BY_ALL.facts_in(self.control)}
        ids: dict[Symbol, int] = {}
        partial: dict[int, dict[int, set[int]]] = {t: defaultdict(set) for t in times}
        seen_from: dict[int, dict[int, set]] = defaultdict(lambda: defaultdict(set))
        for t, key, value in FEATURE.facts_in(self.control):
            if key not in grouping:
                k = ids.setdefault(key, len(ids))
                partial[t.number][k].add(ids.setdefault(value, len(ids)))
                if sources and key.name == "after":
                    seen_from[t.number + _actions_in(key.arguments[0])][t.number].add(k)
        return (partial, seen_from) if sources else partial


def prepass(theory: Theory, facts: Sequence[Symbol], future_depth: int) -> Grounding:
    """The theory grounded with the facts alone: what it derives for certain, before any search."""
    return Grounding(theory, facts, future_depth).ground()


@dataclass
class Classes:
    """Time points grouped by the features every time point shows (view; heading with the metrical level).

    A class is named by the key term the theory folds from those features (``class_key/2`` in
    core/partition.lp). ``lower[c]`` is a proved lower bound on the dstates of class c: the size of a set
    of its time points that pairwise disagree on some feature (e.g. what they saw after the same
    actions), so that no two of them can share a dstate.
    """

    keys: list[Symbol | None]               # the key term of each class, by first appearance (None: no key)
    times: list[int]                        # the time points grouped (all of a tableau, or an excerpt)
    of_time: list[int]                      # class of each of those time points
    sizes: list[int]                        # time points per class
    prev: list[int | None]                  # previous time point of the same class
    lower: list[int]                        # dstates each class needs at least

    @property
    def count(self) -> int:
        return len(self.sizes)

    @property
    def lower_bound(self) -> int:
        return sum(self.lower)

    def same_class(self, a: int, b: int) -> bool:
        """Can time points a and b share a dstate at all: both have a key, and the same one?"""
        ca, cb = self.of_time[self.times.index(a)], self.of_time[self.times.index(b)]
        return ca == cb and self.keys[ca] is not None

    def layout(self, bound: int, spare: int | None = None) -> list[Symbol]:
        """The layout for a search with at most ``bound`` dstates. Within the bound a class can hold its
        own lower bound plus what the others leave over; ``spare`` caps that (a quick, incomplete try)."""
        if spare is None:
            spare = bound - self.lower_bound
        out = [DSTATE_BOUND(bound)]
        for key, size, low in zip(self.keys, self.sizes, self.lower):
            out.append(SLOTS(key, min(size, low + spare)))
        for t, p in zip(self.times, self.prev):
            if p is not None:
                out.append(PREV_IN_CLASS(p, t))
        return out


def key_with_view(key: Symbol, view: Symbol) -> Symbol:
    """A class key (``k(F, X, Rest)`` folded in core/partition.lp) with its view replaced."""
    if key.type != clingo.SymbolType.Function or key.name != "k" or len(key.arguments) != 3:
        return key
    feature, value, rest = key.arguments
    if feature.type == clingo.SymbolType.Function and feature.name == "view" and not feature.arguments:
        value = view
    return Function("k", [feature, value, key_with_view(rest, view)])


def _actions_in(sequence: Symbol) -> int:
    """The number of actions in a sequence ``c(A, c(A2, ... nil))`` (causal.lp's futures)."""
    n = 0
    while sequence.type == clingo.SymbolType.Function and sequence.name == "c" and len(sequence.arguments) == 2:
        n, sequence = n + 1, sequence.arguments[1]
    return n


def _members(classes: "Classes", leave_out: Collection[int] = ()) -> list[list[int]]:
    """The time points of each class, but those left out."""
    members: list[list[int]] = [[] for _ in classes.sizes]
    for t, c in zip(classes.times, classes.of_time):
        if t not in leave_out:
            members[c].append(t)
    return members


def _apart(a: dict, b: dict) -> bool:
    """Two time points disagree on a feature both show, so they cannot share a dstate."""
    small, large = (a, b) if len(a) <= len(b) else (b, a)
    return any(k in large and large[k] != v for k, v in small.items())


def apart_clique(times: Sequence[int], partial, at_most: int | None = None) -> int:
    """Size of a set of time points that pairwise disagree (greedy, forwards, backwards and the time points
    showing most features first, since those disagree most; at least 1 unless there are none). Given
    ``at_most``, a bound no such set can exceed (the dstates a valid map gives them), the search stops
    once it is reached: the answer is the same, sooner."""
    best = min(1, len(times))
    richest = sorted(times, key=lambda t: -len(partial[t]))
    for order in (times, times[::-1], richest):
        clique: list[int] = []
        for t in order:
            if all(_apart(partial[t], partial[m]) for m in clique):
                clique.append(t)
                if at_most is not None and len(clique) >= at_most:
                    return len(clique)
        best = max(best, len(clique))
    return best
