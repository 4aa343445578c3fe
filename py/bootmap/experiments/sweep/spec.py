"""Sweep files: the grid of experiments a sweep runs, read from TOML and checked key by key.

A sweep file names the axes of a grid; every combination is one *cell*, one run of
:func:`bootmap.experiments.world.run_experiment`::

    [grid]
    worlds = ["notched_rectangle", "taylor_hall"]   # names in worlds/ or paths (relative to this file)
    seeds = "1-20"                                  # or [1, 2, 3]
    clusterers = ["kmeans"]                         # views: kmeans, gaussian-mixture, ward (default kmeans)
    learners = ["1-NN"]                             # recognition beside 1-NN (default 1-NN alone)
    levels = ["all"]                                # resolver levels: "all" or e.g. "causal,topological"
    quantum = ["learned"]                           # "learned" action types, or degrees to round to
    logs = ["killian"]                              # robots' logs (bootmap experiment --log), beside or
                                                    # instead of worlds: each log x quantum x seed is a cell

    [[noise]]                                       # one level of the noise axis (default: the world as shipped)
    name = "2x laser"
    "laser.noise_sd" = 0.02                         # any SECTION.FIELD of a world file (docs/noise.md)
    "laser.dropout" = 0.002

    [run]                                           # the same for every cell
    circuits = 50          # run length of worlds of the circuits policy (default: the paper's, 50)
    steps = 100            # ... of explored worlds (default 100)
    k_max = 12
    time_limit = 60        # seconds for each map
    cell_timeout = 600     # seconds for a whole cell; a cell that runs over is recorded as timed out

Every mistake is a :class:`~bootmap.errors.SweepError` naming the file and the key (``paper.toml:
grid.seeds: expected ...``); worlds and noise settings are loaded here, so a typo fails before any cell runs.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import tomllib
from dataclasses import asdict, dataclass, field
from itertools import product
from pathlib import Path
from typing import Any

from ... import arguments
from ...errors import BootmapError, SweepError

AXES = ("worlds", "logs", "seeds", "clusterers", "learners", "levels", "quantum")
#: The noise axis of a log's cells: the log is what it is.
AS_RECORDED = "as recorded"
RUN_DEFAULTS = {"circuits": None, "steps": None, "k_max": 12, "time_limit": 60.0, "cell_timeout": 600.0}


@dataclass(frozen=True)
class Noise:
    """One level of the noise axis: a name and the world fields it sets (``(("laser.noise_sd", 0.02),)``)."""

    name: str
    settings: tuple[tuple[str, Any], ...] = ()


@dataclass(frozen=True)
class Cell:
    """One experiment of the grid: everything :func:`~bootmap.experiments.sweep.cells.run_cell` needs, as plain data
    (it travels to worker processes and Dask workers by pickle)."""

    world: str                        # as the sweep file names it (shown in tables)
    world_path: str                   # the file it was read from (for messages)
    world_text: str = field(repr=False)  # the file itself: workers need no copy of it
    seed: int
    noise: Noise
    clusterer: str = "kmeans"
    learner: str = "1-NN"
    levels: tuple[str, ...] | None = None   # None: every level
    quantum_deg: float | None = None        # None: learned action types
    circuits: int | None = None
    steps: int | None = None
    k_max: int = 12
    time_limit: float = 60.0
    cell_timeout: float = 600.0
    log: str | None = None                  # a robot's log instead of a world (``world`` is its name)
    runs_dir: str | None = None             # where the sweep keeps simulated runs its cells share (no parameter)

    @property
    def id(self) -> str:
        """Stable across runs and machines: readable axes, then a hash of every parameter (so a cell whose
        run options changed is not taken for a finished one on ``--resume``)."""
        # Where a world lies is no parameter; a world's cell has no log (ids as before logs came in).
        params = {k: v for k, v in asdict(self).items()
                  if k not in ("world_path", "runs_dir") and not (k == "log" and v is None)}
        digest = hashlib.sha1(json.dumps(params, sort_keys=True, default=str).encode()).hexdigest()[:10]
        return f"{self.world}/seed{self.seed}/{self.noise.name}/{self.clusterer}/{self.learner}/" \
               f"{self.levels_text}/{self.quantum_text}/{digest}"

    @property
    def run(self) -> tuple:
        """What decides the simulated run the cell's experiment makes: cells that agree on it share the run
        (:class:`bootmap.experiments.runs.RunStore`)."""
        return self.world_text, self.noise.settings, self.seed, self.circuits, self.steps, self.log

    @property
    def levels_text(self) -> str:
        return "all" if self.levels is None else ",".join(self.levels)

    @property
    def quantum_text(self) -> str:
        return "learned" if self.quantum_deg is None else f"{self.quantum_deg:g}"


@dataclass(frozen=True)
class SweepSpec:
    """A parsed sweep file: ``cells`` in grid order (worlds, then noise, then the other axes, seeds last)."""

    source: str
    name: str
    cells: tuple[Cell, ...] = field(repr=False)
    text: str = field(default="", repr=False)   # the file as read, kept beside the results


def load_spec(path: str | Path) -> SweepSpec:
    """Read and check a sweep file; see the module docstring."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise SweepError(f"cannot read: {getattr(e, 'strerror', None) or e}", str(path)) from None
    return loads_spec(text, str(path), base=path.parent)


