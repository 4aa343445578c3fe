"""The stock axioms replayed on repeated experience, step by step: what keeps a streamed map current in
a few milliseconds.

:class:`~.stream.MapStream` extends the minimal maps of a tableau to new steps (its docstring has the
argument why the extensions the axioms accept are the minimal maps of the longer experience). Whether
a map so extended still satisfies the axioms, clingo can say by grounding the whole tableau with the
partition fixed; but that grounds every step again on every step. For the axiom files bootmap ships,
the answer needs only what the new steps change, and :class:`Replay` keeps it as the steps arrive:

* causal.lp: a time point shows its dstate's view (``one_value_per_feature``). Where determinism places
  it, what it saw after a sequence of actions (``after(S)``) then follows from the views and
  determinism, and ``next/3`` gains no transition, so ``deterministic_action`` and the whole
  topological level (which reads only ``next/3``) hold as before. Where its action was never taken
  from the dstate before it (a new transition), no other time point at a dstate took the same actions
  up to it, so no ``after(S)`` feature disagrees; ``next/3`` gains the transition, which the topological
  level is asked of (:meth:`.mapcheck.MapCheck.each`, in the stream).
* metrical.lp: the heading after an action is the heading before plus the action's type angle, and must
  be its dstate's; a travel's length type must be the one its dstate's travels have (a dstate's one
  travel: a new one from a dstate is its first).

What the resolver does with the longer tableau also depends on what it derives before any search, and
:class:`Replay` keeps that too, as :mod:`.grounding`'s prepass would derive it: the classes of time points
(view and heading), the features only some time points show (``after(S)``, ``length``: all of them,
where the prepass reads only those its class shows with two values or more, core/prepass.lp, which
tell the same time points apart), and, where some
views are suspect (:class:`~.misreads.SuspectWatch`), the classes' lower bounds, recomputed only for the
classes whose time points a step changed.

A resolution needs the same before its search: :class:`Prepassed` works out, from a tableau's steps, the
classes and the features that tell time points of a class apart, as the prepass grounds them (and
whether the causal and metrical axioms accept one dstate per class, :meth:`Prepassed.one_per_class`), so
that a resolution under the stock files grounds no prepass, and no first try over its time points.

These arguments are about the stock files, which :func:`covers` recognises by their digests (a test pins
them to ``asp/``), on tableaux of a robot that stopped at every dstate: their rules for a log that drove
through dstates (``passes_through``) never fire here, since :class:`~.stream.MapStream` resolves such a
tableau anew; nor do core/assert.lp's, which a person's assertions switch on and a stream never has. A
theory with a file a user added or edited is checked by clingo instead, so the axioms a user writes are
always honoured.
"""

from __future__ import annotations

from collections import ChainMap
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np
from clingo import Number, String, Symbol

from ..tableau import Step, Turn
from .cogmap import CognitiveMap, Reading
from .grounding import Classes, PartialFeatures, apart_clique
from .misreads import MIN_VISITS, SuspectWatch
from .theory import STOCK_DIGESTS, Theory, covers, digest  # noqa: F401 (the replay's record, kept beside the files)
from .vocabulary import (CLASS_KEY_TERM, DSTATE, HEADING_FEATURE, HEADING_OF, NEXT, NIL, VIEW_FEATURE, VIEW_OF,
                         Atoms, action_term)

def action_key(step: Step, angle: int) -> tuple:
    """The action from a step as causal.lp names it (``turn(A)`` or ``travel``), as a Python value."""
    return ("turn", angle) if isinstance(step.action, Turn) else ("travel",)


def action_symbol_of(key: tuple) -> Symbol:
    """A replayed action (:func:`action_key`) as the causal level names it."""
    return action_term(key[0], key[1] if len(key) > 1 else 0)


