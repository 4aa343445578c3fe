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
from dataclasses import dataclass, field
from typing import Callable, Collection, Sequence

import clingo
from clingo import Symbol

from .facts import add_facts
from .mapcheck import SHOW_MAP
from .theory import Theory
from .trace import Instrumented, load_instrumented
from .vocabulary import (AFTER, CLASS_KEY, CLASS_KEY_TERM, CLASSES_GIVEN, DSTATE_BOUND, FEATURE, FUTURE_DEPTH_CONST,
                         PREPASS_PART, PREV_IN_CLASS, SEQUENCE, SHOWN_BY_ALL, SLOTS, TELLING, VIEW_FEATURE)


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


def wait_until(handle, deadline: Deadline) -> bool:
    """Wait for an asynchronous solve (a ``clingo.SolveHandle``) until it is done (True) or ``deadline``
    has passed (False). One ``handle.wait(timeout)`` is not enough: clasp waits once on a condition
    variable and reports "not done" at its first wake-up, which may come before the time-out (a spurious
    wake-up); taken for the time-out, it made a solve that needed a fraction of a second end as out of
    its 60 s."""
    while not handle.wait(deadline.remaining()):
        if deadline.passed():
            return False
    return True


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
    leave_out : sequence of str
        Levels that judge the map alone (:attr:`Theory.map_levels`) not to load: each model then shows
        its transitions and dstates, for :class:`~.mapcheck.MapCheck` to ask those levels of.
    """

    def __init__(self, theory: Theory, facts: Sequence[Symbol], future_depth: int, options: Sequence[str] = (),
                 instrumented: bool = False, leave_out: Sequence[str] = ()):
        self.control = clingo.Control(["--warn=none", "-c", f"{FUTURE_DEPTH_CONST}={int(future_depth)}", *options])
        self.rules: Instrumented | None = load_instrumented(theory, self.control) if instrumented else None
        if self.rules is None:
            theory.load_into(self.control, leave_out)
            if leave_out:  # each model shows the map the levels left out are asked of (.mapcheck)
                self.control.add("base", [], SHOW_MAP)
        add_facts(self.control, facts)
        self.grounded = False
        # how many of its resolution's carried reasons (SearchState.rejected_reasons) are ruled out in it
        self.reasons_ruled_out = 0
        self.ground_s = 0.0
        self.ground_cpu_s = 0.0  # the process's CPU time grounding: what another process's load leaves alone
        self.solve_s = 0.0

    def ground(self, parts: Sequence[str] = ("base",)) -> "Grounding":
        """Ground these program parts (clingo cannot interrupt this: callers check their deadline before).
        An instrumented theory's switches are left free, so that each solve's assumptions set them."""
        t0, cpu0 = time.perf_counter(), time.process_time()
        self.control.ground([(part, []) for part in parts])
        if self.rules is not None:
            for r in self.rules.switchable:
                self.control.assign_external(self.rules.on(r), None)
        self.ground_s += time.perf_counter() - t0
        self.ground_cpu_s += time.process_time() - cpu0
        self.grounded = True
        return self

    def solve(self, deadline: Deadline, on_model: Callable[[clingo.Model], None] | None = None,
              assumptions: Sequence = ()) -> clingo.SolveResult | None:
        """Solve until done or the deadline: clingo's result, or None when the deadline came first."""
        t0 = time.perf_counter()
        with self.control.solve(assumptions=list(assumptions), on_model=on_model, async_=True) as handle:
            finished = wait_until(handle, deadline)
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
        return Classes.grouped(times, [key_of.get(t) for t in times])

    def lower_bounds(self, classes: "Classes", leave_out: Collection[int] = ()) -> list[int]:
        """Per class, a set of time points that pairwise disagree on a feature only some of them show
        (e.g. the view seen after the same actions): no two of them can share a dstate. Time points
        ``left_out`` (suspect views, which may be at a dstate of another class) are not counted, nor
        is what was seen at them (as if they were suspects in this grounding's facts)."""
        return self.partial_features(classes.times).lower_bounds(classes, leave_out)

    def loners(self, classes: "Classes", leave_out: Collection[int] = ()) -> list[int]:
        """Time points that disagree with every other time point of their class: read as seen, each is
        a dstate of its own (the views seen at ``leave_out`` not relied on)."""
        return self.partial_features(classes.times).loners(classes, leave_out)

    def inflators(self, classes: "Classes", leave_out: Collection[int] = ()) -> list[int]:
        """Time points whose view, as the time points before them saw it later, raises the lower bounds
        of those time points' classes (:meth:`PartialFeatures.inflators`)."""
        return self.partial_features(classes.times).inflators(classes, leave_out)

    def partial_features(self, times: Sequence[int]) -> "PartialFeatures":
        """Each time point's features that only some time points show, as small ints (comparing clingo
        symbols costs a C call each), and the time point each view seen later was seen at (``after(S)``
        of causal.lp is seen len(S) actions on). Read once: the same features without the views of
        some time points (suspects) need no other grounding."""
        cached = getattr(self, "_partial", None)
        if cached is not None and cached[0] == list(times):
            return cached[1]
        ids: dict[Symbol, int] = {}
        distance: dict[int, int] = {}  # a view seen later: how many actions on
        partial: dict[int, dict[int, set[int]]] = {t: defaultdict(set) for t in times}
        seen_from: dict[int, dict[int, set]] = defaultdict(lambda: defaultdict(set))
        # Only the features that tell time points of a class apart (core/prepass.lp): on the paper's
        # tableau with an apart, 18 of 3,390 feature atoms (each a few calls into clingo to read). An
        # axiom directory copied before that file existed has no such part: there, every feature not
        # all time points show (the same lower bounds, read more slowly).
        if any(sig[:2] == (TELLING.name, TELLING.arity) for sig in self.control.symbolic_atoms.signatures):
            told = TELLING.facts_in(self.control)
        else:
            grouping = {args[0] for args in SHOWN_BY_ALL.facts_in(self.control)}
            told = (args for args in FEATURE.facts_in(self.control) if args[1] not in grouping)
        for t, key, value in told:
            k = ids.get(key)
            if k is None:
                k = ids[key] = len(ids)
                if AFTER.matches(key):
                    distance[k] = _actions_in(key.arguments[0])
            n = t.number  # (a call into clingo: once)
            partial[n][k].add(ids.setdefault(value, len(ids)))
            if k in distance:
                seen_from[n + distance[k]][n].add(k)
        features = PartialFeatures(partial, seen_from, distance)
        self._partial = (list(times), features)
        return features


