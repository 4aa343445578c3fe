"""Misread abduction: some views may be misreads (:mod:`bootmap.mapping.misreads` names the suspects and
prices them), and the resolver keeps the better of two explanations of the experience.

Read as seen, every view is evidence and the exact minimal map follows. With some suspects taken as
misreads, a map may need fewer dstates; it is chosen only when it saves more dstates than its misreads
cost (a dstate costs ``DSTATE_COST``). A suspect allowed as a misread may belong to the classes of the
views its context expects (``may_be/2``); the classes' lower bounds without the suspects' views are read
from the one prepass the exact search made. Where the suspects cannot reach the bound they leave, the
views that make a dstate of their own (*ghosts*) become suspects too.
"""

from __future__ import annotations

import time
from collections import defaultdict
from contextvars import ContextVar
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np
from clingo import String, Symbol

from ...errors import InconsistentTableau
from ...images import as_images
from ...tableau import Tableau
from ..cogmap import CognitiveMap, Try
from ..facts import action_symbols
from ..grounding import key_with_view
from ..misreads import (AS_EXPECTED, BESIDE, GHOST, MIN_VISITS, MISREAD_COST, RARE_VIEW, Suspect, context_views,
                        find_suspects, has_images, rare_clustered_views, read_as_expected, skipping_views)
from ..vocabulary import DSTATE_COST, MAY_BE, SUSPECT

if TYPE_CHECKING:
    from .budget import Budget
    from .exact import ExactSearch
    from .state import SearchState

#: The share of the time left (and at most so many seconds) spent checking that reading every view as
#: seen does not explain the experience more cheaply than the misreads do, when the bounds do not say.
VERIFY_SHARE, VERIFY_MAX_S = 0.25, 10.0

#: The share of the time left (and at most so many seconds) for resolving the experience with its clear
#: suspects read as their contexts expect (:meth:`MisreadAbduction._as_expected`).
AS_EXPECTED_SHARE = (0.5, 60.0)

#: Set while a resolution weighs the clear suspects read as expected: the resolution it makes of those views
#: does not read them so again.
_reading_as_expected: ContextVar[bool] = ContextVar("reading_as_expected", default=False)


