"""Maps that keep up with a robot as it explores: extend the map by each new step, re-solve only when
that does not stand.

A robot explores step by step, and most steps repeat what it has done before: the same action from
the same dstate. When the map of the experience so far is the unique minimal map, a new time point
reached by an action already taken from the same dstate must be at the dstate that action led to
before (determinism). If the map so extended still satisfies every axiom, it is the unique minimal map
of the longer experience as well:

* minimal: a map of the longer experience restricted to the old steps is a map of them, so it has at
  least as many dstates as their minimal map; the extension adds none;
* unique: every minimal map of the longer experience restricts to the old steps' unique map, and
  determinism then places the new time point.

So the result equals a fresh resolve of the same steps, which is what the tests check on every prefix
of long walks. A new step reached by an action never taken from its dstate before is placed by the
axioms instead, where they allow one place only: the last map with the new time point at each dstate of
its view, checked by clingo in one grounding (the old partition fixed, the new point's dstate chosen
among those). If exactly one is accepted, that map is the unique minimal map of the longer experience:

* minimal: it has as many dstates as the last map, which no map of the longer experience has fewer of;
* unique: a minimal map of the longer experience restricts to the old steps' unique map, and puts the
  new time point at one of its dstates, of which the axioms accepted one.

Anything else (a new transition the axioms accept nowhere or in several places, a changed action type, a
view that may be a misread, an ambiguous map) is resolved again from scratch, from the dstates the last
map proved necessary: a minimal map read as seen has as many as any map of the longer experience needs
at least; one more where it was the only one and does not extend (a new step the axioms place nowhere,
or not where determinism puts it); so the search skips the bounds below. (The minimal maps it finds are
shown in their canonical order, as a fresh resolve shows them; where they are more than the resolver
lists, which ones are listed depends on the search's path, and the stream resolves from scratch.) Where
some views are suspect (possible misreads, :mod:`.misreads`), the map is extended only where the
resolver too would keep the exact map without weighing them: one dstate per class, experience too little
repeated for misreads to show, or as many dstates as the classes' proved lower bounds.

Who checks: with the axiom files bootmap ships, :mod:`.replay` keeps, step by step, what the axioms
derive from the experience (headings, classes, the features that tell time points apart, the suspect
views, the classes' lower bounds) and checks only what the new steps change: a few milliseconds a step,
however long the tableau. With a theory a user added to or edited, clingo checks the whole extended map
with the partition fixed (``fixed/2``), so the user's axioms are honoured.

Example
-------
>>> from bootmap.examples import notched_rectangle
>>> stream = MapStream()
>>> full = notched_rectangle(3)
>>> for n in range(1, len(full) + 1):
...     cmap = stream.update(full.prefix(n))
>>> cmap.n_dstates, stream.extended_, stream.resolved_ > 0
(8, 16, True)
"""

from __future__ import annotations

import time
from dataclasses import replace

from clingo import Symbol

from ..tableau import Tableau
from .cogmap import CognitiveMap, SolveStats, Try, build_map, step_row
from .facts import (action_symbol, action_symbols, passes_through, tableau_facts, travel_length_types,
                    travel_lengths, typing_of)
from .grounding import Deadline, check_fixed, prepass
from .misreads import MIN_VISITS, find_suspects, has_images, rare_clustered_views
from .motion import ActionType
from .replay import Replay, covers, length_labels
from .resolver import Resolver
from .vocabulary import FIXED, fixed_dstate

__all__ = ["MapStream"]


