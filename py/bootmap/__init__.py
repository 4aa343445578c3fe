"""bootmap: bootstrap learning of a robot's cognitive map (Kuipers & Beeson, AAAI 2002).

Data flows one way: world -> simulation -> tableau -> views -> map -> recognition -> service.
"""

from importlib import metadata

try:
    __version__ = metadata.version("bootmap")  # set by the release tag when the package was built or installed
except metadata.PackageNotFoundError:  # run from the source tree, not installed
    __version__ = "0.0.0+unknown"
