"""Odometry calibrated by the laser (bootmap.ingest.calibrate): a drive round a ring corridor whose wheels
bend the heading is straightened by the scans; a drive whose odometry is right is left as it is."""

import math

import numpy as np
import pytest

from bootmap.ingest.calibrate import OdometryCalibration
from bootmap.ingest.ingest import log_tableau
from bootmap.ingest.scans import Scan, between, compose
from support.raycast import cast
from synthetic import ring_poses, ring_walls

MAX_RANGE = 30.0


def drive(drift_deg_per_m: float, turn_scale: float = 1.0, noise_m: float = 0.01) -> list[Scan]:
    """Two laps of the ring corridor, its scans ray-cast from the true poses (with range noise), its
    odometry the true motion with every turn scaled and the heading bent so many degrees a metre."""
    truth = []
    for pose in ring_poses(laps=2, step=0.5):  # a corner turned on the spot 15 degrees a scan
        if truth:
            turned = math.remainder(pose[2] - truth[-1][2], 2 * math.pi)
            for k in range(1, int(abs(turned) // math.radians(15))):
                truth.append((*truth[-1][:2], truth[-1][2] + math.copysign(math.radians(15), turned)))
        truth.append(pose)
    walls, rng = ring_walls(), np.random.default_rng(0)
    odometry, pose = [truth[0]], truth[0]
    for a, b in zip(truth, truth[1:]):
        x, y, turn = between(a, b)
        pose = compose(pose, (x, y, turn * turn_scale + math.radians(drift_deg_per_m) * math.hypot(x, y)))
        odometry.append(pose)
    return [Scan(float(k), cast(walls, p, beams=180, max_range=MAX_RANGE, noise_m=noise_m, rng=rng),
                 -math.pi / 2, math.pi / 179, MAX_RANGE, o, truth=p) for k, (p, o) in enumerate(zip(truth, odometry))]


def heading_error(scans: list[Scan]) -> float:
    """The largest gap between the odometry's heading change since the start and the true one (degrees)."""
    o = np.unwrap([s.odometry[2] for s in scans])
    t = np.unwrap([s.truth[2] for s in scans])
    return float(np.degrees(np.abs((o - o[0]) - (t - t[0])).max()))


@pytest.mark.parametrize("drift, scale", [(-1.0, 1.0), (0.6, 1.03)])
def test_a_bending_heading_is_read_from_the_laser_and_taken_out(drift, scale):
    scans = drive(drift, scale)
    fitted = OdometryCalibration(max_range=MAX_RANGE).fit(scans)
    assert fitted.applied_ and fitted.steps_measured_ > 0.9 * (len(scans) - 1)
    assert fitted.drift_deg_per_m_ == pytest.approx(drift, abs=0.15)
    assert fitted.turn_scale_ == pytest.approx(scale, abs=0.01)
    before, after = heading_error(scans), heading_error(fitted.transform(scans))
    assert before > 40 and after < before / 5
    # the log's tableau is made on the calibrated track, and says so
    tableau = log_tableau(scans, max_range=MAX_RANGE)
    assert tableau.meta["odometry"]["calibration"]["applied"]
    assert "calibration" not in log_tableau(scans, max_range=MAX_RANGE, calibrate=False).meta["odometry"]


def test_odometry_that_is_right_is_left_as_it_is():
    scans = drive(0.0)
    fitted = OdometryCalibration(max_range=MAX_RANGE).fit(scans)
    assert not fitted.applied_ and abs(fitted.drift_deg_per_m_) < fitted.min_drift_deg_per_m
    assert [s.odometry for s in fitted.transform(scans)] == [s.odometry for s in scans]


def test_scans_that_show_nothing_leave_the_odometry_alone():
    scans = [Scan(float(k), np.full(180, MAX_RANGE), -math.pi / 2, math.pi / 179, MAX_RANGE, (0.3 * k, 0.0, 0.01 * k))
             for k in range(30)]
    fitted = OdometryCalibration(max_range=MAX_RANGE).fit(scans)
    assert fitted.steps_measured_ == 0 and not fitted.applied_
    assert fitted.transform(scans) == scans
