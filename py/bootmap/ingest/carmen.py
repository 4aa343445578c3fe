"""CARMEN logs: the text format most public 2-D laser datasets use (Radish, the Freiburg and MIT logs).

One message a line, its type first. The reader takes

- ``ROBOTLASER1 type start_angle fov resolution max_range accuracy remission_mode n r_1..r_n
  n_remissions rem_1..rem_k laser_x laser_y laser_theta robot_x robot_y robot_theta tv rv
  forward_safety side_safety turn_axis timestamp host logger_timestamp``: a scan with the robot's
  (odometry) pose;
- ``FLASER n r_1..r_n x y theta odom_x odom_y odom_theta timestamp host logger_timestamp``: a front
  laser of 180 degrees; its pose ``x y theta`` is the laser's (corrected, in a corrected log);
- ``RAWLASER1`` (a ``ROBOTLASER1`` without poses), paired with the latest ``ODOM x y theta tv rv accel
  timestamp host logger_timestamp``;
- ``TRUEPOS true_x true_y true_theta odom_x odom_y odom_theta timestamp host logger_timestamp``
  (simulators write it): the true pose of the scans that follow.

Other messages (``PARAM``, ``SYNC``, ``RLASER``, sonar, ...) and ``#`` comments are skipped. A malformed
line raises :class:`~bootmap.errors.LogError` naming the file and line.

Example
-------
>>> text = "ODOM 1 2 0 0 0 0 5.0 h 5.0\\nRAWLASER1 0 -1.5708 3.1416 1.5708 50 0.01 0 3 1 2 3 0 5.1 h 5.1\\n"
>>> [(s.ranges.tolist(), s.odometry) for s in read_carmen_text(text)]
[([1.0, 2.0, 3.0], (1.0, 2.0, 0.0))]
"""

from __future__ import annotations

import gzip
import math
from dataclasses import replace
import zlib
from pathlib import Path
from typing import Iterable, Iterator

import numpy as np

from ..errors import LogError
from .scans import Pose, Scan, between, compose, turn_in_place, wrap

# After a ROBOTLASER1's ranges and remissions: laser pose (3), robot pose (3), tv, rv, forward and side
# safety distances, turn axis (5), timestamp, host, logger timestamp (3).
_ROBOTLASER_TAIL = 14
_ODOM_FIELDS = 10  # ODOM x y theta tv rv accel timestamp host logger_timestamp
_TRUEPOS_FIELDS = 10
GZIP_MAGIC = b"\x1f\x8b"
#: A corrected log's layout: at least this share of its FLASER lines are followed by an ODOM restart.
RESTART_SHARE = 0.9
#: Poses this close (m, rad) are the same pose (a log prints six or so significant digits).
POSE_TOLERANCE = 1e-4
#: A corrected log may miss the wheel increments before this share of its scans (each is then read as
#: the turn on the spot the laser shows, or else as no motion, and marked); more, and the odometry is not
#: in the log.
MAX_GAP_SHARE = 0.05


def records(lines, source: str):
    """The tokens of each line of a text log that holds a record (not blank, not a ``#`` comment), with
    where it is (``source: line N``) for error messages."""
    for number, line in enumerate(lines, 1):
        tokens = line.split()
        if tokens and not tokens[0].startswith("#"):
            yield tokens, f"{source}: line {number}"

def read_carmen(path: str | Path, corrected: bool = False) -> Iterator[Scan]:
    """The scans of a CARMEN log file (plain text, or gzip whatever its name), in the file's order.

    Parameters
    ----------
    path : str or Path
        The log.
    corrected : bool
        The log's laser poses are corrected (optimised) poses: use them as the true pose of each scan.
        Without it, only ``TRUEPOS`` lines give true poses, unless the log is laid out as a corrected
        log with odometry restarts (see :func:`read_carmen_text`), which is recognised by itself.
    """
    path = Path(path)
    try:
        with _open_text(path) as f:
            lines = list(f)
    except OSError as e:
        raise LogError(f"cannot read: {e.strerror or e}", str(path)) from None
    except EOFError:
        raise LogError("the gzip stream ends early: a truncated file", str(path)) from None
    except zlib.error as e:
        raise LogError(f"corrupt gzip data ({e}): a damaged file", str(path)) from None
    scans = read_carmen_text(lines, str(path), corrected)
    first = next(scans, None)
    if first is None:
        raise LogError(no_scans_reason(lines), str(path))
    yield first
    yield from scans


