"""One resolution's search for the minimal maps of a tableau, one module per concern:

- :mod:`.state`: what the search knows so far (the facts, the classes, what is proved, the best map);
- :mod:`.budget`: the deadline, shares of it, and the grounding-size check before each grounding;
- :mod:`.retyping`: actions taken as mistyped, chosen before the search;
- :mod:`.exact`: the minimal maps of the facts in force, bound by bound (the steps in
  :mod:`bootmap.mapping.resolver`);
- :mod:`.abduction`: views taken as misreads, weighed against reading every view as seen.

:class:`Search` wires them for one resolution and decides which runs when;
:class:`~bootmap.mapping.resolver.Resolver` holds the settings and makes a ``Search`` per tableau.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Sequence

from clingo import Symbol

from ...tableau import Tableau
from ..assertions import Assertion
from ..cogmap import CognitiveMap
from ..grounding import Deadline
from .abduction import MisreadAbduction
from .budget import Budget
from .exact import ExactSearch
from .retyping import Retyping
from .state import SearchState

if TYPE_CHECKING:
    from ..resolver import Resolver

__all__ = ["Search"]


class Search:
    """One resolution: the search state and budget it shares, and the concerns that work on them."""

    def __init__(self, resolver: Resolver, tableau: Tableau, deadline: Deadline,
                 assertions: Sequence[Assertion] = (), at_least: int = 0,
                 rejected: list[list[Symbol]] | None = None):
        self.state = SearchState(resolver, tableau, assertions, at_least, rejected)
        self.budget = Budget(deadline, self.state.timed_out)
        self.retyping = Retyping(self.state, self.budget)
        self.exact = ExactSearch(self.state, self.budget)
        self.abduction = MisreadAbduction(self.state, self.budget, self.exact)

    def run(self) -> CognitiveMap:
        """Retype the actions the theory finds mistyped; try one dstate per class; where that does not
        settle it (or some views are suspect), weigh misreads, else bound the classes from below and
        find the minimal maps. Then, where a person made soft assertions, keep those worth their cost."""
        return self.exact.preferring(self.fewest())

    def fewest(self) -> CognitiveMap:
        resolver = self.state.resolver
        if resolver.retype and self.state.grid is not None:
            self.retyping.retype()
        found = self.exact.first_try()
        suspects = self.abduction.suspects(found)
        if found and not suspects:
            return found
        if suspects:
            return self.abduction.robust(suspects, found)
        self.exact.check_asserted_same()
        self.exact.bound_classes_from_below(keep_features=False)  # no view is weighed as a misread
        return self.exact.minimal_maps()
