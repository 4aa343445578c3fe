"""What one resolution knows as its search goes on: the tableau as facts, its classes of time points,
the dstates proved necessary, the best map found so far and the figures every map reports.

The search's concerns share one :class:`SearchState` and add to it as they learn: retyping
(:mod:`.retyping`) chooses the action angles the facts are made from, the abduction (:mod:`.abduction`)
adds the suspects it allows as misreads, the exact search (:mod:`.exact`) learns the classes and
proves bounds. The state turns models into maps, each with a snapshot of the figures, and words a
time-out with what was proved and found.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Sequence

from clingo import Symbol

from ...errors import SolveTimeout
from ...tableau import Tableau
from ..assertions import Assertion, assertion_facts
from ..cogmap import CognitiveMap, Reading, SolveStats, Try, build_map, map_of
from ..facts import passes_through, tableau_facts, travel_length_types, typing_of
from ..grounding import Classes, Grounding, PartialFeatures
from ..mapcheck import MapCheck
from ..misreads import Suspect
from ..motion import TypeSuspect
from ..replay import Prepassed
from .retyping import MISTYPE_COST

if TYPE_CHECKING:
    from ..resolver import Resolver


class SearchState:
    """One resolution: the tableau as facts, its classes, the figures, the best map so far."""

    def __init__(self, resolver: Resolver, tableau: Tableau, assertions: Sequence[Assertion] = (),
                 at_least: int = 0, rejected: list[list[Symbol]] | None = None):
        self.resolver, self.tableau = resolver, tableau
        self.at_least = at_least  # dstates the caller proved necessary, reading every view as seen
        self.assertions = list(assertions)  # a person's word (.assertions): facts beside the experience
        self.start = time.perf_counter()
        # the actions' angles and types, and the learned types' grid (None with a fixed quantum)
        self.typing = typing_of(tableau, resolver.quantum_deg)
        self.angles, self.action_types, self.grid = self.typing.angles, self.typing.types, self.typing.grid
        # the travels' length types, learned once (the facts and every map built read them)
        self.lengths, self.length_types = travel_length_types(tableau)
        self._facts: list[Symbol] | None = None  # the tableau as facts, made when first asked (facts)
        self.retyped: list[TypeSuspect] = []  # actions taken as mistyped
        self.first: Grounding | None = None  # the first try's grounding
        # the prepass, grounded before the first try where the caller's bound may make that try needless
        # (.exact.first_try), with the facts it was grounded on: the lower bounds read it then
        self.prepassed: tuple[list[Symbol], Grounding] | None = None
        self._stock: tuple[list[int], Prepassed] | None = None  # the same, from the steps, by the angles read
        self.suspects: dict[int, Suspect] = {}  # views the search may take as misreads (robust only)
        self.as_seen: int | None = None  # dstates proved necessary reading every view as seen
        self.depth = 0  # futures only matter once one dstate per class has failed
        self.classes: Classes | None = None  # known after the first try
        self.features: PartialFeatures | None = None  # what the prepass derives, read once
        self.proved = 1  # dstates proved necessary so far
        self.best: CognitiveMap | None = None
        self.ground_s = self.solve_s = 0.0
        self.tries: list[Try] = []
        # the levels that judge the map alone, asked of each map found rather than searched with (.exact)
        self.deferred_levels = resolver.theory.map_levels if resolver.defer_map_levels else ()
        self.map_check = MapCheck(resolver.theory, self.deferred_levels) if self.deferred_levels else None
        # maps a search set aside, rejected by those levels but not learned from (.exact): the next search
        # that learns learns from them before it solves
        self.set_aside: list[list[Symbol]] = []
        # the transitions those levels rejected together, in any search of this resolution or of the
        # earlier ones the caller kept them from (Resolver.resolve's ``rejected``): every later search rules
        # them out (as themselves) before it solves, as they reject any map they are in
        self.rejected_reasons: list[list[Symbol]] = rejected if rejected is not None else []

    @property
    def facts(self) -> list[Symbol]:
        """The facts in force: the experience's (with the action angles read, and a person's assertions) until
        a concern changes them (retyped actions, views allowed as misreads). Made when first asked: a first
        try checked from the steps needs none (:meth:`.exact.ExactSearch.one_per_class_replayed`)."""
        if self._facts is None:
            self._facts = self.experience_facts(self.angles)
        return self._facts

    @facts.setter
    def facts(self, facts: list[Symbol]) -> None:
        self._facts = facts

    def learn_classes(self) -> Classes:
        """The classes of time points, read from the first try's grounding once needed (or from the steps,
        under the stock axioms: :meth:`stock_prepass`); that grounding (a whole control, the largest object
        of a long resolution: 420 MiB at 100,000 steps) is let go then."""
        if self.classes is None:
            stock = self.stock_prepass()
            self.classes = stock.classes if stock is not None else self.first.classes(range(len(self.tableau)))
        self.first = None
        return self.classes

    def stock_prepass(self) -> Prepassed | None:
        """What a prepass of the facts in force derives, worked out from the steps (:class:`.replay.Prepassed`)
        where the stock axioms are loaded and those facts are the experience's alone (no person's assertion,
        no suspect view, a robot that stopped at every dstate, every step but the last with its action);
        else None (a prepass grounds them)."""
        if self.suspects:
            return None
        if self._stock is None or self._stock[0] is not self.angles:
            stock = self.stock_prepass_with(self.angles)
            if stock is None:
                return None
            self._stock = (self.angles, stock)
        return self._stock[1]

    def stock_prepass_with(self, angles: Sequence[int]) -> Prepassed | None:
        """:meth:`stock_prepass` of the experience with these action angles (the retyping's trials)."""
        if (not self.resolver.stock or self.assertions or passes_through(self.tableau)
                or any(s.action is None for s in self.tableau.steps[:-1])):
            return None
        return Prepassed(self.tableau.steps, angles, self.lengths, "metrical" in self.resolver.theory.levels,
                         self.resolver.future_depth)

    def experience_facts(self, angles: Sequence[int]) -> list[Symbol]:
        """The tableau as facts with these action angles, and the person's assertions."""
        return tableau_facts(self.tableau, angles=angles, lengths=self.lengths) + assertion_facts(self.assertions)

    def build(self, models: list[list[Symbol]], exhausted: bool, minimal: bool = True) -> CognitiveMap:
        """The map of these models, with the misreads and retyped actions allowed, and the figures so far."""
        return build_map(self.tableau, models, exhausted, self.resolver.theory.levels, self.stats(),
                         minimal=minimal, action_types=self.action_types,
                         misread_costs=self.misread_costs(), retyped_steps=self.retyped_steps(),
                         length_types=self.length_types)

    def build_from(self, readings: list[Reading], exhausted: bool) -> CognitiveMap:
        """:meth:`build` of maps kept in Python (:class:`.cogmap.Reading`), not read from models."""
        return map_of(self.tableau, readings, exhausted, self.resolver.theory.levels, self.stats(),
                      action_types=self.action_types, misread_costs=self.misread_costs(),
                      retyped_steps=self.retyped_steps(), length_types=self.length_types)

    def retyped_steps(self) -> list[dict]:
        return [s.to_dict(MISTYPE_COST) for s in self.retyped]

    def misread_costs(self) -> dict[int, int]:
        return {t: s.cost for t, s in self.suspects.items()}

    def stats(self) -> SolveStats:
        """The figures so far, as a snapshot: each map keeps its own."""
        return SolveStats(classes=self.classes.count if self.classes else 0, lower_bound=self.proved,
                          as_seen_lower_bound=self.as_seen if self.suspects else None,
                          ground_s=self.ground_s, solve_s=self.solve_s,
                          total_s=time.perf_counter() - self.start, bounds=tuple(self.tries))

    def timed_out(self, what: str, improving: list, limit: float | None) -> SolveTimeout:
        """Out of time (``limit`` seconds) while looking for ``what``: the error carries the dstates proved
        necessary and the best map so far (the optimiser's last, smallest, improving model if any)."""
        if improving:  # the optimiser's last (smallest) model so far
            self.best = self.build(improving[-1:], False, minimal=False)
        found = (f"best map so far: {self.best.n_dstates} dstates, not proved minimal" if self.best
                 else "no map found yet")
        return SolveTimeout(f"time limit of {limit:g} s reached while looking for {what}; "
                            f"at least {self.proved} dstates are proved necessary; {found}",
                            lower_bound=self.proved, best_map=self.best, time_limit_s=limit, stage=what)
