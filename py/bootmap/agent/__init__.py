"""The robot as an agent: exploration that uses its own map (after the mapping stage, above the simulator).

The simulator's policies (``bootmap.sim.policies``) see only the robot's percepts and odometry. The
active policy (:class:`~bootmap.agent.active.Active`) also keeps a map of its experience current and
rehearses while that map is not unique: it needs the mapping stack, so it lives here, and the simulator
runs it as it runs any policy object. :func:`make_policy` names every policy, the simulator's and this one.
"""

from __future__ import annotations

from ..sim.simulation import POLICIES as SIM_POLICIES
from ..sim.simulation import make_policy as sim_policy
from ..sim.world import World

POLICIES = SIM_POLICIES + ("active",)
ACTIVE_MAX_STEPS = 400  # the active policy's cap when no --steps is given


def make_policy(policy: str | object, world: World, steps: int | None = None, direction: str = "cw"):
    """A policy object from its name (:data:`POLICIES`), or the object itself. ``steps`` caps the
    ``active`` policy (default :data:`ACTIVE_MAX_STEPS`); the world's laser range scales its view labels."""
    if policy == "active":
        from .active import Active  # imports the mapping stack (clingo): only when asked for

        return Active(max_steps=steps or ACTIVE_MAX_STEPS, max_range=world.laser.range_max)
    return sim_policy(policy, direction=direction, wander=steps is not None)
