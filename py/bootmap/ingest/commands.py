"""The ``ingest`` sub-command; :func:`register` adds it to the ``bootmap`` command.

``bootmap ingest LOG -o run.json`` reads a robot's log (g2o, CARMEN, ROS bag, or ``killian``), chooses
its dstates and writes the tableau. Exit codes: 0 success, 1 the output cannot be written, 2 a bad log.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from .. import arguments
from ..errors import EXIT_BAD_INPUT, EXIT_FAILURE, EXIT_OK, BadInput, error_line
from .calibrate import OdometryCalibration
from .dstates import JunctionDetector, TurnDetector
from .places import PlaceDetector


def register(subparsers) -> None:
    """Add ``ingest`` to an ``argparse`` sub-parsers object."""
    p = subparsers.add_parser(
        "ingest", help="read a robot's laser log (g2o, CARMEN, ROS bag) into a tableau",
        description="Read a robot's log (a g2o file or .zip with ROBOTLASER1 lines, a CARMEN log, a ROS 1 "
                    ".bag or ROS 2 bag with sensor_msgs/LaserScan and nav_msgs/Odometry, or 'killian' for "
                    "the MIT Killian Court log of the rtb-data package) and write the tableau of its dstates: "
                    "the scans where odometry shows a turn between travels (each turn's start and end), "
                    "the actions odometry measured between them, the log's true poses as 'pose' and, where "
                    "the log has them, the true dstates (place + heading sector) as 'truth'.")
    p.add_argument("log", help="log file or ROS 2 bag directory, or 'killian'")
    p.add_argument("-o", "--output", metavar="FILE", help="write the tableau here (default: stdout)")
    p.add_argument("--window", type=arguments.positive("metres"), default=TurnDetector.window_m, metavar="M",
                   help=f"metres of travel over which heading changes are summed (default {TurnDetector.window_m:g})")
    p.add_argument("--turn", type=arguments.positive("degrees"), default=TurnDetector.turn_deg, metavar="DEG",
                   help=f"least heading change that is a turn (default {TurnDetector.turn_deg:g})")
    p.add_argument("--max-range", type=arguments.positive("metres"), default=20.0, metavar="M",
                   help="clip images at this range (default 20 m)")
    p.add_argument("--radius", type=arguments.positive("metres"), default=3.0, metavar="M",
                   help="dstates whose true poses lie this close are one place (default 3 m)")
    p.add_argument("--junctions", action="store_true",
                   help="a junction passed straight through (a side opening 1.5-5 m wide mid-travel) is a "
                        "dstate too, not only a turn's two ends")
    p.add_argument("--dstates", choices=arguments.DSTATE_CHOICES, default="turns",
                   help="where dstates are chosen: turns (default: each end of a turn odometry shows) or places "
                        "(every pass through a junction, corner or room the laser shows: its gateways)")
    p.add_argument("--scan-topic", help="ROS: the LaserScan topic (when the bag has several)")
    p.add_argument("--odom-topic", help="ROS: the Odometry topic (when the bag has several)")
    p.add_argument("--truth-topic", help="ROS: an Odometry topic of true poses")
    arguments.add_calibrate(p)
    p.add_argument("--no-place-matches", action="store_true",
                   help="leave out the laser's place matches between visits (meta.place_matches: each visit's "
                        "local map matched with the earlier visits odometry allows, verified by the places "
                        "around it), which loop closing weighs beside odometry; they take most of the time")
    p.add_argument("--no-progress", action="store_true", help="no progress count")
    p.set_defaults(handler=cmd_ingest)


def cmd_ingest(args: argparse.Namespace) -> int:
    from .ingest import log_tableau, read_log

    start = time.perf_counter()
    ros = {k: v for k, v in (("scan_topic", args.scan_topic), ("odom_topic", args.odom_topic),
                             ("truth_topic", args.truth_topic)) if v}
    try:
        scans = read_log(args.log, progress=not args.no_progress, **ros)
        detector = TurnDetector(window_m=args.window, turn_deg=args.turn)
        junctions = JunctionDetector() if args.junctions else None
        places = PlaceDetector() if args.dstates == "places" else None
        calibration = None if args.no_calibrate else OdometryCalibration().fit(scans)
        tableau = log_tableau(scans, detector, max_range=args.max_range, radius_m=args.radius, source=args.log,
                              junctions=junctions, places=places, calibrate=not args.no_calibrate,
                              calibration=calibration)
        if not args.no_place_matches:
            from ..experiments.log import place_matches

            seen = scans if calibration is None else calibration.transform(scans)
            if not args.no_progress:  # the longest part of an ingest: say what it is doing
                print(f"matching the places of {len(tableau)} dstates with the earlier ones odometry allows "
                      f"(--no-place-matches leaves it out) ...", file=sys.stderr, flush=True)
            tableau.meta["place_matches"] = place_matches(tableau, seen, args.radius, args.max_range).pairs()
    except BadInput as e:
        print(error_line("ingest", e, EXIT_BAD_INPUT), file=sys.stderr)
        return EXIT_BAD_INPUT
    text = tableau.dumps()
    if not args.output:
        print(text)
        return EXIT_OK
    try:
        Path(args.output).write_text(text + "\n")
    except OSError as e:
        print(error_line("ingest", f"cannot write {args.output}: {e.strerror}", EXIT_FAILURE), file=sys.stderr)
        return EXIT_FAILURE
    seconds = time.perf_counter() - start
    print(f"{args.output}: {len(tableau)} dstates from {len(scans)} scans ({len(scans) / seconds:.0f} scans/s)"
          + _recall_note(tableau.meta) + _gap_note(tableau.meta) + _calibration_note(tableau.meta)
          + _matches_note(tableau.meta), file=sys.stderr)
    return EXIT_OK


def _matches_note(meta: dict) -> str:
    """How many place matches the laser gives loop closing to weigh ("" where they were left out)."""
    if "place_matches" not in meta:
        return ""
    matches = meta["place_matches"]
    return f"; {len(matches)} place match{'' if len(matches) == 1 else 'es'} between visits"


def _recall_note(meta: dict) -> str:
    recall = meta.get("truth", {}).get("corner_recall")
    if not recall:
        return ""
    return f"; turns found at {recall['found']} of {recall['corners']} corners seen in the true poses"


def _gap_note(meta: dict) -> str:
    gaps = meta.get("odometry_gaps")
    if not gaps:
        return ""
    laser = sum(g["read_as"] == "laser" for g in gaps)
    return (f"; the log holds no wheel odometry before {len(gaps)} scan(s) (first: scan {gaps[0]['scan']}): "
            f"{laser} read as the turn on the spot the laser shows, {len(gaps) - laser} as no motion")


def _calibration_note(meta: dict) -> str:
    from .calibrate import calibration_text

    said = calibration_text(meta.get("odometry", {}).get("calibration"))
    return f"; {said}" if said else ""
