"""From a robot's log to a tableau: images at the scans where a control law would have settled, and the
actions odometry measured between them.

1. :func:`read_log` reads any supported log into :class:`~bootmap.ingest.scans.Scan` records (format by
   name: ``killian``, a ``.g2o`` or ``.zip``, a ROS bag (``.bag``, ``.db3``, ``.mcap`` or a ROS 2 bag
   directory), else a CARMEN log).
2. :func:`~bootmap.ingest.dstates.find_turns` cuts the odometry into travels and turns; each turn gives
   two dstates, its start and its end. Where asked for, :func:`~bootmap.ingest.dstates.find_passes` adds a
   dstate where a travel passes straight through a junction.
3. :func:`log_tableau` writes one step per dstate: the scan as an image (the simulator's format), the
   action to the next dstate as odometry measured it (a turn: its angle; a travel: its length and net
   heading change), the odometry's pose as ``odometry`` (evidence: :mod:`bootmap.mapping.loops`), the
   true pose as ``pose`` and, when the log has true poses, the true dstate as ``truth``
   (:mod:`bootmap.ingest.truth`). The learning never reads ``pose`` or ``truth``. The tableau says
   ``passes_through``: the robot did not stop at its dstates, so a travel may have passed some.
"""

from __future__ import annotations

import math
import sys
from dataclasses import asdict
from pathlib import Path
from typing import Iterable, Iterator

import numpy as np

from ..errors import LogError
from ..tableau import Step, Tableau, Travel, Turn
from .calibrate import OdometryCalibration
from .dstates import (FoundTurn, JunctionDetector, TurnDetector, dstate_scans, find_passes, find_turns,
                      odometry_track, side_ranges)
from .scans import IMAGE_ANGLE_MAX, IMAGE_ANGLE_MIN, IMAGE_BEAMS, Scan, to_image, wrap
from .places import PlaceDetector, find_visits
from ..paths import simplify
from ..paths import main_axis
from .truth import corner_recall, corners_in_poses, true_dstates

ROS_SUFFIXES = (".bag", ".db3", ".mcap")
#: How far the drawn true path may stray from the log's poses (metres).
TRAJECTORY_TOLERANCE_M = 0.05


def read_log(log: str | Path, progress: bool = False, **ros_options) -> list[Scan]:
    """Every scan of a log, in time order. ``log`` is a path, or ``killian`` for the MIT Killian Court
    log of the ``rtb-data`` package. ``ros_options`` go to :func:`bootmap.ingest.rosbag.read_rosbag`."""
    if str(log) == "killian" and not Path(log).exists():
        from .g2o import killian

        return killian()
    path = Path(log)
    if not path.exists():
        raise LogError("no such file or directory", str(path))
    if path.suffix in (".g2o", ".zip"):
        from .g2o import read_g2o

        return read_g2o(path)
    if path.is_dir() or path.suffix in ROS_SUFFIXES:
        from .rosbag import read_rosbag

        return list(_shown(read_rosbag(path, **ros_options), progress))
    from .carmen import read_carmen

    return list(_shown(read_carmen(path), progress))


def _shown(scans: Iterable[Scan], progress: bool) -> Iterator[Scan]:
    """The scans, with a progress count on stderr for a long log."""
    if not progress:
        return iter(scans)
    from tqdm import tqdm

    return iter(tqdm(scans, unit=" scans", file=sys.stderr, dynamic_ncols=True, desc="reading", leave=False))