@dataclass
class PartialFeatures:
    """The features only some time points show, read from a prepass: ``of[t]`` maps each feature (a
    small int) to the values t shows (one, unless no map exists); ``seen_from[u][t]`` names the features
    t shows by the view seen at u (what t saw ``u - t`` actions on).

    A suspect view is not relied on (causal.lp's future_view_is_feature): :meth:`without` gives the
    features as a prepass with those suspects would derive them, without grounding again."""

    of: dict[int, dict[int, set[int]]]
    seen_from: dict[int, dict[int, set[int]]]
    distance: dict[int, int] = field(default_factory=dict)  # feature -> actions on, for views seen later
    # for the classes they were worked out for (lower_bounds): each class's bound with nothing left out,
    # and the bounds of every set of time points left out asked so far
    _whole_bounds: tuple = field(default=(None, (), {}), repr=False, compare=False)

    def without(self, views_at: Collection[int]) -> "dict[int, dict] | ChainMap":
        """The features, but for those shown by the views seen at ``views_at``."""
        dropped: dict[int, set[int]] = defaultdict(set)
        for u in views_at:
            for t, keys in self.seen_from.get(u, {}).items():
                dropped[t] |= keys
        if not dropped:
            return self.of
        return ChainMap({t: {k: v for k, v in self.of[t].items() if k not in keys}
                         for t, keys in dropped.items()}, self.of)

    def lower_bounds(self, classes: "Classes", leave_out: Collection[int] = ()) -> list[int]:
        """Per class, the size of a set of its time points (but those left out) that pairwise disagree:
        a proved lower bound on its dstates. The views seen at ``leave_out`` are not relied on. A class
        none of whose time points is left out or saw a view left out has the bound it has with nothing
        left out, worked out once (the abduction asks again with each set of suspects, and at times with
        the same set twice: answered from what it found the first time)."""
        kept, whole, asked = self._whole_bounds
        if kept is not classes:
            kept, whole, asked = classes, [None] * len(classes.sizes), {}
            self._whole_bounds = (kept, whole, asked)
        key = frozenset(leave_out)
        if key in asked:
            return list(asked[key])
        features = self.without(leave_out)
        touched = set(leave_out)
        for u in leave_out:
            touched.update(self.seen_from.get(u, {}))
        out = []
        for c, ts in enumerate(_members(classes, leave_out)):
            if touched.isdisjoint(ts) and len(ts) == classes.sizes[c]:
                if whole[c] is None:
                    whole[c] = apart_clique(ts, self.of, exact=True)
                out.append(whole[c])
            else:
                out.append(apart_clique(ts, features, exact=True))
        asked[key] = list(out)
        return out

    def loners(self, classes: "Classes", leave_out: Collection[int] = ()) -> list[int]:
        """Time points that disagree with every other time point of their class."""
        features = self.without(leave_out)
        return sorted(t for ts in _members(classes) if len(ts) > 1 for t in ts
                      if all(_apart(features[t], features[m]) for m in ts if m != t))

    def inflators(self, classes: "Classes", leave_out: Collection[int] = ()) -> list[int]:
        """Time points whose view, as the time points before them saw it later, raises the lower bounds
        of those time points' classes: without that view (as if it were a misread), fewer dstates are
        proved. A misread no rule suspected shows so: the time points before it saw another view, at
        its distance, than their class-mates did. Time points ``left_out`` are suspects already (their
        views not relied on).

        Two time points stay apart without u's view unless every feature they disagree on is one that
        one of them shows by the view seen at u: so only the pairs that u alone keeps apart are
        compared again, and only in their class (classes of more than ``EXACT_CLIQUE_UP_TO`` time
        points are not searched)."""
        partial = self.without(leave_out)
        found: set[int] = set()
        for ts in _members(classes, leave_out):
            if not 1 < len(ts) <= EXACT_CLIQUE_UP_TO:
                continue
            adjacent = [0] * len(ts)
            kept_by: dict[int, list[tuple[int, int]]] = defaultdict(list)  # u -> the pairs only u keeps apart
            for i, a in enumerate(ts):
                for j in range(i + 1, len(ts)):
                    b = ts[j]
                    apart, only = self._kept_apart_by(a, b, partial)
                    if apart:
                        adjacent[i] |= 1 << j
                        adjacent[j] |= 1 << i
                        for u in only:
                            kept_by[u].append((i, j))
            lower = _max_clique_bits(adjacent, 1)
            for u, pairs in kept_by.items():
                if u in leave_out or u in found:
                    continue
                without_u = list(adjacent)
                for i, j in pairs:
                    without_u[i] &= ~(1 << j)
                    without_u[j] &= ~(1 << i)
                if _max_clique_bits(without_u, 1) < lower:
                    found.add(u)
        return sorted(found)

    def _kept_apart_by(self, a: int, b: int, features) -> tuple[bool, set[int]]:
        """Whether time points a and b disagree on a feature both show, and the time points whose views
        alone keep them apart (each feature they disagree on is one of them seeing that view; empty when
        some feature does not depend on a single view, or two views do)."""
        fa, fb = features[a], features[b]
        if len(fa) > len(fb):
            fa, fb = fb, fa
            a, b = b, a
        only: set[int] | None = None
        for k, v in fa.items():
            if k in fb and fb[k] != v:
                d = self.distance.get(k)
                sources = set() if d is None else {a + d, b + d}
                only = sources if only is None else only & sources
                if not only:
                    return True, set()
        return only is not None, only or set()


