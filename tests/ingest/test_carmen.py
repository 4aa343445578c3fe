"""The CARMEN reader: the Killian excerpt written as CARMEN lines reads back the same; bad lines are named."""

import numpy as np
import pytest

from bootmap.errors import LogError
from bootmap.ingest.carmen import read_carmen, read_carmen_text


def _robotlaser(s):
    """A ROBOTLASER1 line in CARMEN's layout: laser pose = truth, robot pose = odometry."""
    spec = f"0 {s.angle_min} 3.141593 {s.angle_increment} {s.range_max} 0.1 0 {len(s.ranges)}"
    poses = " ".join(f"{v!r}" for v in (*s.truth, *s.odometry))
    return f"ROBOTLASER1 {spec} {' '.join(map(repr, s.ranges.tolist()))} 0 {poses} 0 0 0 0 0 {s.time!r} iB21 0"


def _flaser(s):
    poses = " ".join(f"{v!r}" for v in (*s.truth, *s.odometry))
    return f"FLASER {len(s.ranges)} {' '.join(map(repr, s.ranges.tolist()))} {poses} {s.time!r} iB21 0"


@pytest.mark.parametrize("line", [_robotlaser, _flaser])
def test_excerpt_as_carmen_reads_back(tmp_path, excerpt_scans, line):
    scans = excerpt_scans[:40]
    path = tmp_path / "killian.log"
    path.write_text("# CARMEN log\nPARAM robot_width 0.5 nohost 0\n" + "\n".join(line(s) for s in scans) + "\n")
    back = list(read_carmen(path, corrected=True))
    assert len(back) == 40
    np.testing.assert_array_equal(np.stack([s.ranges for s in back]), np.stack([s.ranges for s in scans]))
    assert [s.odometry for s in back] == [s.odometry for s in scans]
    assert [s.truth for s in back] == [s.truth for s in scans]
    assert back[0].angle_increment == pytest.approx(np.radians(1), abs=1e-6)


def test_laser_poses_are_truth_only_in_a_corrected_log(excerpt_scans):
    text = _robotlaser(excerpt_scans[0])
    assert next(read_carmen_text(text)).truth is None
    assert next(read_carmen_text(text, corrected=True)).truth == excerpt_scans[0].truth


def test_rawlaser_takes_the_latest_odom_and_truepos():
    text = ("TRUEPOS 9 9 1 0 0 0 1.0 h 1.0\nODOM 1 2 0.5 0 0 0 1.0 h 1.0\n"
            "RAWLASER1 0 -1.5708 3.1416 1.5708 8 0.01 0 3 1 2 3 0 1.1 h 1.1\n"
            "ODOM 3 4 0.25 0 0 0 2.0 h 2.0\nRAWLASER1 0 -1.5708 3.1416 1.5708 8 0.01 0 3 4 5 6 0 2.1 h 2.1\n")
    scans = list(read_carmen_text(text))
    assert [(s.odometry, s.truth, s.time) for s in scans] == [((1.0, 2.0, 0.5), (9.0, 9.0, 1.0), 1.1),
                                                               ((3.0, 4.0, 0.25), (9.0, 9.0, 1.0), 2.1)]


@pytest.mark.parametrize("text, message", [
    ("FLASER 3 1 2 3 0 0 0 0 0 0 1.0 h\n", r"line 1: FLASER with 3 beams needs 14 fields, found 13"),
    ("FLASER 3 1 2\n", r"line 1: FLASER declares 3 beams but the line ends after 2"),
    ("FLASER 3 1 nan 3 0 0 0 0 0 0 1.0 h 1.0\n", r"line 1: a range reads 'nan', not a finite number"),
    ("# c\nODOM 1 2\n", r"line 2: ODOM needs 10 fields, found 3"),
    ("RAWLASER1 0 -1.5708 3.1416 1.5708 8 0.01 0 3 1 2 3 0 1.1 h 1.1\n", r"line 1: RAWLASER1 before any ODOM"),
    ("FLASER x 1\n", r"line 1: the number of beams is 'x', not a whole number"),
])
def test_bad_lines_are_refused_naming_the_line(text, message):
    with pytest.raises(LogError, match=message):
        list(read_carmen_text(text, "run.log"))


def test_a_missing_file_is_named(tmp_path):
    with pytest.raises(LogError, match=f"{tmp_path / 'none.log'}: cannot read"):
        list(read_carmen(tmp_path / "none.log"))
