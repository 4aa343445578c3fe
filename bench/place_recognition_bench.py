"""Place recognition along the whole drive of every real log, judged against the corrected poses.

The map's dstates give a log a handful of revisits (2 on ACES, 6 on CSAIL), too few for a precision-recall
curve to say much. Here every log is sampled at a visit every 2 m of odometry's path
(``bootmap.experiments.log.place_recognition_along``): each visit's local map, matched among the earlier
visits odometry allows to be one place, verified by its surroundings, the best sought within dead reckoning
re-anchored at the revisits recognised before it: the method the experiment is judged by. One row per log (every log in
a folder, default ``../shared/logs`` beside the repository, and the MIT Killian Court log): visits, queries
(visits with an earlier one the robot has left), true revisits, revisits whose best match is right, recall at
95% and 99% precision, average precision, seconds.

Target, on every log: recall at 95% precision >= 80% (FLIRT's figures beside it: Intel 0.96, FR079 0.98,
CSAIL 0.89, every scan of their preparation of those logs).

Run: nice -n 10 .venv/bin/python bench/place_recognition_bench.py [--logs DIR] [--no-killian] [--every M]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from bootmap.experiments.log import ALONG_EVERY_M, place_recognition_along
from real_logs_bench import ANCHORS, logs_in
from targets import Targets

ROOT = Path(__file__).resolve().parents[1]
COLUMNS = ["log", "visits", "queries", "revisits", "best match right", "recall@95%P", "recall@99%P",
           "average precision", "seconds"]
RECALL_AT_95 = 0.80


def _f(x) -> str:
    return "-" if x is None else f"{x:.2f}"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--logs", type=Path, default=ROOT.parent / "shared" / "logs",
                   help="a folder of logs (default ../shared/logs beside the repository)")
    p.add_argument("--no-killian", action="store_true", help="leave the MIT Killian Court log out")
    p.add_argument("--every", type=float, default=ALONG_EVERY_M, help="metres of the drive between visits")
    args = p.parse_args(argv)
    logs = logs_in(args.logs) + ([] if args.no_killian else ["killian"])
    rows, runs = [], []
    for log in logs:
        start = time.perf_counter()
        r = place_recognition_along(log, every_m=args.every)
        seconds = time.perf_counter() - start
        name = "killian" if log == "killian" else Path(log).name.removesuffix(".log.gz").removesuffix("-corrected")
        rows.append([name, str(r["visits"]), str(r["queries"]), str(r["revisits"]), str(r["best_correct"]),
                     _f(r["recall_at_95_precision"]), _f(r["recall_at_99_precision"]), _f(r["average_precision"]),
                     f"{seconds:.1f}"])
        runs.append((name, r))
        print(f"{name}: {seconds:.1f} s", file=sys.stderr, flush=True)
    print(f"place recognition along the drive, a visit every {args.every:g} m:")
    print("| " + " | ".join(COLUMNS) + " |")
    print("|" + "---|" * len(COLUMNS))
    for r in rows:
        print("| " + " | ".join(r) + " |")
    print()
    print("\n".join(f"anchor, {a}" for a in ANCHORS if a.startswith("FLIRT")))
    print()
    targets = Targets()
    for name, r in runs:
        targets.check(f"{name}: recall at 95% precision along the drive", r["recall_at_95_precision"], ">=",
                      RECALL_AT_95, fmt="{:.2f}", bound_text=f"{RECALL_AT_95:.2f}")
    return targets.exit_status()


if __name__ == "__main__":
    sys.exit(main())
