"""Writing small ROS bags with rosbags' own writers, for the reader's tests (a test helper, not bootmap)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from rosbags.rosbag1 import Writer as Ros1Writer
from rosbags.rosbag2 import StoragePlugin
from rosbags.rosbag2 import Writer as Ros2Writer
from rosbags.typesys import Stores, get_typestore

from bootmap.ingest.scans import Scan

ROS1, SQLITE3, MCAP = "ros1", "sqlite3", "mcap"


def write_bag(path: Path, kind: str, scans: list[Scan], truth_topic: str | None = None,
              scan_topic: str | None = "/scan", odom_topic: str | None = "/odom", nan_at: int | None = None,
              scans_at: set[int] | None = None, odometry_at: set[int] | None = None) -> Path:
    """A bag of ``scans`` as LaserScan on ``scan_topic`` and their odometry as Odometry on ``odom_topic``
    (each odometry message stamped like its scan), the truth on ``truth_topic``. ``nan_at`` puts a NaN
    in that scan; ``scans_at`` (``odometry_at``) writes the laser (odometry) of those scans only. Returns the path to give the reader."""
    store = get_typestore(Stores.ROS1_NOETIC if kind == ROS1 else Stores.ROS2_HUMBLE)
    types = store.types
    target = path if kind != ROS1 else path.with_suffix(".bag")
    writer = Ros1Writer(target) if kind == ROS1 else \
        Ros2Writer(target, version=9, storage_plugin=StoragePlugin.MCAP if kind == MCAP else StoragePlugin.SQLITE3)
    serialize = store.serialize_ros1 if kind == ROS1 else store.serialize_cdr
    with writer:
        topics = [(scan_topic, "sensor_msgs/msg/LaserScan"), (odom_topic, "nav_msgs/msg/Odometry"),
                  (truth_topic, "nav_msgs/msg/Odometry")]
        conns = {t: writer.add_connection(t, m, typestore=store) for t, m in topics if t}
        for k, s in enumerate(scans):
            ns = int(round(s.time * 1e9))
            header = _header(types, ns, kind)
            if odom_topic and (odometry_at is None or k in odometry_at):
                writer.write(conns[odom_topic], ns, serialize(_odometry(types, header, s.odometry), "nav_msgs/msg/Odometry"))
            if truth_topic:
                writer.write(conns[truth_topic], ns, serialize(_odometry(types, header, s.truth), "nav_msgs/msg/Odometry"))
            if scan_topic and (scans_at is None or k in scans_at):
                ranges = s.ranges.astype(np.float32)
                if k == nan_at:
                    ranges[3] = np.nan
                writer.write(conns[scan_topic], ns, serialize(_laser(types, header, s, ranges), "sensor_msgs/msg/LaserScan"))
    return target


def _header(types, ns: int, kind: str):
    stamp = types["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
    if kind == ROS1:
        return types["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id="base_link")
    return types["std_msgs/msg/Header"](stamp=stamp, frame_id="base_link")


def _laser(types, header, s: Scan, ranges: np.ndarray):
    n = len(ranges)
    return types["sensor_msgs/msg/LaserScan"](
        header=header, angle_min=s.angle_min, angle_max=s.angle_min + (n - 1) * s.angle_increment,
        angle_increment=s.angle_increment, time_increment=0.0, scan_time=0.0, range_min=0.0,
        range_max=s.range_max, ranges=ranges, intensities=np.zeros(0, dtype=np.float32))


def _odometry(types, header, pose):
    x, y, theta = pose
    point = types["geometry_msgs/msg/Point"](x=x, y=y, z=0.0)
    q = types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(theta / 2), w=math.cos(theta / 2))
    covariance = np.zeros(36)
    pose_msg = types["geometry_msgs/msg/PoseWithCovariance"](pose=types["geometry_msgs/msg/Pose"](position=point, orientation=q),
                                                             covariance=covariance)
    zero = types["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)
    twist = types["geometry_msgs/msg/TwistWithCovariance"](twist=types["geometry_msgs/msg/Twist"](linear=zero, angular=zero),
                                                           covariance=covariance)
    return types["nav_msgs/msg/Odometry"](header=header, child_frame_id="base_link", pose=pose_msg, twist=twist)
