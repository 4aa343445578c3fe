"""Exceptions bootmap raises. Every one carries a message a person can act on."""


class BootmapError(Exception):
    """Base class of every error bootmap raises on purpose."""


class TableauError(BootmapError, ValueError):
    """A tableau is malformed. ``where`` names the place: file, step index, field."""

    def __init__(self, message: str, where: str = ""):
        self.where = where
        self.reason = message
        super().__init__(f"{where}: {message}" if where else message)


class AxiomError(BootmapError):
    """The axiom files cannot be loaded: missing directory, unknown level, or clingo rejects the text."""


class InconsistentTableau(BootmapError):
    """No map satisfies the axioms for this tableau, whatever the number of dstates."""


class SolveTimeout(BootmapError):
    """The solver ran out of time before it proved a minimal map.

    ``lower_bound`` dstates are proved necessary; ``best_map`` is a valid map found on the way (not proved
    minimal), or None.
    """

    def __init__(self, message: str, lower_bound: int = 0, best_map=None):
        self.lower_bound = lower_bound
        self.best_map = best_map
        super().__init__(message)


class WorldError(BootmapError, ValueError):
    """A world file is malformed. ``where`` names the file and the field (``worlds/x.toml: laser.max_range``)."""

    def __init__(self, message: str, where: str = ""):
        self.where = where
        self.reason = message
        super().__init__(f"{where}: {message}" if where else message)


class ExplainError(BootmapError, ValueError):
    """A question the explainer cannot take, e.g. a time point or dstate the map does not have."""
