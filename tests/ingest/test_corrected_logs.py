"""Corrected CARMEN logs (gmapping's ``*-corrected.log``): the raw odometry is rebuilt from the ODOM
restarts and increments, the corrected poses are the truth only; gzip is read whatever the file's name;
gaps in the wheel odometry are marked, and a log without its increments is refused.

The hand-made log is a square driven twice: the truth is exact, the wheels read every distance 3% short
and every turn 4% long and drift 0.5 degree a metre, so the raw track and the truth part by metres,
and the reader must give back exactly the raw track the increments make.
"""

import gzip
import math
import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bootmap.errors import LogError
from bootmap.ingest.carmen import read_carmen, read_carmen_text, rebuilt_odometry
from bootmap.ingest.calibrate import OdometryCalibration
from bootmap.ingest.ingest import log_tableau
from bootmap.ingest.scans import between, compose

from synthetic import ring_poses, ring_walls, square_poses, write_drive_log

BEAMS = 180


def _raw_increments(truth: list[tuple]) -> list[tuple]:
    """What biased wheels measure between consecutive true poses."""
    out = []
    for a, b in zip(truth, truth[1:]):
        dx, dy, dtheta = between(a, b)
        length = math.hypot(dx, dy)
        out.append((0.97 * dx, 0.97 * dy, 1.04 * dtheta + math.radians(0.5) * length))
    return out


def _line(kind: str, pose: tuple, t: float, ranges=None) -> str:
    p = " ".join(repr(float(v)) for v in pose)
    if kind == "ODOM":
        return f"ODOM {p} 0 0 0 {t!r} h {t!r}"
    r = " ".join(f"{v:.2f}" for v in ranges)
    return f"FLASER {len(ranges)} {r} {p} {p} {t!r} h {t!r}"


def corrected_log(truth: list[tuple], increments: list[tuple], gaps: set = frozenset(), start=(0.0, 0.0, 0.0)) -> str:
    """A corrected log as gmapping writes one: before scan 0 the raw reading ``start``; after each scan
    an ODOM restart from its corrected pose, then three ODOM lines adding the raw increment (none before
    a scan in ``gaps``)."""
    lines = ["# corrected log", "PARAM robot_length 0.6 nohost 0", _line("ODOM", start, 0.0)]
    ranges = 2.0 + np.sin(np.arange(BEAMS) / 9.0)
    for k, pose in enumerate(truth):
        t = 1.0 + k
        lines += [_line("FLASER", pose, t, ranges), "NEFF 30 h 0", _line("ODOM", pose, 0.0)]
        if k + 1 < len(truth) and k + 1 not in gaps:
            dx, dy, dtheta = increments[k]
            for part in (1 / 3, 2 / 3, 1.0):
                lines.append(_line("ODOM", compose(pose, (part * dx, part * dy, part * dtheta)), t + part))
    return "\n".join(lines) + "\n"


def chained(start: tuple, increments: list[tuple]) -> np.ndarray:
    track = [start]
    for inc in increments:
        track.append(compose(track[-1], inc))
    return np.array(track)


def _same_poses(a, b, tol=1e-6):
    a, b = np.asarray(a, float), np.asarray(b, float)
    assert np.abs(a[:, :2] - b[:, :2]).max() < tol
    assert np.abs((a[:, 2] - b[:, 2] + np.pi) % (2 * np.pi) - np.pi).max() < tol


@pytest.fixture(scope="module")
def square():
    truth = square_poses(laps=2, side=10.0, step=1.0, turn_scans=3)
    return truth, _raw_increments(truth)


def test_the_raw_track_is_rebuilt_from_the_increments_and_the_truth_is_the_corrected_pose(square):
    truth, increments = square
    scans = list(read_carmen_text(corrected_log(truth, increments), "square.log"))
    assert len(scans) == len(truth)
    _same_poses([s.truth for s in scans], truth)
    _same_poses([s.odometry for s in scans], chained((0.0, 0.0, 0.0), increments))
    # The rebuilt track is the wheels', not the truth moved: after two laps it is metres off.
    start, end = scans[0], scans[-1]
    drifted = compose(start.truth, between(start.odometry, end.odometry))
    assert math.dist(drifted[:2], end.truth[:2]) > 2.0
    assert not any(s.odometry_gap for s in scans)


def test_the_first_scan_starts_at_odometrys_own_reading(square):
    truth, increments = square
    scans = list(read_carmen_text(corrected_log(truth, increments, start=(3.0, -1.0, 0.5))))
    assert scans[0].odometry == (3.0, -1.0, 0.5)
    _same_poses([s.odometry for s in scans], chained((3.0, -1.0, 0.5), increments))


