"""The resolver: abduce dstates, places and paths from a tableau with clingo.

The search, in the paper's terms: dstates with the same view are equal unless the axioms prove them
different. Concretely:

1. Ground the theory once with the tableau alone and read the *features* it derives for certain.
   Features every time point shows (its view; with the metrical level, its heading) group time points
   into *classes*: only time points of one class can share a dstate. Features only some show (what was
   seen after a given sequence of actions) tell time points of a class apart: a set of pairwise
   disagreeing time points is a lower bound on the dstates of that class.
2. For a bound N on the number of dstates, from the sum of those lower bounds upwards: give each class
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

    def facts(self, bound: int) -> list[Symbol]:
        # Within the bound, class c can hold at most its own lower bound plus what the others leave over.
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
    """

    axioms: str | Path | None = None
    levels: Sequence[str] | None = None
    quantum_deg: float = 15.0
    time_limit: float | None = 60.0
    max_models: int = 10
    theory: Theory = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.theory = load_theory(self.axioms, self.levels)

    def resolve(self, tableau: Tableau) -> CognitiveMap:
        start = time.perf_counter()
        deadline = None if self.time_limit is None else start + self.time_limit
        facts = tableau_facts(tableau, self.quantum_deg)
        classes = self.classes(facts, len(tableau))
        stats = {"ground_s": 0.0, "solve_s": 0.0, "bounds": [], "classes": classes.count,
                 "lower_bound": classes.lower_bound}
        for bound in range(classes.lower_bound, len(tableau) + 1):
            outcome = self._solve(facts, classes.facts(bound), deadline, stats)
            stats["bounds"].append({"bound": bound, "result": outcome.result})
            if outcome.result == "timeout":
                raise SolveTimeout(f"time limit of {self.time_limit} s reached while trying {bound} dstates "
                                   f"({bound - 1} or fewer was proved impossible); no map was proved minimal",
                                   lower_bound=bound)
            if outcome.models:
                stats["total_s"] = time.perf_counter() - start
                return build_map(tableau, outcome.models, outcome.exhausted, self.theory, stats)
        raise InconsistentTableau(
            "no map satisfies the axioms, even with every time point its own dstate; "
            f"levels: {', '.join(self.theory.levels)}")

    def classes(self, facts: list[Symbol], n: int) -> Classes:
        """Group time points by the features the theory derives for certain (as facts) at every time point.

        Features only some time points have (e.g. the view seen after a particular action sequence) do
        not group, but they tell time points of a class apart and so bound its dstates from below.
        """
        features = self._certain_features(facts, n)
        total = set.intersection(*(set(f) for f in features)) if features else set()
        ids: dict[tuple, int] = {}
        of_time, members, prev, last = [], [], [], {}
        for t in range(n):
            key = tuple(sorted((k, tuple(sorted(features[t][k]))) for k in total))
            c = ids.setdefault(key, len(ids))
            if c == len(members):
                members.append([])
            members[c].append(t)
            of_time.append(c)
            prev.append(last.get(c))
            last[c] = t
        partial = [{k: v for k, v in f.items() if k not in total} for f in features]
        lower = [_apart_clique(ts, partial) for ts in members]
        return Classes(of_time, [len(m) for m in members], prev, lower)

    def _certain_features(self, facts: list[Symbol], n: int) -> list[dict[int, set[int]]]:
        """Per time point: feature key -> values, as small ints (comparing clingo symbols costs a C call)."""
        ctl = clingo.Control(["--warn=none"])
        self.theory.load_into(ctl)
        add_facts(ctl, facts)
        ctl.ground([("base", [])])
        ids: dict[Symbol, int] = {}
        features: list[dict[int, set[int]]] = [defaultdict(set) for _ in range(n)]
        for sa in ctl.symbolic_atoms.by_signature("feature", 3):
            if sa.is_fact:
                t, key, value = sa.symbol.arguments
                features[t.number][ids.setdefault(key, len(ids))].add(ids.setdefault(value, len(ids)))
        return features

    def _solve(self, facts, layout, deadline, stats) -> "_Outcome":
        ctl = clingo.Control(["--warn=none", str(self.max_models + 1)])
        self.theory.load_into(ctl)
        add_facts(ctl, facts + layout)
        t0 = time.perf_counter()
        ctl.ground([("base", [])])
        t1 = time.perf_counter()
        stats["ground_s"] += t1 - t0
        models: list[list[Symbol]] = []
        remaining = None if deadline is None else max(0.0, deadline - t1)
        with ctl.solve(on_model=lambda m: models.append(m.symbols(shown=True)), async_=True) as handle:
            finished = handle.wait(remaining)
            if not finished:
                handle.cancel()
            result = handle.get()
        stats["solve_s"] += time.perf_counter() - t1
        if not finished:
            return _Outcome("timeout", models, False)
        return _Outcome("sat" if result.satisfiable else "unsat", models, bool(result.exhausted))

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
