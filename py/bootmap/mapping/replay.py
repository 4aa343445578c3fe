"""The stock axioms replayed on repeated experience, step by step: what keeps a streamed map current in
a few milliseconds.

:class:`~.stream.MapStream` extends the unique minimal map of a tableau by determinism when new steps
repeat transitions already taken. Whether the map so extended still satisfies the axioms, and whether a
fresh resolve would keep it, clingo can say by grounding the whole tableau with the partition fixed; but
that grounds every step again on every step. For the axiom files bootmap ships, the answer needs only
what the new steps change, and :class:`Replay` keeps it as the steps arrive:

* causal.lp: a time point shows its dstate's view (``one_value_per_feature``). What it saw after a
  sequence of actions (``after(S)``) then follows from the views and determinism, and ``next/3`` gains no
  transition, so ``deterministic_action`` and the whole topological level (which reads only ``next/3``)
  hold as before.
* metrical.lp: the heading after an action is the heading before plus the action's type angle, and must
  be its dstate's; a travel's length type must be the one its dstate's travels have.

What the resolver does with the longer tableau also depends on what it derives before any search, and
:class:`Replay` keeps that too, as :mod:`.grounding`'s prepass would derive it: the classes of time points
(view and heading), the features only some time points show (``after(S)``, ``length``: all of them,
where the prepass reads only those its class shows with two values or more, core/prepass.lp, which
tell the same time points apart), and, where some
views are suspect (:class:`~.misreads.SuspectWatch`), the classes' lower bounds, recomputed only for the
classes whose time points a step changed.

These arguments are about the stock files, which :func:`covers` recognises by their digests (a test pins
them to ``asp/``), on tableaux of a robot that stopped at every dstate: their rules for a log that drove
through dstates (``passes_through``) never fire here, since :class:`~.stream.MapStream` resolves such a
tableau anew; nor do core/assert.lp's, which a person's assertions switch on and a stream never has. A
theory with a file a user added or edited is checked by clingo instead, so the axioms a user writes are
always honoured.
"""

from __future__ import annotations

import hashlib
from collections import ChainMap
from pathlib import Path
from typing import Sequence

from ..tableau import Step, Turn
from .cogmap import CognitiveMap
from .grounding import apart_clique
from .misreads import MIN_VISITS, SuspectWatch
from .theory import Theory

#: The axiom files the replay's argument is about (path in the axiom directory -> sha256). When one
#: changes, check the argument above against it, then update its digest (tests/mapping/test_stream.py).
STOCK_DIGESTS = {
    "causal.lp": "c53ada773c9738d3654228e1c660ac260badc953658d8500509d83f0c2c4f473",
    "metrical.lp": "4628513194f19408c98f56c8d15750bd6f1cb69f46904f76d5521ada01d6dbb5",
    "topological.lp": "729a309a6a1c99d71f9769994c8d83671d5bdf02b740bfac88e3f71b7759cb71",
    "core/ask.lp": "2e8adf403568adf1bc5e166b19bde32ba2fdaac7f873adef0930bb9071c939ca",
    "core/partition.lp": "5a5041dcda4ff90134c77b13f5c751ef32325af467a675c6f5272a5a5f7f41c0",
    "core/assert.lp": "2c01befdceb28aa69c8a639e07b55dc2b96f6280fd2d7f052fe55fa211a76c17",
    "core/prepass.lp": "7c0467733eb5c9806a227948479ee56cca2bf41d51a193d0f00b736594110478",
}


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def covers(theory: Theory) -> bool:
    """Every file of the theory is a stock axiom file, unchanged (a subset of the levels will do)."""
    for f in theory.files:
        name = f.relative_to(theory.directory).as_posix()
        if STOCK_DIGESTS.get(name) != digest(f):
            return False
    return True


def action_key(step: Step, angle: int) -> tuple:
    """The action from a step as causal.lp names it (``turn(A)`` or ``travel``), as a Python value."""
    return ("turn", angle) if isinstance(step.action, Turn) else ("travel",)