@pytest.mark.parametrize("name", ["square.log.gz", "square.log", "square.gz.bak"])
def test_gzip_is_read_whatever_the_name(tmp_path, square, name):
    truth, increments = square
    text = corrected_log(truth, increments)
    plain = list(read_carmen_text(text))
    path = tmp_path / name
    path.write_bytes(gzip.compress(text.encode()))
    back = list(read_carmen(path))
    assert [s.odometry for s in back] == [s.odometry for s in plain]
    assert [s.truth for s in back] == [s.truth for s in plain]
    np.testing.assert_array_equal(back[7].ranges, plain[7].ranges)


def test_plain_text_named_gz_is_read(tmp_path, square):
    truth, increments = square
    path = tmp_path / "square.log.gz"
    path.write_text(corrected_log(truth, increments))
    assert len(list(read_carmen(path))) == len(truth)


def test_a_truncated_gzip_is_refused_naming_the_file(tmp_path, square):
    truth, increments = square
    data = gzip.compress(corrected_log(truth, increments).encode())
    path = tmp_path / "cut.log.gz"
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(LogError, match=r"cut\.log\.gz: .*(truncated|ends early)"):
        list(read_carmen(path))


def test_a_scan_without_increments_is_a_marked_gap_of_no_motion(square):
    truth, increments = square
    scans = list(read_carmen_text(corrected_log(truth, increments, gaps={5})))
    assert [k for k, s in enumerate(scans) if s.odometry_gap] == [5]
    assert scans[5].odometry == scans[4].odometry
    # Past the gap, the increments chain on as before.
    expected = chained((0.0, 0.0, 0.0), increments[:4] + [(0.0, 0.0, 0.0)] + increments[5:])
    _same_poses([s.odometry for s in scans], expected)
    tableau = log_tableau(scans, source="square.log")
    # Every scan of this log reads the same ranges: the laser cannot tell a turn, and says nothing.
    assert tableau.meta["odometry_gaps"] == [{"scan": 5, "read_as": "still"}]


def test_a_turn_on_the_spot_the_wheels_did_not_record_is_read_from_the_laser(tmp_path):
    """In a ray-cast corridor ring the robot turns 90 degrees on the spot at a corner, and the log holds
    no odometry for it: the two scans' beams show the turn, and the track turns with the truth."""
    poses = ring_poses(laps=1)
    corner = next(k for k, (a, b) in enumerate(zip(poses, poses[1:]), 1) if abs(b[2] - a[2]) > 1.0)
    assert math.dist(poses[corner - 1][:2], poses[corner][:2]) < 0.6  # the last step before the turn
    still = [(*poses[corner - 1][:2], poses[corner][2])]  # turn on the spot first, then drive on
    drive = poses[:corner] + still + poses[corner:]
    log = write_drive_log(tmp_path / "ring.log", ring_walls(), drive, gaps={corner})
    scans = list(read_carmen(log))
    assert scans[corner].odometry_gap == "laser"
    turned = scans[corner].odometry[2] - scans[corner - 1].odometry[2]
    assert math.degrees((turned + math.pi) % (2 * math.pi) - math.pi) == pytest.approx(90.0, abs=2.0)
    # From the turn on, the track is the truth's, moved to where the robot was before it.
    base = scans[corner - 1]
    moved = [compose(base.truth, between(base.odometry, s.odometry)) for s in scans[corner:]]
    _same_poses(moved, [s.truth for s in scans[corner:]], tol=0.3)


def test_a_log_without_its_increments_is_refused_not_guessed(square):
    truth, increments = square
    most = set(range(1, len(truth), 2))
    with pytest.raises(LogError, match=r"orebro\.log: a corrected log whose odometry cannot be rebuilt: "
                                       rf"{len(most)} of {len(truth)} scans"):
        list(read_carmen_text(corrected_log(truth, increments, gaps=most), "orebro.log"))


def test_a_bad_line_in_a_corrected_log_is_named(square):
    truth, increments = square
    lines = corrected_log(truth, increments).splitlines()
    lines[9] = "ODOM 1 2 x 0 0 0 1.0 h 1.0"
    with pytest.raises(LogError, match=r"run\.log: line 10: a pose reads 'x', not a number"):
        list(read_carmen_text("\n".join(lines), "run.log"))