def loads_spec(text: str, source: str = "sweep", base: Path | None = None) -> SweepSpec:
    """Parse sweep TOML text; world paths are taken relative to ``base`` when they are files there."""
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise SweepError(f"not valid TOML: {e}", source) from None
    at = _Where(source)
    _only(doc, {"name", "grid", "noise", "run"}, at, "")
    grid = _table(doc, "grid", at, required=True)
    _only(grid, set(AXES), at, "grid.")
    run = _run_options(_table(doc, "run", at), at)
    logs = _logs(_list(grid, "logs", at), at, base)
    worlds = _worlds(_list(grid, "worlds", at, required=not logs) or [], at, base)
    seeds = _seeds(grid.get("seeds"), at)
    noises = _noises(doc.get("noise"), at)
    clusterers = _choices(grid, "clusterers", ["kmeans"], _known_clusterers(), at)
    learners = _choices(grid, "learners", ["1-NN"], _known_learners(), at)
    levels = [_levels(v, f"grid.levels[{i}]", at) for i, v in enumerate(_list(grid, "levels", at) or ["all"])]
    quanta = [_quantum(v, f"grid.quantum[{i}]", at) for i, v in enumerate(_list(grid, "quantum", at) or ["learned"])]
    policies = _check_worlds(worlds, noises, at)
    texts = {wp: Path(wp).read_text(encoding="utf-8") for _, wp in worlds}  # read (and checked) just above
    cells = tuple(
        Cell(world=w, world_path=wp, world_text=texts[wp], seed=s, noise=n, clusterer=c, learner=le, levels=lv, quantum_deg=q,
             circuits=run["circuits"] if policies[w] != "explore" else None,
             steps=run["steps"] if policies[w] == "explore" else None,
             k_max=run["k_max"], time_limit=run["time_limit"], cell_timeout=run["cell_timeout"])
        for (w, wp), n, c, le, lv, q, s in product(worlds, noises, clusterers, learners, levels, quanta, seeds))
    # A log's cell is the experiment on it (views by k-means, 1-NN, every level): the log x quantum x seed.
    cells += tuple(
        Cell(world=name, world_path=path, world_text="", seed=s, noise=Noise(AS_RECORDED), quantum_deg=q,
             k_max=run["k_max"], time_limit=run["time_limit"], cell_timeout=run["cell_timeout"], log=path)
        for (name, path), q, s in product(logs, quanta, seeds))
    name = doc.get("name", Path(source).stem)
    if not isinstance(name, str):
        raise SweepError(f"expected a string, got {name!r}", at("name"))
    return SweepSpec(source=source, name=name, cells=cells, text=text)


