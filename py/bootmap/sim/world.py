"""Worlds: the rooms and hallways the simulated robot lives in, read from TOML files in ``worlds/``.

A world file is declarative (see ``worlds/README.md`` for every field): the outer boundary as a
polygon, extra walls as polylines, clutter (boxes and discs), the robot's start pose, the laser and
noise parameters, the control-law distances, and the ground truth the evaluation needs - the places
(regions) and paths. A true dstate is a place and a heading sector (``"P3:E"``); :meth:`World.true_dstate`
computes it from a pose. The control laws never see any of this: they see the laser scan and odometry.

Loading validates everything a person can get wrong and raises :class:`~bootmap.errors.WorldError`
naming the file, the field and the problem.

Example
-------
>>> w = load_world("notched_rectangle")
>>> w.name, len(w.places), w.truth_dstates
('notched_rectangle', 4, 8)
>>> w.true_dstate((0.5, 2.5, 1.5708))
'P0:N'
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..errors import WorldError

FORMAT = "bootmap.world/1"
SECTORS = ("E", "N", "W", "S")  # heading sectors, 90 degrees wide, centred on the axes


def worlds_dir() -> Path:
    """The folder of named worlds: ``$BOOTMAP_WORLDS``, else the copy inside an installed wheel
    (``bootmap/worlds``), else ``worlds/`` at the top of the repository."""
    env = os.environ.get("BOOTMAP_WORLDS")
    if env:
        return Path(env)
    package = Path(__file__).resolve().parents[1]  # bootmap/
    shipped = package / "worlds"
    return shipped if shipped.is_dir() else package.parents[1] / "worlds"


def world_names() -> list[str]:
    """Names of the worlds in :func:`worlds_dir`, sorted."""
    return sorted(p.stem for p in worlds_dir().glob("*.toml"))


# --------------------------------------------------------------------------- the world's parts

@dataclass(frozen=True)
class RobotSpec:
    """The robot's body and limits; ``start`` is (x, y, heading in radians)."""

    radius: float
    start: tuple[float, float, float]
    max_speed: float
    max_turn_rate: float  # rad/s


@dataclass(frozen=True)
class LaserSpec:
    """A planar laser range-finder, in ROS LaserScan terms: beam i points at ``angle_min + i * angle_increment``."""

    beams: int
    angle_min: float  # rad, relative to the robot's heading; negative is to the right
    angle_max: float
    range_max: float
    noise_sd: float
    dropout: float

    @property
    def angle_increment(self) -> float:
        return (self.angle_max - self.angle_min) / (self.beams - 1)

    @property
    def angles(self) -> np.ndarray:
        return self.angle_min + self.angle_increment * np.arange(self.beams)


@dataclass(frozen=True)
class MotionNoise:
    """How the body's motion departs from the command, and how odometry departs from the truth.

    See ``worlds/README.md`` (the noise model) for what each parameter does and why its default.

    Attributes
    ----------
    slip_v, slip_omega : float
        Relative standard deviations of achieved against commanded (v, omega), drawn afresh every
        control period (white slip: it averages out over a long motion).
    turn_scale : float
        Relative standard deviation of a slowly wandering error of the achieved turn rate (wheel scrub
        on turning in place): it persists through a whole turn, so a turn's measured angle is off by
        about this fraction of the angle.
    turn_scale_time_s : float
        Correlation time of that error, seconds.
    drift_deg_s : float
        Standard deviation of the odometry heading's drift (a gyro's bias), degrees per second.
    drift_time_s : float
        Correlation time of the drift, seconds.
    """

    slip_v: float = 0.06
    slip_omega: float = 0.06
    turn_scale: float = 0.05
    turn_scale_time_s: float = 5.0
    drift_deg_s: float = 0.15
    drift_time_s: float = 60.0


@dataclass(frozen=True)
class ControlSpec:
    """Distances the control laws hold: wall following, stopping before a wall, what counts as an opening."""

    wall_distance: float
    stop_distance: float
    open_range: float
    # How precisely the hill-climbing settles at a dstate: where the robot comes to rest varies within
    # these, and that (with sensor noise) is the image variability the views must absorb.
    stop_tolerance: float = 0.008
    align_tolerance_deg: float = 0.6


