"""Real robots' logs: read them (g2o, CARMEN, ROS bags), choose their dstates, and measure the map
against their poses.

``read_log`` yields :class:`~bootmap.ingest.scans.Scan` records whatever the format; ``log_tableau``
turns them into a tableau the rest of the pipeline reads (``bootmap ingest LOG -o run.json``).
"""

from .ingest import ingest, log_tableau, read_log
from .scans import Scan

__all__ = ["Scan", "ingest", "log_tableau", "read_log"]