def check_fixed(theory: Theory, facts: Sequence[Symbol], future_depth: int,
                deadline: Deadline, models: int = 1) -> tuple[list[list[Symbol]] | None, Grounding]:
    """Whether a partition fixed among ``facts`` (``fixed/2``) satisfies the theory: up to ``models``
    models' shown symbols (empty: the axioms reject it; a time point fixed at several dstates is at one
    of them in each model), or None when the deadline came first; and the grounding, for its times. The
    check of loop closing's partitions and of a streamed map extended by determinism."""
    grounding = Grounding(theory, facts, future_depth, [str(models)]).ground()
    found: list[list[Symbol]] = []
    result = grounding.solve(deadline, lambda m: found.append(m.symbols(shown=True)))
    return (None if result is None else found), grounding


def prepass(theory: Theory, facts: Sequence[Symbol], future_depth: int) -> Grounding:
    """The theory grounded with the facts alone: what it derives for certain, before any search; with
    the ``prepass`` part (core/prepass.lp), which picks the features :meth:`Grounding.partial_features`
    reads. The levels that judge the map alone (:attr:`Theory.map_levels`) read only the map's transitions
    and dstates, which no fact gives, so derive nothing here: left out (2,000 steps: 0.12 s against 0.15 s)."""
    return Grounding(theory, facts, future_depth, leave_out=theory.map_levels).ground(("base", PREPASS_PART))


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
    given: bool = False                     # the keys were worked out from the steps (replay.Prepassed):
                                            # a layout gives them, and core/partition.lp folds none

    @property
    def count(self) -> int:
        return len(self.sizes)

    @classmethod
    def grouped(cls, times: Sequence[int], keys: Sequence) -> "Classes":
        """The time points grouped by their keys (``keys[i]`` that of ``times[i]``), classes numbered by first
        appearance, each named by its key; every lower bound 1."""
        ids: dict = {}
        named, of_time, sizes, prev, last = [], [], [], [], {}
        for t, key in zip(times, keys):
            c = ids.setdefault(key, len(ids))
            if c == len(sizes):
                named.append(key)
                sizes.append(0)
            sizes[c] += 1
            of_time.append(c)
            prev.append(last.get(c))
            last[c] = t
        return cls(named, list(times), of_time, sizes, prev, [1] * len(sizes))

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
        if self.given:
            out.append(CLASSES_GIVEN())
            out.extend(CLASS_KEY(t, self.keys[c]) for t, c in zip(self.times, self.of_time))
        return out