@dataclass(frozen=True)
class Box:
    """A rectangular obstacle (locker, desk, bench, blackboard); ``jitter`` > 0 moves it between visits."""

    center: tuple[float, float]
    size: tuple[float, float]
    angle: float = 0.0
    kind: str = "box"
    jitter: float = 0.0

    def corners(self, offset: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
        """The four corners, counter-clockwise, shifted by ``offset``."""
        w, h = self.size[0] / 2, self.size[1] / 2
        local = np.array([[-w, -h], [w, -h], [w, h], [-w, h]])
        c, s = math.cos(self.angle), math.sin(self.angle)
        return local @ np.array([[c, s], [-s, c]]) + np.add(self.center, offset)


@dataclass(frozen=True)
class Disc:
    """A round obstacle (trash can, pillar); ``jitter`` > 0 moves it between visits."""

    center: tuple[float, float]
    radius: float
    kind: str = "disc"
    jitter: float = 0.0


@dataclass(frozen=True)
class Place:
    """A ground-truth place: the axis-aligned region where the robot's dstates at that place lie."""

    id: str
    rect: tuple[float, float, float, float]  # xmin, ymin, xmax, ymax

    def contains(self, x: float, y: float) -> bool:
        return self.rect[0] <= x <= self.rect[2] and self.rect[1] <= y <= self.rect[3]

    @property
    def center(self) -> tuple[float, float]:
        return ((self.rect[0] + self.rect[2]) / 2, (self.rect[1] + self.rect[3]) / 2)


@dataclass(frozen=True)
class PathTruth:
    """A ground-truth path: the places on it, in order."""

    id: str
    places: tuple[str, ...]


@dataclass(frozen=True)
class World:
    """A validated world. Build one with :func:`load_world` or :meth:`World.from_dict`."""

    name: str
    boundary: np.ndarray  # (n, 2) closed polygon, the outer walls
    walls: tuple[np.ndarray, ...]  # extra polylines, each (m, 2), closed ones repeat the first point
    boxes: tuple[Box, ...]
    discs: tuple[Disc, ...]
    robot: RobotSpec
    laser: LaserSpec
    motion_noise: MotionNoise
    control: ControlSpec
    places: tuple[Place, ...]
    paths: tuple[PathTruth, ...] = ()
    truth_dstates: int | None = None
    policy: str = "circuits"
    description: str = ""
    source: str = ""
    extra: dict = field(default_factory=dict)

    # ------------------------------------------------------------------ geometry
    def wall_segments(self) -> np.ndarray:
        """Every fixed wall segment (boundary and extra walls) as rows ``x0, y0, x1, y1``."""
        rings = [np.vstack([self.boundary, self.boundary[:1]])] + list(self.walls)
        return np.vstack([np.hstack([r[:-1], r[1:]]) for r in rings])

    def box_segments(self, offsets: dict[int, tuple[float, float]] | None = None) -> np.ndarray:
        """The edges of every box, shifted by ``offsets[i]`` for moved boxes, as rows ``x0, y0, x1, y1``."""
        if not self.boxes:
            return np.zeros((0, 4))
        offsets = offsets or {}
        out = []
        for i, b in enumerate(self.boxes):
            c = b.corners(offsets.get(i, (0.0, 0.0)))
            out.append(np.hstack([c, np.roll(c, -1, axis=0)]))
        return np.vstack(out)

    def disc_array(self, offsets: dict[int, tuple[float, float]] | None = None) -> np.ndarray:
        """Every disc as rows ``x, y, radius``."""
        offsets = offsets or {}
        rows = [(d.center[0] + offsets.get(i, (0, 0))[0], d.center[1] + offsets.get(i, (0, 0))[1], d.radius)
                for i, d in enumerate(self.discs)]
        return np.array(rows, dtype=float).reshape(-1, 3)

    def clearance(self, xy: np.ndarray) -> np.ndarray:
        """Distance from each point to the nearest wall, box or disc surface (no offsets)."""
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        segs = np.vstack([self.wall_segments(), self.box_segments()])
        d = _point_segment_distance(xy, segs).min(axis=1)
        discs = self.disc_array()
        if len(discs):
            dd = np.hypot(xy[:, None, 0] - discs[:, 0], xy[:, None, 1] - discs[:, 1]) - discs[:, 2]
            d = np.minimum(d, dd.min(axis=1))
        return d

    def inside(self, xy: np.ndarray) -> np.ndarray:
        """Whether each point lies inside the boundary polygon (even-odd rule)."""
        return _inside_polygon(np.atleast_2d(np.asarray(xy, dtype=float)), self.boundary)

    def in_free_space(self, xy: np.ndarray, tolerance: float = 0.01) -> np.ndarray:
        """Whether a robot centred at each point fits: inside the boundary, ``radius`` clear of everything."""
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        return self.inside(xy) & (self.clearance(xy) >= self.robot.radius - tolerance)

    def bounds(self) -> tuple[float, float, float, float]:
        lo, hi = self.boundary.min(axis=0), self.boundary.max(axis=0)
        return float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])

    # ------------------------------------------------------------------ ground truth
    def place_at(self, x: float, y: float) -> str | None:
        """The id of the place whose region holds (x, y), or None between places."""
        for p in self.places:
            if p.contains(x, y):
                return p.id
        return None

    def true_dstate(self, pose) -> str | None:
        """The true dstate of a pose: ``"<place>:<sector>"``, or None if the pose is at no place."""
        place = self.place_at(pose[0], pose[1])
        if place is None:
            return None
        return f"{place}:{heading_sector(pose[2])}"

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_dict(cls, data: Any, source: str = "world") -> "World":
        """Validate a parsed TOML document and build the world; errors name ``source`` and the field."""
        return _build(data, source)


