"""The robot's body: a pymunk disc driven by a differential-drive command (v, omega), with slip and odometry.

The robot is a dynamic body, so walls and clutter stop it physically. It is not moved by overwriting its
velocity (that pushes it into walls): a kinematic *control body* carries the commanded velocity, and a
pivot joint and a gear joint with no position correction (``max_bias = 0``) drag the robot along with
bounded force and torque, like wheel friction (pymunk's "tank" example does the same).

The wheels are commanded (v, omega); the body achieves them only up to slip (the world's ``motion_noise``,
documented in ``worlds/README.md``): a relative Gaussian error drawn every control period on both, and on
the turn rate a relative error that wanders slowly (wheel scrub: it holds through a whole turn, so white
slip alone, which averages out, would understate a real robot's turn errors). Odometry integrates what
the wheel encoders report - the commanded motion - and its heading drifts besides, by a bias that
wanders slowly (a gyro's). So odometry is off from the truth by the slip and the drift, as on a real
robot; the control laws, which stop at dstates by the laser, do not let either move a dstate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pymunk

from .laser import Scene
from .world import World

ROBOT_CATEGORY = 0b10  # the laser's shape filter leaves the robot's own body out
MASS = 20.0  # kg, about an RWI Magellan's


@dataclass
class Odometry:
    """Pose and path length as the wheel encoders report them, in the robot's own odometry frame.

    ``distance`` is the path length driven either way; ``progress`` counts reversing as negative, so it
    says how far along its path the robot is after backing up to a fixed point it overshot.
    """

    x: float = 0.0
    y: float = 0.0
    theta: float = 0.0
    distance: float = 0.0
    progress: float = 0.0

    def advance(self, v: float, omega: float, dt: float) -> None:
        """Integrate a constant (v, omega) for dt along the exact arc."""
        if abs(omega) < 1e-9:
            self.x += v * dt * math.cos(self.theta)
            self.y += v * dt * math.sin(self.theta)
        else:
            r = v / omega
            t1 = self.theta + omega * dt
            self.x += r * (math.sin(t1) - math.sin(self.theta))
            self.y -= r * (math.cos(t1) - math.cos(self.theta))
        self.theta += omega * dt
        self.distance += abs(v) * dt
        self.progress += v * dt

    def copy(self) -> "Odometry":
        return Odometry(self.x, self.y, self.theta, self.distance, self.progress)


class Wander:
    """A slowly wandering Gaussian error: a first-order autoregressive process (a random walk pulled back
    to zero, so it stays within a few standard deviations however long the run).

    Parameters
    ----------
    sd : float
        Its standard deviation at any moment (the first value is drawn from it too).
    time_s : float
        Correlation time: values this far apart in time are correlated by 1/e.
    dt : float
        Time between updates.
    rng : numpy.random.Generator

    Examples
    --------
    >>> w = Wander(0.05, 5.0, 0.1, np.random.default_rng(0))
    >>> xs = [w.step() for _ in range(20000)]
    >>> round(float(np.std(xs)), 2), abs(float(np.corrcoef(xs[:-50], xs[50:])[0, 1]) - math.exp(-1)) < 0.1
    (0.05, True)
    """

    def __init__(self, sd: float, time_s: float, dt: float, rng: np.random.Generator):
        self.sd, self.rng = sd, rng
        self.keep = math.exp(-dt / time_s)
        self.fresh = sd * math.sqrt(1.0 - self.keep ** 2)  # keeps the variance at sd**2
        self.value = sd * float(rng.normal()) if sd > 0 else 0.0

    def step(self) -> float:
        """Advance one update; the new value."""
        if self.sd > 0:
            self.value = self.keep * self.value + self.fresh * float(self.rng.normal())
        return self.value


class PhysicalRobot:
    """A disc robot in a pymunk space built from a world.

    Parameters
    ----------
    world : World
        Walls, clutter, the robot's radius and start pose, and the slip noise.
    rng : numpy.random.Generator
        The simulation's generator (slip and drift).
    dt : float
        The control period, seconds (the wandering errors are updated once per period).
    substeps : int
        Physics steps per control period; pymunk integrates constant velocities exactly, so a few suffice.
    start : (x, y, theta), optional
        Start pose in metres and radians instead of the world's.

    Attributes
    ----------
    odometry : Odometry
        What the robot believes from its encoders.
    contacts : int
        Control periods during which the body touched a wall or obstacle.
    """

    def __init__(self, world: World, rng: np.random.Generator, dt: float = 0.1, substeps: int = 2,
                 start: tuple[float, float, float] | None = None):
        self.world, self.rng, self.substeps = world, rng, substeps
        noise = world.motion_noise
        self.turn_scale = Wander(noise.turn_scale, noise.turn_scale_time_s, dt, rng)
        self.drift = Wander(math.radians(noise.drift_deg_s), noise.drift_time_s, dt, rng)
        self.space = pymunk.Space()
        self.space.collision_slop = 0.001  # metres, not pixels
        self.space.iterations = 10
        self._static: list[pymunk.Shape] = []
        self.set_obstacles(Scene.of_world(world))
        self.body, self.control = self._add_robot(world, start or world.robot.start)
        self.odometry = Odometry()
        self.contacts = 0

    def _add_robot(self, world: World, start) -> tuple[pymunk.Body, pymunk.Body]:
        r = world.robot.radius
        x, y, theta = start
        body = pymunk.Body(MASS, pymunk.moment_for_circle(MASS, 0, r))
        body.position, body.angle = (x, y), theta
        shape = pymunk.Circle(body, r)
        shape.friction = 0.3
        shape.filter = pymunk.ShapeFilter(categories=ROBOT_CATEGORY)
        control = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        control.position = (x, y)
        pivot = pymunk.PivotJoint(control, body, (0, 0), (0, 0))
        pivot.max_bias, pivot.max_force = 0.0, 2000.0  # velocity only, bounded force: wheel traction
        gear = pymunk.GearJoint(control, body, 0.0, 1.0)
        gear.max_bias, gear.max_force = 0.0, 500.0
        self.space.add(body, shape, control, pivot, gear)
        return body, control

    def set_obstacles(self, scene: Scene) -> None:
        """Replace the static walls and clutter (clutter may move between visits)."""
        if self._static:
            self.space.remove(*self._static)
        sb = self.space.static_body
        shapes: list[pymunk.Shape] = [pymunk.Segment(sb, (x0, y0), (x1, y1), 0.0)
                                      for x0, y0, x1, y1 in scene.segments]
        shapes += [pymunk.Circle(sb, r, (cx, cy)) for cx, cy, r in scene.discs]
        for s in shapes:
            s.friction = 0.3
        self.space.add(*shapes)
        self._static = shapes

    @property
    def pose(self) -> tuple[float, float, float]:
        """The true pose (x, y, theta); the control laws never see it."""
        p = self.body.position
        return (p.x, p.y, self.body.angle)

    def drive(self, v: float, omega: float, dt: float) -> None:
        """Command (v, omega) for one control period: slip on the body; the command, and the drift,
        into odometry."""
        noise = self.world.motion_noise
        slip_v, slip_w = self.rng.normal(0.0, 1.0, 2)
        scale, drift = self.turn_scale.step(), self.drift.step()
        v_true = v * (1.0 + noise.slip_v * slip_v)
        w_true = omega * (1.0 + scale + noise.slip_omega * slip_w)
        h = dt / self.substeps
        body, control = self.body, self.control
        control.angular_velocity = w_true
        for _ in range(self.substeps):
            a = body.angle
            control.velocity = (v_true * math.cos(a), v_true * math.sin(a))
            self.space.step(h)
        self.odometry.advance(v, omega + drift, dt)
        if self._touching():
            self.contacts += 1

    def _touching(self) -> bool:
        touching = []
        self.body.each_arbiter(lambda arb: touching.append(1))
        return bool(touching)
