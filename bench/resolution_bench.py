"""Readings recorded at any resolution: the map of noisy experience, whatever step the log records on.

Real logs record distances to the centimetre and angles to a tenth of a degree, but a robot's encoders or
a logger may record on any step: 5 cm and half a degree, 25 cm and 2.5 degrees (coarser than the noise:
most readings of a corridor fall on one value), an encoder's tick of 12.3 mm. For each seed, a tableau
(the paper's notched rectangle, 8-12 circuits, or an exploration of a random 4 x 4 grid world, 150-210
steps) is read with odometry noise (turns sd 3 degrees, travel drift 1.2, distances 3%), then recorded at
each resolution; the resolver (20 s limit) must give the true map of every one.

Target: every map exact (time points on their true dstate, best one-to-one renaming). Exits 1 on a miss.
Run: PYTHONPATH=py:bench:tests .venv/bin/python bench/resolution_bench.py [--seeds 53400-53449]
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from bootmap import examples
from bootmap.arguments import seeds as parse_seeds
from bootmap.errors import BootmapError
from bootmap.mapping.resolver import Resolver
from bootmap.metrics import dstate_accuracy
from support.gridworld import random_world, walk
from support.noise import Rounding, rounded, with_odometry_noise
from targets import Targets

#: Steps a log may record on (distance, angle); None: unrounded.
RESOLUTIONS = {"unrounded": None, "1 cm, 0.1 deg": Rounding(0.01, 0.1), "1 mm, 0.01 deg": Rounding(0.001, 0.01),
               "5 cm, 0.5 deg": Rounding(0.05, 0.5), "20 cm, 2 deg": Rounding(0.2, 2.0),
               "25 cm, 2.5 deg": Rounding(0.25, 2.5), "50 cm, 5 deg": Rounding(0.5, 5.0),
               "tick 12.3 mm, 0.7 deg": Rounding(0.0123, 0.7), "1 m, 1 deg": Rounding(1.0, 1.0)}


def experience(seed: int):
    """The seed's tableau, read with odometry noise (unrounded), and its true dstates."""
    rng = np.random.default_rng(seed)
    if seed % 3 == 0:
        clean = examples.notched_rectangle(circuits=8 + seed % 5)
    else:
        world = random_world(rng, 4, 4, extra_edges=seed % 3, landmarks=0.4)
        clean = walk(world, 150 + 20 * (seed % 4), rng, policy="explore")
    noisy = with_odometry_noise(clean, 3.0, 1.2, rng, distance_sd=0.03, rounding=None)
    return noisy, [s.truth for s in clean.steps]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="53400-53449", help="seeds, e.g. 53400-53449 (default)")
    args = ap.parse_args(argv)
    seeds = parse_seeds(args.seeds)
    exact = {name: 0 for name in RESOLUTIONS}
    slowest = {name: 0.0 for name in RESOLUTIONS}
    print(f"{len(seeds)} seeds; per resolution: maps exact, slowest seconds")
    for seed in seeds:
        noisy, truth = experience(seed)
        for name, resolution in RESOLUTIONS.items():
            t0 = time.perf_counter()
            try:
                cmap = Resolver(time_limit=20).resolve(rounded(noisy, resolution))
                ok = dstate_accuracy(truth, cmap.dstate_of) == 1.0
            except BootmapError as e:
                ok = False
                print(f"  seed {seed}, {name}: {type(e).__name__}", flush=True)
            exact[name] += ok
            slowest[name] = max(slowest[name], time.perf_counter() - t0)
            if not ok:
                print(f"  seed {seed}, {name}: not the true map", flush=True)
    targets = Targets()
    for name in RESOLUTIONS:
        print(f"{name:24} {exact[name]:4d} of {len(seeds)}  {slowest[name]:6.2f} s")
        targets.check(f"maps exact, {name}", exact[name], "==", len(seeds), fmt="{}")
    return targets.exit_status()


if __name__ == "__main__":
    sys.exit(main())
