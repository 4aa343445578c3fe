"""When no map satisfies the axioms: which level fails?

"No map satisfies the axioms" leaves a user with every .lp file to suspect. The levels are families of
axioms over the causal level (the one that defines dstates), so the resolver tries the causal level
alone and then each other level beside it alone, as far as the deadline allows: a level that fails
beside the causal level alone contradicts this experience by itself; if each passes alone, only the
levels together fail. The answer travels in :class:`~bootmap.errors.InconsistentTableau`'s fields and in
its message, for ``bootmap map`` and the service alike.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..errors import InconsistentTableau, SolveTimeout
from ..tableau import Tableau
from .grounding import Deadline
from .theory import MANDATORY

if TYPE_CHECKING:
    from .resolver import Resolver


def failing_levels(resolver: "Resolver", tableau: Tableau, deadline: Deadline) -> tuple[list[str], bool]:
    """The levels that fail on their own beside the causal level (``["causal"]`` if it fails alone),
    and whether every try finished by the deadline."""
    levels = list(resolver.theory.levels)
    tries = [(MANDATORY,)] + [(MANDATORY, lv) for lv in levels if lv != MANDATORY]
    failing, complete = [], True
    for subset in tries:
        if deadline.passed():
            return failing, False
        try:
            resolver.with_levels(subset).resolve(tableau, deadline)
        except InconsistentTableau:
            failing.append(subset[-1])
            if subset == (MANDATORY,):
                break  # every other try includes the causal level
        except SolveTimeout:
            complete = False
    return failing, complete


def diagnosed(e: InconsistentTableau, resolver: "Resolver", tableau: Tableau,
              deadline: Deadline) -> InconsistentTableau:
    """``e`` with the failing levels found, in its fields and its message."""
    if len(resolver.theory.levels) == 1:  # the causal level alone just failed: no need to solve it again
        failing, complete = list(resolver.theory.levels), True
    else:
        failing, complete = failing_levels(resolver, tableau, deadline)
    return InconsistentTableau(f"{e}; {_why(failing, complete)}", levels=e.levels, failing_levels=tuple(failing),
                               diagnosed=complete)


def _why(failing: list[str], complete: bool) -> str:
    if failing == [MANDATORY]:
        return "the causal axioms alone already fail"
    if failing:
        names = ", ".join(failing)
        plural = len(failing) > 1
        return (f"the {names} level{'s' if plural else ''} fail{'' if plural else 's'} "
                "even with the causal level alone beside it")
    if complete:
        return "each level is satisfiable beside the causal one; only the levels together fail"
    return "the failing level could not be narrowed down within the time limit"
