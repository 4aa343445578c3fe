"""g2o pose graphs with laser scans: the MIT Killian Court log as Peter Corke's Robotics Toolbox ships it.

The file mixes three kinds of line:

- ``VERTEX_SE2 id x y theta``: the optimised pose of scan ``id``, the log's truth;
- ``ROBOTLASER1 ...`` (CARMEN's, see :mod:`bootmap.ingest.carmen`), right after the vertex it was taken at.
  Its own laser and robot poses are the optimised vertex pose again, not odometry;
- ``EDGE_SE2 i j dx dy dtheta`` + 6 information values: the measured motion from ``i`` to ``j`` in
  ``i``'s frame. Edges ``i -> i+1`` are the wheel odometry (stored out of order: 0-1, 1-2, 4-5, 3-4,
  ...); the others are loop closures, which the reader leaves out.

So the odometry pose of each scan is dead-reckoned along the chain of edges ``i -> i+1``, starting
from the first vertex's pose (the odometry frame and the truth's then agree at the start).

:func:`killian` reads the Killian log from the ``rtb-data`` package (``pip install 'bootmap[logs]'``).
"""

from __future__ import annotations

import io
import zipfile
from pathlib import Path
from typing import Iterable

from ..errors import LogError
from .carmen import _count, _numbers, records, robotlaser
from .scans import Pose, Scan, compose

KILLIAN_ZIP = "data/killian.g2o.zip"  # inside the rtb-data package (import name rtbdata)


def read_g2o(path: str | Path) -> list[Scan]:
    """The scans of a g2o file (plain, or a ``.zip`` holding one ``.g2o``), in vertex order."""
    path = Path(path)
    try:
        if path.suffix == ".zip":
            return _read_zip(path.read_bytes(), str(path))
        with path.open("r", encoding="utf-8", errors="replace") as f:
            return read_g2o_text(f, str(path))
    except OSError as e:
        raise LogError(f"cannot read: {e.strerror}", str(path)) from None


def killian() -> list[Scan]:
    """The whole MIT Killian Court log (3,873 scans), from the installed ``rtb-data`` package."""
    from importlib import resources

    try:
        data = resources.files("rtbdata").joinpath(KILLIAN_ZIP).read_bytes()
    except ModuleNotFoundError:
        raise LogError("the Killian Court log comes with the rtb-data package: pip install 'bootmap[logs]'",
                       "killian") from None
    return _read_zip(data, f"rtbdata/{KILLIAN_ZIP}")


def _read_zip(data: bytes, source: str) -> list[Scan]:
    try:
        archive = zipfile.ZipFile(io.BytesIO(data))
    except zipfile.BadZipFile:
        raise LogError("not a zip archive", source) from None
    names = [n for n in archive.namelist() if n.endswith(".g2o") and not n.startswith("__MACOSX")]
    if len(names) != 1:
        raise LogError(f"expected one .g2o file in the archive, found {len(names)}", source)
    text = io.TextIOWrapper(archive.open(names[0]), encoding="utf-8", errors="replace")
    return read_g2o_text(text, f"{source}/{names[0]}")


def read_g2o_text(lines: Iterable[str] | str, source: str = "g2o") -> list[Scan]:
    """The scans of g2o text (a string or an iterable of lines); errors name ``source`` and the line."""
    if isinstance(lines, str):
        lines = lines.splitlines()
    vertices: dict[int, Pose] = {}
    lasers: dict[int, tuple[Scan, str]] = {}
    edges: dict[int, tuple[Pose, str]] = {}
    last_vertex: int | None = None
    for tokens, where in records(lines, source):
        if tokens[0] == "VERTEX_SE2":
            last_vertex, pose = _vertex(tokens, where)
            vertices[last_vertex] = pose
        elif tokens[0] == "ROBOTLASER1":
            if last_vertex is None:
                raise LogError("ROBOTLASER1 before any VERTEX_SE2: the scan belongs to no pose", where)
            if last_vertex in lasers:
                raise LogError(f"a second scan for vertex {last_vertex} (first at {lasers[last_vertex][1]})", where)
            lasers[last_vertex] = (robotlaser(tokens, where), where)
        elif tokens[0] == "EDGE_SE2":
            i, j, motion = _edge(tokens, where)
            if j == i + 1:  # the odometry chain; every other edge is a loop closure
                edges[i] = (motion, where)
    return _chain(vertices, lasers, edges, source)


def _vertex(tokens: list[str], where: str) -> tuple[int, Pose]:
    if len(tokens) != 5:
        raise LogError(f"VERTEX_SE2 needs an id and x y theta (5 fields), found {len(tokens)}", where)
    x, y, theta = _numbers(tokens[2:5], where, "pose")
    return _count(tokens[1], where, "the vertex id"), (x, y, theta)


def _edge(tokens: list[str], where: str) -> tuple[int, int, Pose]:
    if len(tokens) != 12:
        raise LogError(f"EDGE_SE2 needs 2 ids, dx dy dtheta and 6 information values (12 fields), found "
                       f"{len(tokens)}", where)
    dx, dy, dtheta = _numbers(tokens[3:6], where, "motion")
    return _count(tokens[1], where, "the vertex id"), _count(tokens[2], where, "the vertex id"), (dx, dy, dtheta)


def _chain(vertices: dict[int, Pose], lasers: dict[int, tuple[Scan, str]], edges: dict[int, tuple[Pose, str]],
           source: str) -> list[Scan]:
    """Scans in vertex order, each with its odometry (the chain of edges dead-reckoned) and its truth."""
    if not lasers:
        raise LogError("no ROBOTLASER1 line: the file has no laser scans", source)
    ids = sorted(vertices)
    odometry = vertices[ids[0]]
    scans = []
    for k, i in enumerate(ids):
        if k:
            if ids[k - 1] != i - 1 or i - 1 not in edges:
                raise LogError(f"no odometry edge {i - 1} -> {i}: the chain of sequential EDGE_SE2 is broken",
                               source)
            odometry = compose(odometry, edges[i - 1][0])
        if i not in lasers:
            raise LogError(f"vertex {i} has no ROBOTLASER1 line after it", source)
        scan = lasers[i][0]
        scans.append(Scan(scan.time, scan.ranges, scan.angle_min, scan.angle_increment, scan.range_max,
                          odometry, vertices[i]))
    return scans