def no_scans_reason(lines: list[str]) -> str:
    """Why text with no laser scan is not a log: empty, binary, or without scan lines.

    >>> no_scans_reason(["# a comment", "ODOM 1 2 0 0 0 0 5.0 h 5.0"])
    'no laser scan: none of its 1 records is a FLASER, ROBOTLASER1 or RAWLASER1 line'
    """
    if not lines:
        return "the file is empty: no laser scan"
    if any("\x00" in line or "\ufffd" in line for line in lines[:1000]):
        return "binary data, not a CARMEN log (text, or text compressed by gzip): no laser scan"
    n = sum(1 for _ in records(lines, ""))
    if n == 0:
        return "no laser scan: the file holds only blank lines and comments"
    return f"no laser scan: none of its {n} records is a FLASER, ROBOTLASER1 or RAWLASER1 line"


def _open_text(path: Path):
    """The file as text lines, through gzip when it starts with gzip's magic bytes."""
    with path.open("rb") as f:
        magic = f.read(2)
    if magic == GZIP_MAGIC:
        return gzip.open(path, "rt", encoding="utf-8", errors="replace")
    return path.open("r", encoding="utf-8", errors="replace")


def read_carmen_text(lines: Iterable[str] | str, source: str = "log", corrected: bool = False) -> Iterator[Scan]:
    """The scans of CARMEN log text (a string or an iterable of lines); errors name ``source``.

    A log corrected by a SLAM program (gmapping's ``*-corrected.log``) is recognised by its layout:
    each ``FLASER`` holds the corrected pose in both its pose fields, and the ``ODOM`` line after it
    restarts from that pose; the ``ODOM`` lines that follow add the raw wheel increments up to the next
    scan. There the corrected poses are the truth and the odometry is rebuilt from those increments
    (:func:`rebuilt_odometry`), never read from the scan's own fields.
    """
    if isinstance(lines, str):
        lines = lines.splitlines()
    rows = list(records(lines, source))
    if not corrected and _has_odometry_restarts(rows):
        yield from _corrected_with_restarts(rows, source)
        return
    odometry: Pose | None = None
    truth: Pose | None = None
    for tokens, where in rows:
        kind = tokens[0]
        if kind == "ODOM":
            odometry = _pose(_fields(tokens, _ODOM_FIELDS, where), 1, where)
        elif kind == "TRUEPOS":
            truth = _pose(_fields(tokens, _TRUEPOS_FIELDS, where), 1, where)
        elif kind == "ROBOTLASER1":
            scan = robotlaser(tokens, where)
            yield _with_truth(scan, truth, corrected)
        elif kind == "FLASER":
            yield _with_truth(flaser(tokens, where), truth, corrected)
        elif kind == "RAWLASER1":
            if odometry is None:
                raise LogError("RAWLASER1 before any ODOM line: the scan has no odometry pose", where)
            yield _with_truth(rawlaser(tokens, odometry, where), truth, corrected)


def _has_odometry_restarts(rows: list[tuple[list[str], str]]) -> bool:
    """Whether the log is a corrected log with odometry restarts: most ``FLASER`` lines hold one pose
    twice and the next ``ODOM`` line starts from it."""
    flasers = restarts = 0
    pending: Pose | None = None
    for tokens, where in rows:
        if tokens[0] == "FLASER":
            flasers += 1
            poses = _flaser_poses(tokens)
            pending = poses[0] if poses and _same_pose(*poses) else None
        elif tokens[0] == "ODOM" and pending is not None:
            restarts += _same_pose(_pose(_fields(tokens, _ODOM_FIELDS, where), 1, where), pending)
            pending = None
    return flasers >= 2 and restarts >= RESTART_SHARE * flasers


def _flaser_poses(tokens: list[str]) -> tuple[Pose, Pose] | None:
    """A ``FLASER`` line's two poses, read from its last fields without its ranges (the layout test looks
    at every scan; the reading that follows parses each line once, and names what is wrong with it); None
    where they do not read as numbers."""
    try:
        x, y, theta, ox, oy, otheta = (float(v) for v in tokens[-9:-3])
    except ValueError:
        return None
    return (x, y, theta), (ox, oy, otheta)


