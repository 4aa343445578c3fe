"""Wall time of the whole experiment per world, and of each stage (issue 5's speed targets).

Targets on the 2-core machine: the k sweep on 400 images of 180 values under 1 s; the whole
notched_rectangle experiment (50 circuits) under 10 s; taylor_hall under 20 s.

Run: .venv/bin/python bench/experiment_bench.py
"""

import time
import warnings

from bootmap.experiment import run_experiment


def main() -> None:
    warnings.filterwarnings("ignore")
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


if __name__ == "__main__":
    main()
