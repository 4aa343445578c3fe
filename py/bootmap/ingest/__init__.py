"""Real robots' logs: read them (g2o, CARMEN, ROS bags), choose their dstates, and measure the map
against their poses.

``read_log`` yields :class:`~bootmap.ingest.scans.Scan` records whatever the format; ``log_tableau``
turns them into a tableau the rest of the pipeline reads (``bootmap ingest LOG -o run.json``).
"""

from importlib import import_module

# (``ingest``, the function that does both, is ``bootmap.ingest.ingest.ingest``: the package's name
# ``ingest`` is its module, which importing it sets.)
__all__ = ["Scan", "log_tableau", "read_log"]
_HOME = {"Scan": ".scans", "log_tableau": ".ingest", "read_log": ".ingest"}


def __getattr__(name: str):
    """The package's names, imported when first used (PEP 562): the command line registers ``bootmap
    ingest`` without loading the log readers and scipy."""
    if name in _HOME:
        value = getattr(import_module(_HOME[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
