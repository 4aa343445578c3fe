"""The resolver: abduce dstates, places and paths from a tableau with clingo.

The search, in the paper's terms: dstates with the same view are equal unless the axioms prove them
different. Concretely:

1. Features every time point shows (its view; with the metrical level, its heading) group time points
   into *classes*, named by a key term the theory folds from them (core/partition.lp): only time points
   of one class can share a dstate. The first try, in a single grounding, is one dstate per class;
   usually that settles it, by propagation alone.
2. Otherwise, features only some time points show (what was seen after a given sequence of actions)
   tell time points of a class apart: a set of pairwise disagreeing time points is a proved lower bound
   on the dstates of that class. Try exactly those bounds.
3. Otherwise find some valid map, allowing a few spare dstates per class: an upper bound.
4. Ground once within that bound and let clingo minimise the number of dstates (core-guided, so what it
   learns carries from one bound to the next), then enumerate the minimal maps (up to ``max_models``):
   one means the map is unique.

In every step each class gets only the candidate dstates ("slots", numbered by first appearance in
core/partition.lp) that the bound leaves it, so the ground program stays small when the lower bound is
tight.

Example
-------
>>> from bootmap.tableau import Tableau
>>> steps = [{"view": v, "action": {"type": "turn", "angle_deg": -90}} for v in "ABAB"] + [{"view": "A"}]
>>> m = Resolver().resolve(Tableau.from_dict({"format": "bootmap.tableau/1", "steps": steps}))
>>> m.n_dstates, m.n_places, m.unique
(4, 1, True)
"""

from __future__ import annotations

import time
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import clingo
from clingo import Function, Number, Symbol

from .axioms import Theory, load_theory
from .cogmap import CognitiveMap, build_map
from .errors import InconsistentTableau, SolveTimeout
from .facts import add_facts, tableau_facts
from .tableau import Tableau


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

    def facts(self, bound: int, spare: int | None = None) -> list[Symbol]:
        """The layout for a search with at most ``bound`` dstates. Within the bound a class can hold its
        own lower bound plus what the others leave over; ``spare`` caps that (a quick, incomplete try)."""
        if spare is None:
            spare = bound - self.lower_bound
        out = [Function("dstate_bound", [Number(bound)])]
        for key, size, low in zip(self.keys, self.sizes, self.lower):
            out.append(Function("slots", [key, Number(min(size, low + spare))]))
        for t, p in zip(self.times, self.prev):
            if p is not None:
                out.append(Function("prev_in_class", [Number(p), Number(t)]))
        return out


@dataclass
class Resolver:
    """Resolve tableaux into cognitive maps.

    Parameters
    ----------
    axioms : path, optional
        Axiom directory (default: BOOTMAP_AXIOMS, else the shipped ``asp/``).
    levels : sequence of str, optional
        Levels (file stems) to load, e.g. ``["causal", "topological"]``; default all.
    quantum_deg : float
        Turn angles and heading changes are rounded to this many degrees.
    time_limit : float or None
        Seconds for the whole search; on time-out :class:`SolveTimeout` is raised with the number of
        dstates proved necessary so far and, if one was found, a valid map not proved minimal.
    max_models : int
        Minimal maps to enumerate before calling the count capped.
    future_depth : int
        How many actions ahead the causal level compares what time points saw, to tell them apart
        before the search (the ``future_depth`` constant of causal.lp).
    """

    axioms: str | Path | None = None
    levels: Sequence[str] | None = None
    quantum_deg: float = 15.0
    time_limit: float | None = 60.0
    max_models: int = 10
    future_depth: int = 8
    theory: Theory = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.theory = load_theory(self.axioms, self.levels)

    def resolve(self, tableau: Tableau) -> CognitiveMap:
        """The minimal map(s) of the tableau.

        Raises
        ------
        InconsistentTableau
            No map satisfies the axioms.
        SolveTimeout
            Out of time; it carries the dstates proved necessary and, if one was found on the way,
            a valid map that is not proved minimal (``best_map``).
        """
        search = _Search(self, tableau)
        found = search.one_per_class()
        if found:
            return found
        search.bound_classes_from_below()
        if search.classes.lower_bound > search.classes.count:
            found = search.bounded(search.classes.lower_bound)
            if found:
                return found
        return search.optimise(search.some_map())

    def ground_prepass(self, facts: list[Symbol], depth: int) -> clingo.Control:
        """The theory grounded with the tableau alone: what it derives for certain, before any search."""
        ctl = self._control(facts, depth)
        ctl.ground([("base", [])])
        return ctl

    def _control(self, facts: list[Symbol], depth: int, *options: str) -> clingo.Control:
        """A clingo control holding the theory and these facts, looking ``depth`` actions ahead."""
        ctl = clingo.Control(["--warn=none", "-c", f"future_depth={int(depth)}", *options])
        self.theory.load_into(ctl)
        add_facts(ctl, facts)
        return ctl

    def classes(self, grounded: clingo.Control, times: Sequence[int]) -> Classes:
        """Group time points by the class key the theory derived for each (``class_key/2``)."""
        key_of: dict[int, Symbol] = {}
        for sa in grounded.symbolic_atoms.by_signature("class_key", 2):
            if sa.is_fact:
                t, key = sa.symbol.arguments
                key_of[t.number] = key
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

    def lower_bounds(self, prepass: clingo.Control, classes: Classes) -> list[int]:
        """Per class, a set of time points that pairwise disagree on a feature only some of them show
        (e.g. the view seen after the same actions): no two of them can share a dstate."""
        grouping = {sa.symbol.arguments[0] for sa in prepass.symbolic_atoms.by_signature("shown_by_all", 1)}
        ids: dict[Symbol, int] = {}  # small ints: comparing clingo symbols costs a C call each
        partial: dict[int, dict[int, set[int]]] = {t: defaultdict(set) for t in classes.times}
        for sa in prepass.symbolic_atoms.by_signature("feature", 3):
            t, key, value = sa.symbol.arguments
            if sa.is_fact and key not in grouping:
                partial[t.number][ids.setdefault(key, len(ids))].add(ids.setdefault(value, len(ids)))
        members: list[list[int]] = [[] for _ in classes.sizes]
        for t, c in zip(classes.times, classes.of_time):
            members[c].append(t)
        return [_apart_clique(ts, partial) for ts in members]