@dataclass
class Partition:
    """One map of the replayed experience, its dstates numbered by first appearance (as the map names
    them, ``S0, S1, ...``; a new dstate, the last to appear, takes the next number): each time point's
    dstate, where each (dstate, action) led, each dstate's view, heading (None without the metrical level)
    and travels' length type, and the dstates of each class; and what the levels that judge the map alone
    show of it (:mod:`.mapcheck`, its dstates ``Number`` terms), once asked, with the transitions added
    since (``added``), which they have not judged yet."""

    dstate_of: list[int]
    led: dict[tuple[int, tuple], int] = field(default_factory=dict)
    view_of: dict[int, str] = field(default_factory=dict)
    heading_of: dict[int, int | None] = field(default_factory=dict)
    length_of: dict[int, int] = field(default_factory=dict)
    in_class: dict[tuple, list[int]] = field(default_factory=dict)
    shown: Atoms | None = None
    added: list[tuple[int, tuple, int]] = field(default_factory=list)
    origin: object = field(default_factory=object)  # the map shown was asked of; its branches share it

    def transitions(self, leave_out: Sequence[tuple[int, tuple, int]] = ()) -> list[Symbol]:
        """The map as the levels that judge the map alone read it (:mod:`.mapcheck`): its ``next/3``
        transitions (but those left out) and the ``dstate/1`` they and the first time point's make."""
        kept = {(d, a, d2) for (d, a), d2 in self.led.items()} - set(leave_out)
        known = {d for d, _, d2 in kept for d in (d, d2)} | {self.dstate_of[0]}
        return ([NEXT(Number(d), action_symbol_of(a), Number(d2)) for d, a, d2 in kept]
                + [DSTATE(Number(d)) for d in known])

    def reading(self, metrical: bool) -> Reading:
        """The map as the cognitive map is built from it: its partition, its dstates' views and headings, and
        what the levels that judge the map alone showed of it (``shown``)."""
        ids: dict[int, int] = {}
        seq = [ids.setdefault(d, len(ids)) for d in self.dstate_of]
        terms = {d: Number(d) for d in ids}
        more = {VIEW_OF: [(terms[d], String(v)) for d, v in self.view_of.items()]}
        if metrical:
            more[HEADING_OF] = [(terms[d], Number(h)) for d, h in self.heading_of.items()]
        return Reading(seq, {terms[d]: i for d, i in ids.items()}, (self.shown or Atoms(())).plus(more))

    def branch(self) -> "Partition":
        """A copy to extend another way."""
        return Partition(list(self.dstate_of), dict(self.led), dict(self.view_of), dict(self.heading_of),
                         dict(self.length_of), {k: list(v) for k, v in self.in_class.items()}, self.shown,
                         list(self.added), self.origin)


def partition_of(dstate_of: list[int], read: "Replay | Prepassed") -> Partition:
    """The map that puts each time point at ``dstate_of[t]``, of an experience as the stock axioms read it
    (its views, actions, headings with the metrical level, travels' length types and classes): each
    dstate's view, heading and class as its first time point's, its transitions, its travels' length type."""
    p = Partition(list(dstate_of))
    for t, d in enumerate(dstate_of):
        if d not in p.view_of:
            p.view_of[d] = read.views[t]
            p.heading_of[d] = read.headings[t] if read.metrical else None
            p.in_class.setdefault(read.class_of[t], []).append(d)
        if t + 1 < len(dstate_of):
            p.led[(d, read.actions[t])] = dstate_of[t + 1]
        if t in read.lengths:
            p.length_of[d] = read.lengths[t]
    return p


