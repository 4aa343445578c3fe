"""The simulation loop: a robot, its laser and its control laws in a world, producing a tableau.

Every control period (10 Hz by default) the laser takes a noisy scan at the robot's true pose, the
active control law turns its percept and the odometry into a command (v, omega), and the physics
advances. When the law reaches its fixed point the robot is at a dstate: the scan there is the step's
image, the odometry-measured action becomes the previous step's action, and the true pose and true
dstate (place and heading sector, from the world's ground truth) are recorded for evaluation only.

One ``numpy.random.Generator`` seeded in :meth:`Simulation.reset` drives all randomness (slip, range
noise, drop-outs, moved clutter, random exploration choices): the same seed gives the same tableau.
"""

from __future__ import annotations

import math
import os
import sys
import time
from dataclasses import dataclass, field

import numpy as np

from ..errors import BootmapError
from ..paths import simplify
from ..tableau import Action, Step, Tableau
from .control import ControlLaw, Limits, Travel, Turn
from .laser import Laser, Scene
from .perception import Perception
from .physics import PhysicalRobot
from .policies import Circuits, Decision, Explore, Observation, RandomWalk
from .world import World, load_world

DSTATES_PER_CIRCUIT = 8  # a room has four corners, and a dstate before and after each turn
MOVE_PROBABILITY = 0.2  # chance that a jittery clutter object has moved when the robot reaches a dstate


class SimulationError(BootmapError):
    """The robot got stuck: a control law did not reach its fixed point in time.

    Raised from :meth:`Simulation.run` once a dstate has been recorded, it carries ``run``: the
    :class:`Run` up to the last dstate reached."""

    run: "Run | None" = None


@dataclass
class Run:
    """The outcome of a run: the tableau, and what only the simulator knows.

    Attributes
    ----------
    tableau : Tableau
        Images, actions, true dstates and poses.
    trajectory : ndarray, shape (n, 3)
        The true pose after every control period.
    sim_time : float
        Simulated seconds.
    contacts : int
        Control periods in which the robot touched a wall or obstacle.
    wall_time : float
        Seconds the run took.
    dstate_ticks : ndarray of int, shape (len(tableau),)
        The row of ``trajectory`` where each dstate was reached (what the robot truly did between two
        dstates, e.g. how far a turn rotated on its way, is the trajectory between them).
    """

    tableau: Tableau
    trajectory: np.ndarray
    sim_time: float
    contacts: int
    wall_time: float = 0.0
    explored: bool | None = None
    dstate_ticks: np.ndarray | None = None


@dataclass
class _Record:
    images: list = field(default_factory=list)
    poses: list = field(default_factory=list)
    truths: list = field(default_factory=list)
    actions: list = field(default_factory=list)
    ticks: list = field(default_factory=list)
    bounded: list = field(default_factory=list)  # laws that ended by a phase's bound, not at tolerance


