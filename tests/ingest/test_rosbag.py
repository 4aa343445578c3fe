"""The ROS bag reader: bags written by rosbags' own writers (ROS 1, ROS 2 sqlite3 and MCAP) read back
as the scans they were written from; bad bags are refused naming the bag and the message."""

import numpy as np
import pytest

pytest.importorskip("rosbags")

from log_bags import MCAP, ROS1, SQLITE3, write_bag  # noqa: E402

from bootmap.errors import LogError  # noqa: E402
from bootmap.ingest.ingest import read_log  # noqa: E402
from bootmap.ingest.rosbag import read_rosbag  # noqa: E402


@pytest.mark.parametrize("kind", [ROS1, SQLITE3, MCAP])
def test_a_bag_reads_back_as_its_scans(tmp_path, excerpt_scans, kind):
    scans = excerpt_scans[:30]
    path = write_bag(tmp_path / "run", kind, scans, truth_topic="/ground_truth")
    back = read_log(path, truth_topic="/ground_truth")
    assert len(back) == 30
    # LaserScan ranges are float32 on the wire.
    # ... and a reading beyond range_max saw nothing (REP 117): it reads range_max.
    sent = np.minimum(np.stack([s.ranges for s in scans]), 50.0)
    np.testing.assert_allclose(np.stack([s.ranges for s in back]), sent, atol=1e-5)
    np.testing.assert_allclose([s.odometry for s in back], [s.odometry for s in scans], atol=1e-9)
    np.testing.assert_allclose([s.truth for s in back], [s.truth for s in scans], atol=1e-9)
    assert back[0].time == pytest.approx(scans[0].time, abs=1e-6)


def test_odometry_is_interpolated_at_the_scan_stamp(tmp_path, excerpt_scans):
    # Odometry at scans 0 and 2 only; the laser at scan 1, between them in time.
    path = write_bag(tmp_path / "mid", SQLITE3, excerpt_scans[:3], scans_at={1}, odometry_at={0, 2})
    (scan,) = read_rosbag(path)
    t0, t1, t2 = (s.time for s in excerpt_scans[:3])
    share = (t1 - t0) / (t2 - t0)
    first, last = np.array(excerpt_scans[0].odometry), np.array(excerpt_scans[2].odometry)
    assert scan.odometry == pytest.approx(tuple(first + share * (last - first)), abs=1e-6)
    assert 0.1 < share < 0.9 and scan.odometry != pytest.approx(excerpt_scans[0].odometry)


def test_an_empty_bag_is_refused(tmp_path):
    path = write_bag(tmp_path / "empty", ROS1, [])
    with pytest.raises(LogError, match=r"empty.bag: the bag has no messages"):
        read_log(path)


def test_a_bag_without_laserscan_names_its_topics(tmp_path, excerpt_scans):
    path = write_bag(tmp_path / "odom", MCAP, excerpt_scans[:3], scan_topic=None)
    with pytest.raises(LogError, match=r"no sensor_msgs/LaserScan in the bag \(its topics: /odom\)"):
        read_log(path)


def test_a_nan_range_names_the_message(tmp_path, excerpt_scans):
    path = write_bag(tmp_path / "nan", SQLITE3, excerpt_scans[:5], nan_at=2)
    # Messages alternate odometry, scan: scan 2 is message 5.
    with pytest.raises(LogError, match=r"nan: message 5 \(/scan\): range 3 is NaN"):
        read_log(path)


def test_several_odometry_topics_must_be_named(tmp_path, excerpt_scans):
    path = write_bag(tmp_path / "two", ROS1, excerpt_scans[:3], truth_topic="/ground_truth")
    with pytest.raises(LogError, match=r"several nav_msgs/Odometry topics \(/ground_truth, /odom\): say which"):
        read_log(path)
    assert len(read_log(path, odom_topic="/odom")) == 3


@pytest.mark.parametrize("data", [bytes(range(256)) * 8, b"garbage\xff\xfe text" * 40])
def test_a_file_of_other_bytes_named_bag_is_refused_as_no_bag(tmp_path, data):
    path = tmp_path / "junk.bag"
    path.write_bytes(data)
    with pytest.raises(LogError, match=r"junk\.bag: (not a ROS bag|cannot read the bag)") as e:
        list(read_rosbag(path))
    assert "UnicodeDecodeError" not in str(e.value)