def key_with_view(key: Symbol, view: Symbol) -> Symbol:
    """A class key (``k(F, X, Rest)`` folded in core/partition.lp) with its view replaced."""
    if not CLASS_KEY_TERM.matches(key):
        return key
    feature, value, rest = key.arguments
    if VIEW_FEATURE.matches(feature):
        value = view
    return CLASS_KEY_TERM(feature, value, key_with_view(rest, view))


def _actions_in(sequence: Symbol) -> int:
    """The number of actions in a sequence ``c(A, c(A2, ... nil))`` (causal.lp's futures)."""
    n = 0
    while SEQUENCE.matches(sequence):
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


def apart_clique(times: Sequence[int], partial, exact: bool = False, at_most: int | None = None) -> int:
    """Size of a set of time points that pairwise disagree (greedy, forwards, backwards and the time points
    showing most features first, since those disagree most; at least 1 unless there are none). With
    ``exact``, the largest such set where the class is small enough to search (:func:`_max_clique`):
    a greedy set misses a few (a 600-step exploration with misreads: 103 where 116 are proved), and
    every dstate the bound misses is a try the resolver makes. Given ``at_most``, a bound no such set
    can exceed (the dstates a valid map gives them), the search stops once it is reached: the answer is
    the same, sooner."""
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
    if exact and best < len(times) <= EXACT_CLIQUE_UP_TO:
        best = _max_clique(times, partial, best)
    return best


#: Classes of up to so many time points get the exact bound (their pairs are compared once), each search
#: within ``CLIQUE_BUDGET`` steps (beyond it, the largest set found so far). A 600-step exploration's
#: classes hold up to 46; longer tableaux's larger classes keep the greedy bound (comparing their
#: pairs took a second of a 2,000-step resolve without landmarks).
EXACT_CLIQUE_UP_TO, CLIQUE_BUDGET = 48, 20_000


def _max_clique(times: list[int], partial, known: int, budget: int = CLIQUE_BUDGET) -> int:
    """The largest set of pairwise disagreeing time points, if larger than ``known`` (branch and bound
    over bit sets; a set is pruned when it cannot beat the best)."""
    n = len(times)
    adjacent = [0] * n
    for i in range(n):
        for j in range(i + 1, n):
            if _apart(partial[times[i]], partial[times[j]]):
                adjacent[i] |= 1 << j
                adjacent[j] |= 1 << i
    return _max_clique_bits(adjacent, known, budget)


def _max_clique_bits(adjacent: list[int], known: int, budget: int = CLIQUE_BUDGET) -> int:
    """The size of the largest clique of a graph given as bit sets of neighbours, if larger than
    ``known`` (else ``known``); within ``budget`` steps, the largest found so far."""
    n = len(adjacent)
    best, steps = known, 0

    def expand(size: int, candidates: int) -> None:
        nonlocal best, steps
        while candidates:
            steps += 1
            if steps > budget or size + candidates.bit_count() <= best:
                return
            v = (candidates & -candidates).bit_length() - 1
            candidates &= ~(1 << v)
            joined = candidates & adjacent[v]
            if joined:
                expand(size + 1, joined)
            elif size + 1 > best:
                best = size + 1

    expand(0, (1 << n) - 1)
    return best