class Replay:
    """A tableau's experience as the stock axioms read it before any search, and its minimal maps, kept
    up to date as steps are appended.

    Parameters
    ----------
    metrical : bool
        The metrical level is loaded: headings group time points, and travel lengths are features.
    future_depth : int
        How many actions ahead ``after(S)`` features look (causal.lp's ``future_depth``).
    """

    def __init__(self, metrical: bool, future_depth: int):
        self.metrical, self.depth = metrical, future_depth
        self.views: list[str] = []
        self.actions: list[tuple] = []          # the action from each time point but the last
        self.angles: list[int] = []             # its type angle
        self.lengths: dict[int, int] = {}       # time point -> length type of its travel
        self.headings: list[int] = []           # with the metrical level
        self.partial: list[dict] = []           # features only some time points show
        self.class_of: list[tuple] = []         # (view, heading) of each time point
        self.members: dict[tuple, list[int]] = {}
        self.watch = SuspectWatch()
        self.maps: list[Partition] = []         # every minimal map, the one shown first
        # class -> its lower bound (and the map's dstates in the class that capped its search), while no step
        # changes the class's time points or the features that tell them apart
        self._lower: dict[tuple, tuple[int | None, int]] = {}
        self._without: dict[tuple, tuple[int | None, int]] = {}  # ... and without the clear suspects' views
        self._values: dict[tuple, dict[tuple, set]] = {}  # class -> feature -> the values its time points show
        self._cleared: frozenset[int] = frozenset()
        self.refuted = False                    # the last extension left no map with as many dstates

    # ------------------------------------------------------------------------------------------------

    @classmethod
    def of(cls, steps: Sequence[Step], angles: Sequence[int], lengths: dict[int, int], cmap: CognitiveMap,
           metrical: bool, future_depth: int) -> "Replay":
        """The replay of a tableau's steps and its minimal maps (the map and its alternatives), from scratch."""
        replay = cls(metrical, future_depth)
        for t in range(len(steps)):
            replay._observe(t, steps, angles, lengths, watch=False)
        replay.watch = SuspectWatch.of(replay.views, replay.actions)
        return replay.rebased(cmap)

    def rebased(self, cmap: CognitiveMap) -> "Replay":
        """This replay with the minimal maps of ``cmap`` (the map and its alternatives), a map of the steps
        it has observed (a resolve of them, where the maps it kept did not extend)."""
        self.maps = [self._partition([int(d[1:]) for d in names])
                     for names in [cmap.dstate_of] + list(cmap.alternatives)]
        self.refuted = False
        return self

    def _partition(self, dstate_of: list[int]) -> Partition:
        """The map that puts each time point at ``dstate_of[t]``."""
        return partition_of(dstate_of, self)

    def extend(self, steps: Sequence[Step], angles: Sequence[int], lengths: dict[int, int],
               at_most: int) -> list[Partition] | None:
        """Every minimal map extended to the new time points as the causal and metrical axioms allow (see
        :meth:`_placed`): each is a map of the longer experience with as many dstates, or with one more
        where a new time point's class is new (no other time point has its view and heading, so every map
        gives it a dstate of its own). Of the maps returned, those with ``added`` transitions the levels
        that judge the map alone must still accept. Empty where none extends (``refuted``: no map of the
        longer experience has as few dstates); None where the action types learned from the longer
        experience read an old action anew, or the maps grow past ``at_most`` (the replay is then stale:
        make a new one)."""
        self.refuted = False
        if angles[:len(self.actions)] != self.angles or any(lengths.get(t) != v for t, v in self.lengths.items()):
            return None
        for t in range(len(self.views), len(steps)):
            self._observe(t, steps, angles, lengths)
            fresh = len(self.members[self.class_of[t]]) == 1
            extended = [e for m in self.maps for e in self._placed(m, t, fresh)]
            self.maps = extended
            if not extended:
                self.refuted = True
                return []
            if len(extended) > at_most:
                return None
        return self.maps

    def _placed(self, m: Partition, t: int, fresh: bool) -> list[Partition]:
        """Map ``m`` extended to time point t, every way the causal and metrical axioms accept:

        - a transition taken before from t - 1's dstate: where it led (determinism), if t shows that
          dstate's view and heading and the travel has its length type;
        - a transition never taken from there: at each dstate of t's class, or at a new dstate where the
          class is new. What the experience shows after an action sequence (``after(S)``) tells nothing
          against it: time points at one dstate that took the same actions would have taken this
          transition before. (A new transition is one the map's levels have not judged: ``added``.)
        """
        d_before, action = m.dstate_of[t - 1], self.actions[t - 1]
        d = m.led.get((d_before, action))
        if d is not None:
            if not self._fits(m, t, d, d_before):
                return []
            m.dstate_of.append(d)
            return [m]
        key = self.class_of[t]
        targets = [len(m.view_of)] if fresh else list(m.in_class.get(key, ()))
        out = []
        for i, d in enumerate(targets):
            b = m if i == len(targets) - 1 else m.branch()
            b.dstate_of.append(d)
            b.led[(d_before, action)] = d
            if t - 1 in self.lengths:
                b.length_of[d_before] = self.lengths[t - 1]
            if fresh:
                b.view_of[d], b.heading_of[d] = self.views[t], self.headings[t] if self.metrical else None
                b.in_class.setdefault(key, []).append(d)
            b.added.append((d_before, action, d))
            out.append(b)
        return out

    def _fits(self, m: Partition, t: int, d: int, d_before: int) -> bool:
        """Whether the stock axioms accept time point t at dstate d of map m (where determinism places it)."""
        if m.view_of[d] != self.views[t]:
            return False  # another view at its end
        if self.metrical and m.heading_of.get(d) != self.headings[t]:
            return False  # the action's type angle does not lead to the dstate's heading
        if self.metrical and t - 1 in self.lengths and self.lengths[t - 1] != m.length_of.get(d_before):
            return False  # a travel of another length than the dstate's travels
        return True

    def exact_stands(self, n_dstates: int, images: bool = False) -> bool:
        """The resolver keeps the exact map without weighing misreads: no view is suspect; or one dstate
        per class; or experience too little repeated for misreads to show (``MIN_VISITS``); or the
        classes' lower bounds add up to the map's dstates and the misreads are not evident (leaving the
        clear suspects' views out lowers the bounds by less than one dstate per suspect: the resolver's
        ``_misreads_evident``, which otherwise weighs them against the exact bound)."""
        count = len(self.members)
        if not self.watch.suspects or count == n_dstates or len(self.views) < MIN_VISITS * count:
            return True
        bound = self._bounds(self._lower, lambda times: (times, _telling(times, self.partial)))
        if bound != n_dstates:
            return False
        clear = self._clear(images)
        if clear != self._cleared:  # the views left out changed: every class's bound without them may too
            self._without, self._cleared = {}, clear
        without = None  # the features without the clear suspects' views, made once some class needs them

        def left(times: list[int]) -> tuple[list[int], dict]:
            nonlocal without
            if without is None:
                without = self.without(clear)
            return [t for t in times if t not in clear], _telling(times, without, self.partial)

        return bound - self._bounds(self._without, left) < len(clear)

    def _bounds(self, cache: dict[tuple, tuple[int | None, int]], clique_of) -> int:
        """The classes' lower bounds added up, each worked out again (``clique_of(times)``: the time points
        and the features :func:`apart_clique` reads) where ``cache`` has none for the class, or one searched
        with another cap (the map's dstates in the class)."""
        for key, times in self.members.items():
            at_most = self._dstates_in(key)
            cached = cache.get(key)
            if cached is None or cached[0] != at_most:
                cache[key] = (at_most, apart_clique(*clique_of(times), exact=True, at_most=at_most))
        return sum(value for _, value in cache.values())

    def _dstates_in(self, key: tuple) -> int | None:
        """A class's dstates in a map (the first): as many as any set of its time points that pairwise
        disagree can hold."""
        return len(self.maps[0].in_class[key]) if self.maps and key in self.maps[0].in_class else None

    def _clear(self, images: bool) -> frozenset[int]:
        """The suspects the resolver would leave out first: the clear ones, or all where none is clear
        (views with one or two images are suspects only in a tableau of images)."""
        rare = () if images else self.watch.rare_names
        suspects = [t for t in self.watch.suspects if self.views[t] not in rare]
        clear = [t for t in suspects if t in self.watch.clear_suspects]
        return frozenset(clear or suspects)

    def without(self, views_at: frozenset[int]):
        """The features, but for those shown by the views seen at ``views_at`` (what the time points
        before them saw there): causal.lp does not rely on a suspect's view."""
        dropped: dict[int, set] = {}
        for u in views_at:
            for t in range(max(0, u - self.depth), u):
                dropped.setdefault(t, set()).add(("after", tuple(self.actions[t:u])))
        return ChainMap({t: {k: v for k, v in self.partial[t].items() if k not in keys}
                         for t, keys in dropped.items()}, self.partial)

    # ------------------------------------------------------------------------------------------------

    def _class(self, view: str, heading: int | None) -> tuple:
        return (view, heading if self.metrical else None)

    def _observe(self, t: int, steps: Sequence[Step], angles: Sequence[int], lengths: dict[int, int],
                 watch: bool = True) -> None:
        """Time point t (the next one): its view, the action that led to it, and what that adds to the
        features of the time points before it."""
        view = steps[t].view
        before = None
        if t > 0:
            before = action_key(steps[t - 1], angles[t - 1])
            self.actions.append(before)
            self.angles.append(angles[t - 1])
            if self.metrical and t - 1 in lengths:  # metrical.lp's length_is_feature
                self.lengths[t - 1] = lengths[t - 1]
                self._feature(t - 1, ("length",), lengths[t - 1])
            if self.metrical:
                self.headings.append((self.headings[t - 1] + angles[t - 1]) % 360)
        elif self.metrical:
            self.headings.append(0)
        self.views.append(view)
        self.partial.append({})
        # What each of the last few time points saw after the actions from it up to t.
        for s in range(max(0, t - self.depth), t):
            self._feature(s, ("after", tuple(self.actions[s:t])), view)
        key = self._class(view, self.headings[t] if self.metrical else None)
        self.class_of.append(key)
        self.members.setdefault(key, []).append(t)
        self._lower.pop(key, None)
        self._without.pop(key, None)
        if watch:
            self.watch.append(view, before)

    def _feature(self, t: int, key: tuple, value) -> None:
        """Time point t shows ``value`` of feature ``key``. Its class's bounds change only where the feature
        tells some of its time points apart (:func:`_telling`): where the class shows another value of it;
        a feature the class shows one value of is no evidence (1,774 of a 2,000-step stream's steps add
        such features to eight time points each, and the bounds were worked out again for each)."""
        self.partial[t][key] = value
        cls = self.class_of[t]
        shown = self._values.setdefault(cls, {}).setdefault(key, set())
        if shown and shown != {value}:
            self._lower.pop(cls, None)
            self._without.pop(cls, None)
        shown.add(value)


