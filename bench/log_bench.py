"""The experiment on a real robot's log: seconds for ingest + pipeline on the whole Killian log, scans
per second, and the targets set for a real log beside what was measured (and the paper's Taylor Hall numbers).

Targets: the whole run under 120 s; the accuracy targets are printed as measured
(corner recall 95%, turn angles within 10 degrees, 80% of visits in their true dstate, 60% nearest
neighbour on revisited dstates): they are ambitious for a log whose dstates are mostly seen once.

Run: nice -n 10 .venv/bin/python bench/log_bench.py [--log killian] [--repeat 3]
"""

from __future__ import annotations

import argparse
import sys
import time

from bootmap.experiments.log import headline, run_log_experiment
from targets import Targets

# The paper's Taylor Hall run, for comparison (Kuipers & Beeson 2002): 100 images of 20 dstates seen
# many times, every dstate told apart, nearest neighbour 88% at 90 images.
PAPER = "paper, Taylor Hall: 100 images, 20 dstates, 7 places; map exact; 1-NN 88% at 90 images"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--log", default="killian", help="any log bootmap ingest reads (default killian)")
    p.add_argument("--repeat", type=int, default=3, help="runs; the fastest is reported")
    args = p.parse_args(argv)
    seconds, r = [], None
    for _ in range(args.repeat):
        start = time.perf_counter()
        r = run_log_experiment(args.log)
        seconds.append(time.perf_counter() - start)
    best = min(seconds)
    print("\n".join(headline(r)))
    stages = ", ".join(f"{k.removesuffix('_s')} {v:.2f}" for k, v in r["timings"].items())
    print(f"{args.log}: {r['scans']} scans, ingest + pipeline {best:.1f} s ({r['scans'] / best:.0f} scans/s; "
          f"fastest of {args.repeat}, the first {seconds[0]:.1f} s with its imports; {stages} s)")
    print(PAPER)
    targets = Targets()
    targets.check("ingest + pipeline, whole log", best, "<", 120.0, fmt="{:.1f}", unit=" s")
    for name, t in r["targets"].items():
        targets.check(f"target: {name}", t["measured"], t["op"], t["target"], fmt="{:.1%}",
                      bound_text=f"{t['target']:.0%}")
    return targets.exit_status()


if __name__ == "__main__":
    sys.exit(main())
