"""Wall time of the whole experiment per world, and of each stage (the speed targets).

Targets on the 2-core machine: the k sweep on 400 images of 180 values under 1 s (the views stage of
notched_rectangle); the whole notched_rectangle experiment (50 circuits) under 10 s; taylor_hall under
20 s; and on both, every check of what the paper's experiment must show holds. Each is printed beside
the measured figure; the exit status is 1 if any is missed.

Run: .venv/bin/python bench/experiment_bench.py
"""

import sys
import time
import warnings

from bootmap.experiments.world import CHECKS, run_experiment
from targets import Targets

MAX_S = {"notched_rectangle": 10.0, "taylor_hall": 20.0}  # the whole experiment
K_SWEEP_MAX_S = 1.0  # notched_rectangle's views stage: k = 1..12 on 400 x 180 images


def main() -> int:
    warnings.filterwarnings("ignore")
    targets = Targets()
    for world, kw in (("notched_rectangle", {"circuits": 50}), ("taylor_hall", {"steps": 100})):
        t0 = time.perf_counter()
        r = run_experiment(world, seed=1, time_limit=20.0, **kw)
        total = time.perf_counter() - t0
        m = r["map"]
        verdict = ("no map" if "error" in m else
                   f"{m['dstates']} dstates, {m['places']} places, {m['paths']} paths, "
                   f"{m['dstate_accuracy']:.0%} right{'' if m['proved_minimal'] else ', NOT proved minimal'}")
        stages = ", ".join(f"{k[:-2]} {v:.2f}" for k, v in r["timings"].items())
        print(f"{world:18} {r['images']:4} images: {total:6.2f} s ({stages}); k = {r['views']['k']}; {verdict}")
        targets.check(f"  {world}: whole experiment", total, "<", MAX_S[world], fmt="{:.2f}", unit=" s")
        if world == "notched_rectangle":
            targets.check(f"  {world}: k sweep (views stage)", r["timings"]["views_s"], "<", K_SWEEP_MAX_S,
                          fmt="{:.2f}", unit=" s")
        targets.check(f"  {world}: checks that hold", sum(r["checks"].values()), "==", len(CHECKS), fmt="{}",
                      bound_text=f"{len(CHECKS)} (all)")
    return targets.exit_status()


if __name__ == "__main__":
    sys.exit(main())