# ---------------------------------------------------------------------------------------------------
# One check per key: each names the key it reads
# ---------------------------------------------------------------------------------------------------

class _Where:
    """``file: key`` for messages."""

    def __init__(self, source: str):
        self.source = source

    def __call__(self, key: str) -> str:
        return f"{self.source}: {key}"


def _only(table: dict, known: set[str], at: _Where, prefix: str) -> None:
    for key in table:
        if key not in known:
            raise SweepError(f"unknown key; known here: {', '.join(sorted(known))}", at(prefix + key))


def _table(doc: dict, key: str, at: _Where, required: bool = False) -> dict:
    value = doc.get(key)
    if value is None:
        if required:
            raise SweepError(f"missing: a sweep file needs a [{key}] table", at(key))
        return {}
    if not isinstance(value, dict):
        raise SweepError(f"expected a table ([{key}]), got {value!r}", at(key))
    return value


def _list(table: dict, key: str, at: _Where, required: bool = False) -> list | None:
    value = table.get(key)
    if value is None:
        if required:
            raise SweepError("missing: give at least one", at(f"grid.{key}"))
        return None
    if not isinstance(value, list) or not value:
        raise SweepError(f"expected a non-empty list, got {value!r}", at(f"grid.{key}"))
    return value


def _run_options(run: dict, at: _Where) -> dict:
    _only(run, set(RUN_DEFAULTS), at, "run.")
    out = dict(RUN_DEFAULTS)
    for key, value in run.items():
        minimum = 2 if key == "steps" else 1
        if key in ("circuits", "steps", "k_max"):
            ok = isinstance(value, int) and not isinstance(value, bool) and value >= minimum
            expected = f"a whole number >= {minimum}"
        else:  # seconds
            ok = isinstance(value, (int, float)) and not isinstance(value, bool) and 0 < value < float("inf")
            expected = "seconds (a number > 0)"
        if not ok:
            raise SweepError(f"expected {expected}, got {value!r}", at(f"run.{key}"))
        out[key] = float(value) if key in ("time_limit", "cell_timeout") else value
    return out


def _worlds(values: list, at: _Where, base: Path | None) -> list[tuple[str, str]]:
    """(name as written, file) per world; a path is read relative to the sweep file first."""
    from ...sim.world import resolve_world_path

    out = []
    for i, w in enumerate(values):
        if not isinstance(w, str) or not w:
            raise SweepError(f"expected a world name or file, got {w!r}", at(f"grid.worlds[{i}]"))
        candidate = base / w if base is not None else None
        try:
            path = candidate if candidate is not None and candidate.is_file() else resolve_world_path(w)
        except BootmapError as e:
            raise SweepError(getattr(e, "reason", str(e)), at(f"grid.worlds[{i}] ({w})")) from None
        out.append((Path(w).stem if w.endswith(".toml") else w, str(path)))
    return out


def _logs(values: list | None, at: _Where, base: Path | None) -> list[tuple[str, str]]:
    """(name, path) per log: ``killian`` (the rtb-data package's), or a file or ROS 2 bag directory,
    relative to the sweep file first. Dask workers read the log from that path: it must be there too."""
    out = []
    for i, log in enumerate(values or []):
        if not isinstance(log, str) or not log:
            raise SweepError(f"expected 'killian' or a log file, got {log!r}", at(f"grid.logs[{i}]"))
        if log == "killian":
            out.append((log, log))
            continue
        path = base / log if base is not None and (base / log).exists() else Path(log)
        if not path.exists():
            raise SweepError("no such log file or bag directory", at(f"grid.logs[{i}] ({log})"))
        out.append((path.name, str(path)))
    return out


