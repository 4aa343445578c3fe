"""Mistyped actions: an action whose reading lies far from its learned type's angle may be of the
neighbouring type (:func:`~bootmap.mapping.motion.type_suspects`), as a view may be a misread.

An action's angle sets the heading of every later time point, and headings are class features, so the
typing is chosen once, before the search: each suspect action is retyped where that lowers the dstates
the theory proves necessary by more than retyping costs. The map lists the actions taken as mistyped
(``retyped_steps``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Sequence

import numpy as np

from ...walls import wrap_deg
from ..grounding import prepass
from ..motion import TypeSuspect, action_types
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
        suspects = state.typing.suspects(state.angles)
        if not suspects:
            return
        share = self.budget.deadline.share(RETYPE_SHARE, RETYPE_MAX_S)
        angles = list(state.angles)
        best = DSTATE_COST * self.proved_with(angles)
        # First, jointly: the suspects whose retyping the views and headings alone call for (a wrong turn
        # puts every later time point in another heading, so mistyped turns are weighed together).
        joint = jointly_retyped(suspects, angles, state.tableau.views)
        if joint:
            trial = list(angles)
            for s in joint:
                trial[s.t] = s.alternative
            score = DSTATE_COST * self.proved_with(trial) + MISTYPE_COST * len(joint)
            if score < best:
                angles, best = trial, score - MISTYPE_COST * len(joint)
                state.retyped.extend(joint)
        # Then each other suspect in turn, by the dstates the theory proves necessary.
        for s in suspects:
            if share.passed():
                break
            if s in state.retyped:
                continue
            trial = list(angles)
            trial[s.t] = s.alternative
            score = DSTATE_COST * self.proved_with(trial) + MISTYPE_COST * (len(state.retyped) + 1)
            if score < best + MISTYPE_COST * len(state.retyped):
                angles, best = trial, score - MISTYPE_COST * (len(state.retyped) + 1)
                state.retyped.append(s)
        if state.retyped:
            state.retyped.sort(key=lambda s: s.t)
            state.angles = angles
            state.facts = state.experience_facts(angles)
            state.action_types = action_types(state.typing.read, angles)

    def proved_with(self, angles: list[int]) -> int:
        """The dstates the theory proves necessary (the classes' lower bounds) with these action angles
        (under the stock axioms worked out from the steps, else from a prepass)."""
        state = self.state
        stock = state.stock_prepass_with(angles)
        if stock is not None:
            return sum(stock.features.lower_bounds(stock.classes))
        grounded = prepass(state.resolver.theory, state.experience_facts(angles),
                           state.resolver.future_depth)
        state.ground_s += grounded.ground_s
        classes = grounded.classes(range(len(state.tableau)))
        return sum(grounded.lower_bounds(classes))


def view_headings(views: Sequence[str | None], angles: Sequence[int]) -> int:
    """How many (view, heading) pairs the time points show with these action angles: a dstate has one
    view and one heading, so at least as many dstates are necessary."""
    heading = np.concatenate([[0], np.cumsum(np.asarray(angles, dtype=np.int64))]) % 360
    return len(set(zip(views, heading[:len(views)].tolist())))


def jointly_retyped(suspects: Sequence[TypeSuspect], angles: Sequence[int], views: Sequence[str | None]
                    ) -> list[TypeSuspect]:
    """The suspects to retype by the views and headings alone (:func:`view_headings`), best first: each
    round retypes the suspect that removes the most pairs, while that is more than retyping costs (one
    dstate). Mistyped turns are found together, where the theory's bound, one suspect at a time, sees
    none of them pay: after two wrong turns, righting the first alone leaves as many headings wrong."""
    angles = list(angles)
    pairs = view_headings(views, angles)
    chosen: list[TypeSuspect] = []
    left = list(suspects)
    while left:
        gains = []
        for s in left:
            trial = list(angles)
            trial[s.t] = s.alternative
            gains.append(pairs - view_headings(views, trial))
        # the largest gain; between equal gains, the reading furthest from its type
        i = max(range(len(left)), key=lambda k: (gains[k], abs(wrap_deg(left[k].measured - left[k].angle))))
        if gains[i] * DSTATE_COST <= MISTYPE_COST:
            break
        s = left.pop(i)
        angles[s.t] = s.alternative
        pairs -= gains[i]
        chosen.append(s)
    return chosen
