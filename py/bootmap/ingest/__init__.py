"""Real robots' logs: read them (g2o, CARMEN, ROS bags), choose their dstates, and measure the map
against their poses.

``read_log`` yields :class:`~bootmap.ingest.scans.Scan` records whatever the format; ``log_tableau``
turns them into a tableau the rest of the pipeline reads (``bootmap ingest LOG -o run.json``).
"""

from ..lazy import exports

# (``ingest``, the function that does both, is ``bootmap.ingest.ingest.ingest``: the package's name
# ``ingest`` is its module, which importing it sets.)
__all__ = ["Scan", "log_tableau", "read_log"]
_HOME = {"Scan": ".scans", "log_tableau": ".ingest", "read_log": ".ingest"}


__getattr__ = exports(__name__, _HOME)  # the command line registers this package's commands without loading it