def _corrected_with_restarts(rows: list[tuple[list[str], str]], source: str) -> Iterator[Scan]:
    """The scans of a corrected log with odometry restarts: truth = the corrected pose, odometry =
    rebuilt from the raw increments (see :func:`rebuilt_odometry`)."""
    scans: list[Scan] = []
    predicted: list[Pose | None] = []   # per scan: odometry's prediction of its pose (last ODOM before it)
    last: Pose | None = None            # the latest ODOM since the previous scan's restart
    restarting = False                  # the next ODOM is the restart after a scan
    for tokens, where in rows:
        if tokens[0] == "ODOM":
            pose = _pose(_fields(tokens, _ODOM_FIELDS, where), 1, where)
            if restarting:
                restarting = False
                if _same_pose(pose, scans[-1].truth):
                    continue
            last = pose
        elif tokens[0] == "FLASER":
            scan = flaser(tokens, where)
            scans.append(replace(scan, odometry=scan.truth))
            predicted.append(last)
            last, restarting = None, True
    gaps = [k for k, p in enumerate(predicted) if p is None and k > 0]
    if len(gaps) > MAX_GAP_SHARE * len(scans):
        raise LogError(
            f"a corrected log whose odometry cannot be rebuilt: {len(gaps)} of {len(scans)} scans have no "
            f"ODOM line between the previous scan's restart and themselves (the first is scan {gaps[0]}), "
            "so the raw wheel increments are not in the log; the corrected poses are not odometry, and no "
            "odometry is guessed", source)
    # Where the wheels recorded nothing, the laser may show the turn the robot made on the spot.
    turns = {k: turn_in_place(scans[k - 1], scans[k]) for k in gaps}
    bridged = {k: (0.0, 0.0, turn) for k, turn in turns.items() if turn is not None}
    odometry = rebuilt_odometry([s.truth for s in scans], predicted, bridged)
    for k, (scan, pose) in enumerate(zip(scans, odometry)):
        gap = "" if k not in turns else ("laser" if k in bridged else "still")
        yield replace(scan, odometry=pose, odometry_gap=gap)


def rebuilt_odometry(corrected: list[Pose], predicted: list[Pose | None],
                     bridged: dict[int, Pose] | None = None) -> list[Pose]:
    """The raw dead-reckoned track of a corrected log.

    ``predicted[k]`` is odometry's prediction of scan ``k``: the last ``ODOM`` before it, which started
    from scan ``k - 1``'s corrected pose. The raw increment from scan ``k - 1`` to scan ``k`` is
    ``corrected[k-1]^-1 (+) predicted[k]``; chaining the increments from the first prediction (the raw
    reading at the first scan, or the origin) gives the track the robot itself measured. Where a scan has no
    prediction (no ``ODOM`` line after the previous scan's restart) the increment is ``bridged[k]`` (a
    turn on the spot the laser showed), else none.

    >>> track = rebuilt_odometry([(5, 5, 0), (6, 5, 0)], [None, (6.1, 5, 0.1)])
    >>> [tuple(round(v, 9) for v in pose) for pose in track]
    [(0.0, 0.0, 0.0), (1.1, 0.0, 0.1)]
    """
    start = predicted[0] if predicted and predicted[0] is not None else (0.0, 0.0, 0.0)
    track = [tuple(float(v) for v in start)]
    bridged = bridged or {}
    for k, (before, prediction) in enumerate(zip(corrected, predicted[1:]), 1):
        step = bridged.get(k, (0.0, 0.0, 0.0)) if prediction is None else between(before, prediction)
        track.append(compose(track[-1], step))
    return track


def robotlaser(tokens: list[str], where: str) -> Scan:
    """A ``ROBOTLASER1`` line as a scan: odometry = its robot pose, ``truth`` = its laser pose.

    (A corrected log's laser pose is the optimised one; :func:`read_carmen_text` keeps it only when
    told the log is corrected.)
    """
    n, ranges, rest = _ranges(tokens, 8, where)
    tail = _after_remissions(rest, n, where)
    if len(tail) != _ROBOTLASER_TAIL:
        raise LogError(f"ROBOTLASER1 with {n} beams needs {9 + n + 1 + _ROBOTLASER_TAIL} fields after its "
                       f"remissions, found {len(tokens)}: a truncated line or a wrong beam count", where)
    spec = _numbers(tokens[2:6], where)
    laser, robot = _pose(tail, 0, where), _pose(tail, 3, where)
    return Scan(time=_number(tail[11], where), ranges=ranges, angle_min=spec[0], angle_increment=spec[2],
                range_max=spec[3], odometry=robot, truth=laser)


