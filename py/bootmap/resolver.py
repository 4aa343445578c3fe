"""The resolver: abduce dstates, places and paths from a tableau with clingo.

The search, in the paper's terms: dstates with the same view are equal unless the axioms prove them
different. Concretely:

1. Ground the theory once with the tableau alone and read the *features* it derives for certain.
   Features every time point shows (its view; with the metrical level, its heading) group time points
   into *classes*: only time points of one class can share a dstate, so one dstate per class is the
   first bound tried. If that fails, features only some time points show (what was seen after a given
   sequence of actions) tell time points of a class apart: a set of pairwise disagreeing time points is
   a lower bound on the dstates of that class, and the search goes on from the sum of those bounds.
2. For a bound N on the number of dstates, from that lower bound upwards: give each class
   as many candidate slots as the bound leaves it (core/partition.lp numbers them by first appearance)
   and ask clingo for maps with at most N dstates. The first N that is satisfiable is the minimal
   number of dstates: every smaller bound was proved unsatisfiable.
3. At that bound, enumerate the minimal maps (up to ``max_models``): one means the map is unique.

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

    ``lower[c]`` is a proved lower bound on the dstates of class c: the size of a set of its time points
    that pairwise disagree on some feature (e.g. what they saw after the same actions), so that no two of
    them can share a dstate.
    """

    of_time: list[int]                      # class id of each time point, numbered by first appearance
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
        for c, size in enumerate(self.sizes):
            out.append(Function("slots", [Number(c), Number(min(size, self.lower[c] + spare))]))
        for t, c in enumerate(self.of_time):
            out.append(Function("class", [Number(t), Number(c)]))
            if self.prev[t] is not None:
                out.append(Function("prev_in_class", [Number(self.prev[t]), Number(t)]))  # type: ignore[list-item]
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
        Seconds for the whole search; on time-out :class:`SolveTimeout` is raised, saying how many
        dstates were proved necessary so far.
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
        start = time.perf_counter()
        deadline = None if self.time_limit is None else start + self.time_limit
        facts = tableau_facts(tableau, self.quantum_deg)
        # Futures only matter once one dstate per class has failed: leave them out until then.
        depth = 0
        classes = self.classes(self._ground_prepass(facts, depth), len(tableau))
        stats = {"ground_s": 0.0, "solve_s": 0.0, "bounds": [], "classes": classes.count}
        bound, best = classes.count, None
        while bound <= len(tableau):
            outcome = self._solve(facts, classes.facts(bound), deadline, stats, depth)
            stats["bounds"].append({"bound": bound, "result": outcome.result})
            stats["lower_bound"] = max(classes.lower_bound, bound if outcome.result == "sat" else bound + 1)
            if outcome.result == "timeout":
                raise self._timed_out(bound, best)
            if outcome.models:
                stats["total_s"] = time.perf_counter() - start
                return build_map(tableau, outcome.models, outcome.exhausted, self.theory, stats)
            if bound == classes.count:
                # One dstate per class did not do: bound each class from below before trying more.
                depth = self.future_depth
                classes.lower = self.lower_bounds(self._ground_prepass(facts, depth), classes)
            elif best is None:
                # The search will take a while: find some valid map to fall back on if time runs out.
                best = self._some_map(tableau, facts, classes, deadline, stats, depth)
            bound = max(bound + 1, classes.lower_bound)
        raise InconsistentTableau(
            "no map satisfies the axioms: no partition of the time points into dstates explains this "
            f"experience (levels: {', '.join(self.theory.levels)})")

    def _some_map(self, tableau, facts, classes, deadline, stats, depth) -> CognitiveMap | None:
        """A valid map with at most one dstate more per class than its lower bound, if one is found
        within a quarter of the remaining time. Not minimal: a fall-back for time-outs only."""
        quick = None if deadline is None else time.perf_counter() + (deadline - time.perf_counter()) / 4
        outcome = self._solve(facts, classes.facts(len(tableau), spare=1), quick, stats, depth, models=1)
        stats["bounds"].append({"bound": None, "result": f"fallback {outcome.result}"})
        if not outcome.models:
            return None
        return build_map(tableau, outcome.models, False, self.theory, dict(stats), minimal=False)

    def _timed_out(self, bound: int, best: CognitiveMap | None) -> SolveTimeout:
        found = (f"; best map so far: {best.n_dstates} dstates, not proved minimal" if best
                 else "; no map found yet")
        return SolveTimeout(f"time limit of {self.time_limit} s reached while trying {bound} dstates "
                            f"({bound - 1} or fewer was proved impossible){found}", lower_bound=bound, best_map=best)

    def _ground_prepass(self, facts: list[Symbol], depth: int) -> clingo.Control:
        """The theory grounded with the tableau alone: what it derives for certain, before any search."""
        ctl = clingo.Control(["--warn=none", "-c", f"future_depth={int(depth)}"])
        self.theory.load_into(ctl)
        add_facts(ctl, facts)
        ctl.ground([("base", [])])
        return ctl

    def classes(self, prepass: clingo.Control, n: int) -> Classes:
        """Group time points by the features every time point shows (``group_by/3`` facts)."""
        interned: dict[Symbol, int] = {}  # small ints: comparing clingo symbols costs a C call each
        keys: list[list[tuple[int, int]]] = [[] for _ in range(n)]
        for sa in prepass.symbolic_atoms.by_signature("group_by", 3):
            if sa.is_fact:
                t, key, value = sa.symbol.arguments
                keys[t.number].append((interned.setdefault(key, len(interned)),
                                       interned.setdefault(value, len(interned))))
        ids: dict[tuple, int] = {}
        of_time, sizes, prev, last = [], [], [], {}
        for t in range(n):
            c = ids.setdefault(tuple(sorted(keys[t])), len(ids))
            if c == len(sizes):
                sizes.append(0)
            sizes[c] += 1
            of_time.append(c)
            prev.append(last.get(c))
            last[c] = t
        return Classes(of_time, sizes, prev, [1] * len(sizes))

    def lower_bounds(self, prepass: clingo.Control, classes: Classes) -> list[int]:
        """Per class, a set of time points that pairwise disagree on a feature only some of them show
        (e.g. the view seen after the same actions): no two of them can share a dstate."""
        grouping = {sa.symbol.arguments[0] for sa in prepass.symbolic_atoms.by_signature("shown_by_all", 1)}
        ids: dict[Symbol, int] = {}  # small ints: comparing clingo symbols costs a C call each
        partial: list[dict[int, set[int]]] = [defaultdict(set) for _ in classes.of_time]
        for sa in prepass.symbolic_atoms.by_signature("feature", 3):
            t, key, value = sa.symbol.arguments
            if sa.is_fact and key not in grouping:
                partial[t.number][ids.setdefault(key, len(ids))].add(ids.setdefault(value, len(ids)))
        members: list[list[int]] = [[] for _ in classes.sizes]
        for t, c in enumerate(classes.of_time):
            members[c].append(t)
        return [_apart_clique(ts, partial) for ts in members]

    def _solve(self, facts, layout, deadline, stats, depth, models: int | None = None) -> "_Outcome":
        wanted = self.max_models + 1 if models is None else models
        ctl = clingo.Control(["--warn=none", "-c", f"future_depth={int(depth)}", str(wanted)])
        self.theory.load_into(ctl)
        add_facts(ctl, facts + layout)
        t0 = time.perf_counter()
        ctl.ground([("base", [])])
        t1 = time.perf_counter()
        stats["ground_s"] += t1 - t0
        found: list[list[Symbol]] = []
        remaining = None if deadline is None else max(0.0, deadline - t1)
        with ctl.solve(on_model=lambda m: found.append(m.symbols(shown=True)), async_=True) as handle:
            finished = handle.wait(remaining)
            if not finished:
                handle.cancel()
            result = handle.get()
        stats["solve_s"] += time.perf_counter() - t1
        if not finished:
            return _Outcome("timeout", found, False)
        return _Outcome("sat" if result.satisfiable else "unsat", found, bool(result.exhausted))

def _apart(a: dict, b: dict) -> bool:
    """Two time points disagree on a feature both show, so they cannot share a dstate."""
    small, large = (a, b) if len(a) <= len(b) else (b, a)
    return any(k in large and large[k] != v for k, v in small.items())


def _apart_clique(times: list[int], partial: list[dict]) -> int:
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
