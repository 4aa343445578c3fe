"""ROS bags: ``sensor_msgs/LaserScan`` with ``nav_msgs/Odometry``, from ROS 1 ``.bag`` files and ROS 2
bags (sqlite3 or MCAP storage), read with the ``rosbags`` package (no ROS install needed;
``pip install 'bootmap[logs]'``).

Each scan takes the odometry pose interpolated at its header stamp (the odometry comes at its own rate);
scans from before the first or after the last odometry message have no pose and are left out. A second
odometry topic (``truth_topic``, e.g. a simulator's ground truth or a localiser's output) gives the
true poses. Readings follow REP 117: ``+inf`` or beyond ``range_max`` saw nothing; ``-inf`` or below
``range_min`` was too close to measure (read as ``range_min``); NaN, a failed reading, is refused, as
every malformed message is, with a :class:`~bootmap.errors.LogError` naming the bag, the message index
and the topic.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

import numpy as np

from ..errors import LogError
from .scans import Pose, Scan

LASER_SCAN = "sensor_msgs/msg/LaserScan"
ODOMETRY = "nav_msgs/msg/Odometry"


@dataclass
class _Timed:
    """Poses of one odometry topic in time order (seconds; x, y, unwrapped heading)."""

    times: list
    poses: list

    def at(self, t: np.ndarray) -> np.ndarray:
        order = np.argsort(self.times, kind="stable")  # header stamps need not follow the bag's order
        p, times = np.asarray(self.poses)[order], np.asarray(self.times)[order]
        heading = np.unwrap(p[:, 2])  # interpolate across +-pi without a jump
        return np.column_stack([np.interp(t, times, p[:, 0]), np.interp(t, times, p[:, 1]),
                                np.interp(t, times, heading)])


def read_rosbag(path: str | Path, scan_topic: str | None = None, odom_topic: str | None = None,
                truth_topic: str | None = None) -> Iterator[Scan]:
    """The scans of a ROS 1 or ROS 2 bag with their odometry (and true) poses, in time order.

    Parameters
    ----------
    path : str or Path
        A ROS 1 ``.bag`` file, or a ROS 2 bag directory (or its ``.db3`` / ``.mcap`` file).
    scan_topic, odom_topic : str, optional
        The ``LaserScan`` and ``Odometry`` topics; needed only when the bag has several of a type.
    truth_topic : str, optional
        An ``Odometry`` topic whose poses are the truth.
    """
    try:
        from rosbags.highlevel import AnyReader
    except ModuleNotFoundError:
        raise LogError("reading ROS bags needs the rosbags package: pip install 'bootmap[logs]'",
                       str(path)) from None
    path = Path(path)
    bag = path.parent if path.is_file() and path.suffix in (".db3", ".mcap") else path
    try:
        with AnyReader([bag]) as reader:
            yield from _scans(reader, str(path), scan_topic, odom_topic, truth_topic)
    except LogError:
        raise
    except UnicodeDecodeError:  # a header of bytes that no bag writes: some other binary file
        raise LogError("not a ROS bag: its header does not read as a bag's (another kind of file, or a damaged "
                       "one); bootmap ingest reads ROS 1 .bag files and ROS 2 bags (.db3, .mcap, or their "
                       "directory)", str(path)) from None
    except Exception as e:  # rosbags' own errors (unreadable, unknown storage, truncated): say which bag
        raise LogError(f"cannot read the bag: {type(e).__name__}: {e}", str(path)) from None


def _scans(reader, source: str, scan_topic, odom_topic, truth_topic) -> Iterator[Scan]:
    by_type: dict[str, list] = {}
    for c in reader.connections:
        by_type.setdefault(c.msgtype, []).append(c)
    if not reader.connections or not reader.message_count:
        raise LogError("the bag has no messages", source)
    scans = _topic(by_type, LASER_SCAN, scan_topic, source)
    odom = _topic(by_type, ODOMETRY, odom_topic, source, leave_out=truth_topic)
    truth = _topic(by_type, ODOMETRY, truth_topic, source) if truth_topic else None
    wanted = [c for c in (scans, odom, truth) if c is not None]
    raw_scans, tracks = [], {odom.topic: _Timed([], []), **({truth.topic: _Timed([], [])} if truth else {})}
    keep = {c.topic for c in wanted}
    for index, (conn, stamp, data) in enumerate(reader.messages()):  # index: the message's place in the bag
        if conn.topic not in keep:
            continue
        where = f"{source}: message {index} ({conn.topic})"
        msg = reader.deserialize(data, conn.msgtype)
        t = _time(msg.header.stamp, stamp)
        if conn.topic == scans.topic:
            raw_scans.append((t, msg, where))
        else:
            track = tracks[conn.topic]
            track.times.append(t)
            track.poses.append(_pose(msg.pose.pose, where))
    yield from _paired(raw_scans, tracks[odom.topic], tracks[truth.topic] if truth else None, source)


def _topic(by_type: dict, msgtype: str, topic: str | None, source: str, leave_out: str | None = None):
    """The one connection of ``msgtype`` (on ``topic`` when given)."""
    found = [c for c in by_type.get(msgtype, []) if c.topic != leave_out and (topic is None or c.topic == topic)]
    topics = sorted({c.topic for cs in by_type.values() for c in cs})
    if not found:
        which = f" on topic {topic}" if topic else ""
        raise LogError(f"no {msgtype.replace('/msg/', '/')}{which} in the bag (its topics: "
                       f"{', '.join(topics) or 'none'})", source)
    if len({c.topic for c in found}) > 1:
        raise LogError(f"several {msgtype.replace('/msg/', '/')} topics ({', '.join(sorted({c.topic for c in found}))}): "
                       "say which", source)
    return found[0]


def _paired(raw_scans: list, odom: _Timed, truth: _Timed | None, source: str) -> Iterator[Scan]:
    if not raw_scans:
        raise LogError("the bag has no LaserScan messages", source)
    if not odom.times:
        raise LogError("the bag has no Odometry messages: the scans have no poses", source)
    times = np.array([t for t, _, _ in raw_scans])
    inside = (times >= min(odom.times)) & (times <= max(odom.times))
    if not inside.any():
        raise LogError("no LaserScan falls within the odometry's time span", source)
    odometry = odom.at(times)
    true = truth.at(times) if truth is not None and truth.times else None
    for k in np.flatnonzero(inside):
        t, msg, where = raw_scans[k]
        yield Scan(t, _ranges(msg, where), float(msg.angle_min), float(msg.angle_increment), float(msg.range_max),
                   _as_pose(odometry[k]), None if true is None else _as_pose(true[k]))


def _ranges(msg, where: str) -> np.ndarray:
    r = np.asarray(msg.ranges, dtype=float)
    if not len(r):
        raise LogError("a LaserScan with no ranges", where)
    if msg.angle_increment == 0 or not math.isfinite(msg.angle_increment):
        raise LogError(f"angle_increment is {msg.angle_increment}", where)
    expected = round((msg.angle_max - msg.angle_min) / msg.angle_increment) + 1
    if abs(len(r) - expected) > 1:  # drivers disagree by one on whether angle_max has a beam
        raise LogError(f"{len(r)} ranges where angle_min, angle_max and angle_increment make {expected} beams: "
                       "a wrong beam count", where)
    if np.isnan(r).any():
        raise LogError(f"range {int(np.flatnonzero(np.isnan(r))[0])} is NaN (a failed reading)", where)
    r = np.where(r < msg.range_min, msg.range_min, r)  # -inf and too-close readings (REP 117)
    return np.where(r > msg.range_max, msg.range_max, r)  # +inf: nothing seen


def _time(stamp, bag_ns: int) -> float:
    """A header stamp in seconds; a zero stamp (unset by the driver) falls back on the bag's time."""
    t = stamp.sec + stamp.nanosec * 1e-9
    return t if t > 0 else bag_ns * 1e-9


def _pose(pose, where: str) -> Pose:
    q = pose.orientation
    values = (pose.position.x, pose.position.y, q.x, q.y, q.z, q.w)
    if not all(math.isfinite(v) for v in values):
        raise LogError("an Odometry pose is not finite", where)
    yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
    return (float(pose.position.x), float(pose.position.y), yaw)


def _as_pose(row: np.ndarray) -> Pose:
    return (float(row[0]), float(row[1]), float(math.atan2(math.sin(row[2]), math.cos(row[2]))))
