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
tight. Each step is one :class:`~.grounding.Grounding`, solved by the resolution's
:class:`~.grounding.Deadline`; the tableau's actions reach the axioms as the robot's learned action
types (:mod:`.motion`) unless a fixed quantum is asked for.

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
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Sequence

import clingo
import numpy as np
from clingo import String, Symbol

from ..errors import InconsistentTableau, SolveTimeout
from ..images import as_images
from ..tableau import Tableau
from .cogmap import CognitiveMap, SolveStats, Try, build_map
from .diagnosis import diagnosed
from .facts import action_symbols, tableau_facts, typed_actions
from .motion import TypeSuspect, action_types, type_suspects
from .grounding import Classes, Deadline, Grounding, PartialFeatures, key_with_view, prepass
from .theory import Theory, load_theory
from .misreads import GHOST, context_views, MIN_VISITS, MISREAD_COST, RARE_VIEW, Suspect, find_suspects, has_images, rare_clustered_views
from .vocabulary import DSTATE_COST, FUTURE_DEPTH, MAY_BE, MINIMISE_DSTATES, ONE_PER_CLASS, SLOTS, SUSPECT


#: The share of the time left (and at most so many seconds) spent checking that reading every view as
#: seen does not explain the experience more cheaply than the misreads do, when the bounds do not say.
VERIFY_SHARE, VERIFY_MAX_S = 0.25, 10.0
#: What taking an action as mistyped costs (a dstate costs ``DSTATE_COST``): an action is retyped only where
#: its learned type needs more than one dstate more.
MISTYPE_COST = DSTATE_COST
#: The share of the time (and at most so many seconds) spent weighing mistyped actions.
RETYPE_SHARE, RETYPE_MAX_S = 0.25, 15.0
#: Where the classes' lower bound is refuted, the bounds just above it are tried one by one (so many, in
#: this share of the time left and at most so many seconds) before any map is looked for and minimised.
CLIMB_STEPS, CLIMB_SHARE = 3, (0.6, 60.0)
#: A search's grounding time grows faster than its size (:meth:`_Search._grounding_size`): the places
#: and paths of the topological level pair up candidate dstates (600 steps: 2.8 s for a layout, 18.5 s
#: for one with 1.9 times the size). Grounding and the first solve's preparation, which cannot be
#: interrupted either, take about ``PREPARE_FACTOR`` times the grounding (18.5 s, then 30 s).
GROUND_POWER, PREPARE_FACTOR, GROUND_GRACE_S = 2.0, 2.5, 1.0
#: Before any search is grounded, the first try's rate predicts the first search's: searches measured
#: 0.11-0.35 of it (600-step explorations with misreads; the first try's share of fixed costs is higher).
FIRST_TRY_SHARE = 0.35


