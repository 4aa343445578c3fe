"""The time a resolution may spend, and when to stop before a grounding that would overrun it.

clingo can interrupt a solve at the deadline, but neither a grounding nor the preparation of its first
solve. So before each search is grounded the budget predicts how long that takes, from how large the
grounding will be (:func:`grounding_size`) and how fast this machine has grounded this tableau so far,
and stops there with a :class:`~bootmap.errors.SolveTimeout` rather than overrun the caller's time limit;
once it is grounded, a search is solved only if the preparation of its first solve would end in time
(:meth:`Budget.prepares_in_time`).
Work that is only worth a part of the time left (checking an alternative, climbing a bound) runs within
a share of it (:meth:`Budget.within_share`).
"""

from __future__ import annotations

from typing import Callable, Sequence

from clingo import Symbol

from ...errors import SolveTimeout
from ..grounding import Classes, Deadline
from ..vocabulary import DSTATE_BOUND, MAY_BE, SLOTS

#: A search's grounding time grows faster than its size (:func:`grounding_size`): the places
#: and paths of the topological level pair up candidate dstates (600 steps: 2.8 s for a layout, 18.5 s
#: for one with 1.9 times the size). Grounding and the first solve's preparation, which cannot be
#: interrupted either, take about ``PREPARE_FACTOR`` times the grounding (18.5 s, then 30 s).
GROUND_POWER, PREPARE_FACTOR, GROUND_GRACE_S = 2.0, 2.5, 1.0
#: Before any search is grounded, the first try's rate predicts the first search's: searches measured
#: 0.11-0.35 of it (600-step explorations with misreads; the first try's share of fixed costs is higher).
FIRST_TRY_SHARE = 0.35

#: How the search words running out of time: ``(what it was looking for, the optimiser's improving models
#: so far, the time limit in force) -> SolveTimeout``.
TimedOut = Callable[[str, list, "float | None"], SolveTimeout]


class Budget:
    """One resolution's clock: the deadline in force (a share of the caller's while a bounded piece of work
    runs) and how fast this machine grounds this tableau, learned from the groundings made so far.

    ``timed_out`` words the error when time runs out (the search state knows what was proved and found).
    """

    def __init__(self, deadline: Deadline, timed_out: TimedOut):
        self.deadline = deadline
        self._timed_out = timed_out
        self.ground_rate: float | None = None  # seconds per grounding size ** GROUND_POWER, the worst seen
        self.fixed_ground_s = 0.0  # the first try's grounding: the costs every grounding has
        self.rate_size = 0  # the size of the search grounding that set ground_rate (0: the first try did)

    def timed_out(self, what: str, improving: list) -> SolveTimeout:
        """The error to raise: out of time while looking for ``what`` (``improving``: the optimiser's models
        so far, the last the smallest)."""
        return self._timed_out(what, improving, self.deadline.limit_s)

    def within_share(self, work: Callable[[], object], share: tuple[float, float]):
        """``work()`` within a share of the time left (``(fraction, at most seconds)``); None if that runs
        out."""
        full = self.deadline
        self.deadline = full.share(*share)
        try:
            return work()
        except SolveTimeout:
            return None
        finally:
            self.deadline = full

    def check_clock(self, what: str) -> None:
        """Out of time before a grounding starts: stop here (clingo cannot interrupt a grounding)."""
        if self.deadline.passed():
            raise self.timed_out(what, [])

    def check_grounding(self, what: str, size: int) -> None:
        """Out of time before a grounding starts that would end well past the deadline, as the
        groundings of this resolution so far predict it (clingo can interrupt neither a grounding nor
        the preparation of its first solve, which takes about as long again)."""
        left = self.deadline.remaining()
        if left is None or self.ground_rate is None:
            return
        predicted = PREPARE_FACTOR * (self.fixed_ground_s + self.ground_rate * size ** GROUND_POWER)
        if predicted > left + GROUND_GRACE_S:
            raise self.timed_out(f"{what} (not started: its grounding would take about {predicted:.0f} s "
                                 f"with {left:.1f} s left)", [])

    def prepares_in_time(self, ground_s: float) -> bool:
        """A search just grounded in ``ground_s`` may be solved: the preparation of its first solve, which
        clingo cannot interrupt, takes about ``PREPARE_FACTOR - 1`` times its grounding, and would end
        before the deadline. (A solve started with half a second left on a grounding of 6.3 s stopped 10 s
        past the time limit: 600 steps, 5% misreads.)"""
        left = self.deadline.remaining()
        return left is None or (PREPARE_FACTOR - 1) * ground_s <= left + GROUND_GRACE_S

    def first_try_grounded(self, ground_s: float, time_points: int) -> None:
        """The first try (one slot for each time point) was grounded in ``ground_s``: what every grounding of
        this tableau costs (the theory, the facts), and until a search is grounded, how fast this machine
        grounds. The caller gives the process's CPU time where it is the smaller: a small first try is
        extrapolated a hundredfold and more, and a moment the process spent waiting for the processor (a
        busy host: 84 ms for a grounding of 5 ms) would refuse every search ("about 50 s with 29.9 s
        left", the paper's room at 43 steps)."""
        self.fixed_ground_s = ground_s
        self.ground_rate = FIRST_TRY_SHARE * ground_s / max(time_points, 1) ** GROUND_POWER

    def search_grounded(self, ground_s: float, size: int) -> None:
        """A search of this size was grounded in ``ground_s``."""
        if size >= self.rate_size:
            # The largest search so far, less the fixed costs (which dominate small groundings and would
            # make a larger one look far slower than it is), predicts the next.
            self.ground_rate = max(ground_s - self.fixed_ground_s, 0.0) / size ** GROUND_POWER
            self.rate_size = size


def layout_slots(layout: list[Symbol]) -> dict[Symbol, int]:
    """Each class's slots in a layout (its ``slots/2`` facts), by class key. A layout of
    :meth:`.Classes.layout` gives them first, after its bound: read there, not among the thousands of
    facts after them (reading a symbol is a call into clingo)."""
    if layout and DSTATE_BOUND.matches(layout[0]):
        slots = {}
        for s in layout[1:]:
            if not SLOTS.matches(s):
                break
            key, m = s.arguments
            slots[key] = m.number
        return slots
    return {key: m.number for key, m in SLOTS.args(layout)}


def may_be(facts: Sequence[Symbol]) -> list[tuple[int, Symbol]]:
    """The classes each suspect may have been misread from (the ``may_be/2`` facts), as (time point, class)."""
    return [(t.number, key) for t, key in MAY_BE.args(facts)]


def grounding_size(slots: dict[Symbol, int], classes: Classes, misread_from: Sequence[tuple[int, Symbol]]) -> int:
    """How large a search's grounding will be, before it is made: the candidate dstates of each
    time point (its class's ``slots`` in the layout, and those of the classes a suspect may be misread
    from, ``misread_from``: :func:`may_be`) times those of the next (what experience/next and determinism
    are grounded over)."""
    keys, of_time = classes.keys, classes.of_time
    cand = [slots.get(keys[c], 0) for c in of_time]
    for t, key in misread_from:
        cand[t] += slots.get(key, 0)
    return sum(a * b for a, b in zip(cand, cand[1:])) + len(cand)