class MisreadAbduction:
    """Weighs reading every view as seen against taking some suspect views as misreads: it changes the
    facts the exact search (``search``) reads (``state.facts``, ``state.suspects``) and asks it for maps."""

    def __init__(self, state: SearchState, budget: Budget, search: ExactSearch):
        self.state, self.budget, self.search = state, budget, search

    def suspects(self, found: CognitiveMap | None) -> list[Suspect]:
        """The views the search may take as misreads: none unless allowed; where one dstate per class
        explains the experience, only views with one or two images (each made a dstate of its own)."""
        state = self.state
        tableau = state.tableau
        if not state.resolver.misreads or (found and not rare_clustered_views(tableau)):
            return []
        images = _images(tableau)
        actions = action_symbols(tableau, state.angles)
        suspects = find_suspects(tableau.views, actions, images)
        if images is None:
            # A rare view is suspect where views come from clustering images (one image a passer-by
            # filled); a label given with no image is the user's word (a landmark seen once).
            suspects = [s for s in suspects if s.reason != RARE_VIEW]
        # A view is surprising in its context only against experience the robot has repeated: not
        # where one dstate per class explains it, nor in early exploration (few visits per class).
        repeated = not found and len(tableau) >= MIN_VISITS * state.classes.count
        return suspects if repeated else [s for s in suspects if s.reason == RARE_VIEW]

    def robust(self, suspects: list[Suspect], exact: CognitiveMap | None = None) -> CognitiveMap:
        """The better of two explanations, when some views are suspect: read as seen (the exact minimal
        map), or with some suspects taken as misreads (the fewest dstates any such map needs, then the
        fewest misread costs). A misread map is chosen only when it needs fewer dstates than reading every
        view as seen by more than its misreads cost (a dstate costs ``DSTATE_COST``): proved by the exact
        lower bound where that suffices, else by asking for an exact map within the difference."""
        state, search = self.state, self.search
        exact_facts = state.facts
        state.learn_classes()
        search.bound_classes_from_below()
        exact_lower = state.classes.lower
        clear = [s for s in suspects if s.clear] or suspects
        above = None  # the exact maps a few dstates above the lower bound
        if exact is None and state.classes.lower_bound > state.classes.count and not self._misreads_evident(clear):
            exact = search.bounded(state.classes.lower_bound)  # reading every view as seen, when that is easy
            if exact is None:
                # Where no misread is evident, a bound that falls a few dstates short (a person's apart
                # splits what determinism then carries back) is the likelier reason: the exact maps just
                # above it (ExactSearch.climb), in a share of the time. With one in hand, misreads are
                # weighed only where they could pay (2,000 steps with an apart: 5.7 s in all, against
                # 25 s weighing misreads at every bound up to it).
                above = self.budget.within_share(search.climb, (VERIFY_SHARE, VERIFY_MAX_S))
        known = exact or above
        state.as_seen = known.n_dstates if known else max(state.proved, sum(exact_lower))
        if exact is not None:
            # Reading every view as seen is easy (its lower bound holds): a misread that carries a
            # contradiction forward would have made it hard. Only views with one or two images, each a
            # dstate of its own in the exact map, are left to weigh.
            suspects = [s for s in suspects if s.reason == RARE_VIEW]
            if not suspects:
                return exact
        fewest = self._allow_misreads(exact_facts, clear)
        if known is not None:
            # The exact map is in hand: misreads must save more dstates than the cheapest of them costs,
            # and are looked for in a share of the time (clean experience must not wait for them).
            if DSTATE_COST * (known.n_dstates - fewest) <= min(s.cost for s in clear):
                misread = None
            else:
                misread = self.budget.within_share(lambda: self._misread_map(fewest, known.n_dstates - 1),
                                                   (VERIFY_SHARE, VERIFY_MAX_S))
                if misread is None:  # none in the layouts the bounds set: in a guess's, in a share as well
                    guessed = self._as_expected(exact_facts, clear, (VERIFY_SHARE, VERIFY_MAX_S))
                    misread = guessed[0] if guessed is not None else None
        else:
            misread = self._misread_map(fewest, state.as_seen, exact_facts, suspects)
        if misread is None:  # the misreads save nothing: read every view as seen
            state.facts, state.suspects, state.classes.lower = exact_facts, {}, exact_lower
            return known or search.minimal_maps()
        cost = sum(state.suspects[s["t"]].cost for s in misread.suspect_steps)
        saved = state.as_seen - misread.n_dstates  # at least this many more dstates without the misreads
        if not misread.suspect_steps or DSTATE_COST * saved > cost:
            return misread
        if known is not None:  # the exact map is minimal: the misreads do not pay for themselves
            state.suspects = {}
            return known
        # Not proved by the bound: is there a map reading every view as seen within the misreads' cost?
        # Looked for in a share of the time left: where reading misreads as seen is hard to explain, the
        # search for it is hard too, and the misread map is kept (the tries say the check timed out).
        suspects = state.suspects
        state.facts, state.suspects, state.classes.lower = exact_facts, {}, exact_lower

        def exact_within_cost() -> CognitiveMap | None:
            for bound in range(state.as_seen, misread.n_dstates + cost // DSTATE_COST + 1):
                found = search.bounded(bound)
                if found:
                    return found
            return None

        found = self.budget.within_share(exact_within_cost, (VERIFY_SHARE, VERIFY_MAX_S))
        state.suspects = suspects
        return found or misread

    def _misreads_evident(self, clear: list[Suspect]) -> bool:
        """Leaving the clear suspects' views out lowers the classes' bounds by a dstate or more per suspect:
        reading them as seen is what splits the classes. Then the exact map at its lower bound (a search
        that fails, and slowly: 1-8 s on 600-step explorations with 2% misreads) is not tried first; the
        misreads are weighed against the exact lower bound instead. On clean experience whose suspects
        are chance (aliasing), leaving them out lowers the bounds by less than one per suspect (0-7 for
        1-84 suspects on 600-step explorations)."""
        state = self.state
        without = sum(state.features.lower_bounds(state.classes, leave_out={s.t for s in clear}))
        return state.classes.lower_bound - without >= len(clear)

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
        state, search = self.state, self.search
        clear = chosen = list(state.suspects.values())
        planned, proved = state.classes.lower, state.proved
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
            misread = search.optimise(None, lowest) or self._beside(exact_facts, chosen, lowest)
            if misread is not None:
                return misread
            state.classes.lower, state.proved = planned, max(proved, lowest + 1)
        misread = search.optimise(None, fewest)
        guessed = None  # the best map in the layout of a guess, and the misreads it allowed (then in force)
        if misread is None and exact_facts is not None:
            before = state.proved
            guessed = self._as_expected(exact_facts, chosen)
            if guessed is None:
                state.classes.lower, state.proved = planned, before
        taken = {s.t for s in chosen}
        others = [s for s in wider if s.t not in taken]
        if misread is None and exact_facts is not None and others:
            # The layout stays the one the clear suspects set: the others may join their classes'
            # dstates, but each class keeps its dstates (a small search, where misreads are few). With a
            # guess's map in hand, in a share of the time, and the cheaper of the two kept.
            self._allow_misreads(exact_facts, chosen + others)
            state.classes.lower, state.proved = planned, proved
            def weigh() -> CognitiveMap | None:
                return search.optimise(None, fewest)

            misread = weigh() if guessed is None else self.budget.within_share(weigh, AS_EXPECTED_SHARE)
            if misread is not None and guessed is not None and _cost(*guessed) < _cost(misread, state.suspects):
                misread = None
            if misread is None and guessed is not None:
                self._allow_misreads(exact_facts, list(guessed[1].values()))
            elif misread is None:  # each dstate more is a slot more for every class, and each suspect's
                self._allow_misreads(exact_facts, chosen)  # other classes' slots with it: too many
                state.classes.lower, state.proved = planned, proved
        if misread is None and guessed is not None:
            return guessed[0]
        cheapest = min((s.cost for s in state.suspects.values()), default=0)
        while misread is None and fewest < ceiling:
            fewest += 1
            state.proved = max(state.proved, fewest)
            if DSTATE_COST * (state.as_seen - fewest) <= cheapest:
                # A map with misreads and this many dstates saves too few against reading every view as
                # seen (at least as_seen dstates) to pay for a misread, and so does every map with more.
                # Where the exact map is in hand (the ceiling below it), none is looked for; else only a
                # map at the ceiling can be one reading every view as seen, and one search there finds
                # the cheapest map within it, where the bounds one by one took a search each (a stream's
                # misread resolves, 5x5 grid: 78 to 82 dstates in six searches).
                if ceiling < state.as_seen:
                    return None
                fewest = ceiling
            misread = search.optimise(None, fewest)
        return misread

    def _beside(self, exact_facts: list[Symbol], chosen: list[Suspect], bound: int) -> CognitiveMap | None:
        """The best map with misreads in the layout ``bound`` set (the ghosts' bounds), where the time points
        beside the suspects ``chosen`` may be misreads too; None if there is none.

        Where a dstate was seen only three or four times and two of those visits were misread, its
        contexts hold as many misreads as true views: the misread there looks ordinary, and the time point
        whose transition it breaks, next to it, is the one suspected. Allowed beside every suspect, the
        missed misread is found in the same layout (which keeps every class's dstates: a small search,
        where a dstate more in the bound would give every class a slot more). A suspect next to such a
        misread was expected, by the side that saw it, to be what the misread showed (a true .FR. read as
        L..B after a true L..B read as LFRB was expected only as LFRB): each suspect may then also have
        been misread from any view its one-step contexts saw. And a context next to a suspect shows the
        suspect's view, misread or not: each time point beside a suspect (and each suspect beside another)
        may also have been misread from what the contexts that skip that suspect saw (three misreads in a
        row, at places seen four and seven times, each expected only as the next misread showed). So may the
        first and the last time point: each has one side only, and a misread there surprises no context
        seen more than twice (the last of 600 steps, misread, left no map with the ghosts' bound)."""
        state = self.state
        layout = list(state.classes.lower)
        taken = {s.t for s in chosen}
        last = len(state.tableau) - 1
        # (and the first and the last time point: each has one side, which a misread there may not surprise)
        near = sorted(({u for t in taken for u in (t - 1, t + 1) if 0 <= u <= last} | {0, last}) - taken)
        if not near:
            return None
        actions = action_symbols(state.tableau, state.angles)
        seen = context_views(state.tableau.views, actions, near + sorted(taken))
        skipped = skipping_views(state.tableau.views, actions, near + sorted(taken), taken)

        def widen(s: Suspect) -> Suspect:  # a suspect that expects any view (expected == ()) stays so
            more = set(seen[s.t]) | set(skipped.get(s.t, ()))
            return replace(s, expected=tuple(sorted(set(s.expected) | more, key=str))) if s.expected else s

        beside = [widen(Suspect(t, MISREAD_COST, seen[t], BESIDE)) for t in near]
        self._allow_misreads(exact_facts, [widen(s) for s in chosen] + beside)
        state.classes.lower = layout  # the suspects beside may lower the bounds: the layout stays the ghosts'
        misread = self.search.optimise(None, bound)
        if misread is None:  # the suspects as they were (the caller lays the classes out anew)
            self._allow_misreads(exact_facts, chosen)
        return misread

    def _as_expected(self, exact_facts: list[Symbol], chosen: list[Suspect],
                     share: tuple[float, float] = AS_EXPECTED_SHARE
                     ) -> tuple[CognitiveMap, dict[int, Suspect]] | None:
        """The best map with misreads in the layout of a guess, where the layouts the bounds set hold none,
        and the suspects it allowed (in force when it returns); None if the guess gives none.

        The bounds set a layout a misread no suspect rule caught can break: read as seen it splits its
        class (a bound above the truth), or the ghosts leave a seldom-seen class no dstate (below it), and
        a dstate more over a bound gives every class a slot more, a search past any time limit. The guess:
        the clear suspects whose contexts expect one view read as that view, found again on the views so
        read (:func:`..misreads.read_as_expected`), and those views resolved, misreads allowed, in a share
        of the time left (``AS_EXPECTED_SHARE``). Half the misreads of a 600-step exploration with 5% of
        its views misclustered are read right so; the rest are few enough for the resolution to name. Its
        map is no answer of its own (its views are a guess): it lays out the search of the experience as
        seen, each class the dstates its time points read as seen hold there, and the time points read as
        expected or named misread there may be misreads, of the view of their dstate there. Where the
        guess is right, the truth is within that layout, and the search finds the best map in it."""
        state = self.state
        if _reading_as_expected.get() or state.assertions:
            return None
        tableau, classes = state.tableau, state.classes
        actions = action_symbols(tableau, state.angles)
        views, changed = read_as_expected(tableau.views, actions)
        if not changed:
            return None
        flag = _reading_as_expected.set(True)
        t0, verdict = time.perf_counter(), "timeout"
        try:
            resolver = replace(state.resolver, diagnose=False)
            guess = self.budget.within_share(
                lambda: resolver.resolve(tableau.with_views(views), self.budget.deadline), share)
        except InconsistentTableau:
            guess, verdict = None, "unsat"
        finally:
            _reading_as_expected.reset(flag)
        what = f"the {len(changed)} clear suspects read as their contexts expect, resolved"
        if guess is not None:
            what, verdict = f"{what}: {guess.n_dstates} dstates, {len(guess.suspect_steps)} misreads", "sat"
        state.tries.append(Try(what, verdict, time.perf_counter() - t0))
        if guess is None:
            return None
        self.budget.check_clock("the layout of the views read as expected")
        guessed = set(changed) | {s["t"] for s in guess.suspect_steps}
        # Each class holds the dstates its time points read as seen are at in the guess; a dstate's
        # class is that of those time points.
        own = dict(zip(classes.times, classes.of_time))
        held: dict[int, set] = defaultdict(set)
        class_of: dict = {}
        view_of: dict[int, str] = {}
        for t, c in own.items():
            if t not in guessed:
                held[c].add(guess.dstate_of[t])
                class_of.setdefault(guess.dstate_of[t], c)
                view_of.setdefault(c, tableau.steps[t].view)
        allowed = {s.t: s for s in chosen}
        for t in sorted(guessed):
            c = class_of.get(guess.dstate_of[t])
            if c is None or c == own.get(t):
                # read as seen there after all (or at a dstate no view read as seen holds there: one of
                # its own class, as the experience read as seen has it)
                if t in own:
                    held[own[t]].add(guess.dstate_of[t])
                continue
            known = allowed.get(t)
            if known is None:
                allowed[t] = Suspect(t, MISREAD_COST, (view_of[c],), AS_EXPECTED)
            elif known.expected and view_of[c] not in known.expected:
                allowed[t] = replace(known, expected=tuple(sorted({*known.expected, view_of[c]}, key=str)))
        self._allow_misreads(exact_facts, list(allowed.values()))
        state.classes.lower = [len(held[c]) for c in range(len(classes.sizes))]
        misread = self.search.optimise(None, classes.lower_bound)
        if misread is None:
            self._allow_misreads(exact_facts, chosen)
            return None
        return misread, allowed

    def _ghosts(self) -> list[Suspect]:
        """Views no suspect rule caught that the experience shows a dstate of their own.

        A misread where the robot has seldom been has no context to make it surprising: reading it as
        seen takes a dstate of its own (and splits those determinism carries it back to), so the suspects
        allowed so far cannot reach the bound. Such a time point, or the one before it, disagrees with
        every other time point of its class (a *loner*; the clear suspects' views already set aside):
        each loner and the time point after it become suspects too. So do the time points whose view,
        as the ones before them saw it later, raises their classes' lower bounds (*inflators*). Few are
        (4-6 loners, 1-13 inflators in a 600-step exploration with 2% misreads)."""
        state = self.state
        loners = state.features.loners(state.classes, leave_out=state.suspects)
        inflators = state.features.inflators(state.classes, leave_out=state.suspects)
        times = sorted(({u for t in loners for u in (t, t + 1) if u < len(state.tableau)} | set(inflators))
                       - set(state.suspects))
        # Each may have been misread from the views its contexts show instead (any view where they show
        # none): every other view would make each ghost a candidate of every class with its heading.
        actions = action_symbols(state.tableau, state.angles)
        expected = context_views(state.tableau.views, actions, times)
        return [Suspect(t, MISREAD_COST, expected[t], GHOST) for t in times]

    def _allow_misreads(self, exact_facts: list[Symbol], suspects: list[Suspect]) -> int:
        """Let these suspects be misreads from now on; the classes' lower bounds without them, and what
        that proves. Returns the dstates the search aims at: the bound the suspects leave."""
        state = self.state
        self.budget.check_clock("the lower bounds with misreads")
        state.suspects = {s.t: s for s in suspects}
        state.facts = exact_facts + [SUSPECT(s.t, s.cost) for s in suspects] + self._may_be(suspects)
        # The prepass with these suspects would derive the same features but those their views show:
        # read from the one prepass made reading every view as seen.
        state.classes.lower = state.features.lower_bounds(state.classes, leave_out=state.suspects)
        state.proved = state.classes.lower_bound  # no explanation, misreads or not, needs fewer dstates
        return state.proved

    def _may_be(self, suspects: list[Suspect]) -> list[Symbol]:
        """For each suspect, the classes it may have been misread from: those of the views the
        experience around it expects (any other view when it expects none), with every other feature
        of its own class (its heading)."""
        classes = self.state.classes
        index = {key: c for c, key in enumerate(classes.keys) if key is not None}
        views = sorted({v for v in self.state.tableau.views}, key=str)
        out = []
        for s in suspects:
            own = classes.keys[classes.of_time[s.t]]
            if own is None:
                continue
            for view in s.expected or views:
                key = key_with_view(own, String(view))
                if key != own and key in index:
                    out.append(MAY_BE(s.t, key))
        return out


def _cost(cmap: CognitiveMap, suspects: dict[int, Suspect]) -> int:
    """What a map with misreads costs: its dstates, and each misread at the cost of the suspect it was."""
    return DSTATE_COST * cmap.n_dstates + sum(suspects[s["t"]].cost for s in cmap.suspect_steps)


def _images(tableau: Tableau) -> np.ndarray | None:
    """The tableau's images when every step has one (their margins price misreads), else None."""
    if not has_images(tableau):
        return None
    return as_images([s.image for s in tableau.steps])