class Simulation:
    """One robot in one world.

    Parameters
    ----------
    world : World
    control_hz : float
        Rate of the control laws (and of the laser).
    substeps : int
        Physics steps per control period.
    limits : Limits, optional
        Speeds and gains; the world's robot section sets the speed limits.

    Examples
    --------
    >>> from bootmap.sim.world import load_world
    >>> sim = Simulation(load_world("notched_rectangle")).reset(seed=1)
    >>> run = sim.run(Circuits(), n_steps=4)
    >>> [s.truth for s in run.tableau.steps]
    ['P0:N', 'P0:E', 'P1:E', 'P1:S']
    """

    def __init__(self, world: World, control_hz: float = 10.0, substeps: int = 2, limits: Limits | None = None):
        self.world = world
        self.dt = 1.0 / control_hz
        self.substeps = substeps
        self.limits = limits or Limits(v_max=world.robot.max_speed, w_max=world.robot.max_turn_rate,
                                       stop_tolerance=world.control.stop_tolerance,
                                       align_tolerance=math.radians(world.control.align_tolerance_deg))
        self.laser = Laser(world.laser)
        self.perception = Perception(world.laser, world.control.open_range)

    def reset(self, seed: int | None = 0, start: tuple[float, float, float] | None = None) -> "Simulation":
        """Start afresh: a new generator from ``seed``, the robot at ``start`` (x, y, theta in radians;
        default the world's start pose)."""
        if start is not None and not self.world.in_free_space(np.array(start[:2]), tolerance=0.0)[0]:
            raise ValueError(f"start pose {start} is not in free space")
        self.rng = np.random.default_rng(seed)
        self.seed = seed
        self.robot = PhysicalRobot(self.world, self.rng, self.dt, self.substeps, start)
        self._box_offsets: dict[int, tuple[float, float]] = {}
        self._disc_offsets: dict[int, tuple[float, float]] = {}
        self.scene = Scene.of_world(self.world)
        self.time = 0.0
        self._trajectory = [self.robot.pose]
        return self

    # ------------------------------------------------------------------ running
    def run(self, policy, n_steps: int | None = None, progress: bool = False) -> Run:
        """Run ``policy`` until it stops or ``n_steps`` dstates are recorded."""
        if not hasattr(self, "rng"):
            self.reset()
        started = time.perf_counter()
        policy.reset(self.rng)
        rec = _Record()
        bar = _progress_bar(progress, n_steps)
        law = self._travel_law(policy)
        image, percept = self._execute(law)
        self._note_bound(rec, law)
        self._record(rec, image, None)
        bar.update(1)
        while n_steps is None or len(rec.images) < n_steps:
            obs = Observation(percept, rec.actions[-1] if rec.actions else None,
                              percept.front > self.world.control.open_range, image)
            decision = policy.decide(obs)
            if decision is None:
                break
            law = self._law(decision, policy)
            try:
                image, percept = self._execute(law)
            except SimulationError as e:
                # Keep the experience up to the dstate where the robot got stuck (benchmarks score it).
                e.run = Run(self._tableau(rec, policy), np.array(self._trajectory), self.time,
                            self.robot.contacts, time.perf_counter() - started,
                            dstate_ticks=np.array(rec.ticks))
                bar.close()
                raise
            self._note_bound(rec, law)
            self._record(rec, image, law.action(self.robot.odometry))
            bar.update(1)
        bar.close()
        return Run(self._tableau(rec, policy), np.array(self._trajectory), self.time, self.robot.contacts,
                   time.perf_counter() - started, getattr(policy, "explored_", None), np.array(rec.ticks))

    def _law(self, decision: Decision, policy) -> ControlLaw:
        if decision.kind == "travel":
            return self._travel_law(policy)
        return Turn(self.limits, decision.angle, perception=self.perception)

    def _travel_law(self, policy) -> Travel:
        c = self.world.control
        return Travel(self.limits, self.perception, policy.follow, c.wall_distance, c.stop_distance,
                      policy.junctions)

    def _execute(self, law: ControlLaw):
        """Run one control law to its fixed point; return the scan there (the image) and its percept."""
        robot, laser, perception, rng = self.robot, self.laser, self.perception, self.rng
        law.begin(robot.odometry)
        deadline = self.time + law.timeout
        while True:
            ranges = laser.scan(self.scene, robot.pose, rng)
            percept = perception(ranges)
            v, omega = law.step(percept, ranges, robot.odometry)
            if law.done:
                return ranges, percept
            robot.drive(v, omega, self.dt)
            self.time += self.dt
            self._trajectory.append(robot.pose)
            if self.time > deadline:
                x, y, th = robot.pose
                raise SimulationError(
                    f"stuck: {type(law).__name__.lower()} did not reach a dstate within {law.timeout:g} s "
                    f"(true pose {x:.2f}, {y:.2f}, {math.degrees(th):.0f} deg; t = {self.time:.1f} s)")

    @staticmethod
    def _note_bound(rec: _Record, law: ControlLaw) -> None:
        """A law that reached a phase's bound settled on filtered readings with widened tolerances, or
        (``widened`` null) stood where it was: the run's record says so, against the dstate it reached."""
        if law.bounded is None:
            return
        rec.bounded.append({"step": len(rec.images), "law": type(law).__name__.lower(), "phase": law.bounded,
                            "ticks": law.ticks,
                            "widened": law.widened if math.isfinite(law.widened) else None})

    def _record(self, rec: _Record, image: np.ndarray, action: Action | None) -> None:
        pose = self.robot.pose
        rec.images.append(tuple(np.round(image, 4).tolist()))
        theta = math.atan2(math.sin(pose[2]), math.cos(pose[2]))
        rec.poses.append((round(pose[0], 4), round(pose[1], 4), round(theta, 5)))
        rec.truths.append(self.world.true_dstate(pose) or "?")
        rec.ticks.append(len(self._trajectory) - 1)
        if action is not None:
            rec.actions.append(action)
        self._move_clutter()

    def _move_clutter(self) -> None:
        """Small dynamic changes between visits: jittery clutter sometimes stands somewhere else."""
        w = self.world
        moved = False
        x, y, _ = self.robot.pose
        for items, offsets in ((w.boxes, self._box_offsets), (w.discs, self._disc_offsets)):
            for i, item in enumerate(items):
                if item.jitter <= 0 or self.rng.random() >= MOVE_PROBABILITY:
                    continue
                r = item.jitter * math.sqrt(self.rng.random())
                a = self.rng.uniform(0, 2 * math.pi)
                off = (r * math.cos(a), r * math.sin(a))
                reach = getattr(item, "radius", None) or 0.5 * math.hypot(*item.size)
                cx, cy = item.center[0] + off[0], item.center[1] + off[1]
                if math.hypot(cx - x, cy - y) < reach + w.robot.radius + 0.1:
                    continue  # never drop an obstacle onto the robot
                offsets[i] = off
                moved = True
        if moved:
            self.scene = Scene.of_world(w, self._box_offsets, self._disc_offsets)
            self.robot.set_obstacles(self.scene)

    def _tableau(self, rec: _Record, policy) -> Tableau:
        steps = tuple(Step(action=rec.actions[i] if i < len(rec.actions) else None, image=rec.images[i],
                           truth=rec.truths[i], pose=rec.poses[i]) for i in range(len(rec.images)))
        spec = self.world.laser
        meta = {
            "generator": "bootmap.sim",
            "seed": self.seed,
            "policy": type(policy).__name__.lower(),
            "sim_seconds": round(self.time, 2),
            "contacts": self.robot.contacts,
            "laser": {"angle_min": spec.angle_min, "angle_max": spec.angle_max,
                      "angle_increment": spec.angle_increment, "range_max": spec.range_max,
                      "beams": spec.beams},
            "trajectory": _thin(np.array(self._trajectory)),
        }
        if rec.bounded:
            meta["bounded_laws"] = rec.bounded
        return Tableau(steps, self.world.name, meta)