def flaser(tokens: list[str], where: str) -> Scan:
    """A ``FLASER`` line: 180 degrees from the right, evenly over its beams; max range 80 m (SICK's
    long mode: a reading at the maximum saw nothing)."""
    n, ranges, rest = _ranges(tokens, 1, where)
    if len(rest) != 9:
        raise LogError(f"FLASER with {n} beams needs {2 + n + 9} fields, found {len(tokens)}: a truncated "
                       "line or a wrong beam count", where)
    increment = math.pi / n if n % 2 == 0 else math.pi / max(n - 1, 1)  # 180 beams at 1 deg, 181 at 1 deg
    return Scan(time=_number(rest[6], where), ranges=ranges, angle_min=-math.pi / 2, angle_increment=increment,
                range_max=80.0, odometry=_pose(rest, 3, where), truth=_pose(rest, 0, where))


def rawlaser(tokens: list[str], odometry: Pose, where: str) -> Scan:
    """A ``RAWLASER1`` line, with the odometry pose of the latest ``ODOM`` line."""
    n, ranges, rest = _ranges(tokens, 8, where)
    tail = _after_remissions(rest, n, where)
    if len(tail) != 3:
        raise LogError(f"RAWLASER1 with {n} beams has {len(tokens)} fields: a truncated line or a wrong beam "
                       "count", where)
    spec = _numbers(tokens[2:6], where)
    return Scan(time=_number(tail[0], where), ranges=ranges, angle_min=spec[0], angle_increment=spec[2],
                range_max=spec[3], odometry=odometry)


def _with_truth(scan: Scan, truth: Pose | None, corrected: bool) -> Scan:
    return scan if corrected else replace(scan, truth=truth)


def _ranges(tokens: list[str], count_at: int, where: str) -> tuple[int, np.ndarray, list[str]]:
    """The beam count at ``tokens[count_at]``, the ranges after it, and the tokens after those."""
    if len(tokens) <= count_at:
        raise LogError(f"{tokens[0]} line cut short: {len(tokens)} fields", where)
    n = _count(tokens[count_at], where, "beams")
    if n == 0:
        raise LogError(f"{tokens[0]} with no beams", where)
    values = tokens[count_at + 1:count_at + 1 + n]
    if len(values) < n:
        raise LogError(f"{tokens[0]} declares {n} beams but the line ends after {len(values)}: a truncated "
                       "line or a wrong beam count", where)
    ranges = np.array(_numbers(values, where, "range"))
    return n, ranges, tokens[count_at + 1 + n:]


def _after_remissions(rest: list[str], n: int, where: str) -> list[str]:
    """The tokens after a laser line's remissions (``rest`` starts with their count)."""
    if not rest:
        return []
    try:
        count = int(rest[0])
    except ValueError:
        # A range where the remission count should be: the line has more beams than it declares.
        raise LogError(f"after the {n} declared beams comes {rest[0]!r} where the number of remissions "
                       "should be: a wrong beam count", where) from None
    return rest[1 + count:]


def _same_pose(a: Pose, b: Pose) -> bool:
    return abs(a[0] - b[0]) <= POSE_TOLERANCE and abs(a[1] - b[1]) <= POSE_TOLERANCE and \
        abs(wrap(a[2] - b[2])) <= POSE_TOLERANCE


def _fields(tokens: list[str], n: int, where: str) -> list[str]:
    if len(tokens) != n:
        raise LogError(f"{tokens[0]} needs {n} fields, found {len(tokens)}", where)
    return tokens


def _pose(tokens: list[str], at: int, where: str) -> Pose:
    x, y, theta = _numbers(tokens[at:at + 3], where, "pose")
    return (x, y, theta)


def _count(token: str, where: str, what: str) -> int:
    try:
        n = int(token)
    except ValueError:
        raise LogError(f"the number of {what} is {token!r}, not a whole number", where) from None
    if n < 0:
        raise LogError(f"the number of {what} is {n}", where)
    return n


def _numbers(tokens: list[str], where: str, what: str = "value") -> list[float]:
    return [_number(t, where, what) for t in tokens]


def _number(token: str, where: str, what: str = "value") -> float:
    try:
        x = float(token)
    except ValueError:
        raise LogError(f"a {what} reads {token!r}, not a number", where) from None
    if not math.isfinite(x):
        raise LogError(f"a {what} reads {token!r}, not a finite number (a laser's missing return is its "
                       "maximum range, never NaN)", where)
    return x