class MapStream:
    """The map of a growing tableau, kept current.

    Parameters
    ----------
    resolver : Resolver, optional
        Resolves from scratch when the map cannot be extended (default ``Resolver()``).

    Attributes
    ----------
    map_ : CognitiveMap or None
        The map of the last tableau given.
    extended_ : int
        Updates answered by extending the map (checked by clingo, no search).
    joined_ : int
        Updates answered by placing a new transition's end at the one dstate the axioms accept there
        (checked by clingo, no search).
    resolved_ : int
        Updates answered by a full resolve.
    """

    def __init__(self, resolver: Resolver | None = None):
        self.resolver = resolver or Resolver()
        self.map_: CognitiveMap | None = None
        self.extended_ = 0
        self.joined_ = 0
        self.resolved_ = 0
        self._joined = False  # the last extension placed a new transition's end (see _join)
        self._at_least = 0  # dstates the last map proves the longer experience needs, for a resolve
        self._tableau: Tableau | None = None
        self._angles: list[int] = []
        # The stock axioms are replayed in Python (:mod:`.replay`); a theory a user changed, by clingo.
        self._replays = covers(self.resolver.theory)
        self._replay: Replay | None = None
        self._images = False  # every step so far has an image (misreads.rare_clustered_views)

    def update(self, tableau: Tableau, deadline: Deadline | None = None) -> CognitiveMap:
        """The map of ``tableau``, which usually extends the last one given by a few steps."""
        deadline = deadline or Deadline.after(self.resolver.time_limit)
        start = time.perf_counter()
        typing = typing_of(tableau, self.resolver.quantum_deg)
        angles, types = typing.angles, typing.types
        cmap = None
        self._joined, self._at_least = False, 0
        # The resolver may take an action as mistyped, against the whole experience: then resolve anew, and
        # the last map (of the old steps read as typed) proves nothing of the new one.
        retyping = self.resolver.retype and typing.suspects()
        if not retyping:
            cmap = self._extended(tableau, angles, types, deadline, start)
        if cmap is None:
            if not retyping:
                self._at_least = max(self._at_least, self._proved(tableau, angles))
            # Where the minimal maps are more than the resolver lists, which ones it lists depends on the
            # search's path, and a search from the bounds the last map proved takes another path than a
            # fresh one: there the stream resolves as a fresh resolve does (where every minimal map is
            # listed, their order is canonical whatever the path: cogmap.canonical_order). A last map
            # with too many to list says the next likely has too.
            capped = self.map_ is not None and self.map_.models_capped
            cmap = self.resolver.resolve(tableau, deadline, at_least=0 if capped else self._at_least)
            if cmap.models_capped and self._at_least and not capped:
                cmap = self.resolver.resolve(tableau, deadline)
            self.resolved_ += 1
            self._replay = None
            self._images = has_images(tableau)
        elif self._joined:
            self.joined_ += 1
        else:
            self.extended_ += 1
        self.map_, self._tableau, self._angles = cmap, tableau, angles
        return cmap

    def _extended(self, tableau: Tableau, angles: list[int], types: list[ActionType], deadline: Deadline,
                  start: float) -> CognitiveMap | None:
        """The last map extended by determinism to the new steps, if it is still the unique minimal map;
        else None."""
        old, cmap = self._tableau, self.map_
        if old is None or cmap is None or not (cmap.unique and cmap.minimal) or cmap.suspect_steps \
                or cmap.retyped_steps:  # its actions were typed against the whole experience: resolve anew
            return None
        n = len(old)
        if not self._continues(tableau, angles):
            return None
        if passes_through(tableau):
            return None  # a travel may end at any dstate further on: determinism alone places nothing
        self._images = self._images and all(s.image is not None for s in tableau.steps[n:])
        if self._replays:
            return self._replayed(tableau, angles, types, deadline, start)
        if self.resolver.misreads and rare_clustered_views(tableau):
            return None  # the resolver weighs views of one or two images against any map: let it
        dstate_of = _by_determinism(cmap, tableau, angles, n)
        placed = dstate_of or _by_determinism(cmap, tableau.prefix(len(tableau) - 1), angles, n)
        if placed is None:
            return None
        facts = tableau_facts(tableau, angles=angles)
        if self.resolver.misreads and self._suspect(tableau, angles) and not self._exact_stands(facts, len(tableau)):
            return None
        if dstate_of is None:  # the last step's action was never taken from its dstate: the axioms place it
            return self._join(tableau, facts, types, placed, deadline, start)
        return self._checked(tableau, facts, types, dstate_of, deadline, start)

    def _proved(self, tableau: Tableau, angles: list[int]) -> int:
        """Dstates every map of the longer tableau needs, reading every view as seen: as many as the last
        map, where that was proved minimal reading every view as seen and the old steps read as before (a
        map of the longer experience restricts to a map of theirs); else 0."""
        old, cmap = self._tableau, self.map_
        if cmap is None or not cmap.minimal or cmap.suspect_steps or cmap.retyped_steps:
            return 0
        if not self._continues(tableau, angles):
            return 0
        if {t: dm for t, dm in travel_lengths(tableau).items() if t < len(old) - 1} != travel_lengths(old):
            return 0  # a travel's length type learned anew from the longer experience
        return cmap.n_dstates

    def _continues(self, tableau: Tableau, angles: list[int]) -> bool:
        """The tableau is the last one with steps after it, its actions read as before (the action types
        learned from the longer experience may read an old action anew)."""
        old = self._tableau
        if old is None or len(tableau) <= len(old) or not _extends(tableau, old):
            return False
        return angles[:len(old) - 1] == self._angles[:len(old) - 1]

    def _one_more(self) -> None:
        """The last map, the only minimal one, does not extend to the new steps: a map of them with as few
        dstates would restrict to it, so every one has a dstate more (for the resolve)."""
        self._at_least = self.map_.n_dstates + 1

    def _replayed(self, tableau: Tableau, angles: list[int], types: list[ActionType], deadline: Deadline,
                  start: float) -> CognitiveMap | None:
        """The stock axioms' verdict on the extended map, from what the new steps change (:mod:`.replay`)."""
        old, cmap = self._tableau, self.map_
        replay = self._replay or Replay.of(old.steps, self._angles, length_labels(travel_lengths(old)), cmap,
                                           "metrical" in self.resolver.theory.levels, self.resolver.future_depth)
        self._replay = None  # stale unless all below holds
        lengths, length_types = travel_length_types(tableau)
        dstate_of = replay.extend(tableau.steps, angles, length_labels(lengths))
        if replay.refuted:
            self._one_more()
        if dstate_of is None and replay.unplaced is None:
            return None
        if self.resolver.misreads and self._images and replay.watch.rare:
            return None  # the resolver weighs views of one or two images against any map: let it
        if self.resolver.misreads and not replay.exact_stands(cmap.n_dstates, self._images):
            return None  # some views are suspect and the bounds do not prove the exact map: resolve
        if dstate_of is None:  # the last step's action was never taken from its dstate: the axioms place it
            return self._join(tableau, tableau_facts(tableau, angles=angles), types, replay.dstate_of, deadline, start)
        self._replay = replay
        rows = cmap.steps[:len(old) - 1] + [step_row(t, tableau.steps[t], dstate_of[t], cmap.place_of, cmap.path_of)
                                           for t in range(len(old) - 1, len(tableau))]
        seconds = time.perf_counter() - start
        stats = SolveStats(classes=len(replay.members), lower_bound=cmap.n_dstates, total_s=seconds,
                           bounds=(Try("the last map extended by determinism (stock axioms replayed)", "sat",
                                       seconds),))
        return replace(cmap, steps=rows, dstate_of=list(dstate_of), action_types=types,
                       length_types=length_types, stats=stats)

    def _join(self, tableau: Tableau, facts: list[Symbol], types, placed: list[str], deadline: Deadline,
              start: float) -> CognitiveMap | None:
        """The last map with the new last time point (``placed`` holds every other's dstate) at the one
        dstate of its view the axioms accept it at, if exactly one: the unique minimal map (module
        docstring). None where they accept it at none or at several. At none, every map of the longer
        experience has a dstate more than the last map (one with as many restricts to it, and puts the new
        point at one of its dstates): that is proved, for the resolve (:meth:`_one_more`); how many
        minimal maps there are then, only a search says. One grounding: the old partition fixed, the new
        point's dstate one of those of its view (``fixed/2`` at each), and clingo asked for two models."""
        if deadline.passed():
            return None
        t = len(tableau) - 1
        candidates = [d for d, view in self.map_.views.items() if view == tableau.steps[t].view]
        if not candidates:
            self._one_more()
            return None
        group = {d: k for k, d in enumerate(dict.fromkeys(placed[:t]))}
        fixed = [FIXED(u, fixed_dstate(group[d])) for u, d in enumerate(placed[:t])]
        fixed += [FIXED(t, fixed_dstate(group[d])) for d in candidates]
        # The stock axioms' after(S) features follow from determinism and the dstates' views (causal.lp):
        # with the partition fixed they decide nothing, and the check grounds without them. A theory a
        # user changed may read them: there, as the resolver does.
        depth = 0 if self._replays else self.resolver.future_depth
        models, grounding = check_fixed(self.resolver.theory, facts + fixed, depth, deadline, models=2)
        if models == []:
            self._one_more()
        if not models or len(models) > 1:
            return None
        self._joined, self._replay = True, None  # the replay knows no dstate for the new point: made anew
        stats = SolveStats(classes=self.map_.stats.classes, lower_bound=self.map_.n_dstates,
                           ground_s=grounding.ground_s, solve_s=grounding.solve_s, total_s=time.perf_counter() - start,
                           bounds=(Try("the last map, the new transition's end at the one dstate the axioms accept",
                                       "sat", grounding.ground_s + grounding.solve_s),))
        return build_map(tableau, models, True, self.resolver.theory.levels, stats, action_types=types)

    def _suspect(self, tableau: Tableau, angles: list[int]) -> bool:
        actions = action_symbols(tableau, angles)
        return bool(find_suspects(tableau.views, actions))

    def _exact_stands(self, facts: list[Symbol], n_times: int) -> bool:
        """Where some views are suspect, the resolver keeps the exact map without weighing misreads when
        it has one dstate per class, or when the experience is too little repeated (``MIN_VISITS``): so
        does the stream, for the last map's dstates on ``n_times`` time points (an extension, or a new
        point placed at one of them, adds none). (Where the exact map has as many dstates as the classes'
        lower bounds, the resolver may still weigh misreads that are evident; the replay of the stock
        axioms mirrors that rule, this check leaves it to a resolve.)"""
        grounded = prepass(self.resolver.theory, facts, self.resolver.future_depth)
        classes = grounded.classes(range(n_times))
        return classes.count == self.map_.n_dstates or n_times < MIN_VISITS * classes.count

    def _checked(self, tableau: Tableau, facts: list[Symbol], types, dstate_of: list[str],
                 deadline: Deadline, start: float) -> CognitiveMap | None:
        """The map of this partition if it satisfies every axiom (clingo, the partition fixed)."""
        group = {d: n for n, d in enumerate(dict.fromkeys(dstate_of))}
        fixed = [FIXED(t, fixed_dstate(group[d])) for t, d in enumerate(dstate_of)]
        models, grounding = check_fixed(self.resolver.theory, facts + fixed, self.resolver.future_depth, deadline)
        if models == []:
            self._one_more()
        if not models:
            return None
        n_dstates = len(set(dstate_of))
        stats = SolveStats(classes=self.map_.stats.classes, lower_bound=n_dstates, ground_s=grounding.ground_s,
                           solve_s=grounding.solve_s, total_s=time.perf_counter() - start,
                           bounds=(Try("the last map extended by determinism", "sat",
                                       grounding.ground_s + grounding.solve_s),))
        return build_map(tableau, models, True, self.resolver.theory.levels, stats, action_types=types)


def _extends(tableau: Tableau, old: Tableau) -> bool:
    """The new tableau is the old one with steps after it (the old last step now has its action)."""
    n = len(old)
    return (tableau.steps[:n - 1] == old.steps[:n - 1]
            and replace(tableau.steps[n - 1], action=None) == replace(old.steps[n - 1], action=None))


def _by_determinism(cmap: CognitiveMap, tableau: Tableau, angles: list[int], n: int) -> list[str] | None:
    """The old partition, each new time point at the dstate its action led to before from the same
    dstate; None if some new step takes an action never taken from there."""
    dstate_of = list(cmap.dstate_of)
    led: dict[tuple[str, Symbol], str] = {}
    for t in range(n - 1):
        led[(dstate_of[t], action_symbol(tableau.steps[t].action, angles[t]))] = dstate_of[t + 1]
    for t in range(n, len(tableau)):
        key = (dstate_of[t - 1], action_symbol(tableau.steps[t - 1].action, angles[t - 1]))
        if key not in led:
            return None
        dstate_of.append(led[key])
    return dstate_of
