"""The resolver: abduce dstates, places and paths from a tableau with clingo.

The search, in the paper's terms: dstates with the same view are equal unless the axioms prove them
different. Concretely:

1. Ground the theory once with the tableau alone and read the *features* every time point shows
   for certain (its view; with the metrical level, its heading). Time points that differ in a feature
   can never share a dstate, so they fall into different *classes*; the number of classes is a lower
   bound on the number of dstates.
2. For a bound N on the number of dstates, from that lower bound upwards: give each class
   ``min(size, N - classes + 1)`` candidate slots (core/partition.lp numbers them by first appearance)
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
    """Time points grouped by the features they show for certain (view, heading, ...)."""

    of_time: list[int]                      # class id of each time point, numbered by first appearance
    sizes: list[int]                        # time points per class
    prev: list[int | None]                  # previous time point of the same class

    @property
    def count(self) -> int:
        return len(self.sizes)

    def facts(self, bound: int) -> list[Symbol]:
        extra = bound - self.count + 1      # a class can hold at most this many dstates within the bound
        out = [Function("dstate_bound", [Number(bound)])]
        for c, size in enumerate(self.sizes):
            out.append(Function("slots", [Number(c), Number(min(size, extra))]))
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
        stats = {"ground_s": 0.0, "solve_s": 0.0, "bounds": [], "classes": classes.count}
        for bound in range(classes.count, len(tableau) + 1):
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
        """Group time points by the features the theory derives for certain (as facts)."""
        ctl = clingo.Control(["--warn=none"])
        self.theory.load_into(ctl)
        add_facts(ctl, facts)
        ctl.ground([("base", [])])
        features: dict[int, list[Symbol]] = defaultdict(list)
        for sa in ctl.symbolic_atoms.by_signature("feature", 3):
            if sa.is_fact:
                features[sa.symbol.arguments[0].number].append(sa.symbol)
        ids: dict[tuple, int] = {}
        of_time, sizes, last, prev = [], [], {}, []
        for t in range(n):
            key = tuple(sorted((s.arguments[1], s.arguments[2]) for s in features[t]))
            c = ids.setdefault(key, len(ids))
            if c == len(sizes):
                sizes.append(0)
            sizes[c] += 1
            of_time.append(c)
            prev.append(last.get(c))
            last[c] = t
        return Classes(of_time, sizes, prev)

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

@dataclass
class _Outcome:
    result: str
    models: list[list[Symbol]]
    exhausted: bool
