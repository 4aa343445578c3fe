"""bootmap: bootstrap learning of a robot's cognitive map (Kuipers & Beeson, AAAI 2002).

Data flows one way: world -> simulation -> tableau -> views -> map -> recognition -> service.
"""

__version__ = "0.1.0"