def _telling(times: Sequence[int], features, among=None) -> dict[int, dict]:
    """The features of ``times`` (one class's time points) that tell some of them apart: those the class
    shows two values of, in ``among`` (default ``features`` itself), as a prepass keeps them
    (:class:`.grounding.PartialFeatures`). The lower bounds' greedy sets try the time points that show
    most such features first: with every feature counted, their order, and at times the bound (a class of
    64 time points: 3 dstates where the resolver proves 4), were not the resolver's."""
    among = features if among is None else among
    values: dict = {}
    for t in times:
        for k, v in among[t].items():
            values.setdefault(k, set()).add(v)
    telling = {k for k, vs in values.items() if len(vs) > 1}
    return {t: {k: v for k, v in features[t].items() if k in telling} for t in times}


class Prepassed:
    """What :func:`.grounding.prepass` derives from a tableau's facts under the stock axioms (:func:`covers`),
    worked out in Python from the steps, with no grounding: the classes of time points (view, and heading
    with the metrical level; their keys the terms core/partition.lp folds, ``k(heading, H, k(view, V,
    nil))``) and the features that tell time points of one class apart (core/prepass.lp's ``telling/3``:
    ``after(S)``, the view seen after the action sequence S, up to ``future_depth`` actions on, and a
    travel's ``length``, each where its class shows it with two values or more). The same arguments as
    :class:`Replay`'s, for a robot that stopped at every dstate (not ``passes_through``), without a
    person's assertions or suspect views among the facts (their features are core/assert.lp's and
    causal.lp's to derive); the property tests compare both with a prepass.

    A resolution reads the classes first (a pass over the steps), and the features only where one dstate
    per class is not the answer (:meth:`refutes_one_per_class`, or the first try failed).
    """

    def __init__(self, steps: Sequence[Step], angles: Sequence[int], lengths: dict[int, int], metrical: bool,
                 future_depth: int):
        self.lengths, self.metrical, self.depth = lengths, metrical, future_depth
        n = len(steps)
        self.views = [s.view for s in steps]
        self.actions = [action_key(steps[t], angles[t]) for t in range(n - 1)]
        heading, headings = 0, [0]
        for angle in angles[:n - 1]:  # metrical.lp: a turn or a travel adds its angle type
            heading = (heading + angle) % 360
            headings.append(heading)
        self.headings = headings
        # The classes, grouped by (view, heading), then each named by the key term partition.lp folds.
        self.classes = Classes.grouped(range(n), [(v, h if metrical else None) for v, h in zip(self.views, headings)])
        self.classes.keys = [_class_key(view, heading) for view, heading in self.classes.keys]
        self.classes.given = True
        self.class_of = self.classes.of_time

    def refutes_one_per_class(self) -> bool:
        """Two time points of one class took one action to time points of two classes: with one dstate per
        class, determinism (causal.lp) fails there."""
        led: dict[tuple[int, tuple], int] = {}
        class_of = self.class_of
        for t, action in enumerate(self.actions):
            if led.setdefault((class_of[t], action), class_of[t + 1]) != class_of[t + 1]:
                return True
        return False

    def one_per_class(self) -> Partition | None:
        """The map with one dstate per class (numbered as the classes are, by first appearance), where the
        causal and metrical axioms accept it: determinism over the classes (:meth:`refutes_one_per_class`),
        and every travel from a dstate of one length type (metrical.lp's ``length`` feature); views and
        headings are the classes' own. None where they do not (the levels that judge the map alone are
        the caller's to ask, :meth:`Partition.transitions`)."""
        if self.refutes_one_per_class():
            return None
        if self.metrical:
            length_of: dict[int, int] = {}
            for t, dm in self.lengths.items():
                if length_of.setdefault(self.class_of[t], dm) != dm:
                    return None
        return partition_of(self.class_of, self)

    @property
    def features(self) -> PartialFeatures:
        """The features that tell time points of a class apart, as :meth:`.Grounding.partial_features`
        reads them from a prepass (small ints; each feature's values a set of one). Worked out anew on each
        call: the caller keeps them as long as it needs them (140 MiB at 100,000 steps)."""
        n, views, actions, class_of = len(self.views), self.views, self.actions, self.class_of
        depth = max(0, min(self.depth, n - 1))
        # What each time point saw d actions on (d = 1..depth), as ints: the action sequence (a future,
        # built one action at a time: (shorter, action) -> int) and the view. -1 past the last time point.
        view_id: dict[str, int] = {}
        seen = np.fromiter((view_id.setdefault(v, len(view_id)) for v in views), dtype=np.int64, count=n)
        feature = np.full((n, depth), -1, dtype=np.int64)
        sequence: dict[tuple, int] = {}
        distance: dict[int, int] = {}
        for t in range(n - 1):
            s, row = -1, feature[t]
            for d in range(1, min(depth, n - 1 - t) + 1):
                step = (s, actions[t + d - 1])
                s = sequence.get(step, -2)
                if s == -2:
                    s = sequence[step] = len(sequence)
                    distance[s] = d
                row[d - 1] = s
        value = np.full((n, depth), -1, dtype=np.int64)
        for d in range(1, depth + 1):
            value[:n - d, d - 1] = seen[d:]
        # A travel's length is one more feature (its int after every sequence's), its values after the views'.
        times = np.repeat(np.arange(n), depth)
        feature, value = feature.ravel(), value.ravel()
        if self.metrical and self.lengths:
            travelled = np.fromiter(self.lengths, dtype=np.int64, count=len(self.lengths))
            length_id: dict[int, int] = {}
            measured = np.fromiter((len(view_id) + length_id.setdefault(dm, len(length_id))
                                    for dm in self.lengths.values()), dtype=np.int64, count=len(self.lengths))
            times = np.concatenate([times, travelled])
            feature = np.concatenate([feature, np.full(len(travelled), len(sequence), dtype=np.int64)])
            value = np.concatenate([value, measured])
        shown = feature >= 0
        times, feature, value = times[shown], feature[shown], value[shown]
        # core/prepass.lp: a feature tells time points apart only in a class that shows two values of it.
        classes = np.asarray(class_of, dtype=np.int64)[times]
        pair = classes * (len(sequence) + 1) + feature
        distinct = np.unique(np.stack([pair, value]), axis=1)[0]  # each (class, feature) once per value
        keys, counts = np.unique(distinct, return_counts=True)
        telling = np.isin(pair, keys[counts > 1])
        of: dict[int, dict[int, set[int]]] = {t: {} for t in range(n)}
        seen_from: dict[int, dict[int, set[int]]] = {}
        for t, f, x in zip(times[telling].tolist(), feature[telling].tolist(), value[telling].tolist()):
            of[t][f] = {x}
            d = distance.get(f)
            if d is not None:
                seen_from.setdefault(t + d, {}).setdefault(t, set()).add(f)
        return PartialFeatures(of, seen_from, distance)


def _class_key(view: str, heading: int | None) -> Symbol:
    """The key term core/partition.lp folds from a class's grouping features, in the order of their names:
    ``k(heading, H, k(view, V, nil))``, or ``k(view, V, nil)`` without the metrical level."""
    key = CLASS_KEY_TERM(VIEW_FEATURE(), String(view), NIL())  # type: ignore[arg-type]
    return key if heading is None else CLASS_KEY_TERM(HEADING_FEATURE(), Number(heading), key)


def length_labels(lengths: dict[int, int]) -> dict[int, int]:
    """Each travel's length type (time point -> decimetres, :func:`.facts.travel_lengths`) as a label,
    its type's order of first appearance: equal labels exactly where the axioms see equal lengths, and
    labels that stay while the types keep their members (a type's mean moves as travels join it)."""
    first: dict[int, int] = {}
    return {t: first.setdefault(dm, len(first)) for t, dm in sorted(lengths.items())}
