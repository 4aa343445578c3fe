"""How far the simulated robot's measured actions are from what it did: the noise model's figures.

For both of the paper's worlds and a range of seeds, the measured-minus-true angle of every action
(``bootmap.sim.odometry.action_errors``): 90-degree turns, turn-arounds, travels' heading changes;
their RMS, median absolute error, 90th percentile and largest. Beside the default model (a real robot's
odometry, ``worlds/README.md``), the simulator's old one (white slip of 3% only) on the same seeds.
Also how far the robot's true stops at one dstate lie apart (the dstates must not move with odometry).

Targets: 90-degree turns measured with an RMS error of 4-10 degrees (a real robot's, the old model's
was under 1); at least three times the old model's RMS; dstates' stops still within 5 cm.

Run: nice -n 10 .venv/bin/python bench/odometry_bench.py [--seeds 0-9]
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from bootmap.arguments import seeds as parse_seeds
from bootmap.sim import run
from bootmap.sim.odometry import action_errors
from bootmap.sim.world import load_world
from targets import Targets

OLD = {"motion_noise.slip_v": 0.03, "motion_noise.slip_omega": 0.03, "motion_noise.turn_scale": 0.0,
       "motion_noise.drift_deg_s": 0.0}
RUNS = {"notched_rectangle": {"circuits": 10}, "taylor_hall": {"policy": "explore", "steps": 100}}


def measure(name: str, settings: dict | None, seeds: list[int]) -> dict:
    """Errors by kind of action over the seeds, and the largest spread of one dstate's true stops."""
    world = load_world(name, settings)
    kinds = {"turn 90": [], "turn 180": [], "travel": []}
    spread = 0.0
    for seed in seeds:
        r = run(world, seed=seed, **RUNS[name])
        e = action_errors(r.tableau)
        kinds["turn 90"] += e.turns[np.abs(np.abs(e.turn_angles) - 90) < 30].tolist()
        kinds["turn 180"] += e.turns[np.abs(e.turn_angles) > 150].tolist()
        kinds["travel"] += e.travels.tolist()
        spread = max(spread, _stop_spread(r.tableau))
    return {"errors": {k: np.array(v) for k, v in kinds.items()}, "stop_spread_m": spread}


def _stop_spread(tableau) -> float:
    """The largest distance of a true stop from the median stop of its dstate, metres."""
    worst = 0.0
    for truth in {s.truth for s in tableau.steps}:
        xy = np.array([s.pose[:2] for s in tableau.steps if s.truth == truth])
        worst = max(worst, float(np.hypot(*(xy - np.median(xy, axis=0)).T).max()))
    return worst


def line(label: str, e: np.ndarray) -> str:
    if not len(e):
        return f"  {label:30} (none)"
    a = np.abs(e)
    return (f"  {label:30} n={len(e):4}  mean {e.mean():+5.2f}  RMS {np.sqrt(np.mean(e ** 2)):5.2f}  "
            f"median |e| {np.median(a):5.2f}  p90 |e| {np.percentile(a, 90):5.2f}  max |e| {a.max():5.2f}")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=parse_seeds, default=parse_seeds("0-9"))
    args = p.parse_args(argv)
    targets = Targets()
    print("measured minus true, degrees")
    for name in RUNS:
        t0 = time.perf_counter()
        new, old = measure(name, None, args.seeds), measure(name, OLD, args.seeds)
        print(f"{name} (seeds {args.seeds[0]}-{args.seeds[-1]}, {time.perf_counter() - t0:.0f} s)")
        for kind in new["errors"]:
            print(line(f"{kind}, default model", new["errors"][kind]))
            print(line(f"{kind}, old model (slip 3%)", old["errors"][kind]))
        print(f"  one dstate's true stops lie within {100 * new['stop_spread_m']:.1f} cm of their median "
              f"(old model {100 * old['stop_spread_m']:.1f} cm)")
        rms_new = float(np.sqrt(np.mean(new["errors"]["turn 90"] ** 2)))
        rms_old = float(np.sqrt(np.mean(old["errors"]["turn 90"] ** 2)))
        targets.check(f"{name}: RMS error of 90-degree turns", rms_new, ">=", 4.0, fmt="{:.2f}", unit=" deg")
        targets.check(f"{name}: RMS error of 90-degree turns", rms_new, "<=", 10.0, fmt="{:.2f}", unit=" deg")
        targets.check(f"{name}: ... against the old model's", rms_new / rms_old, ">=", 3.0, fmt="{:.1f}x", bound_text="3x")
        targets.check(f"{name}: stops of one dstate within", 100 * new["stop_spread_m"], "<", 5.0, fmt="{:.1f}",
                      unit=" cm")
    return targets.exit_status()


if __name__ == "__main__":
    sys.exit(main())
