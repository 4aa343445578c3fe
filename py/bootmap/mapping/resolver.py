"""The resolver: abduce dstates, places and paths from a tableau with clingo.

The search, in the paper's terms: dstates with the same view are equal unless the axioms prove them
different. Concretely:

1. Features every time point shows (its view; with the metrical level, its heading) group time points
   into *classes*, named by a key term the theory folds from them (core/partition.lp): only time points
   of one class can share a dstate. The first try, in a single grounding, is one dstate per class;
   usually that settles it, by propagation alone. (Under the stock axioms the classes are read from the
   steps, and one dstate per class is checked without grounding the tableau: refuted by determinism over
   the classes or a travel's length, else the topological level asked of its transitions alone.)
2. Otherwise, features only some time points show (what was seen after a given sequence of actions)
   tell time points of a class apart (a prepass grounds the theory on the facts alone to read them; under
   the stock axioms they are worked out from the steps, :class:`~.replay.Prepassed`): a set of pairwise disagreeing time points is a proved lower bound
   on the dstates of that class. Try exactly those bounds, then the few just above them (by clingo's
   core-guided optimisation, which opens a class's spare dstate only where a core asks for it).
3. Otherwise find some valid map, allowing a few spare dstates per class: an upper bound.
4. Ground once within that bound and let clingo minimise the number of dstates (core-guided, so what it
   learns carries from one bound to the next), then enumerate the minimal maps (up to ``max_models``):
   one means the map is unique.

In every step each class gets only the candidate dstates ("slots", numbered by first appearance in
core/partition.lp) that the bound leaves it, so the ground program stays small when the lower bound is
tight. Each step is one :class:`~.grounding.Grounding`, solved by the resolution's
:class:`~.grounding.Deadline`; the tableau's actions reach the axioms as the robot's learned action
types (:mod:`.motion`) unless a fixed quantum is asked for.

This module holds the settings (:class:`Resolver`); the search itself is :mod:`.search`, one module per
concern: the exact search, misread abduction, retyping of mistyped actions and the time budget.

Example
-------
>>> from bootmap.tableau import Tableau
>>> steps = [{"view": v, "action": {"type": "turn", "angle_deg": -90}} for v in "ABAB"] + [{"view": "A"}]
>>> m = Resolver().resolve(Tableau.from_dict({"format": "bootmap.tableau/1", "steps": steps}))
>>> m.n_dstates, m.n_places, m.unique
(4, 1, True)
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Sequence

from clingo import Symbol

from ..errors import InconsistentTableau
from ..tableau import Tableau
from .assertions import Assertion
from .cogmap import CognitiveMap
from .diagnosis import diagnosed
from .grounding import Deadline
from .replay import covers
from .search import Search
from .search.retyping import MISTYPE_COST
from .theory import Theory, load_theory
from .vocabulary import FUTURE_DEPTH

# MISTYPE_COST (what taking an action as mistyped costs, :mod:`.search.retyping`) is named here for
# the resolver's callers, beside the setting (``retype``) it prices.
__all__ = ["Resolver", "MISTYPE_COST"]


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
    defer_map_levels : bool
        Leave the levels that judge the map alone (the topological one: :attr:`Theory.map_levels`) out of
        the search and ask them of each map it finds (:mod:`.mapcheck`); the same maps, found sooner.
        False grounds them with every search, as a check of that.

    Attributes
    ----------
    theory : Theory
        The loaded axiom files.
    stock : bool
        They are the stock files, unchanged (:func:`.replay.covers`): the classes and the features a
        prepass would derive are worked out from the steps.
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
    defer_map_levels: bool = True
    theory: Theory = field(init=False, repr=False, compare=False)
    stock: bool = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.levels is not None:
            object.__setattr__(self, "levels", tuple(self.levels))
        object.__setattr__(self, "theory", load_theory(self.axioms, self.levels))
        # The axiom files are the stock ones, unchanged: what a prepass derives can be worked out from the
        # steps (:class:`.replay.Prepassed`) rather than grounded.
        object.__setattr__(self, "stock", covers(self.theory))

    def with_levels(self, levels: Sequence[str]) -> "Resolver":
        """The same resolver (same axiom directory and settings) on other levels, without a diagnosis."""
        return replace(self, axioms=self.theory.directory, levels=tuple(levels), diagnose=False)

    def resolve(self, tableau: Tableau, deadline: Deadline | None = None,
                assertions: Sequence[Assertion] = (), at_least: int = 0,
                rejected: list[list[Symbol]] | None = None) -> CognitiveMap:
        """The minimal map(s) of the tableau, by ``deadline`` (default: ``time_limit`` from now); with a
        person's ``assertions`` (:mod:`.assertions`), the minimal maps that honour the hard ones and keep
        the soft ones unless breaking them saves more than they cost. ``at_least``: dstates the caller has
        proved every map of the tableau needs, reading every view as seen (a stream knows it from the
        map before the last step, :mod:`.stream`); the search for the exact minimal maps starts there.
        ``rejected``: transitions the levels that judge the map alone rejected together in earlier
        resolutions by this resolver (a stream keeps them). Those levels are monotone (a map they reject
        stays rejected with more dstates and transitions, under any names), so such transitions reject
        any map they are in, whatever its tableau: every search rules them out before it solves, and
        this resolution adds to the list what it learns. The maps found are the same, found sooner.

        Raises
        ------
        InconsistentTableau
            No map satisfies the axioms (with the failing levels, when ``diagnose`` and there are no
            hard assertions: where there are, :meth:`.explain.Explainer.conflict` says which clash).
        SolveTimeout
            Out of time; it carries the dstates proved necessary and, if one was found on the way,
            a valid map that is not proved minimal (``best_map``).
        """
        deadline = deadline or Deadline.after(self.time_limit)
        try:
            return Search(self, tableau, deadline, assertions, at_least, rejected).run()
        except InconsistentTableau as e:
            if not self.diagnose or any(not x.soft for x in assertions):
                raise
            raise diagnosed(e, self, tableau, deadline) from None
