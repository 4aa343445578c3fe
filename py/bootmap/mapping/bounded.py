"""A resolution (or explanation) that ends by its time limit for sure: in a child process, stopped if it
runs over.

The resolver keeps its own time limit between groundings and during solving, but clingo cannot interrupt
a grounding, and a hostile or simply large tableau can ground for longer than the limit. So the command
line resolves in a forked child (:mod:`bootmap.proc`) and kills it ``grace_s`` after the limit, as the
service kills its solver processes. The child's answer (a map, or the resolver's own time-out or
inconsistency) comes back as plain data.
"""

from __future__ import annotations

import traceback
from typing import Callable, TypeVar

from ..errors import BootmapError, InconsistentTableau, SolveTimeout
from ..proc import in_child
from ..tableau import Tableau
from .cogmap import CognitiveMap

GRACE_S = 2.0  # beyond the limit: the resolver's own time-out usually lands first
T = TypeVar("T")


def resolve_within(resolver, tableau: Tableau, grace_s: float = GRACE_S) -> CognitiveMap:
    """``resolver.resolve(tableau)``, stopped at ``resolver.time_limit + grace_s`` seconds at the latest.
    Raises what the resolver raises; :class:`SolveTimeout` (stage ``"grounding"``) when it had to be
    stopped."""
    return run_within(lambda: resolver.resolve(tableau), resolver.time_limit, grace_s)


def run_within(work: Callable[[], T], limit: float | None, grace_s: float = GRACE_S,
               stated_s: float | None = None) -> T:
    """``work()`` (a resolution, an explanation) in a forked child (:func:`bootmap.proc.in_child`), stopped
    ``grace_s`` after ``limit``. ``stated_s``: the limit as the user stated it, for the message (``limit``
    may be what is left of it)."""
    if limit is None:
        return work()
    kind, reply = in_child(lambda: _tagged(work), limit + grace_s)
    if kind == "timeout":
        stated = limit if stated_s is None else stated_s
        raise SolveTimeout(f"time limit of {stated:g} s reached while grounding (clingo cannot interrupt a "
                           f"grounding; stopped at {stated + grace_s:g} s); no answer found",
                           time_limit_s=stated, stage="grounding")
    if kind == "failed":
        raise BootmapError(f"the solver process failed: {reply}")
    return _outcome(reply)


def _tagged(work) -> tuple:
    """The work's answer, or what it raised as plain data (bootmap's exceptions with custom fields do not
    pickle)."""
    try:
        return "ok", work()
    except SolveTimeout as e:
        return "timeout", str(e), e.lower_bound, e.best_map, e.time_limit_s, e.stage
    except InconsistentTableau as e:
        return "inconsistent", str(e), e.levels, tuple(e.failing_levels), e.diagnosed
    except BootmapError as e:
        return "error", str(e), e.exit_code
    except Exception:  # a bug: its traceback goes to the parent, which raises it
        return "crash", traceback.format_exc()


def _outcome(reply: tuple):
    kind, *rest = reply
    if kind == "ok":
        return rest[0]
    if kind == "timeout":
        message, lower, best, limit, stage = rest
        raise SolveTimeout(message, lower_bound=lower, best_map=best, time_limit_s=limit, stage=stage)
    if kind == "inconsistent":
        message, levels, failing, diagnosed = rest
        raise InconsistentTableau(message, levels=levels, failing_levels=failing, diagnosed=diagnosed)
    if kind == "error":
        error = BootmapError(rest[0])
        error.exit_code = rest[1]
        raise error
    raise RuntimeError(f"the resolver process failed:\n{rest[0]}")