@dataclass(frozen=True)
class Resolver:
    """Resolve tableaux into cognitive maps. Its settings are fixed when it is made; each resolution
    gets its own deadline.

    Parameters
    ----------
    axioms : path, optional
        Axiom directory (default: BOOTMAP_AXIOMS, else the shipped ``asp/``).
    levels : sequence of str, optional
        Levels (file stems) to load, e.g. ``["causal", "topological"]``; default all.
    quantum_deg : float, optional
        Round each turn angle and heading change to this many degrees. By default the robot's action
        types are learned from the tableau instead (:mod:`.motion`), which odometry noise cannot push
        across a rounding boundary.
    time_limit : float or None
        Seconds for a resolution unless :meth:`resolve` is given a deadline; on time-out
        :class:`SolveTimeout` is raised with the number of dstates proved necessary so far and, if one
        was found, a valid map not proved minimal.
    max_models : int
        Minimal maps to enumerate before calling the count capped.
    future_depth : int
        How many actions ahead the causal level compares what time points saw, to tell them apart
        before the search (the ``future_depth`` constant of causal.lp).
    diagnose : bool
        When no map satisfies the axioms, find which levels fail (:mod:`.diagnosis`), within the
        same deadline.
    retype : bool
        Allow a few actions to be mistyped (:func:`.motion.type_suspects`: a reading far from its learned
        type's angle may be of the neighbouring type), each at ``MISTYPE_COST``: the map then has the
        fewest dstates the theory proves necessary plus the cost of its retyped actions, and lists them
        (``retyped_steps``). Only with learned action types (no ``quantum_deg``).
    misreads : bool
        Allow a few views to be misreads (:mod:`.misreads`) when one dstate per class does not
        explain the experience and some views are suspect: the map then has the fewest dstates plus
        the cost of its misreads, and lists them (``suspect_steps``). With no misread in the best
        map, that map is the exact minimal map.

    Attributes
    ----------
    theory : Theory
        The loaded axiom files.
    """

    axioms: str | Path | None = None
    levels: Sequence[str] | None = None
    quantum_deg: float | None = None
    time_limit: float | None = 60.0
    max_models: int = 10
    future_depth: int = FUTURE_DEPTH
    diagnose: bool = True
    misreads: bool = True
    retype: bool = True
    theory: Theory = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.levels is not None:
            object.__setattr__(self, "levels", tuple(self.levels))
        object.__setattr__(self, "theory", load_theory(self.axioms, self.levels))

    def with_levels(self, levels: Sequence[str]) -> "Resolver":
        """The same resolver (same axiom directory and settings) on other levels, without a diagnosis."""
        return replace(self, axioms=self.theory.directory, levels=tuple(levels), diagnose=False)

    def resolve(self, tableau: Tableau, deadline: Deadline | None = None) -> CognitiveMap:
        """The minimal map(s) of the tableau, by ``deadline`` (default: ``time_limit`` from now).

        Raises
        ------
        InconsistentTableau
            No map satisfies the axioms (with the failing levels, when ``diagnose``).
        SolveTimeout
            Out of time; it carries the dstates proved necessary and, if one was found on the way,
            a valid map that is not proved minimal (``best_map``).
        """
        deadline = deadline or Deadline.after(self.time_limit)
        try:
            return _Search(self, tableau, deadline).run()
        except InconsistentTableau as e:
            if not self.diagnose:
                raise
            raise diagnosed(e, self, tableau, deadline) from None