def heading_sector(theta: float) -> str:
    """The 90-degree sector of a heading in radians: E, N, W or S."""
    return SECTORS[int(round(theta / (math.pi / 2))) % 4]


def resolve_world_path(world: str | os.PathLike) -> Path:
    """A world given as a path, or as the name of a file in :func:`worlds_dir` (with or without .toml)."""
    p = Path(world)
    if p.is_file():
        return p
    for cand in (worlds_dir() / p.name, worlds_dir() / f"{p.name}.toml"):
        if cand.is_file() and p.parent == Path("."):
            return cand
    names = ", ".join(world_names()) or "(none)"
    raise WorldError(f"no such world file or name; known worlds: {names}", str(world))


def load_world(world: str | os.PathLike, settings: dict[str, Any] | None = None) -> World:
    """Read and validate a world file (a path or a name from ``worlds/``); errors name the file.

    ``settings`` overrides fields of the file before it is validated, as ``{"section.field": value}``
    (``{"laser.noise_sd": 0.02}``): the values are checked as the file's own would be, and the error of
    a bad one names the field (see :func:`apply_settings`)."""
    path = resolve_world_path(world)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise WorldError(f"cannot read: {getattr(e, 'strerror', None) or e}", str(path)) from None
    return loads_world(text, str(path), settings)


