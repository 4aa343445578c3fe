"""The robot's body: a pymunk disc driven by a differential-drive command (v, omega), with slip and odometry.

The robot is a dynamic body, so walls and clutter stop it physically. It is not moved by overwriting its
velocity (that pushes it into walls): a kinematic *control body* carries the commanded velocity, and a
pivot joint and a gear joint with no position correction (``max_bias = 0``) drag the robot along with
bounded force and torque, like wheel friction (pymunk's "tank" example does the same).

The wheels are commanded (v, omega); the body achieves them only up to slip, a relative Gaussian error
drawn every control period from the world's ``motion_noise``. Odometry integrates what the wheel encoders
report - the commanded motion - so it drifts from the truth exactly by the slip, as on a real robot.
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


class PhysicalRobot:
    """A disc robot in a pymunk space built from a world.

    Parameters
    ----------
    world : World
        Walls, clutter, the robot's radius and start pose, and the slip noise.
    rng : numpy.random.Generator
        The simulation's generator (slip).
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

    def __init__(self, world: World, rng: np.random.Generator, substeps: int = 2,
                 start: tuple[float, float, float] | None = None):
        self.world, self.rng, self.substeps = world, rng, substeps
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
        """Command (v, omega) for one control period: slip on the body, the command into odometry."""
        noise = self.world.motion_noise
        slip_v, slip_w = self.rng.normal(0.0, 1.0, 2)
        v_true = v * (1.0 + noise.slip_v * slip_v)
        w_true = omega * (1.0 + noise.slip_omega * slip_w)
        h = dt / self.substeps
        body, control = self.body, self.control
        control.angular_velocity = w_true
        for _ in range(self.substeps):
            a = body.angle
            control.velocity = (v_true * math.cos(a), v_true * math.sin(a))
            self.space.step(h)
        self.odometry.advance(v, omega, dt)
        if self._touching():
            self.contacts += 1

    def _touching(self) -> bool:
        touching = []
        self.body.each_arbiter(lambda arb: touching.append(1))
        return bool(touching)