def _seeds(value, at: _Where) -> list[int]:
    if value is None:
        raise SweepError('missing: give seeds as a list [1, 2, 3] or a range "1-20"', at("grid.seeds"))
    if isinstance(value, str):
        try:
            return arguments.seeds(value)
        except argparse.ArgumentTypeError as e:
            raise SweepError(str(e), at("grid.seeds")) from None
    if isinstance(value, list) and value and all(isinstance(s, int) and not isinstance(s, bool) and s >= 0
                                                  for s in value):
        if len(set(value)) != len(value):
            raise SweepError(f"a seed given twice in {value}", at("grid.seeds"))
        return list(value)
    raise SweepError(f'expected a list of seeds (integers >= 0) or a range like "1-20", got {value!r}',
                     at("grid.seeds"))


def _noises(value, at: _Where) -> list[Noise]:
    if value is None:
        return [Noise("as shipped")]
    if not isinstance(value, list) or not value:
        raise SweepError("expected [[noise]] tables, one per noise level", at("noise"))
    out = []
    for i, level in enumerate(value):
        if not isinstance(level, dict):
            raise SweepError(f"expected a table, got {level!r}", at(f"noise[{i}]"))
        settings = {k: v for k, v in level.items() if k != "name"}
        name = level.get("name", ", ".join(f"{k}={v}" for k, v in settings.items()) or "as shipped")
        if not isinstance(name, str) or not name or "/" in name:
            raise SweepError(f"expected a name without '/', got {name!r}", at(f"noise[{i}].name"))
        for key in settings:
            if key.count(".") != 1:
                raise SweepError('expected a world field as "SECTION.FIELD" (e.g. "laser.noise_sd")',
                                 at(f"noise[{i}].{key}"))
        out.append(Noise(name, tuple(sorted(settings.items()))))
    names = [n.name for n in out]
    for i, n in enumerate(names):
        if names.index(n) != i:
            raise SweepError(f"the name {n!r} is given to two noise levels", at(f"noise[{i}].name"))
    return out


def _check_worlds(worlds: list[tuple[str, str]], noises: list[Noise], at: _Where) -> dict[str, str]:
    """Load every world under every noise level now, so a bad field fails before any cell runs; returns
    each world's policy."""
    from ...sim.world import load_world

    policies = {}
    for (w, path), (i, n) in product(worlds, enumerate(noises)):
        try:
            world = load_world(path, dict(n.settings))
        except BootmapError as e:
            where = f"noise[{i}] ({n.name})" if n.settings else f"grid.worlds ({w})"
            raise SweepError(str(e), at(where)) from None
        policies[w] = world.policy or "circuits"
    return policies


def _choices(grid: dict, key: str, default: list[str], known: list[str], at: _Where) -> list[str]:
    values = _list(grid, key, at) or default
    for i, v in enumerate(values):
        if v not in known:
            raise SweepError(f"unknown {key[:-1]} {v!r}; known: {', '.join(known)}", at(f"grid.{key}[{i}]"))
    return values


def _known_clusterers() -> list[str]:
    from ...views import CLUSTERERS

    return list(CLUSTERERS)


def _known_learners() -> list[str]:
    from ...recognise import default_learners

    return list(default_learners())


def _levels(value, key: str, at: _Where) -> tuple[str, ...] | None:
    if not isinstance(value, str) or not value.strip():
        raise SweepError(f'expected "all" or levels like "causal,topological", got {value!r}', at(key))
    if value.strip() == "all":
        return None
    from ...mapping.theory import available_levels, select_levels

    try:
        return tuple(select_levels(arguments.levels(value), available_levels(), "the shipped axioms"))
    except BootmapError as e:
        raise SweepError(str(e), at(key)) from None


def _quantum(value, key: str, at: _Where) -> float | None:
    if value == "learned":
        return None
    if isinstance(value, (int, float)) and not isinstance(value, bool) and 0 < value <= 180:
        return float(value)
    raise SweepError(f'expected "learned" or degrees in (0, 180], got {value!r}', at(key))
