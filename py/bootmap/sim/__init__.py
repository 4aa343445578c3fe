"""The simulator: a physical robot with a laser range-finder in 2-D worlds, producing tableaux.

world file -> :class:`~bootmap.sim.world.World` -> :class:`Simulation` (pymunk physics, laser, control laws,
an exploration policy) -> :class:`~bootmap.tableau.Tableau` of dstate images, actions and ground truth.
"""

from ..lazy import exports

__all__ = ["Circuits", "Explore", "RandomWalk", "Run", "Simulation", "SimulationError", "run", "simulate"]
_HOME = {"Circuits": ".policies", "Explore": ".policies", "RandomWalk": ".policies", "Run": ".simulation",
         "Simulation": ".simulation", "SimulationError": ".simulation", "run": ".simulation", "simulate": ".simulation"}


__getattr__ = exports(__name__, _HOME)  # the command line registers this package's commands without loading it
