"""Maps that keep up with a robot as it explores: extend the minimal maps by each new step, re-solve only
when that does not stand.

A robot explores step by step, and most steps repeat what it has done before: the same action from
the same dstate. The resolver's answer is every minimal map of the experience (where there are more
than it lists, some of them). Listed in full, they are all the stream needs for the next step: a map of
the longer experience restricted to the old steps is a map of them, so it has at least as many dstates
as their minimal maps; one with as many restricts to one of them, and puts the new time point

* where the action led before from the same dstate (determinism), if the action was taken there before;
* else at one of that map's dstates of the new point's class (its view, and heading with the metrical
  level): a transition never taken from there, which the axioms may accept at several dstates or none;
* or, where no time point before it has its class, at a dstate of its own: then every map of the
  longer experience has one more dstate, and those that have no more are exactly the minimal maps so
  extended.

So the minimal maps of the longer experience are the extensions of the last ones that the axioms accept,
where any is accepted: the same maps as a fresh resolve finds, shown in the same (canonical) order, which
the tests check on every prefix of long walks. Where none is accepted, every map of the longer experience
has a dstate more than the last ones, and the resolve starts there.

Where the experience leaves more minimal maps than the resolver lists (``models_capped``), the last maps
are some of them: those that extend are minimal maps of the longer experience, and the stream lists them
(still capped); where none extends, another might, and the stream resolves. Which minimal maps are listed
then depends on the search's path, so a fresh resolve may list others: the stream's are minimal maps with
as many dstates, which the tests check. (Resolving afresh after every such step, to list what a fresh
resolve lists, made 70 of a 6x6 grid's 2,000 steps wait 0.2-0.3 s each.)

Anything else (a changed action type, a view that may be a misread) is resolved again from scratch,
from the dstates the last map proved necessary: a minimal map read as seen has as many as any map of the
longer experience needs at least. Where some views are suspect (possible misreads, :mod:`.misreads`),
the maps are extended only where the resolver too would keep the exact map without weighing them: one
dstate per class, experience too little repeated for misreads to show, or as many dstates as the
classes' proved lower bounds.

Who checks: with the axiom files bootmap ships, :mod:`.replay` keeps, step by step, what the axioms
derive from the experience (headings, classes, the features that tell time points apart, the suspect
views, the classes' lower bounds) and places the new steps in each map as the causal and metrical levels
allow; the levels that judge the map alone (the topological one) are asked by clingo of each map with a
new transition, on its dstates and transitions only (:meth:`.mapcheck.MapCheck.each`: one grounding for
the ways to extend one map). A few milliseconds a step where determinism places it, 15-30 ms where a
transition is new, however long the tableau. With a theory a user added to or edited, clingo checks the
whole extended map with the partition fixed (``fixed/2``), so the user's axioms are honoured; there the
stream extends a unique map only (and places a new transition's end where the axioms accept it at one
dstate only).

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

from clingo import Number, Symbol

from ..tableau import Tableau
from .cogmap import CognitiveMap, SolveStats, Try, build_map, map_of, step_row
from .facts import (action_symbol, action_symbols, passes_through, tableau_facts, travel_length_types,
                    travel_lengths, typing_of)
from .grounding import Deadline, check_fixed, prepass
from .misreads import MIN_VISITS, find_suspects, has_images, rare_clustered_views
from .motion import ActionType
from .mapcheck import MapCheck
from .replay import Partition, Replay, action_symbol_of, length_labels
from .resolver import Resolver
from .topology import link_kind, shape
from .vocabulary import AHEAD, FIXED, LEFT, NEXT, PATH_OF, PLACE_OF, RIGHT, Atoms, fixed_dstate

__all__ = ["MapStream"]

#: The stream keeps so many of the latest rejected transitions for its resolves.
MAX_REJECTED = 5000


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
        Updates answered by extending the minimal maps by determinism (no search).
    joined_ : int
        Updates answered by placing a new transition's end where the axioms accept it, in each minimal
        map (no search).
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
        self._replays = self.resolver.stock
        self._replay: Replay | None = None
        self._observed: Replay | None = None  # a replay that observed every step of this update's tableau
        self._map_check: MapCheck | None = None
        self._kinds: dict[tuple, tuple[int, int]] = {}  # a replayed action as the topological level reads it
        self._terms: list[Symbol] = []  # Number(d), made once
        self._images = False  # every step so far has an image (misreads.rare_clustered_views)
        # transitions the levels that judge the map alone rejected together in earlier resolves: they reject
        # any map they are in, whatever the tableau (Resolver.resolve's ``rejected``), so each resolve rules
        # them out before it solves rather than find such maps again as the map grows
        self._rejected: list[list[Symbol]] = []

    def update(self, tableau: Tableau, deadline: Deadline | None = None) -> CognitiveMap:
        """The map of ``tableau``, which usually extends the last one given by a few steps."""
        deadline = deadline or Deadline.after(self.resolver.time_limit)
        start = time.perf_counter()
        typing = typing_of(tableau, self.resolver.quantum_deg)
        angles, types = typing.angles, typing.types
        cmap = None
        self._joined, self._at_least, self._observed = False, 0, None
        # The resolver may take an action as mistyped, against the whole experience: then resolve anew, and
        # the last map (of the old steps read as typed) proves nothing of the new one.
        retyping = self.resolver.retype and typing.suspects()
        if not retyping:
            cmap = self._extended(tableau, angles, types, deadline, start)
        if cmap is None:
            if not retyping:
                self._at_least = max(self._at_least, self._proved(tableau, angles))
            # (what the levels rejected in earlier resolves is ruled out before the search: see _rejected)
            cmap = self.resolver.resolve(tableau, deadline, at_least=self._at_least, rejected=self._rejected)
            del self._rejected[:-MAX_REJECTED]
            self.resolved_ += 1
            self._replay = self._observed.rebased(cmap) if self._observed is not None else None
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
        if old is None or cmap is None or not cmap.minimal or cmap.suspect_steps \
                or cmap.retyped_steps:  # its actions were typed against the whole experience: resolve anew
            return None
        if (cmap.models_capped or not cmap.unique) and not self._replays:
            return None  # clingo checks one map extended (a theory a user changed): several need a search
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
        """The minimal maps of the longer tableau from the last ones: each extended as the stock axioms
        allow (:mod:`.replay`), a map with a new transition judged by the levels that judge the map alone
        (:meth:`_judged`). None where a resolve must say."""
        old, cmap = self._tableau, self.map_
        replay = self._replay or Replay.of(old.steps, self._angles, length_labels(travel_lengths(old)), cmap,
                                           "metrical" in self.resolver.theory.levels, self.resolver.future_depth)
        self._replay = None  # stale unless all below holds
        lengths, length_types = travel_length_types(tableau)
        unique = len(replay.maps) == 1
        # Where the last maps were some of the minimal maps (more than the resolver lists), those that
        # extend are minimal maps of the longer experience, and some of them; where none does, another
        # might: no dstate more is proved.
        some = cmap.models_capped
        at_most = max(self.resolver.max_models, len(replay.maps)) if some else self.resolver.max_models
        maps = replay.extend(tableau.steps, angles, length_labels(lengths), at_most)
        # Where it observed every step, a resolve of them gives it its maps (update), rather than a replay
        # made anew observing every step again (0.05 s a step at 330 steps: a stream's misread resolves)
        self._observed = replay if maps is not None and len(replay.views) == len(tableau.steps) else None
        if replay.refuted and not some:
            self._one_more()
        if not maps:
            return None
        if self.resolver.misreads and self._images and replay.watch.rare:
            return None  # the resolver weighs views of one or two images against any map: let it
        n_dstates = len(maps[0].view_of)
        if self.resolver.misreads and not replay.exact_stands(n_dstates, self._images):
            return None  # some views are suspect and the bounds do not prove the exact map: resolve
        joined = any(m.added for m in maps)
        if joined or not unique or len(maps) > 1:
            if deadline.passed():
                return None
            maps = self._judged(maps)
            if not maps:  # the levels reject every way to extend: no map has as few dstates
                if not some:
                    self._one_more()
                return None
            replay.maps = maps
        self._replay, self._joined = replay, joined
        seconds = time.perf_counter() - start
        how = ("the last maps extended, new transitions placed where the axioms accept them" if joined else
               "the last map extended by determinism") + " (stock axioms replayed)"
        stats = SolveStats(classes=len(replay.members), lower_bound=n_dstates, total_s=seconds,
                           bounds=(Try(how, "sat", seconds),))
        if unique and len(maps) == 1 and not joined:
            # The last map's places and paths stand, and so do its names: a replayed map numbers its dstates
            # by first appearance, as the map names them (a new dstate, the last to appear, is numbered next).
            rows = cmap.steps[:len(old) - 1] + [step_row(t, tableau.steps[t], f"S{maps[0].dstate_of[t]}", cmap.place_of,
                                                         cmap.path_of) for t in range(len(old) - 1, len(tableau))]
            return replace(cmap, steps=rows, dstate_of=[f"S{d}" for d in maps[0].dstate_of], action_types=types,
                           length_types=length_types, stats=stats)
        readings = sorted((m.reading(replay.metrical) for m in maps), key=lambda r: r.seq)
        return map_of(tableau, readings, not some, self.resolver.theory.levels, stats, action_types=types,
                      length_types=length_types)

    def _judged(self, maps: list[Partition]) -> list[Partition]:
        """The maps the levels that judge the map alone accept (all, where the theory has none), each with
        what they show of it. Maps extended from one map only by their new transitions are asked in one
        grounding (:meth:`.mapcheck.MapCheck.each`)."""
        levels = self.resolver.theory.map_levels
        if not levels:
            for m in maps:
                m.shown, m.added = Atoms(()), []
            return maps
        check = self._map_check or MapCheck(self.resolver.theory, levels)
        self._map_check = check
        if check.fast:  # the stock topological level, read in Python from the partitions themselves
            return [m for m in maps if self._shaped(m)]
        groups: dict[int, list[Partition]] = {}  # by the map they were extended from: its transitions and more
        for m in maps:
            if m.shown is None or m.added:
                groups.setdefault(id(m.origin), []).append(m)
        rejected: set[int] = set()
        for group in groups.values():
            first = group[0]
            inputs = first.transitions(leave_out=first.added)
            options = [[NEXT(Number(d), action_symbol_of(a), Number(d2)) for d, a, d2 in m.added] for m in group]
            for m, shown in zip(group, check.each(inputs, options)):
                if shown is None:
                    rejected.add(id(m))
                else:
                    m.shown, m.added, m.origin = Atoms(shown), [], object()
        return [m for m in maps if id(m) not in rejected]

    def _shaped(self, m: Partition) -> bool:
        """Whether the stock topological level accepts the map ``m``; if it does, what it shows of it is
        kept in ``m`` (:func:`.topology.shape`, read from its transitions without a clingo symbol)."""
        if m.shown is not None and not m.added:
            return True
        dstates = sorted(m.view_of)
        index = {d: i for i, d in enumerate(dstates)}
        kinds = self._kinds
        for _, a in m.led:
            if a not in kinds:
                kinds[a] = link_kind(action_symbol_of(a))
        found = shape([(index[d], *kinds[a], index[d2]) for (d, a), d2 in m.led.items()], len(dstates))
        if found is None:
            return False
        terms = self._terms
        terms.extend(Number(i) for i in range(len(terms), dstates[-1] + 1))
        atoms = found.atoms([terms[d] for d in dstates])
        m.shown = Atoms(()).plus({p: atoms[p.name] for p in (PLACE_OF, PATH_OF, AHEAD, RIGHT, LEFT)})
        m.added = []
        return True

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


