"""Exceptions bootmap raises, and the exit codes the ``bootmap`` command maps them to.

Every exception carries a message a person can act on, and the fields a program needs (where a tableau
is malformed, which levels fail, the dstates proved necessary) as attributes, so nobody has to parse the
message. Each class says how the command ends when it escapes: :data:`EXIT_BAD_INPUT` when the input must
change, :data:`EXIT_FAILURE` when the input is fine but has no answer in time (or at all).
"""

from __future__ import annotations

#: The ``bootmap`` command's exit codes (every sub-command, the simulator's and the service's included).
EXIT_OK, EXIT_FAILURE, EXIT_BAD_INPUT = 0, 1, 2
#: Stopped by Ctrl-C (SIGINT): the shell's code for a command a signal ended, 128 + 2.
EXIT_INTERRUPTED = 130


def error_line(command: str, message: object, exit_code: int) -> str:
    """How every command reports what stopped it: ``bootmap COMMAND: error: ...`` for bad input (exit 2),
    ``bootmap COMMAND: ...`` for a failure (exit 1).

    >>> error_line("token list", "bad setting: db", EXIT_BAD_INPUT), error_line("", "no map", EXIT_FAILURE)
    ('bootmap token list: error: bad setting: db', 'bootmap: no map')
    """
    who = f"bootmap {command}" if command else "bootmap"
    return f"{who}: {'error: ' if exit_code == EXIT_BAD_INPUT else ''}{message}"


class BootmapError(Exception):
    """Base class of every error bootmap raises on purpose."""

    exit_code = EXIT_FAILURE


class BadInput(BootmapError):
    """The input must change: a malformed file, an unknown level, a question about a missing dstate."""

    exit_code = EXIT_BAD_INPUT


class TableauError(BadInput, ValueError):
    """A tableau is malformed. ``where`` names the place: file, step index, field."""

    def __init__(self, message: str, where: str = ""):
        self.where = where
        self.reason = message
        super().__init__(f"{where}: {message}" if where else message)


class AxiomError(BadInput):
    """The axiom files cannot be loaded: missing directory, unknown level, or clingo rejects the text."""


class WorldError(BadInput, ValueError):
    """A world file is malformed. ``where`` names the file and the field (``worlds/x.toml: laser.max_range``)."""

    def __init__(self, message: str, where: str = ""):
        self.where = where
        self.reason = message
        super().__init__(f"{where}: {message}" if where else message)


class LogError(BadInput, ValueError):
    """A robot log (g2o, CARMEN, ROS bag) cannot be read. ``where`` names the file and the line
    (``killian.g2o: line 12``) or the message index (``run.bag: message 3 (/scan)``)."""

    def __init__(self, message: str, where: str = ""):
        self.where = where
        self.reason = message
        super().__init__(f"{where}: {message}" if where else message)


class SweepError(BadInput, ValueError):
    """A sweep file is malformed, or a sweep cannot start (its output directory holds another sweep).
    ``where`` names the file and the key (``sweeps/paper.toml: grid.seeds``)."""

    def __init__(self, message: str, where: str = ""):
        self.where = where
        self.reason = message
        super().__init__(f"{where}: {message}" if where else message)


class ExplainError(BadInput, ValueError):
    """A question the explainer cannot take, e.g. a time point or dstate the map does not have."""


class AssertionsError(BadInput, ValueError):
    """A person's assertions about a map are malformed: bad JSON, an unknown time point, a time point said
    to be apart from itself. ``where`` names the file and the field (``notes.json: assertions[2].apart``)."""

    def __init__(self, message: str, where: str = ""):
        self.where = where
        self.reason = message
        super().__init__(f"{where}: {message}" if where else message)


class InconsistentTableau(BootmapError):
    """No map satisfies the axioms for this tableau, whatever the number of dstates.

    ``levels`` are the levels that were solved together. ``failing_levels`` narrows it down, when the
    resolver could (:mod:`bootmap.mapping.diagnosis`): ``["causal"]`` when the causal axioms alone fail,
    else each level that fails beside the causal level alone; empty when only the levels together fail or
    nothing could be narrowed in time (``diagnosed`` says whether every try finished).
    """

    def __init__(self, message: str, levels: tuple[str, ...] = (), failing_levels: tuple[str, ...] = (),
                 diagnosed: bool = False):
        self.levels = tuple(levels)
        self.failing_levels = list(failing_levels)
        self.diagnosed = diagnosed
        super().__init__(message)


class AssertionConflict(InconsistentTableau):
    """A person's assertions contradict the experience (or each other): no map satisfies the axioms with
    them. ``conflict`` (:class:`bootmap.mapping.assertions.Conflict`) is a minimal clash: the assertions,
    the steps of experience and the axioms (file:line) it needs."""

    def __init__(self, message: str, conflict=None, levels: tuple[str, ...] = (), text: str | None = None):
        self.conflict = conflict  # a Conflict, or its to_dict() where it crossed a process
        self.text = text if text is not None or conflict is None or isinstance(conflict, dict) else conflict.to_text()
        super().__init__(message, levels=levels)


class SolveTimeout(BootmapError):
    """The solver ran out of time before it proved a minimal map (or finished an explanation).

    ``time_limit_s`` is the limit the caller set; ``stage`` what the solver was doing; ``lower_bound``
    dstates are proved necessary; ``best_map`` is a valid map found on the way (not proved minimal), or None.
    """

    def __init__(self, message: str, lower_bound: int = 0, best_map=None, time_limit_s: float | None = None,
                 stage: str = ""):
        self.lower_bound = lower_bound
        self.best_map = best_map
        self.time_limit_s = time_limit_s
        self.stage = stage
        super().__init__(message)
