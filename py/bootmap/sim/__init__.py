"""The simulator: a physical robot with a laser range-finder in 2-D worlds, producing tableaux.

world file -> :class:`~bootmap.sim.world.World` -> :class:`Simulation` (pymunk physics, laser, control laws,
an exploration policy) -> :class:`~bootmap.tableau.Tableau` of dstate images, actions and ground truth.
"""

from importlib import import_module

__all__ = ["Circuits", "Explore", "RandomWalk", "Run", "Simulation", "SimulationError", "run", "simulate"]
_HOME = {"Circuits": ".policies", "Explore": ".policies", "RandomWalk": ".policies", "Run": ".simulation",
         "Simulation": ".simulation", "SimulationError": ".simulation", "run": ".simulation", "simulate": ".simulation"}


def __getattr__(name: str):
    """The package's names, imported when first used (PEP 562): the command line registers ``bootmap
    simulate`` without loading the physics and the policies."""
    if name in _HOME:
        value = getattr(import_module(_HOME[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
