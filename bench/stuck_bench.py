"""Does any simulated robot get stuck? A thousand runs of the paper's experiment's length, at every noise
of ``sweeps/robust.toml``.

Both paper worlds (50 circuits of the notched rectangle, 100 dstates of Taylor Hall), seeds 3000-3099 (no
setting of bootmap was chosen on them), at the shipped noise, 2x and 4x the laser's range noise and
drop-outs, 2x and 3x the odometry's turn-rate error and gyro drift: 2 x 100 x 5 = 1,000 simulations, on a
process pool. A run is stuck when a control law never reaches its fixed point (``SimulationError``); any
other error is reported too. Prints the runs stuck per world and noise, and the seconds.

Target: no run stuck or failed. Run: .venv/bin/python bench/stuck_bench.py [--seeds 3000-3099] [--workers 2]
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor

from bootmap.arguments import seeds as parse_seeds
from targets import Targets

WORLDS = {"notched_rectangle": {"circuits": 50}, "taylor_hall": {"steps": 100}}
#: sweeps/robust.toml's noise levels.
NOISE = {"1x": {}, "2x laser": {"laser.noise_sd": 0.02, "laser.dropout": 0.002},
         "4x laser": {"laser.noise_sd": 0.04, "laser.dropout": 0.004},
         "2x odometry": {"motion_noise.turn_scale": 0.1, "motion_noise.drift_deg_s": 0.3},
         "3x odometry": {"motion_noise.turn_scale": 0.15, "motion_noise.drift_deg_s": 0.45}}


def one(cell: tuple[str, str, int]) -> tuple[str, str, int, str]:
    """Simulate one cell: (world, noise, seed, "" or what went wrong)."""
    from bootmap.sim.simulation import SimulationError, simulate
    from bootmap.sim.world import load_world

    world, noise, seed = cell
    try:
        simulate(load_world(world, NOISE[noise]), seed=seed, **WORLDS[world])
        return world, noise, seed, ""
    except SimulationError as e:
        return world, noise, seed, f"stuck: {e}"
    except Exception as e:  # noqa: BLE001 - a bench reports every failure, whatever it is
        return world, noise, seed, f"failed: {type(e).__name__}: {e}"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=parse_seeds, default=list(range(3000, 3100)))
    p.add_argument("--workers", type=int, default=2)
    args = p.parse_args(argv)
    cells = [(w, n, s) for w in WORLDS for n in NOISE for s in args.seeds]
    start = time.perf_counter()
    with ProcessPoolExecutor(args.workers) as pool:
        results = list(pool.map(one, cells, chunksize=4))
    seconds = time.perf_counter() - start
    bad = Counter((w, n) for w, n, _, why in results if why)
    print(f"{len(cells)} simulations in {seconds:.0f} s on {args.workers} workers")
    print(f"{'world':<18} {'noise':<12} runs  stuck or failed")
    for w in WORLDS:
        for n in NOISE:
            print(f"{w:<18} {n:<12} {len(args.seeds):>4}  {bad[w, n]}")
    for w, n, s, why in results:
        if why:
            print(f"  {w} {n} seed {s}: {why}")
    targets = Targets()
    targets.check("simulations stuck or failed", sum(bad.values()), "<=", 0, fmt="{:d}", bound_text="0")
    return targets.exit_status()


if __name__ == "__main__":
    sys.exit(main())
