"""The search for the minimal maps of the facts in force: one dstate per class, the classes' proved
lower bounds, the bounds just above them, some valid map, then clingo's optimisation (the steps in
:mod:`bootmap.mapping.resolver`).

Each step is one :class:`~bootmap.mapping.grounding.Grounding` whose layout gives every class only the
candidate dstates (slots) the bound leaves it. The facts are the tableau's, read as seen; once the
abduction (:mod:`.abduction`) has allowed some views as misreads, the same steps find the fewest dstates
and misreads.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import clingo
from clingo import Symbol

from ...errors import InconsistentTableau
from ..cogmap import CognitiveMap, Try
from ..grounding import Grounding, prepass
from ..replay import Prepassed
from ..vocabulary import CANDIDATE_DSTATE, DSTATE, DSTATE_COST, MINIMISE_DSTATES, NEXT, ONE_PER_CLASS, Atoms
from .budget import PREPARE_FACTOR, grounding_size, layout_slots, may_be

if TYPE_CHECKING:
    from .budget import Budget
    from .state import SearchState

#: Where the classes' lower bound is refuted, the bounds just above it are tried one by one (so many, in
#: this share of the time left and at most so many seconds) before any map is looked for and minimised.
CLIMB_STEPS, CLIMB_SHARE = 3, (0.6, 60.0)

#: Learning from maps the levels reject pays where the search is large: a search of at least LEARN_MIN_SIZE
#: (:func:`.budget.grounding_size`, pairs of candidate dstates of consecutive time points) learns, and may
#: spend LEARN_SHARE of the time left on it before it searches with the levels instead. Measured: 2,000
#: steps with a person's apart (size 15,989), grounding and solving with the level 3.2 s + 5.4 s, without
#: it 1.0 s + 0.4 s and 0.2-0.4 s learning from two or three rejected maps; a 287-step exploration of a 6x6
#: grid at 118 dstates, 43 s with the level against 6.4 s learning from 27 rejected maps. (Learning was
#: once allowed five times its grounding's time, 0.3 s there: what a search with the level costs is its
#: solve, which its grounding does not tell.) A 257-step exploration with spare dstates (size 1,751), 2.5 s
#: with the level against 0.03 s without, where the level rejects map after map (0.1-0.2 s to learn from
#: each), is below the size that learns. Under the stock topological level, read in Python (:mod:`..topology`:
#: a rejection and its reasons in about a millisecond), a search learns at any size.
LEARN_MIN_SIZE, LEARN_SHARE = 5000, 0.5

#: At most so many renamings of one rejected map's reasons are learned; where the levels' verdicts and
#: reasons are read in Python (``MapCheck.fast``), a rejected map met again costs a millisecond, and at most
#: ``MAX_RENAMINGS_FAST`` (the stream's slowest steps, 5x5 and 6x6 worlds: 0.8 and 2.1 s with 5,000, 0.6
#: and 1.2 s with 1,000 or 200).
MAX_RENAMINGS, MAX_RENAMINGS_FAST = 5000, 1000

#: So many maps a search that seeks no optimum rejects are set aside before it learns from them (its
#: enumeration never finds a map twice; where few are rejected, the reasons cost more than they save).
LAZY_REJECTIONS = 1


@dataclass
class Outcome:
    """What one grounding's solve found: the models (the optimal ones, when optimising), whether clingo
    enumerated them all, and the grounding itself when it is kept for later questions."""

    models: list[list[Symbol]]
    exhausted: bool
    grounding: Grounding | None = None


@dataclass
class Held:
    """A learning search's grounding one dstate above a bound, with every class's spare slot, first solved
    with those slots held empty (the bound's own search) and kept for the search one dstate up: one
    grounding for both (``ExactSearch.bounded``)."""

    bound: int  # the dstates the grounding's layout allows, the spares' included
    facts: list[Symbol]  # the facts it was grounded on (the search's own list object)
    layout: list[Symbol]
    slots: dict[Symbol, int]  # each class's slots in it
    size: int
    grounding: Grounding
    empty_spares: list[tuple[Symbol, bool]]  # the assumptions that hold every spare slot empty


class ExactSearch:
    """The groundings that find and prove minimal maps of ``state.facts``, each checked against the
    budget before it starts; every bound refuted is recorded as proved (``state.proved``)."""

    def __init__(self, state: SearchState, budget: Budget):
        self.state, self.budget = state, budget
        self.held: Held | None = None  # kept for the search one dstate above a refuted bound (.bounded)
        self._may_be: tuple = (None, [])  # the facts in force and their may_be/2 facts, read (._size)

    def minimal_maps(self) -> CognitiveMap:
        """The minimal maps reading every view as seen, once the classes' lower bounds are known (from the
        larger of theirs and the caller's, ``state.at_least``)."""
        classes = self.state.classes
        lower = max(classes.lower_bound, self.state.at_least)
        self.state.proved = max(self.state.proved, lower)
        if lower > classes.count:
            found = self.bounded(lower) or self.budget.within_share(self.climb, CLIMB_SHARE)
            if found:
                return found
        return self.optimise(self.some_map())

    def first_try(self) -> CognitiveMap | None:
        """The map with one dstate per class, if there is one (:meth:`one_per_class`). Under the stock
        axioms the classes are read from the steps first (:class:`~..replay.Prepassed`): one dstate per
        class is refuted where determinism over the classes refutes it (recorded as refuted, in no time),
        not tried where the caller proved more dstates than there are classes, and otherwise checked without
        grounding the tableau (:meth:`one_per_class_replayed`). Otherwise, where the caller
        proved more than one dstate necessary (a stream, from its last map; a person's assertion, from the
        map before it), the prepass is grounded first and its classes read: with fewer classes than the
        dstates proved, one dstate per class cannot do and is not tried (a grounding fewer), and the lower
        bounds later read the same prepass."""
        state = self.state
        stock = state.stock_prepass()
        if stock is not None:
            # The stock axioms' classes, read from the steps: where the caller proved more dstates than
            # there are classes, one dstate per class is not tried; where two time points of a class took
            # one action to two classes, it fails by determinism, without a grounding.
            if state.at_least <= stock.classes.count and not stock.refutes_one_per_class():
                return self.one_per_class_replayed(stock)
            if state.at_least <= stock.classes.count:
                state.tries.append(Try("one dstate per class", "unsat", 0.0))
            state.proved = max(state.proved, state.learn_classes().count + 1)
            return None
        if state.at_least <= 1:
            return self.one_per_class()
        self.budget.check_clock("the classes")
        grounded = prepass(state.resolver.theory, state.facts, state.resolver.future_depth)
        state.ground_s += grounded.ground_s
        # (the costs every grounding of this tableau has, the futures' included: the first try's role)
        self.budget.first_try_grounded(min(grounded.ground_s, grounded.ground_cpu_s), len(state.tableau))
        state.prepassed = (state.facts, grounded)
        state.classes = grounded.classes(range(len(state.tableau)))
        if state.at_least <= state.classes.count:
            return self.one_per_class()
        state.proved = max(state.proved, state.classes.count + 1)
        return None

    def one_per_class_replayed(self, stock: Prepassed) -> CognitiveMap | None:
        """The first try under the stock axioms, without grounding the tableau: the map with one dstate per
        class where the causal and metrical axioms accept it (:meth:`.replay.Prepassed.one_per_class`),
        its transitions asked of the levels that judge the map alone (one grounding over its dstates, not
        its time points). Where no such level is asked of maps (``defer_map_levels`` off), the grounded
        first try."""
        state = self.state
        if state.map_check is None and state.resolver.theory.map_levels:
            return self.one_per_class()
        t0 = time.perf_counter()
        found = stock.one_per_class()
        if found is not None:
            shown = state.map_check.each(found.transitions())[0] if state.map_check is not None else []
            found.shown = None if shown is None else Atoms(shown)
        seconds = time.perf_counter() - t0
        if found is None or found.shown is None:
            state.tries.append(Try("one dstate per class", "unsat", seconds))
            state.proved = state.learn_classes().count + 1
            return None
        state.tries.append(Try("one dstate per class", "sat", seconds))
        cmap = state.build_from([found.reading(stock.metrical)], True)
        return replace(cmap, stats=replace(cmap.stats, classes=cmap.n_dstates, lower_bound=cmap.n_dstates))

    def one_per_class(self) -> CognitiveMap | None:
        """The first try, in one grounding: one dstate per class. If it fails, learn the classes from it."""
        state = self.state
        outcome = self.solve([ONE_PER_CLASS()], "one dstate per class", keep=True)
        state.first = outcome.grounding  # its classes are read only when needed (a Python loop over atoms)
        if outcome.models:  # every class holds its one dstate: as many classes as dstates
            cmap = self._map(outcome)
            return replace(cmap, stats=replace(cmap.stats, classes=cmap.n_dstates, lower_bound=cmap.n_dstates))
        state.proved = state.learn_classes().count + 1
        return None

    def bound_classes_from_below(self, keep_features: bool = True) -> None:
        """The classes' proved lower bounds, from a prepass that compares the time points' futures (under
        the stock axioms worked out from the steps, :class:`~..replay.Prepassed`: at 10,000 steps 0.2 s
        against 0.8 s to ground and read); the features it read are kept for the abduction
        (``state.features``) unless ``keep_features`` is false (a dict per time point: 140 MiB at 100,000
        steps)."""
        state = self.state
        self.budget.check_clock("the lower bounds")
        state.depth = state.resolver.future_depth
        stock = state.stock_prepass()
        if stock is not None:
            features = stock.features  # the stock axioms' prepass, worked out from the steps
        else:
            if state.prepassed is not None and state.prepassed[0] is state.facts:
                grounded = state.prepassed[1]  # grounded before the first try (.first_try), on these facts
            else:
                grounded = prepass(state.resolver.theory, state.facts, state.depth)
                state.ground_s += grounded.ground_s
            state.prepassed = None  # (a whole control: let go once read)
            features = grounded.partial_features(state.classes.times)
        state.classes.lower = features.lower_bounds(state.classes)
        state.features = features if keep_features else None
        state.proved = max(state.proved, state.classes.lower_bound)

    def bounded(self, bound: int) -> CognitiveMap | None:
        """The minimal maps if at most ``bound`` dstates will do, else None (and the bound is proved).

        Above the classes' lower bound every class has spare slots. There clingo's core-guided
        optimisation looks for the maps: it takes every spare as unused and opens those its unsatisfiable
        cores ask for, where a search for any map within the bound tries every way of using them (2,000
        steps with a person's apart, 104 dstates over a bound of 103: 4.5 s against 14.8 s).

        Where a person's hard ``apart`` is among the facts, the lower bound most often falls short: the
        classes' bounds count the split it makes where it is and a step ahead, not where determinism
        carries it back. There a search large enough to learn (``LEARN_MIN_SIZE``) at the lower bound is
        grounded one dstate up, with a spare slot per class, and solved with the spares held empty; where
        the bound is refuted, the search one up (the next :meth:`climb` step) solves that grounding again
        with the spares free: a grounding and its setup fewer (2,000 steps with an apart: 0.17 s of 1.2 s).
        Where the bound holds, the larger grounding costs more than it saves (a fresh 5,000-step resolve
        held so: 1.84 s against 1.58 s), so it is not done without an apart."""
        held = self.held if self.held is not None and self.held.facts is self.state.facts else None
        self.held = None
        spare = bound > self.state.classes.lower_bound
        if held is not None and held.bound == bound and self.state.deferred_levels:
            outcome = self._solve(held.layout, f"at most {bound} dstates", None, True, held.size,
                                  self.state.deferred_levels, True, grounding=held.grounding, slots=held.slots)
            if outcome is not None:
                return self._answer(outcome, bound)
        if not spare:
            held = self._hold(bound)
            if held is not None:
                outcome = self._solve(held.layout, f"at most {bound} dstates", None, False, held.size,
                                      self.state.deferred_levels, True, grounding=held.grounding,
                                      assumptions=held.empty_spares, slots=held.slots)
                if outcome is not None:
                    if not outcome.models:
                        self.held = held
                    return self._answer(outcome, bound)
        layout = self.state.classes.layout(bound) + ([MINIMISE_DSTATES()] if spare else [])
        # Without spare slots the search only assigns time points to the dstates the classes need, and a
        # map of the rest of the theory is most often a map of the whole: ask the levels that judge the map
        # of each map found. With spares, the rest's fewest dstates tend to undercut what those levels
        # allow (views alone join what places and paths keep apart): search with them. Without spares the
        # futures (what time points saw later, causal.lp) are left out: they follow from determinism and
        # the views, and at 10,000 steps grounding them cost 0.5 s more than they saved; with spares they
        # help the optimiser's propagation.
        return self._answer(self.solve(layout, f"at most {bound} dstates", optimise=spare, defer=not spare,
                                       futures=spare), bound)

    def _answer(self, outcome: Outcome, bound: int) -> CognitiveMap | None:
        """The minimal maps a bounded search found, or None with the bound refuted (proved one more). Above
        the classes' lower bound the search optimised over a layout that holds every map within the bound:
        the fewest dstates it found are proved (as a refuted bound below them would prove them)."""
        if outcome.models:
            cmap = self._map(outcome)
            if bound > self.state.classes.lower_bound and cmap.n_dstates > self.state.proved:
                self.state.proved = cmap.n_dstates
                cmap = replace(cmap, stats=replace(cmap.stats, lower_bound=self.state.proved))
            return cmap
        self.state.proved = max(self.state.proved, bound + 1)
        return None

    def _hold(self, bound: int) -> Held | None:
        """The grounding one dstate above ``bound`` with a spare slot per class (:class:`Held`), where the
        search at the bound would learn (the levels that judge the map alone left out of it); else None."""
        state = self.state
        classes = state.classes
        if not state.deferred_levels or not any(x.kind == "apart" and not x.soft for x in state.assertions):
            return None
        spares = [(DSTATE(CANDIDATE_DSTATE(key, low)), False)
                  for key, size, low in zip(classes.keys, classes.sizes, classes.lower) if size > low]
        if not spares:
            return None
        layout = classes.layout(bound + 1) + [MINIMISE_DSTATES()]
        slots, size = self._size(layout)
        if not self._learns(size):
            return None
        # (grounded by its first solve, after the budget's checks: ._solve)
        grounding = Grounding(state.resolver.theory, state.facts + layout, state.depth,
                              ["0", "--opt-mode=optN", "--opt-strategy=usc"], leave_out=state.deferred_levels)
        return Held(bound + 1, state.facts, layout, slots, size, grounding, spares)

    def climb(self) -> CognitiveMap | None:
        """The minimal maps a few dstates above the lower bound, one bound at a time. Where the greedy
        bound falls just short of the truth (experience half explored: many dstates seen once), this is
        quicker than any map with a spare dstate per class and its minimisation (a 257-step exploration,
        93 dstates over a bound of 91: 37 s against 250 s)."""
        start = max(self.state.proved, self.state.at_least)  # the fewest dstates not refuted yet
        # Above the lower bound a bounded search optimises: the bound one up answers for both (its optimum
        # is the first bound that has maps), and a search less is made where the first would be refuted (a
        # stream's resolve that climbed 100, 101, 102 dstates: 0.72 s, and 0.46 s with 101 and 102 in one).
        # Not where the search below left its grounding for this bound (:meth:`_hold`): that costs no
        # grounding at all.
        bounds = range(start, start + CLIMB_STEPS)
        held = self.held is not None and self.held.bound == start
        for bound in (bounds[1:] if start > self.state.classes.lower_bound and not held else bounds):
            found = self.bounded(bound)
            if found:
                return found
        return None

    def some_map(self) -> CognitiveMap:
        """A valid map with few spare dstates per class (doubling the spare until one is found)."""
        state = self.state
        widest = max(size - low for size, low in zip(state.classes.sizes, state.classes.lower))
        spare = 1
        while True:
            layout = state.classes.layout(len(state.tableau), spare=spare)
            outcome = self.solve(layout, f"any map with {spare} spare dstate(s) per class", models=1, defer=False)
            if outcome.models:
                state.best = self._map(outcome, minimal=False)
                return state.best
            if spare >= widest:
                levels = tuple(state.resolver.theory.levels)
                raise InconsistentTableau(
                    "no map satisfies the axioms: no partition of the time points into dstates explains "
                    f"this experience (levels: {', '.join(levels)})", levels=levels)
            spare = min(widest, 2 * spare)

    def optimise(self, upper: CognitiveMap | None, bound: int | None = None) -> CognitiveMap | None:
        """The minimal maps within ``bound`` dstates (default: the upper map's), by clingo's optimisation;
        None if no map has that few."""
        bound = upper.n_dstates if bound is None else bound  # type: ignore[union-attr]
        layout = self.state.classes.layout(bound) + [MINIMISE_DSTATES()]
        what = f"the fewest dstates{' and misreads' if self.state.suspects else ''}, at most {bound} dstates"
        outcome = self.solve(layout, what, optimise=True, defer=False)
        if not outcome.models:  # only when a bound below the upper map's was asked for
            return None
        cmap = self._map(outcome)
        return replace(cmap, stats=replace(cmap.stats, lower_bound=cmap.n_dstates))  # the optimiser proved it

    def check_asserted_same(self) -> None:
        """A person's hard ``same`` of two time points of different classes (their views, or headings,
        differ) holds in no map: say so before any search (where no view may be a misread)."""
        classes = self.state.classes
        for x in self.state.assertions:
            if x.kind == "same" and not x.soft and not classes.same_class(x.a, x.b):
                levels = tuple(self.state.resolver.theory.levels)
                raise InconsistentTableau(f"no map satisfies the axioms with {x}: t{x.a} and t{x.b} differ in a "
                                          "feature every dstate shows one value of (the view, or the heading)",
                                          levels=levels)

    def preferring(self, found: CognitiveMap) -> CognitiveMap:
        """The maps that keep a person's soft assertions unless breaking one saves more than it costs: the
        fewest dstates (each costing ``DSTATE_COST``), misreads and broken preferences together. A map
        with more dstates than ``found`` plus the preferences' whole cost over ``DSTATE_COST`` costs more
        than breaking them all, so that bound holds the answer."""
        state = self.state
        soft = [x for x in state.assertions if x.soft]
        if not soft or not found.minimal:
            return found
        state.learn_classes()  # (where one dstate per class held, each class needs one: .one_per_class)
        bound = found.n_dstates + sum(x.cost for x in soft) // DSTATE_COST
        return self.optimise(found, bound) or found

    def _map(self, outcome: Outcome, minimal: bool = True) -> CognitiveMap:
        models = outcome.models if minimal else outcome.models[:1]
        return self.state.build(models, minimal and outcome.exhausted, minimal=minimal)

    def solve(self, layout: list[Symbol], what: str, models: int | None = None, optimise: bool = False,
              keep: bool = False, defer: bool = False, futures: bool = True) -> Outcome:
        """Ground and solve; on time-out raise SolveTimeout with the best map known. With ``defer``, the
        levels that judge the map alone are left out of the search and asked of each map it finds
        (:mod:`..mapcheck`); where their verdicts settle nothing, the same solve is made with them, and so
        is every later one of this resolution (where they reject the maps found once, they tend to again).
        A large search (``LEARN_MIN_SIZE``) leaves the levels that say they are monotone out whatever it
        asks, and learns from the maps they reject (:meth:`_learn`). Without ``futures`` the search is
        grounded at future depth 0 (what they would tell apart, determinism and the views still do)."""
        state = self.state
        slots, size = self._size(layout)
        learning = self._learns(size, defer)
        deferred = state.deferred_levels if defer or learning else ()
        if deferred:
            outcome = self._solve(layout, what, models, optimise, size, deferred, learning and not keep, keep,
                                  slots=slots, futures=futures)
            if outcome is not None:
                return outcome
            check = state.map_check
            if not learning and not keep and check is not None and check.fast and check.monotone:
                # Read in Python, the levels are learned from rather than grounded (a 142-step exploration
                # of a 6x6 grid: the next search, with them grounded, 1.55 s)
                outcome = self._solve(layout, f"{what}, learning from the maps the {' and '.join(deferred)} "
                                      "level rejects", models, optimise, size, deferred, True, keep,
                                      slots=slots, futures=futures)
                if outcome is not None:
                    return outcome
            what = f"{what}, with the {' and '.join(deferred)} level in the search"
        return self._solve(layout, what, models, optimise, size, (), False, keep, slots=slots, futures=futures)

    def _size(self, layout: list[Symbol]) -> tuple[dict[Symbol, int], int | None]:
        """Each class's slots in ``layout``, and the size of its search's grounding
        (:func:`.budget.grounding_size`; None before the classes are known: the first try)."""
        state = self.state
        slots = layout_slots(layout)
        if state.classes is None:
            return slots, None
        # (only a search that weighs misreads has may_be facts among its facts: .abduction; read once for
        # each set of facts)
        if not state.suspects:
            return slots, grounding_size(slots, state.classes, ())
        if self._may_be[0] is not state.facts:
            self._may_be = (state.facts, may_be(state.facts))
        return slots, grounding_size(slots, state.classes, self._may_be[1])

    def _learns(self, size: int | None, defer: bool = True) -> bool:
        """Whether a search of this size learns from the maps the monotone levels reject: at least
        ``LEARN_MIN_SIZE``; or, where their verdicts are read in Python (``MapCheck.fast``), any search
        that would otherwise be made with them (not ``defer``: one with spare dstates). (A search that
        asks them of each map found without learning costs less where they reject none: a 2,000-step
        walk of a 4x4 grid, 0.23 s against 0.28 s learning.)"""
        check = self.state.map_check
        return check is not None and check.monotone and (
            (size or 0) >= LEARN_MIN_SIZE or (check.fast and not defer))

    def _solve(self, layout: list[Symbol], what: str, models: int | None, optimise: bool, size: int | None,
               deferred: tuple[str, ...], learning: bool, keep: bool = False, *, slots: dict[Symbol, int],
               grounding: Grounding | None = None, assumptions: list[tuple[Symbol, bool]] | None = None,
               futures: bool = True) -> Outcome | None:
        """One grounding (of ``size``: None for the first try) and its solve, without the ``deferred`` levels:
        learning from the maps they reject (``learning``: :meth:`_learn`), or asking them of the maps found
        (then None where their verdicts do not settle the question: see :func:`_settled`). ``slots``: each
        class's slots in ``layout``. A ``grounding`` given (:class:`Held`, made with optimisation and
        unlimited models) is grounded if it is not yet and solved under ``assumptions``, optimising or not
        as asked."""
        state, budget = self.state, self.budget
        cap = state.resolver.max_models + 1 if models is None else models
        if grounding is None:
            options = ["0" if learning else str(cap)]  # learning, clingo's count would include rejected maps
            if optimise:
                options += ["--opt-mode=optN", "--opt-strategy=usc"]
            grounding = Grounding(state.resolver.theory, state.facts + layout, state.depth if futures else 0,
                                  options, leave_out=deferred)
        else:
            grounding.control.configuration.solve.opt_mode = "optN" if optimise else "ignore"
        ground_s0, solve_s0 = grounding.ground_s, grounding.solve_s
        if not grounding.grounded:
            if size is not None:  # the first try always runs: its classes bound the answer
                budget.check_clock(what)
                budget.check_grounding(what, size)
            grounding.ground()
            if size is None:
                budget.first_try_grounded(min(grounding.ground_s, grounding.ground_cpu_s), len(state.tableau))
            else:
                budget.search_grounded(grounding.ground_s, size)
                if not budget.prepares_in_time(grounding.ground_s):
                    state.ground_s += grounding.ground_s
                    state.tries.append(Try(what, "timeout", grounding.ground_s))
                    raise budget.timed_out(f"{what} (grounded, not solved: the solve would take about "
                                           f"{(PREPARE_FACTOR - 1) * grounding.ground_s:.0f} s to start)", [])
        optimal: list[list[Symbol]] = []
        improving: list[list[Symbol]] = []

        def on_model(m: clingo.Model) -> None:
            (optimal if not optimise or m.optimality_proven else improving).append(m.symbols(shown=True))

        unsettled, rejected = False, 0
        if learning:
            learned = self._learn(grounding, cap, optimise, slots, assumptions or [])
            unsettled = learned is None  # not learned in time: search with the levels instead
            result, optimal, improving, rejected = learned or (None, [], [], 0)
        else:
            result = grounding.solve(budget.deadline, on_model, assumptions or [])
        ground_s, solve_s = grounding.ground_s - ground_s0, grounding.solve_s - solve_s0
        state.ground_s += ground_s
        state.solve_s += solve_s
        seconds = ground_s + solve_s
        if deferred and not learning and result is not None:
            # The levels left out judge each map found, where their verdicts can settle the question: every
            # map within the bound was enumerated (a capped enumeration settles nothing, whatever they say).
            accepted = None
            if result.satisfiable and result.exhausted:
                accepted = [c for c in map(state.map_check, optimal) if c is not None]
            unsettled = not _settled(result, accepted, optimise)
            optimal = accepted if accepted is not None else optimal
        if unsettled:
            state.tries.append(Try(what, "unsettled", seconds))
            if not (state.map_check is not None and state.map_check.fast):
                state.deferred_levels = ()  # it will again: the rest of this resolution searches with them
            return None
        verdict = "timeout" if result is None else ("sat" if result.satisfiable and optimal else "unsat")
        state.tries.append(Try(what, verdict, seconds, rejected))
        if result is None:
            if state.classes is None:  # timed out in the first try: the classes still bound the answer
                state.classes = grounding.classes(range(len(state.tableau)))
                state.proved = state.classes.count
            if deferred and not learning:  # the best map so far must be one the levels left out accept
                improving = [c for c in map(state.map_check, improving[-1:]) if c is not None]
            raise budget.timed_out(what, improving)
        return Outcome(optimal, bool(result.exhausted), grounding if keep else None)

    def _learn(self, grounding: Grounding, cap: int, optimise: bool, slots: dict[Symbol, int],
               assumptions: list[tuple[Symbol, bool]]):
        """Solve without the monotone levels that judge the map alone, asking them of each map found. A map
        they reject is ruled out with every map that shares the few transitions they reject it for
        (:meth:`.mapcheck.MapCheck.reasons`: a nogood clingo keeps), under every name the grounding could give
        the dstates of those transitions (:class:`Renamings`), and the search goes on; an accepted map is the
        whole theory's. Optimising, where every optimal map found was rejected, the search is made
        again with what it learned (the optimum then rises). Exact: only maps the levels reject are ruled
        out, so the accepted maps are the whole theory's maps (optimal ones: its optimal maps).

        Learning costs a check of each map found and, for each rejected one, the reasons (a few dozen solves
        of a small grounding) and their renamings. Where the levels reject map after map, a search with them
        may cost less: learning stops once it has taken ``LEARN_SHARE`` of the time left, and None is
        returned (the search with the levels has the rest); so it is where the levels give no reason (a map
        rejected for a dstate no transition reaches), as nothing could be ruled out beside that map.

        Returns clingo's result (None on time-out), the accepted maps (the optimal ones, optimising; at most
        ``cap``), the accepted improving ones, and how many maps were rejected. ``slots``: each class's
        slots in the layout searched (the renamings then look up only the transitions they need);
        ``assumptions``: each solve's (a :class:`Held` grounding's spares held empty)."""
        check, control, deadline = self.state.map_check, grounding.control, self.budget.deadline
        learned: list[list[int]] = []  # the nogoods learned, as program literals, to add again in a solve made again
        rejected, spent = 0, 0.0  # maps rejected; seconds checking maps and learning from the rejected ones
        left = self.budget.deadline.remaining()
        # (read in Python, the levels' verdicts and reasons cost a millisecond: learning is never given up for
        # a search with them grounded, whose grounding the budget cannot foresee from the searches before it,
        # all made without them: 29 s for a 600-step search with misreads whose learning had taken 2 s)
        allowed = math.inf if left is None or check.fast else LEARN_SHARE * left
        most = MAX_RENAMINGS_FAST if check.fast else MAX_RENAMINGS  # renamings of one map's reasons
        renamings: list[Renamings] = []  # indexed at the first map rejected (most searches reject none)
        carried = self.state.rejected_reasons
        if self.state.set_aside:
            # A search before this one (a bound below) set aside maps the levels reject: their reasons are
            # carried with those the searches before learned.
            carried += [r for r in map(check.reasons, self.state.set_aside) if r]
            self.state.set_aside = []
        ruled = grounding.reasons_ruled_out
        if len(carried) > ruled:
            # The searches before this one (bounds below; this bound before the misreads were weighed) found
            # why the levels rejected maps: those transitions reject any map they are in, and are ruled out
            # before the solve starts, as themselves (it would otherwise find such a map first, learn the
            # same, and restart). Not renamed: where few of a climb's maps share a renaming, a thousand
            # renamings of each, ruled out in every later layout, cost more than they save (aliased 30-step
            # walks: 5.8 s against 4.0 s for forty, the slowest 0.8 s against 0.36 s).
            t0 = time.perf_counter()
            _rule_out(control, [own for own in (_literals(control.symbolic_atoms, r) for r in carried[ruled:])
                                if own])
            spent += time.perf_counter() - t0
        grounding.reasons_ruled_out = len(carried)
        while True:
            optimal: list[list[Symbol]] = []
            improving: list[list[Symbol]] = []
            reasonless = False  # a rejected map the levels gave no reason for

            def learn(shown: list[Symbol], context: clingo.SolveControl | None) -> None:
                """Rule out the maps that share a rejected map's reasons, renamed: now (``context``: in this
                solve) and, kept in ``learned``, in any solve made again."""
                nonlocal reasonless
                reasons = check.reasons(shown)
                if not reasons:
                    reasonless = True
                    return
                carried.append(reasons)
                own = _literals(control.symbolic_atoms if context is None else context.symbolic_atoms, reasons)
                if own is not None:
                    learned.append(own)
                if context is None:
                    return
                context.add_nogood([(s, True) for s in reasons])
                if not renamings:
                    renamings.append(Renamings(context.symbolic_atoms, slots, most))
                for renaming in renamings[0](reasons):
                    literals = [lit for _, lit in renaming]
                    if literals != own:  # (compared as program literals: a symbol's comparison calls clingo)
                        context.add_nogood(literals)
                        learned.append(literals)

            def on_model(m: clingo.Model) -> bool:
                nonlocal rejected, spent
                t0 = time.perf_counter()
                shown = m.symbols(shown=True)
                accepted = check(shown)
                if accepted is None:
                    # An enumeration never finds a map twice: where no optimum is sought, the first rejected
                    # maps (LAZY_REJECTIONS) are only set aside, and learned from once more are rejected.
                    rejected += 1
                    pending.append(shown)
                    if optimise or len(pending) > LAZY_REJECTIONS:
                        for each in pending:
                            learn(each, m.context)
                        pending.clear()
                    spent += time.perf_counter() - t0
                    return spent < allowed and not reasonless
                spent += time.perf_counter() - t0
                (optimal if not optimise or m.optimality_proven else improving).append(accepted)
                return len(optimal) < cap

            done = len(learned)
            pending: list[list[Symbol]] = []  # maps rejected in this solve, not learned from yet
            renamings.clear()  # (a solve may drop atoms it proved false: indexed again in each)
            result = grounding.solve(deadline, on_model, assumptions)
            if result is not None and (spent >= allowed or reasonless):
                return None
            if not optimise:
                self.state.set_aside += pending  # rejected, never learned from: the next search will
            if result is None or optimal or not optimise or rejected == 0:
                return result, optimal, improving, rejected
            for each in pending:  # every optimal map found was rejected: the search is made again
                learn(each, None)
            if reasonless:
                return None
            if len(learned) == done:
                return result, optimal, improving, rejected
            _rule_out(control, learned[done:])


class Renamings:
    """The transitions a search's grounding has (candidate dstates d(K, I): slot I of class K, core/partition.lp),
    indexed by their classes and action, to rename a rejected map's reasons with: the levels that judge the
    map alone and say they are monotone judge a map by its shape, not by what its dstates are called (the
    stock topological level's verdicts are tested so), so where they reject some transitions they reject
    every renaming of them that keeps each dstate in its class and tells different dstates apart."""

    def __init__(self, atoms: clingo.SymbolicAtoms, slots: dict[Symbol, int], most: int = MAX_RENAMINGS):
        self.symbolic, self.slots = atoms, slots  # the grounding's atoms; each class's slots in its layout
        self.most = most  # renamings of one set of reasons, at most
        self.atoms: dict[tuple, dict[tuple[int, int], tuple[Symbol, int]]] = {}  # by (class, action, class)

    def _table(self, key: tuple) -> dict[tuple[int, int], tuple[Symbol, int]]:
        """The transitions of this (class, action, class) the grounding has, by their slots: every slot pair
        of the two classes looked up (a few dozen lookups, where reading every transition of the grounding
        reads a thousand)."""
        if key not in self.atoms:
            k1, action, k2 = key
            table = {}
            for i in range(self.slots.get(k1, 0)):
                for j in range(self.slots.get(k2, 0)):
                    symbol = NEXT(CANDIDATE_DSTATE(k1, i), action, CANDIDATE_DSTATE(k2, j))
                    atom = self.symbolic[symbol]
                    if atom is not None:
                        table[i, j] = (symbol, atom.literal)
            self.atoms[key] = table
        return self.atoms[key]

    def __call__(self, reasons: list[Symbol]) -> list[list[tuple[Symbol, int]]]:
        """Every renaming of ``reasons`` whose transitions the grounding has, each transition with its
        program literal (at most ``most``); none where a dstate is not a slot of the layout."""
        edges = [(s.arguments[0], s.arguments[1], s.arguments[2]) for s in reasons]
        if not all(CANDIDATE_DSTATE.matches(d) for a, _, b in edges for d in (a, b)):
            return []
        tables = [list(self._table((a.arguments[0], action, b.arguments[0])).items()) for a, action, b in edges]
        # The dstates and their classes as small ints: comparing or hashing a clingo symbol is a call into
        # clingo, and the search below does it for every renaming tried.
        ids: dict[Symbol, int] = {}
        classes: dict[Symbol, int] = {}
        ends = [(ids.setdefault(a, len(ids)), ids.setdefault(b, len(ids))) for a, _, b in edges]
        class_of = {i: classes.setdefault(d.arguments[0], len(classes)) for d, i in ids.items()}
        found: list[list[tuple[Symbol, int]]] = []

        def extend(i: int, slot: dict[int, int], taken: set[tuple[int, int]], chosen: list) -> None:
            if len(found) >= self.most:
                return
            if i == len(edges):
                found.append(list(chosen))
                return
            a, b = ends[i]
            for (sa, sb), atom in tables[i]:
                if slot.get(a, sa) != sa or slot.get(b, sb) != sb or (a == b and sa != sb):
                    continue
                fresh = dict((d, n) for d, n in ((a, sa), (b, sb)) if d not in slot)
                claims = {(class_of[d], n) for d, n in fresh.items()}
                if claims & taken or len(claims) < len(fresh):
                    continue  # two different dstates of one class given one slot
                slot.update(fresh)
                chosen.append(atom)
                extend(i + 1, slot, taken | claims, chosen)
                chosen.pop()
                for d in fresh:
                    del slot[d]

        extend(0, {}, set(), [])
        return found


def _literals(atoms: clingo.SymbolicAtoms, symbols: list[Symbol]) -> list[int] | None:
    """The program literals of ``symbols``, or None where the grounding lacks one (clingo drops atoms its
    solve proved false from the grounding: a nogood with one holds anyway)."""
    return [atoms[s].literal for s in symbols] if all(s in atoms for s in symbols) else None


def _rule_out(control: clingo.Control, nogoods: list[list[int]]) -> None:
    """Add to a grounded program a constraint against each set of program literals (maps the levels reject)."""
    with control.backend() as backend:
        for nogood in nogoods:
            backend.add_rule([], nogood)


def _settled(result: clingo.SolveResult, accepted: list | None, optimise: bool) -> bool:
    """Whether the maps a search found without the levels that judge the map alone, and those the levels
    accepted (``accepted``; None where they were not asked), answer the search's question as a search with
    the levels would:

    - no map at all: neither has the whole theory;
    - every map enumerated (``exhausted``): the accepted ones are all the maps of the whole theory within
      the bound; optimising, they are all its optimal maps if any optimal map found is accepted (none
      accepted: the whole theory's optimum may be higher).

    Else (an enumeration capped before it ended) it does not: which maps a search with the levels would
    list is not known.
    """
    if not result.satisfiable:
        return True
    if not result.exhausted or accepted is None:
        return False
    return bool(accepted) or not optimise
