"""Odometry calibrated by the laser: a wheeled robot's heading drift, measured scan to scan and taken out.

Wheel odometry errs in proportion to what it measures. A wheelbase read a little wrong scales every turn;
wheels of slightly unequal size bend every straight drive, so the heading drifts by so many degrees per
metre. Over a building that adds up: on one real log the dead-reckoned heading is 58 degrees off after
100 scans, and every corridor driven afterwards points the wrong way. The laser sees how the robot really
turned between two consecutive scans (they see the same walls, a few centimetres and degrees apart), so
the odometry's two error rates can be read from the log itself:

1. **Each step's turn by the laser.** The second scan's returns are aligned onto the surfaces the first
   saw (:func:`bootmap.surfaces.surface_points`) by ICP (point-to-point, ``small_gicp``, Koide's library;
   the 2-D points at z = 0), starting from the motion odometry measured, with correspondences reaching
   1 m, then 30 cm, then :attr:`inlier_m`, iterated until the turn changes by less than a micro-radian
   (the library's default stops at a tenth of a degree, half a drift step). The step is
   evidence where at least :attr:`min_inlier_share` of the second scan's returns end within
   :attr:`inlier_m` of the first's and the laser's turn lies within :attr:`max_turn_deg` of odometry's (else
   ICP slid along a featureless corridor or the scans saw different things).
2. **The error rates.** Odometry's turn of each step is regressed on the laser's turn and the metres
   driven, with no intercept (an error in proportion to the motion, none without it): ``odometry turn =
   turn_scale_ x laser turn + drift_deg_per_m_ x metres``, by Huber's robust regression, so that the few
   steps ICP got wrong weigh little. The scale is fitted only where the robot turned enough for it to show
   (:data:`TURNING_DEG` on :data:`MIN_STEPS` steps), else taken as 1; on straight steps the laser's turn is
   near nought, so the two rates do not stand in for each other.
3. **Taken out where it is odometry's.** The drift is applied only where it is at least
   :attr:`min_drift_deg_per_m` (0.1: ten degrees every 100 m) and :data:`SIGNIFICANCE` standard errors
   from none (the residuals' robust spread over the metres that measured it). The first because the
   laser's own turn between consecutive scans has a small bias (a scan taken while the robot moves is
   skewed; a surface sampled between beams is a chord): on logs whose odometry is good (the MIT Killian
   Court, Intel Seattle and Acapulco logs) it reads as 0.01-0.03 degrees per metre, and correcting by it
   made their heading worse. The second because a log whose consecutive scans lie far apart, or whose
   odometry errs at random rather than steadily, gives a drift the laser cannot pin down (on one log,
   4.6 degrees of spread per step). Then each step's turn becomes ``(turn - drift_deg_per_m_ x metres) /
   turn_scale_``, its motion along the way odometry's.

Never the log's true poses: the laser and the wheels only.

Example
-------
A robot drives 5 m along a room and turns on the spot while its odometry's heading creeps 2 degrees a
metre; the laser reads the creep and takes it out:

>>> import math
>>> from bootmap.ingest.scans import Scan, compose, between
>>> def room(pose):   # ranges to the walls of a 10 x 6 m room, from pose (x, y, heading)
...     a = pose[2] + np.radians(np.arange(-90, 90))
...     c, s = np.cos(a), np.sin(a)
...     with np.errstate(divide="ignore"):
...         tx = np.where(c > 0, (10 - pose[0]) / c, np.where(c < 0, -pose[0] / c, np.inf))
...         ty = np.where(s > 0, (6 - pose[1]) / s, np.where(s < 0, -pose[1] / s, np.inf))
...     return np.minimum(tx, ty)
>>> true = [(2 + 0.25 * k, 3.0, 0.0) for k in range(20)] + [(7.0, 3.0, math.radians(6 * k)) for k in range(1, 31)]
>>> odometry, pose = [true[0]], true[0]
>>> for a, b in zip(true, true[1:]):
...     step = between(a, b)
...     pose = compose(pose, (step[0], step[1], step[2] + math.radians(2.0) * math.hypot(step[0], step[1])))
...     odometry.append(pose)
>>> scans = [Scan(float(k), room(p), -np.pi / 2, np.radians(1), 30.0, o) for k, (p, o) in enumerate(zip(true, odometry))]
>>> fitted = OdometryCalibration().fit(scans)
>>> round(fitted.drift_deg_per_m_, 1), fitted.applied_
(1.9, True)
>>> def heading_after_the_drive(scans):   # degrees, where the robot faced east
...     return round(math.degrees(scans[19].odometry[2]), 1)
>>> heading_after_the_drive(scans), heading_after_the_drive(fitted.transform(scans))
(9.5, 0.4)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Sequence

import numpy as np

from ..surfaces import image_points, in_3d, planar, se2, surface_points
from .scans import IMAGE_BEAMS, Scan, between, compose, to_image, wrap

#: Steps the laser must read before a rate is fitted (and turning steps before the turn scale is).
MIN_STEPS = 10
#: A step turns enough to show odometry's turn scale from this many degrees.
TURNING_DEG = 5.0
#: A drift is applied only where it is this many of its standard errors from none.
SIGNIFICANCE = 3.0


@dataclass
class OdometryCalibration:
    """Odometry's turn scale and heading drift per metre, read from the laser (see the module docstring).

    Parameters
    ----------
    max_range : float
        Returns at or beyond this range (m) are left out: far returns are sparse and swing with heading.
    inlier_m : float
        A return is matched within this many metres of the other scan's (a SICK-class laser's noise is
        1-3 cm; two consecutive scans see the same wall a few cm apart).
    min_inlier_share : float
        A step is evidence where at least this share of the second scan's returns are matched.
    max_turn_deg : float
        ... and where the laser's turn lies within this many degrees of odometry's.
    min_drift_deg_per_m : float
        The calibration is applied where the heading drift it finds is at least this (degrees per metre),
        and significant.

    Attributes
    ----------
    steps_measured_ : int
        Consecutive scan pairs whose turn the laser read.
    turn_scale_ : float
        Odometry's turn per degree the laser saw the robot turn (1: odometry's turns are right).
    drift_deg_per_m_ : float
        The degrees odometry's heading turns (counter-clockwise) per metre driven, beyond what the laser saw.
    drift_se_deg_per_m_ : float
        Its standard error (``inf`` before :data:`MIN_STEPS` steps are read).
    applied_ : bool
        Whether :meth:`transform` corrects the odometry (a drift at least ``min_drift_deg_per_m`` and
        :data:`SIGNIFICANCE` standard errors).
    """

    max_range: float = 20.0
    inlier_m: float = 0.10
    min_inlier_share: float = 0.5
    max_turn_deg: float = 10.0
    min_drift_deg_per_m: float = 0.1

    def fit(self, scans: Sequence[Scan]) -> "OdometryCalibration":
        """Read odometry's error rates from the laser's turns between consecutive scans."""
        from sklearn.linear_model import HuberRegressor

        read = np.asarray(self._laser_turns(scans), dtype=float).reshape(-1, 3)  # laser turn, metres, odometry turn
        self.steps_measured_ = len(read)
        self.turn_scale_, self.drift_deg_per_m_, self.drift_se_deg_per_m_, self.applied_ = 1.0, 0.0, math.inf, False
        if len(read) < MIN_STEPS:  # too few steps say nothing of a rate
            return self
        # odometry's turn = scale x the laser's turn + drift x metres driven; the scale only where the robot
        # turned enough for it to show
        turning = int((np.abs(read[:, 0]) >= TURNING_DEG).sum()) >= MIN_STEPS
        X = read[:, :2] if turning else read[:, 1:2]
        fit = HuberRegressor(epsilon=1.35, fit_intercept=False).fit(X, read[:, 2])
        self.turn_scale_ = float(fit.coef_[0]) if turning else 1.0
        self.drift_deg_per_m_ = float(fit.coef_[-1])
        # the drift's standard error: the residuals' robust spread over the metres that measured it
        residual = read[:, 2] - X @ fit.coef_
        spread = 1.4826 * float(np.median(np.abs(residual - np.median(residual))))
        self.drift_se_deg_per_m_ = spread / max(float(np.sqrt((read[:, 1] ** 2).sum())), 1e-9)
        self.applied_ = (abs(self.drift_deg_per_m_) >= max(self.min_drift_deg_per_m,
                                                           SIGNIFICANCE * self.drift_se_deg_per_m_)
                         and self.turn_scale_ > 0.5)
        return self

    def transform(self, scans: Sequence[Scan]) -> list[Scan]:
        """The scans with their odometry re-chained on the calibrated turns (unchanged where not applied)."""
        if not self.applied_ or len(scans) < 2:
            return list(scans)
        out, pose = [scans[0]], scans[0].odometry
        for before, scan in zip(scans, scans[1:]):
            x, y, turn = between(before.odometry, scan.odometry)
            turn = (turn - math.radians(self.drift_deg_per_m_) * math.hypot(x, y)) / self.turn_scale_
            pose = compose(pose, (x, y, turn))
            out.append(replace(scan, odometry=pose))
        return out

    def to_dict(self) -> dict:
        """What was found, for a tableau's ``meta``."""
        return {"steps_measured": self.steps_measured_, "turn_scale": round(self.turn_scale_, 5),
                "drift_deg_per_m": round(self.drift_deg_per_m_, 4),
                "drift_se_deg_per_m": round(self.drift_se_deg_per_m_, 4) if math.isfinite(self.drift_se_deg_per_m_)
                else None, "applied": self.applied_,
                "min_drift_deg_per_m": self.min_drift_deg_per_m}

    def _laser_turns(self, scans: Sequence[Scan]) -> list[tuple[float, float, float]]:
        """Per step the laser read: the laser's turn (degrees), the metres odometry drove, odometry's turn
        (degrees)."""
        import small_gicp

        read = []
        previous = None
        for before, scan in zip([None, *scans], scans):
            image = to_image(scan, IMAGE_BEAMS, self.max_range)
            points = in_3d(image_points(image, self.max_range))
            cloud = small_gicp.PointCloud(points) if len(points) >= 20 else None
            surface = small_gicp.PointCloud(in_3d(surface_points(image, self.max_range))) if cloud is not None else None
            tree = small_gicp.KdTree(surface) if surface is not None else None
            if before is not None and previous is not None and cloud is not None:
                step = between(before.odometry, scan.odometry)
                T = se2(*step)
                for reach in (1.0, 0.3, self.inlier_m):
                    result = small_gicp.align(previous[0], cloud, previous[1], init_T_target_source=T,
                                              registration_type="ICP", max_correspondence_distance=reach,
                                              max_iterations=100, rotation_epsilon=1e-6, translation_epsilon=1e-6)
                    T = result.T_target_source
                off = math.degrees(wrap(planar(T)[2] - step[2]))
                if result.num_inliers >= self.min_inlier_share * len(points) and abs(off) <= self.max_turn_deg:
                    turn = math.degrees(step[2])
                    read.append((turn + off, math.hypot(step[0], step[1]), turn))
            previous = None if cloud is None else (surface, tree)
        return read


def calibration_text(found: dict | None) -> str:
    """What a tableau's ``meta.odometry.calibration`` (:meth:`OdometryCalibration.to_dict`) says, in words,
    where it was applied; "" where it was not (or was not looked for).

    >>> calibration_text({"applied": True, "drift_deg_per_m": 0.7726, "turn_scale": 0.99813, "steps_measured": 452})
    "odometry's heading calibrated by the laser (drift +0.77 deg/m, turns x0.998, from 452 steps)"
    """
    if not found or not found["applied"]:
        return ""
    return (f"odometry's heading calibrated by the laser (drift {found['drift_deg_per_m']:+.2f} deg/m, turns "
            f"x{found['turn_scale']:.3f}, from {found['steps_measured']} steps)")