def log_tableau(scans: list[Scan], detector: TurnDetector = TurnDetector(), max_range: float = 20.0,
                radius_m: float = 3.0, source: str = "log", junctions: JunctionDetector | None = None,
                places: PlaceDetector | None = None, calibrate: bool = True,
                calibration: OdometryCalibration | None = None) -> Tableau:
    """The tableau of a log: one step per dstate (see the module docstring).

    Parameters
    ----------
    scans : list of Scan
        The log, in time order.
    detector : TurnDetector
        Where turns are found, hence where dstates are (:mod:`bootmap.ingest.dstates`).
    max_range : float
        Images are clipped at this range (m): beyond it a corridor's far end says little, and a long
        reading swings with small changes of heading.
    radius_m : float
        Dstates whose true poses lie this close are one place (for ``truth`` only).
    source : str
        What the log is called in messages and in ``meta.source``.
    junctions : JunctionDetector, optional
        Where travels pass junctions, which are dstates too; None: only turns give dstates.
    places : PlaceDetector, optional
        Choose dstates at the places the laser shows (:mod:`bootmap.ingest.places`: every pass through a
        junction, corner or room is a visit) instead of at the turns odometry shows; ``detector`` and
        ``junctions`` are then not used.
    calibrate : bool
        Calibrate odometry's heading by the laser where it drifts (:mod:`bootmap.ingest.calibrate`): the
        dstates are chosen, and their odometry recorded, on the calibrated track; ``meta.odometry`` says
        what was found and whether it was applied.
    calibration : OdometryCalibration, optional
        One already fitted to these scans (a caller that needs the calibrated scans too), used when
        ``calibrate``; else one is fitted here.
    """
    if len(scans) < 2:
        raise LogError(f"{len(scans)} scan{'' if len(scans) == 1 else 's'}: a log needs at least 2 to have any "
                       "motion", source)
    if calibration is None and calibrate:
        calibration = OdometryCalibration().fit(scans)
    elif not calibrate:
        calibration = None
    if calibration is not None:
        scans = calibration.transform(scans)
    distance, heading = odometry_track([s.odometry for s in scans])
    visits = None
    if places is None:
        turns = find_turns(distance, heading, detector)
        if not turns:
            raise LogError(f"the odometry turns nowhere in {len(scans)} scans (no heading change of "
                           f"{detector.turn_deg:g} degrees or more between travels): no dstate to choose", source)
        passes = [] if junctions is None else find_passes(*side_ranges(scans), distance, turns, junctions)
    else:
        visits = find_visits(scans, distance, heading, places)
        if len(visits) < 2:
            raise LogError(f"the laser shows {len(visits)} place(s) in {len(scans)} scans (a junction, corner or "
                           "room): a map needs at least two", source)
        turns, passes = [], []
        for v in visits:  # a visit that turns gives the turn's two ends, a pass its middle scan
            ends = v.dstates(places.turn_deg)
            if len(ends) == 2:
                turns.append(FoundTurn(*ends, v.angle_deg))
            else:
                passes.append(ends[0])
    chosen = dstate_scans(turns, passes)
    actions = _actions(chosen, turns, distance, heading)
    has_truth = all(s.truth is not None for s in scans)
    if not has_truth:
        truth = [None] * len(chosen)
    elif visits is None:
        truth = _truth(scans, chosen, actions, radius_m)
    else:
        truth = _truth(scans, chosen, actions, radius_m, travels_leave=False)
    steps = tuple(Step(action=actions[k] if k < len(actions) else None,
                       image=to_image(scans[i], IMAGE_BEAMS, max_range), truth=truth[k],
                       pose=_rounded(scans[i].truth) if has_truth else None, odometry=_rounded(scans[i].odometry))
                  for k, i in enumerate(chosen))
    meta = _meta(scans, chosen, turns, detector, max_range, radius_m, source, has_truth, junctions, passes)
    # The building's main axis as the whole odometry track shows it (every scan's pose, not only the
    # dstates'): the sectors a dstate faces are read against it (bootmap.mapping.sectors).
    meta["odometry"] = {"axis_deg": round(math.degrees(main_axis([s.odometry for s in scans])), 2)}
    if calibration is not None:
        meta["odometry"]["calibration"] = calibration.to_dict()
    if visits is not None:
        meta["dstates"].update(detector=None, junctions=None, places=asdict(places),
                               visits=[[v.first, v.last] for v in visits])
    return Tableau(steps, None, meta)


def _actions(chosen: list[int], turns: list[FoundTurn], distance: np.ndarray, heading: np.ndarray) -> list:
    """The actions between consecutive dstates: a turn from a turn's start to its end, else the travel
    odometry measured (its length and net heading change)."""
    angle = {(t.before, t.after): t.angle_deg for t in turns}
    actions: list = []
    for a, b in zip(chosen, chosen[1:]):
        if (a, b) in angle:
            actions.append(Turn(round(angle[a, b], 2)))
        else:
            change = math.degrees(wrap(float(heading[b] - heading[a])))
            actions.append(Travel(round(float(distance[b] - distance[a]), 3), round(change, 2)))
    return actions