class _Search:
    """One resolution: the tableau as facts, its classes, the clock, the figures, the best map so far."""

    def __init__(self, resolver: Resolver, tableau: Tableau, deadline: Deadline):
        self.resolver, self.tableau, self.deadline = resolver, tableau, deadline
        self.start = time.perf_counter()
        # the actions' angles and types, and the learned types' grid (None with a fixed quantum)
        self.angles, self.action_types, self.grid = typed_actions(tableau, resolver.quantum_deg)
        self.facts = tableau_facts(tableau, angles=self.angles)
        self.retyped: list[TypeSuspect] = []  # actions taken as mistyped
        self.first: Grounding | None = None  # the first try's grounding
        self.suspects: dict[int, Suspect] = {}  # views the search may take as misreads (robust only)
        self.as_seen: int | None = None  # dstates proved necessary reading every view as seen
        self.depth = 0  # futures only matter once one dstate per class has failed
        self.classes: Classes | None = None  # known after the first try
        self.features: PartialFeatures | None = None  # what the prepass derives, read once
        self.proved = 1  # dstates proved necessary so far
        self.best: CognitiveMap | None = None
        self.ground_s = self.solve_s = 0.0
        self.ground_rate: float | None = None  # seconds per grounding size ** GROUND_POWER, the worst seen
        self.fixed_ground_s = 0.0  # the first try's grounding: the costs every grounding has
        self.rate_size = 0  # the size of the search grounding that set ground_rate (0: the first try did)
        self.tries: list[Try] = []

    def run(self) -> CognitiveMap:
        if self.resolver.retype and self.grid is not None:
            self.retype()
        found = self.one_per_class()
        suspects = self._suspects(found)
        if found and not suspects:
            return found
        if suspects:
            return self.robust(suspects, found)
        self.bound_classes_from_below()
        return self.exact()

    def exact(self) -> CognitiveMap:
        """The minimal maps reading every view as seen, once the classes' lower bounds are known."""
        if self.classes.lower_bound > self.classes.count:
            found = self.bounded(self.classes.lower_bound) or self._within_share(self._climb, CLIMB_SHARE)
            if found:
                return found
        return self.optimise(self.some_map())

    def retype(self) -> None:
        """Abduce mistyped actions, as misread views are: a reading far from its learned type's angle may
        be of the neighbouring type (:func:`.motion.type_suspects`). Since an action's angle sets the
        heading of every later time point (a class feature), the typing is chosen before the search: each
        suspect in turn is retyped where that lowers the dstates the theory proves necessary (the
        classes' lower bounds, from a prepass) by more than ``MISTYPE_COST`` (one dstate). Clean
        experience has no suspects and is resolved as before; out of its share of the time, the typing
        chosen so far stands."""
        suspects = type_suspects(self.tableau.actions, self.angles, self.grid)
        if not suspects:
            return
        share = self.deadline.share(RETYPE_SHARE, RETYPE_MAX_S)
        angles = list(self.angles)
        best = DSTATE_COST * self._proved_with(angles)
        for s in suspects:
            if share.passed():
                break
            trial = list(angles)
            trial[s.t] = s.alternative
            score = DSTATE_COST * self._proved_with(trial) + MISTYPE_COST * (len(self.retyped) + 1)
            if score < best + MISTYPE_COST * len(self.retyped):
                angles, best = trial, score - MISTYPE_COST * (len(self.retyped) + 1)
                self.retyped.append(s)
        if self.retyped:
            self.angles = angles
            self.facts = tableau_facts(self.tableau, angles=angles)
            self.action_types = action_types(self.tableau.actions, angles)

    def _proved_with(self, angles: list[int]) -> int:
        """The dstates the theory proves necessary (the classes' lower bounds) with these action angles."""
        grounded = prepass(self.resolver.theory, tableau_facts(self.tableau, angles=angles),
                           self.resolver.future_depth)
        self.ground_s += grounded.ground_s
        classes = grounded.classes(range(len(self.tableau)))
        return sum(grounded.lower_bounds(classes))

    def _climb(self) -> CognitiveMap | None:
        """The minimal maps a few dstates above the lower bound, one bound at a time. Where the greedy
        bound falls just short of the truth (experience half explored: many dstates seen once), this is
        quicker than any map with a spare dstate per class and its minimisation (a 257-step exploration,
        93 dstates over a bound of 91: 37 s against 250 s)."""
        for bound in range(self.classes.lower_bound + 1, self.classes.lower_bound + 1 + CLIMB_STEPS):
            found = self.bounded(bound)
            if found:
                return found
        return None

    def robust(self, suspects: list[Suspect], exact: CognitiveMap | None = None) -> CognitiveMap:
        """The better of two explanations, when some views are suspect: read as seen (the exact minimal
        map), or with some suspects taken as misreads (the fewest dstates any such map needs, then the
        fewest misread costs). A misread map is chosen only when it needs fewer dstates than reading every
        view as seen by more than its misreads cost (a dstate costs ``DSTATE_COST``): proved by the exact
        lower bound where that suffices, else by asking for an exact map within the difference."""
        exact_facts = self.facts
        if self.classes is None:
            self.classes = self.first.classes(range(len(self.tableau)))
        self.bound_classes_from_below()
        exact_lower = self.classes.lower
        clear = [s for s in suspects if s.clear] or suspects
        if exact is None and self.classes.lower_bound > self.classes.count and not self._misreads_evident(clear):
            exact = self.bounded(self.classes.lower_bound)  # reading every view as seen, when that is easy
        self.as_seen = exact.n_dstates if exact else max(self.proved, sum(exact_lower))
        if exact is not None:
            # Reading every view as seen is easy (its lower bound holds): a misread that carries a
            # contradiction forward would have made it hard. Only views with one or two images, each a
            # dstate of its own in the exact map, are left to weigh.
            suspects = [s for s in suspects if s.reason == RARE_VIEW]
            if not suspects:
                return exact
        fewest = self._allow_misreads(exact_facts, clear)
        if exact is not None:
            # The exact map is in hand: misreads must save more dstates than the cheapest of them costs,
            # and are looked for in a share of the time (clean experience must not wait for them).
            if DSTATE_COST * (exact.n_dstates - fewest) <= min(s.cost for s in clear):
                misread = None
            else:
                misread = self._within_share(lambda: self._misread_map(fewest, exact.n_dstates - 1))
        else:
            misread = self._misread_map(fewest, self.as_seen, exact_facts, suspects)
        if misread is None:  # the misreads save nothing: read every view as seen
            self.facts, self.suspects, self.classes.lower = exact_facts, {}, exact_lower
            return exact or self.exact()
        cost = sum(self.suspects[s["t"]].cost for s in misread.suspect_steps)
        saved = self.as_seen - misread.n_dstates  # at least this many more dstates without the misreads
        if not misread.suspect_steps or DSTATE_COST * saved > cost:
            return misread
        if exact is not None:  # the exact map is minimal: the misreads do not pay for themselves
            self.suspects = {}
            return exact
        # Not proved by the bound: is there a map reading every view as seen within the misreads' cost?
        # Looked for in a share of the time left: where reading misreads as seen is hard to explain, the
        # search for it is hard too, and the misread map is kept (the tries say the check timed out).
        suspects = self.suspects
        self.facts, self.suspects, self.classes.lower = exact_facts, {}, exact_lower

        def exact_within_cost() -> CognitiveMap | None:
            for bound in range(self.as_seen, misread.n_dstates + cost // DSTATE_COST + 1):
                found = self.bounded(bound)
                if found:
                    return found
            return None

        found = self._within_share(exact_within_cost)
        self.suspects = suspects
        return found or misread

    def _misreads_evident(self, clear: list[Suspect]) -> bool:
        """Leaving the clear suspects' views out lowers the classes' bounds by a dstate or more per suspect:
        reading them as seen is what splits the classes. Then the exact map at its lower bound (a search
        that fails, and slowly: 1-8 s on 600-step explorations with 2% misreads) is not tried first; the
        misreads are weighed against the exact lower bound instead. On clean experience whose suspects
        are chance (aliasing), leaving them out lowers the bounds by less than one per suspect (0-7 for
        1-84 suspects on 600-step explorations)."""
        without = sum(self.features.lower_bounds(self.classes, leave_out={s.t for s in clear}))
        return self.classes.lower_bound - without >= len(clear)

    def _misread_map(self, fewest: int, ceiling: int, exact_facts: list[Symbol] | None = None,
                     wider: list[Suspect] = ()) -> CognitiveMap | None:
        """The best map with misreads and at most ``ceiling`` dstates, from ``fewest`` up; None if none.
        If the suspects allowed so far do not reach ``fewest``, the ``wider`` set is allowed too.

        Where some misread is no suspect (``exact_facts`` given: the first search of a resolution), the
        views that raise their classes' bounds (:meth:`_ghosts`) become suspects first, in Python, as
        long as they lower the bound (one unsuspected misread hides another: the second shows once the
        first is left out), and the search starts from that bound. If it fails there, the layout of the
        clear suspects' bound is tried with the same suspects: their higher bounds are the classes that
        may need a slot back, where a suspect is no misread after all. A dstate more in the bound would
        give every class a slot more instead, and that grounding grows past any time limit (2.8 s at
        the bound, 18.5 s at one more, 600 steps with 27 suspects)."""
        clear = chosen = list(self.suspects.values())
        planned, proved = self.classes.lower, self.proved
        if exact_facts is not None:
            while True:
                ghosts = self._ghosts()
                if not ghosts:
                    break
                lowered = self._allow_misreads(exact_facts, chosen + ghosts)
                if lowered >= (fewest if chosen is clear else lowest):
                    self._allow_misreads(exact_facts, chosen)
                    break
                chosen, lowest = chosen + ghosts, lowered
        if chosen is not clear:
            misread = self.optimise(None, lowest)
            if misread is not None:
                return misread
            self.classes.lower, self.proved = planned, max(proved, lowest + 1)
        misread = self.optimise(None, fewest)
        others = [s for s in wider if s.t not in self.suspects]
        if misread is None and exact_facts is not None and others:
            # The layout stays the one the clear suspects set: the others may join their classes'
            # dstates, but each class keeps its dstates (a small search, where misreads are few).
            self._allow_misreads(exact_facts, chosen + others)
            self.classes.lower, self.proved = planned, proved
            misread = self.optimise(None, fewest)
            if misread is None:  # each dstate more is a slot more for every class, and each suspect's
                self._allow_misreads(exact_facts, chosen)  # other classes' slots with it: too many
                self.classes.lower, self.proved = planned, proved
        while misread is None and fewest < ceiling:
            fewest += 1
            self.proved = max(self.proved, fewest)
            misread = self.optimise(None, fewest)
        return misread

    def _ghosts(self) -> list[Suspect]:
        """Views no suspect rule caught that the experience shows a dstate of their own.

        A misread where the robot has seldom been has no context to make it surprising: reading it as
        seen takes a dstate of its own (and splits those determinism carries it back to), so the suspects
        allowed so far cannot reach the bound. Such a time point, or the one before it, disagrees with
        every other time point of its class (a *loner*; the clear suspects' views already set aside):
        each loner and the time point after it become suspects too. So do the time points whose view,
        as the ones before them saw it later, raises their classes' lower bounds (*inflators*). Few are
        (4-6 loners, 1-13 inflators in a 600-step exploration with 2% misreads)."""
        loners = self.features.loners(self.classes, leave_out=self.suspects)
        inflators = self.features.inflators(self.classes, leave_out=self.suspects)
        times = sorted(({u for t in loners for u in (t, t + 1) if u < len(self.tableau)} | set(inflators))
                       - set(self.suspects))
        # Each may have been misread from the views its contexts show instead (any view where they show
        # none): every other view would make each ghost a candidate of every class with its heading.
        actions = action_symbols(self.tableau, self.angles)
        expected = context_views(self.tableau.views, actions, times)
        return [Suspect(t, MISREAD_COST, expected[t], GHOST) for t in times]

    def _within_share(self, work, share: tuple[float, float] = None):
        """``work()`` within a share of the time left (``(fraction, at most seconds)``, by default
        ``VERIFY_SHARE`` and ``VERIFY_MAX_S``); None if that runs out."""
        full = self.deadline
        self.deadline = full.share(*(share or (VERIFY_SHARE, VERIFY_MAX_S)))
        try:
            return work()
        except SolveTimeout:
            return None
        finally:
            self.deadline = full

    def _allow_misreads(self, exact_facts: list[Symbol], suspects: list[Suspect]) -> int:
        """Let these suspects be misreads from now on; the classes' lower bounds without them, and what
        that proves. Returns the dstates the search aims at: the bound the suspects leave."""
        self._check_clock("the lower bounds with misreads")
        self.suspects = {s.t: s for s in suspects}
        self.facts = exact_facts + [SUSPECT(s.t, s.cost) for s in suspects] + self._may_be(suspects)
        # The prepass with these suspects would derive the same features but those their views show:
        # read from the one prepass made reading every view as seen.
        self.classes.lower = self.features.lower_bounds(self.classes, leave_out=self.suspects)
        self.proved = self.classes.lower_bound  # no explanation, misreads or not, needs fewer dstates
        return self.proved

    def _may_be(self, suspects: list[Suspect]) -> list[Symbol]:
        """For each suspect, the classes it may have been misread from: those of the views the
        experience around it expects (any other view when it expects none), with every other feature
        of its own class (its heading)."""
        index = {key: c for c, key in enumerate(self.classes.keys) if key is not None}
        views = sorted({v for v in self.tableau.views}, key=str)
        out = []
        for s in suspects:
            own = self.classes.keys[self.classes.of_time[s.t]]
            if own is None:
                continue
            for view in s.expected or views:
                key = key_with_view(own, String(view))
                if key != own and key in index:
                    out.append(MAY_BE(s.t, key))
        return out

    def one_per_class(self) -> CognitiveMap | None:
        """The first try, in one grounding: one dstate per class. If it fails, learn the classes from it."""
        outcome = self._solve([ONE_PER_CLASS()], "one dstate per class", keep=True)
        self.first = outcome.grounding  # its classes are read only when needed (a Python loop over atoms)
        if outcome.models:  # every class holds its one dstate: as many classes as dstates
            cmap = self._map(outcome)
            return replace(cmap, stats=replace(cmap.stats, classes=cmap.n_dstates, lower_bound=cmap.n_dstates))
        self.classes = self.first.classes(range(len(self.tableau)))
        self.proved = self.classes.count + 1
        return None

    def _suspects(self, found: CognitiveMap | None) -> list[Suspect]:
        """The views the search may take as misreads: none unless allowed; where one dstate per class
        explains the experience, only views with one or two images (each made a dstate of its own)."""
        if not self.resolver.misreads or (found and not rare_clustered_views(self.tableau)):
            return []
        images = _images(self.tableau)
        actions = action_symbols(self.tableau, self.angles)
        suspects = find_suspects(self.tableau.views, actions, images)
        if images is None:
            # A rare view is suspect where views come from clustering images (one image a passer-by
            # filled); a label given with no image is the user's word (a landmark seen once).
            suspects = [s for s in suspects if s.reason != RARE_VIEW]
        # A view is surprising in its context only against experience the robot has repeated: not
        # where one dstate per class explains it, nor in early exploration (few visits per class).
        repeated = not found and len(self.tableau) >= MIN_VISITS * self.classes.count
        return suspects if repeated else [s for s in suspects if s.reason == RARE_VIEW]

    def bounded(self, bound: int) -> CognitiveMap | None:
        """The minimal maps if at most ``bound`` dstates will do, else None (and the bound is proved)."""
        outcome = self._solve(self.classes.layout(bound), f"at most {bound} dstates")
        if outcome.models:
            return self._map(outcome)
        self.proved = max(self.proved, bound + 1)
        return None

    def bound_classes_from_below(self) -> None:
        self._check_clock("the lower bounds")
        self.depth = self.resolver.future_depth
        grounded = prepass(self.resolver.theory, self.facts, self.depth)
        self.ground_s += grounded.ground_s
        self.features = grounded.partial_features(self.classes.times)
        self.classes.lower = self.features.lower_bounds(self.classes)
        self.proved = max(self.proved, self.classes.lower_bound)

    def some_map(self) -> CognitiveMap:
        """A valid map with few spare dstates per class (doubling the spare until one is found)."""
        widest = max(size - low for size, low in zip(self.classes.sizes, self.classes.lower))
        spare = 1
        while True:
            layout = self.classes.layout(len(self.tableau), spare=spare)
            outcome = self._solve(layout, f"any map with {spare} spare dstate(s) per class", models=1)
            if outcome.models:
                self.best = self._map(outcome, minimal=False)
                return self.best
            if spare >= widest:
                levels = tuple(self.resolver.theory.levels)
                raise InconsistentTableau(
                    "no map satisfies the axioms: no partition of the time points into dstates explains "
                    f"this experience (levels: {', '.join(levels)})", levels=levels)
            spare = min(widest, 2 * spare)

    def optimise(self, upper: CognitiveMap | None, bound: int | None = None) -> CognitiveMap | None:
        """The minimal maps within ``bound`` dstates (default: the upper map's), by clingo's optimisation;
        None if no map has that few."""
        bound = upper.n_dstates if bound is None else bound  # type: ignore[union-attr]
        layout = self.classes.layout(bound) + [MINIMISE_DSTATES()]
        what = f"the fewest dstates{' and misreads' if self.suspects else ''}, at most {bound} dstates"
        outcome = self._solve(layout, what, optimise=True)
        if not outcome.models:  # only when a bound below the upper map's was asked for
            return None
        cmap = self._map(outcome)
        return replace(cmap, stats=replace(cmap.stats, lower_bound=cmap.n_dstates))  # the optimiser proved it

    def _map(self, outcome: "_Outcome", minimal: bool = True) -> CognitiveMap:
        models = outcome.models if minimal else outcome.models[:1]
        return build_map(self.tableau, models, minimal and outcome.exhausted, self.resolver.theory.levels,
                         self._stats(), minimal=minimal, action_types=self.action_types,
                         misread_costs=self._costs(), retyped_steps=self._retyped_steps())

    def _retyped_steps(self) -> list[dict]:
        return [s.to_dict(MISTYPE_COST) for s in self.retyped]

    def _costs(self) -> dict[int, int]:
        return {t: s.cost for t, s in self.suspects.items()}

    def _stats(self) -> SolveStats:
        """The figures so far, as a snapshot: each map keeps its own."""
        return SolveStats(classes=self.classes.count if self.classes else 0, lower_bound=self.proved,
                          as_seen_lower_bound=self.as_seen if self.suspects else None,
                          ground_s=self.ground_s, solve_s=self.solve_s,
                          total_s=time.perf_counter() - self.start, bounds=tuple(self.tries))

    def _solve(self, layout: list[Symbol], what: str, models: int | None = None, optimise: bool = False,
               keep: bool = False) -> "_Outcome":
        """Ground and solve; on time-out raise SolveTimeout with the best map known."""
        size = None
        if self.classes is not None:  # the first try always runs: its classes bound the answer
            self._check_clock(what)
            size = self._grounding_size(layout)
            self._check_grounding(what, size)
        options = [str(self.resolver.max_models + 1 if models is None else models)]
        if optimise:
            options += ["--opt-mode=optN", "--opt-strategy=usc"]
        grounding = Grounding(self.resolver.theory, self.facts + layout, self.depth, options).ground()
        if size is None:
            # The first try (one slot for each time point): what every grounding of this tableau costs
            # (the theory, the facts), and until a search is grounded, how fast this machine grounds.
            self.fixed_ground_s = grounding.ground_s
            self.ground_rate = FIRST_TRY_SHARE * grounding.ground_s / max(len(self.tableau), 1) ** GROUND_POWER
        elif size >= self.rate_size:
            # The largest search so far, less the fixed costs (which dominate small groundings and would
            # make a larger one look far slower than it is), predicts the next.
            self.ground_rate = max(grounding.ground_s - self.fixed_ground_s, 0.0) / size ** GROUND_POWER
            self.rate_size = size
        optimal: list[list[Symbol]] = []
        improving: list[list[Symbol]] = []

        def on_model(m: clingo.Model) -> None:
            (optimal if not optimise or m.optimality_proven else improving).append(m.symbols(shown=True))

        result = grounding.solve(self.deadline, on_model)
        self.ground_s += grounding.ground_s
        self.solve_s += grounding.solve_s
        verdict = "timeout" if result is None else ("sat" if result.satisfiable else "unsat")
        self.tries.append(Try(what, verdict, grounding.ground_s + grounding.solve_s))
        if result is None:
            if self.classes is None:  # timed out in the first try: the classes still bound the answer
                self.classes = grounding.classes(range(len(self.tableau)))
                self.proved = self.classes.count
            raise self._timed_out(what, improving)
        return _Outcome(optimal, bool(result.exhausted), grounding if keep else None)

    def _grounding_size(self, layout: list[Symbol]) -> int:
        """How large a search's grounding will be, before it is made: the candidate dstates of each
        time point (its class's slots, and those of the classes a suspect may be misread from) times
        those of the next (what experience/next and determinism are grounded over)."""
        slots = {key: m.number for key, m in SLOTS.args(layout)}
        keys, of_time = self.classes.keys, self.classes.of_time
        cand = [slots.get(keys[c], 0) for c in of_time]
        for t, key in MAY_BE.args(self.facts):
            cand[t.number] += slots.get(key, 0)
        return sum(a * b for a, b in zip(cand, cand[1:])) + len(cand)

    def _check_grounding(self, what: str, size: int) -> None:
        """Out of time before a grounding starts that would end well past the deadline, as the
        groundings of this resolution so far predict it (clingo can interrupt neither a grounding nor
        the preparation of its first solve, which takes about as long again)."""
        left = self.deadline.remaining()
        if left is None or self.ground_rate is None:
            return
        predicted = PREPARE_FACTOR * (self.fixed_ground_s + self.ground_rate * size ** GROUND_POWER)
        if predicted > left + GROUND_GRACE_S:
            raise self._timed_out(f"{what} (not started: its grounding would take about {predicted:.0f} s "
                                  f"with {left:.1f} s left)", [])

    def _check_clock(self, what: str) -> None:
        """Out of time before a grounding starts: stop here (clingo cannot interrupt a grounding)."""
        if self.deadline.passed():
            raise self._timed_out(what, [])

    def _timed_out(self, what: str, improving: list) -> SolveTimeout:
        if improving:  # the optimiser's last (smallest) model so far
            self.best = build_map(self.tableau, improving[-1:], False, self.resolver.theory.levels,
                                  self._stats(), minimal=False, action_types=self.action_types,
                                  misread_costs=self._costs(), retyped_steps=self._retyped_steps())
        found = (f"best map so far: {self.best.n_dstates} dstates, not proved minimal" if self.best
                 else "no map found yet")
        limit = self.deadline.limit_s
        return SolveTimeout(f"time limit of {limit:g} s reached while looking for {what}; "
                            f"at least {self.proved} dstates are proved necessary; {found}",
                            lower_bound=self.proved, best_map=self.best, time_limit_s=limit, stage=what)


def _images(tableau: Tableau) -> np.ndarray | None:
    """The tableau's images when every step has one (their margins price misreads), else None."""
    if not has_images(tableau):
        return None
    return as_images([s.image for s in tableau.steps])


@dataclass
class _Outcome:
    models: list[list[Symbol]]
    exhausted: bool
    grounding: Grounding | None = None
