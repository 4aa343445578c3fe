"""Mistyped actions: an action whose reading lies far from its learned type's angle may be of the
neighbouring type (:func:`~bootmap.mapping.motion.type_suspects`), as a view may be a misread.

An action's angle sets the heading of every later time point, and headings are class features, so the
typing is chosen once, before the search: each suspect action is retyped where that lowers the dstates
the theory proves necessary by more than retyping costs. The map lists the actions taken as mistyped
(``retyped_steps``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..facts import tableau_facts
from ..grounding import prepass
from ..motion import action_types, type_suspects
from ..vocabulary import DSTATE_COST

if TYPE_CHECKING:
    from .budget import Budget
    from .state import SearchState

#: What taking an action as mistyped costs (a dstate costs ``DSTATE_COST``): an action is retyped only where
#: its learned type needs more than one dstate more.
MISTYPE_COST = DSTATE_COST
#: The share of the time (and at most so many seconds) spent weighing mistyped actions.
RETYPE_SHARE, RETYPE_MAX_S = 0.25, 15.0


class Retyping:
    """Chooses the typing of the actions the search reads: the learned types, but for the suspects whose
    neighbouring type the theory finds cheaper (``state.retyped``, ``state.angles``)."""

    def __init__(self, state: SearchState, budget: Budget):
        self.state, self.budget = state, budget

    def retype(self) -> None:
        """Abduce mistyped actions, as misread views are: a reading far from its learned type's angle may
        be of the neighbouring type (:func:`.motion.type_suspects`). Since an action's angle sets the
        heading of every later time point (a class feature), the typing is chosen before the search: each
        suspect in turn is retyped where that lowers the dstates the theory proves necessary (the
        classes' lower bounds, from a prepass) by more than ``MISTYPE_COST`` (one dstate). Clean
        experience has no suspects and is resolved as before; out of its share of the time, the typing
        chosen so far stands."""
        state = self.state
        suspects = type_suspects(state.tableau.actions, state.angles, state.grid)
        if not suspects:
            return
        share = self.budget.deadline.share(RETYPE_SHARE, RETYPE_MAX_S)
        angles = list(state.angles)
        best = DSTATE_COST * self.proved_with(angles)
        for s in suspects:
            if share.passed():
                break
            trial = list(angles)
            trial[s.t] = s.alternative
            score = DSTATE_COST * self.proved_with(trial) + MISTYPE_COST * (len(state.retyped) + 1)
            if score < best + MISTYPE_COST * len(state.retyped):
                angles, best = trial, score - MISTYPE_COST * (len(state.retyped) + 1)
                state.retyped.append(s)
        if state.retyped:
            state.angles = angles
            state.facts = tableau_facts(state.tableau, angles=angles)
            state.action_types = action_types(state.tableau.actions, angles)

    def proved_with(self, angles: list[int]) -> int:
        """The dstates the theory proves necessary (the classes' lower bounds) with these action angles."""
        state = self.state
        grounded = prepass(state.resolver.theory, tableau_facts(state.tableau, angles=angles),
                           state.resolver.future_depth)
        state.ground_s += grounded.ground_s
        classes = grounded.classes(range(len(state.tableau)))
        return sum(grounded.lower_bounds(classes))