def loads_world(text: str, source: str = "world", settings: dict[str, Any] | None = None) -> World:
    """Parse and validate world TOML text, with ``settings`` applied as in :func:`load_world`."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise WorldError(f"not valid TOML: {e}", source) from None
    if settings:
        data = apply_settings(data, settings, source)
        source = f"{source} (with {', '.join(f'{k}={v!r}' for k, v in settings.items())})"
    return World.from_dict(data, source)


def apply_settings(data: dict, settings: dict[str, Any], source: str = "world") -> dict:
    """A copy of a parsed world document with ``{"section.field": value}`` set.

    Only fields of a plain section (``laser``, ``motion_noise``, ``robot``, ``control``) or the top level
    can be set; the value is validated afterwards with the rest of the file, so a bad one fails as it
    would in the file. A name that is not ``section.field`` or names an array of tables is refused here.

    Examples
    --------
    >>> apply_settings({"laser": {"range_max": 8.0}}, {"laser.noise_sd": 0.02})
    {'laser': {'range_max': 8.0, 'noise_sd': 0.02}}
    """
    out = {k: (dict(v) if isinstance(v, dict) else v) for k, v in data.items()}
    for key, value in settings.items():
        section, _, field_ = key.rpartition(".")
        if not field_ or "." in section:
            raise WorldError("a setting is section.field, e.g. laser.noise_sd", f"{source}: {key}")
        if not section:
            out[field_] = value
            continue
        table = out.setdefault(section, {})
        if not isinstance(table, dict):
            raise WorldError(f"{section} is not a section of plain fields (it is {_kind(table)})",
                             f"{source}: {key}")
        table[field_] = value
    return out


# --------------------------------------------------------------------------- validation
# Each section is a table of field -> (parser, default). A default of _REQUIRED makes the field required.
_REQUIRED = object()


class _Reader:
    """Reads one table of the document, naming ``source: section.field`` in every error."""

    def __init__(self, table: Any, where: str, source: str):
        self.where, self.source = where, source
        if not isinstance(table, dict):
            self.fail("", f"must be a table, got {_kind(table)}")
        self.table = table
        self.seen: set[str] = set()

    def name(self, key: str) -> str:
        return f"{self.where}.{key}" if self.where and key else (self.where or key)

    def fail(self, key: str, message: str):
        raise WorldError(message, f"{self.source}: {self.name(key) or '(top level)'}")

    def get(self, key: str, parse: Callable[[Any, Callable[[str], None]], Any], default: Any = _REQUIRED):
        self.seen.add(key)
        if key not in self.table:
            if default is _REQUIRED:
                self.fail(key, "missing (required)")
            return default
        return parse(self.table[key], lambda msg: self.fail(key, msg))

    def done(self) -> None:
        """Unknown keys are errors: a misspelt field must not silently fall back to a default."""
        unknown = sorted(set(self.table) - self.seen)
        if unknown:
            self.fail(unknown[0], f"unknown field (expected one of: {', '.join(sorted(self.seen))})")


def _kind(x: Any) -> str:
    return {dict: "a table", list: "an array", str: "a string", bool: "a boolean"}.get(type(x), type(x).__name__)


def _number(lo: float | None = None, hi: float | None = None, lo_open: bool = False):
    def parse(x, fail):
        if isinstance(x, bool) or not isinstance(x, (int, float)):
            fail(f"must be a number, got {_kind(x)} {x!r}")
        x = float(x)
        if not math.isfinite(x):
            fail(f"must be finite, got {x}")
        if lo is not None and (x < lo or (lo_open and x == lo)):
            fail(f"must be {'>' if lo_open else '>='} {lo:g}, got {x:g}")
        if hi is not None and x > hi:
            fail(f"must be <= {hi:g}, got {x:g}")
        return x
    return parse


def _integer(lo: int):
    def parse(x, fail):
        if isinstance(x, bool) or not isinstance(x, int):
            fail(f"must be an integer, got {_kind(x)} {x!r}")
        if x < lo:
            fail(f"must be >= {lo}, got {x}")
        return x
    return parse


def _string(x, fail):
    if not isinstance(x, str) or not x.strip():
        fail(f"must be a non-empty string, got {_kind(x)} {x!r}")
    return x


def _vector(n: int, lo: float | None = None):
    num = _number(lo, lo_open=lo is not None)

    def parse(x, fail):
        if not isinstance(x, list) or len(x) != n:
            fail(f"must be an array of {n} numbers, got {_kind(x)} {x!r}")
        return tuple(num(v, lambda m, i=i: fail(f"item {i} {m}")) for i, v in enumerate(x))
    return parse


def _points(min_points: int):
    def parse(x, fail):
        if not isinstance(x, list) or len(x) < min_points:
            fail(f"must be an array of at least {min_points} [x, y] points")
        pts = [_vector(2)(p, lambda m, i=i: fail(f"point {i}: {m}")) for i, p in enumerate(x)]
        arr = np.array(pts, dtype=float)
        if np.any(np.hypot(*np.diff(arr, axis=0).T) < 1e-9):
            fail("has two equal consecutive points (a zero-length wall)")
        return arr
    return parse


def _build(data: Any, source: str) -> World:
    top = _Reader(data, "", source)
    fmt = top.get("format", _string)
    if fmt != FORMAT:
        top.fail("format", f"unsupported format {fmt!r} (expected {FORMAT!r})")
    name = top.get("name", _string)
    description = top.get("description", lambda x, f: x if isinstance(x, str) else f("must be a string"), "")
    policy = top.get("policy", _string, "circuits")
    if policy not in ("circuits", "explore"):
        top.fail("policy", f"unknown policy {policy!r} (expected 'circuits' or 'explore')")

    boundary = _section(top, "boundary", lambda r: r.get("points", _points(3)))
    if abs(_signed_area(boundary)) < 1e-6:
        top.fail("boundary.points", "encloses no area")
    walls = tuple(_wall(r) for r in _array_of_tables(top, "walls"))
    boxes = tuple(_box(r) for r in _array_of_tables(top, "boxes"))
    discs = tuple(_disc(r) for r in _array_of_tables(top, "discs"))
    robot = _section(top, "robot", _robot)
    laser = _section(top, "laser", _laser)
    noise = _section(top, "motion_noise", _motion_noise, optional=True)
    control = _section(top, "control", lambda r: ControlSpec(
        r.get("wall_distance", _number(0, lo_open=True), 0.5),
        r.get("stop_distance", _number(0, lo_open=True), 0.5),
        r.get("open_range", _number(0, lo_open=True), 3.0),
        r.get("stop_tolerance", _number(0, 0.5, lo_open=True), 0.008),
        r.get("align_tolerance_deg", _number(0, 20, lo_open=True), 0.6)), optional=True)
    places = tuple(_place(r) for r in _array_of_tables(top, "places"))
    paths = tuple(_path(r) for r in _array_of_tables(top, "paths"))
    truth_dstates = _section(top, "truth", lambda r: r.get("dstates", _integer(1), None), optional=True)
    top.done()

    world = World(name=name, boundary=boundary, walls=walls, boxes=boxes, discs=discs, robot=robot,
                  laser=laser, motion_noise=noise, control=control, places=places, paths=paths,
                  truth_dstates=truth_dstates, policy=policy, description=description, source=source)
    _check_consistency(world, source)
    return world


def _section(top: _Reader, key: str, build, optional: bool = False):
    top.seen.add(key)
    if key not in top.table:
        if not optional:
            top.fail(key, "missing (required)")
        table = {}
    else:
        table = top.table[key]
    r = _Reader(table, key, top.source)
    out = build(r)
    r.done()
    return out


def _array_of_tables(top: _Reader, key: str) -> list[_Reader]:
    top.seen.add(key)
    items = top.table.get(key, [])
    if not isinstance(items, list):
        top.fail(key, f"must be an array of tables ([[{key}]]), got {_kind(items)}")
    return [_Reader(t, f"{key}[{i}]", top.source) for i, t in enumerate(items)]


def _wall(r: _Reader) -> np.ndarray:
    pts = r.get("points", _points(2))
    closed = r.get("closed", lambda x, f: x if isinstance(x, bool) else f("must be true or false"), False)
    r.done()
    return np.vstack([pts, pts[:1]]) if closed else pts


def _box(r: _Reader) -> Box:
    b = Box(center=r.get("center", _vector(2)), size=r.get("size", _vector(2, lo=0.0)),
            angle=math.radians(r.get("angle_deg", _number(-360, 360), 0.0)),
            kind=r.get("kind", _string, "box"), jitter=r.get("jitter", _number(0, 2), 0.0))
    r.done()
    return b


def _disc(r: _Reader) -> Disc:
    d = Disc(center=r.get("center", _vector(2)), radius=r.get("radius", _number(0, lo_open=True)),
             kind=r.get("kind", _string, "disc"), jitter=r.get("jitter", _number(0, 2), 0.0))
    r.done()
    return d


def _robot(r: _Reader) -> RobotSpec:
    x, y, heading = r.get("start", _vector(3))
    return RobotSpec(radius=r.get("radius", _number(0.05, 2.0), 0.25), start=(x, y, math.radians(heading)),
                     max_speed=r.get("max_speed", _number(0, 5, lo_open=True), 0.8),
                     max_turn_rate=math.radians(r.get("max_turn_rate_deg", _number(0, 720, lo_open=True), 90.0)))


def _motion_noise(r: _Reader) -> MotionNoise:
    d = MotionNoise()  # the defaults: a real robot's odometry (worlds/README.md)
    return MotionNoise(slip_v=r.get("slip_v", _number(0, 0.5), d.slip_v),
                       slip_omega=r.get("slip_omega", _number(0, 0.5), d.slip_omega),
                       turn_scale=r.get("turn_scale", _number(0, 0.5), d.turn_scale),
                       turn_scale_time_s=r.get("turn_scale_time_s", _number(0, 3600, lo_open=True),
                                               d.turn_scale_time_s),
                       drift_deg_s=r.get("drift_deg_s", _number(0, 10), d.drift_deg_s),
                       drift_time_s=r.get("drift_time_s", _number(0, 36000, lo_open=True), d.drift_time_s))


def _laser(r: _Reader) -> LaserSpec:
    spec = LaserSpec(beams=r.get("beams", _integer(2), 180),
                     angle_min=math.radians(r.get("angle_min_deg", _number(-180, 180), -90.0)),
                     angle_max=math.radians(r.get("angle_max_deg", _number(-180, 180), 90.0)),
                     range_max=r.get("range_max", _number(0, 1000, lo_open=True)),
                     noise_sd=r.get("noise_sd", _number(0, 1), 0.01),
                     dropout=r.get("dropout", _number(0, 0.5), 0.001))
    if spec.angle_max <= spec.angle_min:
        r.fail("angle_max_deg", "must be greater than angle_min_deg")
    return spec


def _place(r: _Reader) -> Place:
    rect = r.get("rect", _vector(4))
    if rect[2] <= rect[0] or rect[3] <= rect[1]:
        r.fail("rect", f"must be [xmin, ymin, xmax, ymax] with xmin < xmax and ymin < ymax, got {list(rect)}")
    p = Place(id=r.get("id", _string), rect=rect)
    r.done()
    return p


def _path(r: _Reader) -> PathTruth:
    def ids(x, fail):
        if not isinstance(x, list) or len(x) < 2 or not all(isinstance(s, str) for s in x):
            fail("must be an array of at least two place ids")
        return tuple(x)
    p = PathTruth(id=r.get("id", _string), places=r.get("places", ids))
    r.done()
    return p


def _check_consistency(w: World, source: str) -> None:
    """What no single field can say: unique ids, known places on paths, a start pose in free space."""
    def fail(where: str, msg: str):
        raise WorldError(msg, f"{source}: {where}")

    seen: dict[str, int] = {}
    for i, p in enumerate(w.places):
        if p.id in seen:
            fail(f"places[{i}].id", f"duplicate place id {p.id!r} (also places[{seen[p.id]}])")
        seen[p.id] = i
        if not w.inside(np.array(p.center))[0]:
            fail(f"places[{i}].rect", f"place {p.id!r} lies outside the boundary")
    for i, a in enumerate(w.places):
        for b in w.places[i + 1:]:
            if a.rect[0] < b.rect[2] and b.rect[0] < a.rect[2] and a.rect[1] < b.rect[3] and b.rect[1] < a.rect[3]:
                fail(f"places[{i}].rect", f"place {a.id!r} overlaps place {b.id!r}")
    for i, path in enumerate(w.paths):
        for pid in path.places:
            if pid not in seen:
                fail(f"paths[{i}].places", f"unknown place {pid!r} (known: {', '.join(seen)})")
    x, y, _ = w.robot.start
    if not w.in_free_space(np.array([x, y]), tolerance=0.0)[0]:
        fail("robot.start", f"the robot (radius {w.robot.radius:g} m) does not fit at ({x:g}, {y:g}): "
                            "outside the boundary or overlapping a wall or obstacle")
    for i, d in enumerate(w.discs):
        if not w.inside(np.array(d.center))[0]:
            fail(f"discs[{i}].center", "lies outside the boundary")
    for i, b in enumerate(w.boxes):
        if not w.inside(np.array(b.center))[0]:
            fail(f"boxes[{i}].center", "lies outside the boundary")


# --------------------------------------------------------------------------- small geometry helpers

def _signed_area(poly: np.ndarray) -> float:
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _point_segment_distance(xy: np.ndarray, segs: np.ndarray) -> np.ndarray:
    """(n points) x (m segments) distances."""
    a, b = segs[:, :2], segs[:, 2:]
    ab = b - a
    L2 = np.maximum((ab ** 2).sum(axis=1), 1e-18)
    ap = xy[:, None, :] - a[None]
    t = np.clip((ap * ab[None]).sum(axis=2) / L2, 0.0, 1.0)
    closest = a[None] + t[..., None] * ab[None]
    return np.hypot(*(xy[:, None, :] - closest).transpose(2, 0, 1))


def _inside_polygon(xy: np.ndarray, poly: np.ndarray) -> np.ndarray:
    x, y = xy[:, 0:1], xy[:, 1:2]
    x0, y0 = poly[:, 0], poly[:, 1]
    x1, y1 = np.roll(x0, -1), np.roll(y0, -1)
    crosses = (y0 > y) != (y1 > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xint = x0 + (y - y0) * (x1 - x0) / (y1 - y0)
    return (crosses & (x < xint)).sum(axis=1) % 2 == 1
