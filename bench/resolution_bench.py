"""Readings recorded at any resolution: the map of noisy experience, whatever step the log records on.

Real logs record distances to the centimetre and angles to a tenth of a degree, but a robot's encoders or
a logger may record on any step: 5 cm and half a degree, 25 cm and 2.5 degrees (coarser than the noise:
most readings of a corridor fall on one value), an encoder's tick of 12.3 mm; or print readings on a grid
their printed step does not divide (centimetres converted to feet and printed to the hundredth, a tick of
0.123 mm printed to the micrometre and a gyro's 360/4096 degrees to the hundredth). For each seed, a tableau
(the paper's notched rectangle, 8-12 circuits, or an exploration of a random 4 x 4 grid world, 150-210
steps) is read with odometry noise (turns sd 3 degrees, travel drift 1.2, distances 3%), then recorded at
each resolution; the resolver (20 s limit) must give each the map it gives the readings unrounded (which
is the truth but where the experience leaves two minimal maps: printed beside).

Target: every recording's map the unrounded readings' (time points in the same dstates, best one-to-one
renaming). Exits 1 on a miss.
Run: PYTHONPATH=py:bench:tests .venv/bin/python bench/resolution_bench.py [--seeds 53400-53449]
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace

import numpy as np

from bootmap import examples
from bootmap.arguments import seeds as parse_seeds
from bootmap.errors import BootmapError
from bootmap.mapping.resolver import Resolver
from bootmap.metrics import dstate_accuracy
from bootmap.tableau import Tableau, Travel, Turn
from support.gridworld import random_world, walk
from support.noise import Rounding, rounded, with_odometry_noise
from targets import Targets

#: Steps a log may record on (distance, angle); None: unrounded.
RESOLUTIONS = {"unrounded": None, "1 cm, 0.1 deg": Rounding(0.01, 0.1), "1 mm, 0.01 deg": Rounding(0.001, 0.01),
               "5 cm, 0.5 deg": Rounding(0.05, 0.5), "20 cm, 2 deg": Rounding(0.2, 2.0),
               "25 cm, 2.5 deg": Rounding(0.25, 2.5), "50 cm, 5 deg": Rounding(0.5, 5.0),
               "tick 12.3 mm, 0.7 deg": Rounding(0.0123, 0.7), "1 m, 1 deg": Rounding(1.0, 1.0)}
#: Readings on a grid the printed step does not divide: (distance tick, its printed decimals, a factor the
#: distances are given in, angle tick, its printed decimals).
PRINTED = {"1 cm in feet, to 0.01 ft": (0.01, 2, 3.28084, 0.1, 1),
           "tick 0.123 mm to 1 um, 360/4096 deg to 0.01": (0.000123, 6, 1.0, 360 / 4096, 2)}


def printed(tableau, tick_m: float, decimals_m: int, factor: float, tick_deg: float, decimals_deg: int):
    """The tableau's readings on these ticks, printed to so many decimals (distances times ``factor``)."""
    def on(value, tick, decimals, scale=1.0):
        return round(round(value / tick) * tick * scale, decimals)

    steps = []
    for s in tableau.steps:
        a = s.action
        if isinstance(a, Turn):
            a = Turn(on(a.angle_deg, tick_deg, decimals_deg))
        elif isinstance(a, Travel):
            a = Travel(on(a.distance_m, tick_m, decimals_m, factor), on(a.heading_change_deg, tick_deg, decimals_deg))
        steps.append(replace(s, action=a))
    return Tableau(tuple(steps), tableau.world, dict(tableau.meta))


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
    recordings = {**{name: (lambda t, r=r: rounded(t, r)) for name, r in RESOLUTIONS.items()},
                  **{name: (lambda t, p=p: printed(t, *p)) for name, p in PRINTED.items()}}
    same = {name: 0 for name in recordings}
    true = {name: 0 for name in recordings}
    slowest = {name: 0.0 for name in recordings}
    print(f"{len(seeds)} seeds; per recording: maps as unrounded, maps exact, slowest seconds")
    for seed in seeds:
        noisy, truth = experience(seed)
        unrounded = None
        for name, record in recordings.items():
            t0 = time.perf_counter()
            try:
                dstates = Resolver(time_limit=20).resolve(record(noisy)).dstate_of
            except BootmapError as e:
                dstates = None
                print(f"  seed {seed}, {name}: {type(e).__name__}", flush=True)
            slowest[name] = max(slowest[name], time.perf_counter() - t0)
            unrounded = dstates if unrounded is None else unrounded
            ok = dstates is not None and dstate_accuracy(unrounded, dstates) == 1.0
            same[name] += ok
            true[name] += dstates is not None and dstate_accuracy(truth, dstates) == 1.0
            if not ok:
                print(f"  seed {seed}, {name}: not the map of the readings unrounded", flush=True)
    targets = Targets()
    for name in recordings:
        print(f"{name:44} {same[name]:4d} {true[name]:4d} of {len(seeds)}  {slowest[name]:6.2f} s")
    for name in recordings:
        targets.check(f"maps as unrounded, {name}", same[name], "==", len(seeds), fmt="{}")
    return targets.exit_status()


if __name__ == "__main__":
    sys.exit(main())