def turn_ends(actions: list) -> list[tuple[int, int]]:
    """The (start, end) step pairs of the turns: a turn never leaves its place."""
    return [(k, k + 1) for k, action in enumerate(actions) if isinstance(action, Turn)]


def travel_ends(actions: list) -> list[tuple[int, int]]:
    """The (start, end) step pairs of the travels: a travel always leaves its place."""
    return [(k, k + 1) for k, action in enumerate(actions) if isinstance(action, Travel)]


def _truth(scans: list[Scan], chosen: list[int], actions: list, radius_m: float,
           travels_leave: bool = True) -> list[str]:
    """True dstates of the chosen scans, sectors aligned to the axis of the whole true path: places of
    poses within the radius, a turn's two ends in one (at their middle), and with ``travels_leave`` a
    travel's two ends never in one. A dstate's place is judged where the robot was at it, as loop
    closures are judged (:func:`~bootmap.ingest.truth.visit_positions`): at places too, a visit that
    turned is placed at the middle of its two dstates, not at some scan in between (a visit may wander
    through a hall and leave where it came in). At places a travel may end in the place it left (the
    laser can show one place as two visits in a row), so it need not leave it."""
    axis = main_axis([s.truth for s in scans])
    return true_dstates([scans[i].truth for i in chosen], radius_m, axis, turn_ends(actions),
                        travel_ends(actions) if travels_leave else ())


def _rounded(pose) -> tuple[float, float, float]:
    return (round(pose[0], 4), round(pose[1], 4), round(float(wrap(pose[2])), 5))


def _meta(scans, chosen, turns, detector, max_range, radius_m, source, has_truth, junctions, passes) -> dict:
    # The robot drove on through dstates (a junction passed straight, a corner it only slowed at): a
    # travel may end at any dstate further on (causal.lp's travel_action_passing).
    meta = {"generator": "bootmap.ingest", "source": source, "scans": len(scans), "passes_through": True,
            "laser": {"angle_min": IMAGE_ANGLE_MIN, "angle_max": IMAGE_ANGLE_MAX,
                      "angle_increment": (IMAGE_ANGLE_MAX - IMAGE_ANGLE_MIN) / (IMAGE_BEAMS - 1),
                      "range_max": max_range, "beams": IMAGE_BEAMS,
                      "log_range_max": scans[0].range_max},
            "dstates": {"scans": chosen, "detector": asdict(detector),
                        "junctions": None if junctions is None else asdict(junctions), "passes": passes}}
    gaps = [{"scan": k, "read_as": s.odometry_gap} for k, s in enumerate(scans) if s.odometry_gap]
    if gaps:
        # Scans before which the log holds no wheel odometry: read as the turn on the spot the laser shows
        # ("laser"), or as no motion ("still") (bootmap.ingest.carmen).
        meta["odometry_gaps"] = gaps
    if has_truth:
        truth = [s.truth for s in scans]
        recall = corner_recall(turns, truth, corners_in_poses(truth))
        meta["truth"] = {"radius_m": radius_m, "axis_deg": round(math.degrees(main_axis(truth)), 2),
                         "corner_recall": recall.to_dict()}
        # The true path to draw, thinned to within 5 cm (Ramer-Douglas-Peucker): a whole log's poses
        # would outgrow what a tableau's meta may hold in the service (64 KiB by default).
        xy = np.asarray(truth)[:, :2]
        meta["trajectory"] = np.round(xy[simplify(xy, TRAJECTORY_TOLERANCE_M)], 2).tolist()
    return meta


def ingest(log: str | Path, detector: TurnDetector = TurnDetector(), max_range: float = 20.0,
           radius_m: float = 3.0, progress: bool = False, junctions: JunctionDetector | None = None,
           **ros_options) -> Tableau:
    """:func:`read_log` then :func:`log_tableau`: a log file (or ``killian``) to a tableau."""
    scans = read_log(log, progress=progress, **ros_options)
    return log_tableau(scans, detector, max_range, radius_m, source=str(log), junctions=junctions)


