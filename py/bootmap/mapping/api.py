"""The one door to mapping: :class:`Mapper` finds a tableau's map, says why two time points are one
dstate or not, keeps a map current as steps come, and plans what to do when the minimal maps disagree.
Which search finds the map is chosen here, once:

``fewest``
    The map with the fewest dstates the axioms allow, proved minimal (:class:`~.resolver.Resolver`).
``loops``
    Loop closing (:class:`~.loops.LoopCloser`): dead reckoning proposes which visits are one dstate, every
    axiom checks the partition. For a robot that drove through dstates without stopping (a real log),
    whose views cannot carry the fewest dstates.
``auto``
    Loop closing for a tableau that says the robot drove through dstates (``meta.passes_through``, which
    ``bootmap ingest`` sets), else the fewest dstates.

The command line (``bootmap map``, ``why``, ``rehearse``), the service's solver processes, the log
experiment and the active policy all map through a :class:`Mapper`.

Example
-------
>>> from bootmap import examples
>>> mapper = Mapper()
>>> mapper.map(examples.notched_rectangle(circuits=2)).n_dstates
8
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Sequence

from ..errors import AssertionConflict, ExplainError, InconsistentTableau
from ..tableau import Tableau
from .assertions import AssertedMap, Assertion, hard, resolve_names
from .cogmap import CognitiveMap
from .diff import MapDiff
from .explain import Explainer
from .grounding import Deadline
from .loops import MAPPERS, LoopCloser, closes_loops
from .rehearsal import Plan, Rehearsal
from .resolver import Resolver
from .stream import MapStream


@dataclass(frozen=True)
class Mapper:
    """Map tableaux, explain their maps, keep maps current. Settings are fixed when it is made; each call
    may bring its own deadline (default: ``time_limit`` from the call).

    Parameters
    ----------
    axioms, levels, quantum_deg, time_limit, max_models, misreads
        As for :class:`~.resolver.Resolver`.
    how : {"auto", "fewest", "loops"}
        Which search finds the map (module docstring).

    Attributes
    ----------
    resolver : Resolver
        The search for the fewest dstates, with these settings (loop closing checks its partitions
        with it too).
    """

    axioms: str | Path | None = None
    levels: Sequence[str] | None = None
    quantum_deg: float | None = None
    time_limit: float | None = 60.0
    max_models: int = 10
    misreads: bool = True
    how: str = "auto"
    resolver: Resolver = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.how not in MAPPERS:
            raise ValueError(f"unknown mapper {self.how!r}; known: {', '.join(MAPPERS)}")
        object.__setattr__(self, "resolver", Resolver(self.axioms, self.levels, self.quantum_deg, self.time_limit,
                                                      self.max_models, misreads=self.misreads))

    @cached_property
    def closer(self) -> LoopCloser:
        return LoopCloser(self.resolver)

    @cached_property
    def explainer(self) -> Explainer:
        return Explainer(axioms=self.axioms, levels=self.levels, quantum_deg=self.quantum_deg,
                         time_limit=self.time_limit)

    def closes_loops(self, tableau: Tableau) -> bool:
        """Whether the map of ``tableau`` is found by loop closing."""
        return closes_loops(tableau, self.how)

    def map(self, tableau: Tableau, deadline: Deadline | None = None, stream: MapStream | None = None,
            assertions: Sequence[Assertion] = ()) -> CognitiveMap:
        """The map of ``tableau``. With a ``stream`` (:meth:`stream`) that saw an earlier prefix of it, the
        same map sooner where the new steps repeat what it knew (loop-closed maps are found afresh). With a
        person's ``assertions`` (time points, :mod:`.assertions`), the map that honours them (no stream),
        or :class:`~bootmap.errors.AssertionConflict` with the clash; :meth:`honour` also says what they
        changed."""
        if assertions:
            return self._honoured(tableau, assertions, deadline or Deadline.after(self.time_limit))
        if self.closes_loops(tableau):
            return self.closer.resolve(tableau, deadline)
        if stream is not None:
            return stream.update(tableau, deadline)
        return self.resolver.resolve(tableau, deadline)

    def honour(self, tableau: Tableau, assertions: Sequence[Assertion], deadline: Deadline | None = None,
               before: CognitiveMap | None = None, source: str | None = None,
               baseline: Sequence[Assertion] = ()) -> AssertedMap:
        """The map of ``tableau`` that honours a person's ``assertions`` (:mod:`.assertions`), beside the
        map ``before`` them (resolved here without them unless given) and what changed; or, where no map
        honours the hard ones, the conflict: which assertions clash, with the steps and axioms. Dstate
        names are those of ``before`` (an error names the file, ``source``, they were read from).
        ``baseline``: the assertions a given ``before`` honours (none: the map of the experience alone)."""
        deadline = deadline or Deadline.after(self.time_limit)
        before = before or self.map(tableau, deadline)
        assertions = resolve_names(assertions, before, source)
        try:
            after = self._honoured(tableau, assertions, deadline, before, proved(before, baseline, assertions))
        except AssertionConflict as e:
            return AssertedMap(before, assertions, conflict=e.conflict)
        return AssertedMap(before, assertions, after, MapDiff.between(before, after))

    def _honoured(self, tableau: Tableau, assertions: Sequence[Assertion], deadline: Deadline,
                  before: CognitiveMap | None = None, at_least: int = 0) -> CognitiveMap:
        """The map that honours ``assertions`` (time points), or AssertionConflict with the clash (``before``,
        the map without them, is resolved for it when needed and not given; ``at_least``, the dstates it
        proves every map with them needs: :func:`proved`)."""
        levels = tuple(self.resolver.theory.levels)
        if self.closes_loops(tableau):
            try:
                return self.closer.resolve(tableau, deadline, assertions,
                                           prior=before.dstate_of if before is not None else None)
            except InconsistentTableau:
                if not hard(assertions):
                    raise
                before = before or self.closer.resolve(tableau, deadline)
                conflict = self.closer.conflict(tableau, assertions, before, deadline)
                raise AssertionConflict(conflict.sentence, conflict, levels) from None
        if any(x.kind == "same" for x in hard(assertions)):
            # a clash the steps around a "same" show is found in a few small groundings; the search would
            # look for a map through ever larger ones before it gave up
            conflict = self.explainer.conflict(tableau, assertions, deadline, before, local=True)
            if conflict is not None:
                raise AssertionConflict(conflict.sentence, conflict, levels)
        try:
            return self.resolver.resolve(tableau, deadline, assertions, at_least=at_least)
        except InconsistentTableau:
            conflict = self.explainer.conflict(tableau, assertions, deadline, before) if hard(assertions) else None
            if conflict is None:
                raise
            raise AssertionConflict(conflict.sentence, conflict, levels) from None

    def remember(self, tableau: Tableau, cmap: CognitiveMap) -> None:
        """Keep ``cmap`` (found by :meth:`map`) as the minimal map questions about ``tableau`` are about,
        so that the first :meth:`explain` need not resolve it again (the explainer enumerates the
        default number of minimal maps: other settings, or a loop-closed map, are not kept)."""
        if not self.closes_loops(tableau) and self.max_models == Resolver.max_models and self.misreads:
            self.explainer.remember(tableau, cmap)

    def explain(self, tableau: Tableau, a: int | str, b: int | str | None = None,
                deadline: Deadline | None = None, assertions: Sequence[Assertion] = ()):
        """Why time points (``t4``, ``4``) or dstates (``S4``) ``a`` and ``b`` are one dstate or not; with
        ``b`` None, whether time point ``a``'s view is read as seen or as a misread. With a person's
        ``assertions`` (time points), in the map that honours them."""
        if self.closes_loops(tableau):
            if b is None:
                raise ExplainError("a loop-closed map lists its misreads (bootmap map); ask why about two time "
                                   "points or dstates")
            return self.closer.explain(tableau, a, b, deadline, assertions)
        if b is None:
            if assertions:
                raise ExplainError("ask why about two time points or dstates of a map with assertions")
            return self.explainer.explain_step(tableau, a, deadline)
        return self.explainer.explain(tableau, a, b, deadline, assertions)

    def stream(self) -> MapStream:
        """A map kept current as steps are appended (give it to :meth:`map`, or ``update`` it)."""
        return MapStream(self.resolver)

    def rehearse(self, tableau: Tableau, max_length: int = 10, cmap: CognitiveMap | None = None,
                 deadline: Deadline | None = None) -> Plan:
        """What to do next when the minimal maps of ``tableau`` disagree (the paper's rehearsal)."""
        return Rehearsal(self.resolver, max_length).plan(tableau, cmap=cmap, deadline=deadline)


def proved(before: CognitiveMap, baseline: Sequence[Assertion], assertions: Sequence[Assertion]) -> int:
    """The dstates every map that honours ``assertions`` needs reading every view as seen, as the map
    ``before`` them proves it (0 where it proves nothing): as many as ``before`` has, where it is proved
    minimal, reads every view as seen and every action as typed, honours only hard assertions
    (``baseline``, by time points) and those are all among the new ones. A map that honours the new ones
    then honours the old, so has at least as many dstates as the fewest that do (a minimal map with no
    misread has no fewer dstates than any map reading every view as seen). One more where ``before`` is
    the only minimal map and breaks a new one: every map with as few dstates is it."""
    if not before.minimal or before.suspect_steps or before.retyped_steps:
        return 0
    if any(x.soft or not isinstance(x.a, int) or not isinstance(x.b, int) for x in baseline):
        return 0
    now = hard(assertions)
    if not {(x.kind, x.a, x.b) for x in baseline} <= {(x.kind, x.a, x.b) for x in now}:
        return 0
    broken = before.unique and not all(x.holds_in(before) for x in now)
    return before.n_dstates + broken
