"""The simulator: a physical robot with a laser range-finder in 2-D worlds, producing tableaux.

world file -> :class:`~bootmap.sim.world.World` -> :class:`Simulation` (pymunk physics, laser, control laws,
an exploration policy) -> :class:`~bootmap.tableau.Tableau` of dstate images, actions and ground truth.
"""

from .policies import Circuits, Explore, RandomWalk
from .simulation import Run, Simulation, SimulationError, run, simulate

__all__ = ["Circuits", "Explore", "RandomWalk", "Run", "Simulation", "SimulationError", "run", "simulate"]