class Replay:
    """A tableau's experience as the stock axioms read it before any search, and the last map, kept up
    to date as steps are appended.

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
        # The map: each time point's dstate; where each (dstate, action) led; each dstate's features.
        self.dstate_of: list[str] = []
        self.led: dict[tuple[str, tuple], str] = {}
        self.view_of: dict[str, str] = {}
        self.heading_of: dict[str, int] = {}
        self.length_of: dict[str, int] = {}
        self.dstates_in: dict[tuple, int] = {}  # class -> its dstates in the map
        self._lower: dict[tuple, int] = {}      # class -> its lower bound, while no step changes it
        self._without: dict[tuple, int] = {}    # ... and without the clear suspects' views
        self._cleared: frozenset[int] = frozenset()
        self.unplaced: int | None = None        # the last extension's new time point no transition placed
        self.refuted = False                    # ... or the one it placed where the axioms refuse it

    # ------------------------------------------------------------------------------------------------

    @classmethod
    def of(cls, steps: Sequence[Step], angles: Sequence[int], lengths: dict[int, int], cmap: CognitiveMap,
           metrical: bool, future_depth: int) -> "Replay":
        """The replay of a tableau's steps and its map, from scratch."""
        replay = cls(metrical, future_depth)
        for t in range(len(steps)):
            replay._observe(t, steps, angles, lengths, watch=False)
        replay.watch = SuspectWatch.of(replay.views, replay.actions)
        replay.dstate_of = list(cmap.dstate_of)
        replay.view_of, replay.heading_of = dict(cmap.views), dict(cmap.headings)
        for t in range(len(steps) - 1):
            d = cmap.dstate_of[t]
            replay.led[(d, replay.actions[t])] = cmap.dstate_of[t + 1]
            if t in lengths:
                replay.length_of[d] = lengths[t]
        for d in cmap.views:
            key = replay._class(cmap.views[d], cmap.headings.get(d))
            replay.dstates_in[key] = replay.dstates_in.get(key, 0) + 1
        return replay

    def extend(self, steps: Sequence[Step], angles: Sequence[int], lengths: dict[int, int]) -> list[str] | None:
        """The dstate of each new time point by determinism, if the map so extended satisfies the
        stock axioms; else None (the replay is then stale: make a new one). Where only the last new time
        point is reached by a transition never taken from its dstate before, ``unplaced`` names it (the
        experience, but no dstate, is then read up to it: :attr:`watch` and :meth:`exact_stands` hold);
        where determinism placed a new point where the axioms refuse it, ``refuted`` says so."""
        self.unplaced, self.refuted = None, False
        if angles[:len(self.actions)] != self.angles or any(lengths.get(t) != v for t, v in self.lengths.items()):
            return None  # the action types learned from the longer experience read an old action anew
        for t in range(len(self.views), len(steps)):
            d_before = self.dstate_of[t - 1]
            self._observe(t, steps, angles, lengths)
            d = self.led.get((d_before, self.actions[t - 1]))
            if d is None:  # a transition never taken from there
                self.unplaced = t if t == len(steps) - 1 else None
                return None
            if not self._fits(t, d, d_before):
                self.refuted = True
                return None
            self.dstate_of.append(d)
        return self.dstate_of

    def _fits(self, t: int, d: str, d_before: str) -> bool:
        """Whether the stock axioms accept time point t at dstate d (where determinism places it)."""
        if self.view_of[d] != self.views[t]:
            return False  # another view at its end
        if self.metrical and self.heading_of.get(d) != self.headings[t]:
            return False  # the action's type angle does not lead to the dstate's heading
        if self.metrical and t - 1 in self.lengths and self.lengths[t - 1] != self.length_of.get(d_before):
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
        for key, times in self.members.items():
            if key not in self._lower:
                self._lower[key] = apart_clique(times, self.partial, exact=True, at_most=self.dstates_in.get(key))
        bound = sum(self._lower.values())
        if bound != n_dstates:
            return False
        clear = self._clear(images)
        if clear != self._cleared:  # the views left out changed: every class's bound without them may too
            self._without, self._cleared = {}, clear
        without = self.without(clear)
        for key, times in self.members.items():
            if key not in self._without:
                self._without[key] = apart_clique([t for t in times if t not in clear], without, exact=True,
                                                  at_most=self.dstates_in.get(key))
        return bound - sum(self._without.values()) < len(clear)

    def _clear(self, images: bool) -> frozenset[int]:
        """The suspects the resolver would leave out first: the clear ones, or all where none is clear
        (views with one or two images are suspects only in a tableau of images)."""
        suspects = [t for t in self.watch.suspects if images or self.views[t] not in self.watch.rare_names]
        clear = [t for t in suspects if self.watch.clear(t)]
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
        self.partial[t][key] = value
        self._lower.pop(self.class_of[t], None)
        self._without.pop(self.class_of[t], None)


def length_labels(lengths: dict[int, int]) -> dict[int, int]:
    """Each travel's length type (time point -> decimetres, :func:`.facts.travel_lengths`) as a label,
    its type's order of first appearance: equal labels exactly where the axioms see equal lengths, and
    labels that stay while the types keep their members (a type's mean moves as travels join it)."""
    first: dict[int, int] = {}
    return {t: first.setdefault(dm, len(first)) for t, dm in sorted(lengths.items())}