class _Search:
    """One resolution: the tableau as facts, its classes, the clock, the figures, the best map so far."""

    def __init__(self, resolver: Resolver, tableau: Tableau):
        self.resolver, self.tableau = resolver, tableau
        self.start = time.perf_counter()
        self.deadline = None if resolver.time_limit is None else self.start + resolver.time_limit
        self.facts = tableau_facts(tableau, resolver.quantum_deg)
        self.depth = 0  # futures only matter once one dstate per class has failed
        self.classes: Classes = None  # type: ignore[assignment]  # known after the first try
        self.proved = 1  # dstates proved necessary so far
        self.best: CognitiveMap | None = None
        self.stats: dict = {"ground_s": 0.0, "solve_s": 0.0, "bounds": []}

    def one_per_class(self) -> CognitiveMap | None:
        """The first try, in one grounding: one dstate per class. If it fails, learn the classes from it."""
        outcome = self._solve([Function("one_per_class")], "one dstate per class", keep=True)
        if outcome.models:  # every class holds its one dstate: as many classes as dstates
            cmap = self._finish(outcome.models, outcome.exhausted)
            self.stats["classes"] = self.stats["lower_bound"] = cmap.n_dstates
            return cmap
        self.classes = self.resolver.classes(outcome.control, range(len(self.tableau)))
        self.stats["classes"] = self.classes.count
        self.proved = self.classes.count + 1
        return None

    def bounded(self, bound: int) -> CognitiveMap | None:
        """The minimal maps if at most ``bound`` dstates will do, else None (and the bound is proved)."""
        outcome = self._solve(self.classes.facts(bound), f"at most {bound} dstates")
        if outcome.models:
            return self._finish(outcome.models, outcome.exhausted)
        self.proved = max(self.proved, bound + 1)
        return None

    def bound_classes_from_below(self) -> None:
        self._check_clock("the lower bounds")
        self.depth = self.resolver.future_depth
        prepass = self.resolver.ground_prepass(self.facts, self.depth)
        self.classes.lower = self.resolver.lower_bounds(prepass, self.classes)
        self.proved = max(self.proved, self.classes.lower_bound)

    def some_map(self) -> CognitiveMap:
        """A valid map with few spare dstates per class (doubling the spare until one is found)."""
        widest = max(size - low for size, low in zip(self.classes.sizes, self.classes.lower))
        spare = 1
        while True:
            layout = self.classes.facts(len(self.tableau), spare=spare)
            outcome = self._solve(layout, f"any map with {spare} spare dstate(s) per class", models=1)
            if outcome.models:
                self.best = build_map(self.tableau, outcome.models, False, self.resolver.theory,
                                      dict(self.stats), minimal=False)
                return self.best
            if spare >= widest:
                raise InconsistentTableau(
                    "no map satisfies the axioms: no partition of the time points into dstates explains "
                    f"this experience (levels: {', '.join(self.resolver.theory.levels)})")
            spare = min(widest, 2 * spare)

    def optimise(self, upper: CognitiveMap) -> CognitiveMap:
        """The minimal maps within the upper map's number of dstates, by clingo's optimisation."""
        layout = self.classes.facts(upper.n_dstates) + [Function("minimise_dstates")]
        outcome = self._solve(layout, f"the fewest dstates, at most {upper.n_dstates}", optimise=True)
        cmap = self._finish(outcome.models, outcome.exhausted)
        self.stats["lower_bound"] = cmap.n_dstates  # the optimiser proved it
        return cmap

    def _finish(self, models, exhausted) -> CognitiveMap:
        self.stats["lower_bound"] = self.proved
        self.stats["total_s"] = time.perf_counter() - self.start
        return build_map(self.tableau, models, exhausted, self.resolver.theory, self.stats)

    def _solve(self, layout, what: str, models: int | None = None, optimise: bool = False,
               keep: bool = False) -> "_Outcome":
        """Ground and solve; on time-out raise SolveTimeout with the best map known."""
        if self.classes is not None:  # the first try always runs: its classes bound the answer
            self._check_clock(what)
        r = self.resolver
        options = [str(r.max_models + 1 if models is None else models)]
        if optimise:
            options += ["--opt-mode=optN", "--opt-strategy=usc"]
        ctl = r._control(self.facts + layout, self.depth, *options)
        t0 = time.perf_counter()
        ctl.ground([("base", [])])
        t1 = time.perf_counter()
        optimal: list[list[Symbol]] = []
        improving: list[list[Symbol]] = []

        def on_model(m: clingo.Model) -> None:
            (optimal if not optimise or m.optimality_proven else improving).append(m.symbols(shown=True))

        remaining = None if self.deadline is None else max(0.0, self.deadline - t1)
        with ctl.solve(on_model=on_model, async_=True) as handle:
            finished = handle.wait(remaining)
            if not finished:
                handle.cancel()
            result = handle.get()
        self.stats["ground_s"] += t1 - t0
        self.stats["solve_s"] += time.perf_counter() - t1
        verdict = "timeout" if not finished else ("sat" if result.satisfiable else "unsat")
        self.stats["bounds"].append({"dstates": what, "result": verdict})
        if not finished:
            if self.classes is None:  # timed out in the first try: the classes still bound the answer
                self.classes = self.resolver.classes(ctl, range(len(self.tableau)))
                self.proved = self.classes.count
            raise self._timed_out(what, improving)
        return _Outcome(verdict, optimal, bool(result.exhausted), ctl if keep else None)

    def _check_clock(self, what: str) -> None:
        """Out of time before a grounding starts: stop here (clingo cannot interrupt a grounding)."""
        if self.deadline is not None and time.perf_counter() >= self.deadline:
            raise self._timed_out(what, [])

    def _timed_out(self, what: str, improving: list) -> SolveTimeout:
        if improving:  # the optimiser's last (smallest) model so far
            self.best = build_map(self.tableau, improving[-1:], False, self.resolver.theory, dict(self.stats),
                                  minimal=False)
        found = (f"best map so far: {self.best.n_dstates} dstates, not proved minimal" if self.best
                 else "no map found yet")
        return SolveTimeout(f"time limit of {self.resolver.time_limit} s reached while looking for {what}; "
                            f"at least {self.proved} dstates are proved necessary; {found}",
                            lower_bound=self.proved, best_map=self.best)


def _apart(a: dict, b: dict) -> bool:
    """Two time points disagree on a feature both show, so they cannot share a dstate."""
    small, large = (a, b) if len(a) <= len(b) else (b, a)
    return any(k in large and large[k] != v for k, v in small.items())


def _apart_clique(times: list[int], partial: dict[int, dict]) -> int:
    """Size of a set of time points that pairwise disagree (greedy, forwards and backwards; at least 1)."""
    best = 1
    for order in (times, times[::-1]):
        clique: list[int] = []
        for t in order:
            if all(_apart(partial[t], partial[m]) for m in clique):
                clique.append(t)
        best = max(best, len(clique))
    return best


@dataclass
class _Outcome:
    result: str
    models: list[list[Symbol]]
    exhausted: bool
    control: clingo.Control | None = None