def test_a_raw_log_keeps_its_own_odometry_fields():
    """A FLASER whose two poses differ is an ordinary (uncorrected) log: no restarts to read."""
    ranges = " ".join(["2.0"] * 180)
    text = (f"FLASER 180 {ranges} 1 2 0.1 1.5 2.5 0.2 1.0 h 1.0\nODOM 1.6 2.5 0.2 0 0 0 1.1 h 1.1\n"
            f"FLASER 180 {ranges} 3 2 0.1 3.5 2.5 0.2 2.0 h 2.0\n")
    scans = list(read_carmen_text(text))
    assert [s.odometry for s in scans] == [(1.5, 2.5, 0.2), (3.5, 2.5, 0.2)]
    assert [s.truth for s in scans] == [None, None]


_pose = st.tuples(st.floats(-50, 50), st.floats(-50, 50), st.floats(-3.1, 3.1))
_step = st.tuples(st.floats(-2, 2), st.floats(-2, 2), st.floats(-1.5, 1.5))


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(_pose, _step), min_size=2, max_size=12))
def test_the_rebuilt_track_depends_on_the_increments_alone(pairs):
    """Whatever the corrected poses, predictions made from them by the same increments give back the
    same track: the truth never leaks into the odometry."""
    corrected = [p for p, _ in pairs]
    increments = [s for _, s in pairs[:-1]]
    predicted = [None] + [compose(c, inc) for c, inc in zip(corrected, increments)]
    _same_poses(rebuilt_odometry(corrected, predicted), chained((0.0, 0.0, 0.0), increments), tol=1e-6)


# -- a real corrected log, where the machine has the logs -------------------------------------------------

def _logs_folder() -> Path:
    return Path(os.environ.get("BOOTMAP_LOGS", Path(__file__).resolve().parents[2].parent / "shared" / "logs"))


@pytest.fixture(scope="module")
def aces():
    path = _logs_folder() / "aces-corrected.log.gz"
    if not path.exists():
        pytest.skip(f"no real logs at {path.parent} (set BOOTMAP_LOGS)")
    return path, list(read_carmen(path))


def test_a_real_corrected_log_reads_its_truth_and_its_wheels(aces):
    path, scans = aces
    assert len(scans) == 440
    assert scans[0].truth == (0.89706, -0.180771, -0.454003)   # the first FLASER's corrected pose
    assert scans[0].odometry == (0.909588, -0.135916, -0.475854)  # the raw ODOM reading at that scan
    # Between consecutive scans (about a metre apart) the wheels agree with the corrected poses to a
    # few centimetres ...
    steps = [np.hypot(*np.subtract(between(a.odometry, b.odometry)[:2], between(a.truth, b.truth)[:2]))
             for a, b in zip(scans, scans[1:])]
    assert np.median(steps) < 0.1
    # ... and over the whole drive they drift, as real odometry does.
    end = compose(scans[0].truth, between(scans[0].odometry, scans[-1].odometry))
    errors = [math.dist(compose(scans[0].truth, between(scans[0].odometry, s.odometry))[:2], s.truth[:2])
              for s in scans]
    assert max(errors) > 5.0 and math.dist(end[:2], scans[-1].truth[:2]) > 1.0


def test_a_real_corrected_log_becomes_a_tableau_with_true_dstates(aces):
    path, scans = aces
    tableau = log_tableau(scans, source=str(path), calibrate=False)
    assert len(tableau) >= 10
    assert all(s.truth is not None and s.truth.startswith("P") for s in tableau.steps)
    chosen = tableau.meta["dstates"]["scans"]
    assert all(math.dist(s.odometry[:2], scans[i].odometry[:2]) < 1e-3 for s, i in zip(tableau.steps, chosen))
    assert all(math.dist(s.pose[:2], scans[i].truth[:2]) < 1e-3 for s, i in zip(tableau.steps, chosen))



def test_a_real_logs_drifting_heading_is_calibrated_by_the_laser(aces):
    # ACES's wheels turn the heading a third of a degree per metre; the laser reads it, scan to scan, and
    # the calibrated heading strays less far from the true one.
    path, scans = aces
    fitted = OdometryCalibration().fit(scans)
    assert fitted.applied_ and fitted.drift_deg_per_m_ > 0.2 and fitted.steps_measured_ > 0.9 * (len(scans) - 1)

    def stray(track):  # the largest heading error since the start, degrees
        o = np.unwrap([s.odometry[2] for s in track])
        t = np.unwrap([s.truth[2] for s in track])
        return float(np.degrees(np.abs((o - o[0]) - (t - t[0])).max()))

    assert stray(fitted.transform(scans)) < 0.8 * stray(scans)
    tableau = log_tableau(scans, source=str(path))
    assert tableau.meta["odometry"]["calibration"]["applied"]