#: How far the drawn path may stray from where the robot was (metres): a tenth of the robot's width.
TRAJECTORY_TOLERANCE_M = 0.02


def _thin(traj: np.ndarray, tolerance_m: float = TRAJECTORY_TOLERANCE_M) -> list[list[float]]:
    """The trajectory as the fewest [x, y] points that keep the drawn path within ``tolerance_m`` of every
    position (Ramer-Douglas-Peucker, :func:`bootmap.paths.simplify`): a straight travel is its two ends,
    so a long run stays within what the service takes as a tableau's ``meta``."""
    xy = np.asarray(traj, dtype=float)[:, :2]
    return np.round(xy[simplify(xy, tolerance_m)], 3).tolist()


class _NoBar:
    def update(self, n: int = 1) -> None:
        pass

    def close(self) -> None:
        pass


def _progress_bar(enabled: bool, total: int | None):
    if not enabled:
        return _NoBar()
    from tqdm import tqdm

    return tqdm(total=total, unit="dstate", file=sys.stderr, dynamic_ncols=True)


POLICIES = ("circuits", "explore", "random")  # the simulator's own; bootmap.agent adds the active one


def make_policy(policy: str | object, direction: str = "cw", wander: bool = False):
    """A policy object from its name (:data:`POLICIES`), or the object itself (any policy, e.g. the
    active one of :mod:`bootmap.agent`, which names it)."""
    if not isinstance(policy, str):
        return policy
    if policy == "circuits":
        return Circuits(direction)
    if policy == "explore":
        return Explore(wander=wander)
    if policy == "random":
        return RandomWalk()
    raise ValueError(f"unknown policy {policy!r} (expected one of: {', '.join(POLICIES)}, or a policy object)")


def run(world: World | str | os.PathLike, policy: str | object = "circuits", circuits: int = 50,
        steps: int | None = None, seed: int = 0, progress: bool = False, direction: str = "cw",
        start: tuple[float, float, float] | None = None) -> Run:
    """Like :func:`simulate`, but return the whole :class:`Run` (trajectory, contacts, timings);
    ``start`` (x, y, heading in degrees) overrides the world's start pose."""
    if not isinstance(world, World):
        world = load_world(world)
    pol = make_policy(policy, direction=direction, wander=steps is not None)
    if steps is None and isinstance(pol, RandomWalk):
        raise ValueError("a random walk never stops by itself: give it a number of steps")
    if steps is None and isinstance(pol, Circuits):
        steps = DSTATES_PER_CIRCUIT * circuits
    if start is not None:
        start = (start[0], start[1], math.radians(start[2]))
    return Simulation(world).reset(seed, start).run(pol, n_steps=steps, progress=progress)


def simulate(world: World | str | os.PathLike, policy: str | object = "circuits", circuits: int = 50,
             steps: int | None = None, seed: int = 0, progress: bool = False, direction: str = "cw") -> Tableau:
    """Simulate the robot in a world and return its tableau (images, actions, truth, poses).

    Parameters
    ----------
    world : World, or a path, or the name of a file in ``worlds/``
    policy : {"circuits", "explore", "random"} or a policy object
        ``circuits`` runs the paper's circuits of a room (8 dstates each); ``explore`` explores a
        hallway systematically and stops when every path direction is explored, or, given ``steps``,
        goes on at random until it has that many dstates; ``random`` walks at random (give ``steps``).
        A policy object runs as given, e.g. ``bootmap.agent.make_policy("active", world)``, which keeps
        its map current and rehearses until the map is unique and complete (``steps`` caps it).
    circuits : int
        Number of circuits (``circuits`` policy, unless ``steps`` is given).
    steps : int, optional
        Exact number of dstates to record.
    seed : int
        Seeds the run's only random generator: the same seed gives the same tableau.
    progress : bool
        Show a progress bar on stderr.
    direction : {"cw", "ccw"}
        Direction of the circuits.

    Examples
    --------
    >>> t = simulate("notched_rectangle", circuits=1, seed=3)
    >>> len(t), sorted(set(s.truth for s in t.steps))
    (8, ['P0:E', 'P0:N', 'P1:E', 'P1:S', 'P2:S', 'P2:W', 'P3:N', 'P3:W'])
    """
    return run(world, policy, circuits, steps, seed, progress, direction).tableau
