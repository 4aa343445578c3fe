"""Tableaux made elsewhere: the same experience written as other software might write it, the same map.

For each seed, a tableau (the paper's notched rectangle, 8-12 circuits, or an exploration of a random
4 x 4 grid world, 150-210 steps) is read with odometry noise (turns sd 3 degrees, travel drift 1.2,
distances 3%, recorded to the centimetre and the tenth of a degree), then written other ways: turns from 0
to 360 degrees, travels without heading changes, every reading to three significant figures, distances in
feet, a gyro that reads every turn 6% long, 7% short, 9% long with turns wrapped into (-180, 180], 5% short
with distances in feet. The resolver (20 s limit) must give each the map it gives the tableau as written
here (printed beside: how often that map is the truth).

Target: every variant's map the same (time points in the same dstates, best one-to-one renaming). Exits 1
on a miss. Run: PYTHONPATH=py:bench:tests .venv/bin/python bench/formats_bench.py [--seeds 54400-54439]
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace

import numpy as np

from bootmap import examples
from bootmap.arguments import seeds as parse_seeds
from bootmap.errors import BootmapError
from bootmap.mapping.resolver import Resolver
from bootmap.metrics import dstate_accuracy
from bootmap.tableau import Tableau, Travel, Turn
from support.gridworld import random_world, walk
from support.noise import with_odometry_noise
from targets import Targets

FEET = 3.28084


def _actions(tableau: Tableau, turn=lambda a: a, travel=lambda a: a) -> Tableau:
    """The tableau with each turn and travel rewritten."""
    steps = [s if s.action is None else replace(s, action=turn(s.action) if isinstance(s.action, Turn)
                                                else travel(s.action)) for s in tableau.steps]
    return Tableau(tuple(steps), tableau.world, dict(tableau.meta))


def _figures(x: float, n: int = 3) -> float:
    return float(f"{x:.{n}g}") if x else 0.0


def _scaled(k: float, wrap: bool = False):
    def turn(a: Turn) -> Turn:
        angle = a.angle_deg * k
        return Turn(round((angle + 180.0) % 360.0 - 180.0 if wrap else angle, 1))
    return turn


def _feet(a: Travel) -> Travel:
    return Travel(round(a.distance_m * FEET, 2), a.heading_change_deg)


VARIANTS = {
    "turns 0..360": lambda t: _actions(t, turn=lambda a: Turn(a.angle_deg % 360.0)),
    "no heading changes": lambda t: _actions(t, travel=lambda a: Travel(a.distance_m)),
    "3 significant figures": lambda t: _actions(t, turn=lambda a: Turn(_figures(a.angle_deg)),
                                                travel=lambda a: Travel(_figures(a.distance_m),
                                                                        _figures(a.heading_change_deg))),
    "feet": lambda t: _actions(t, travel=_feet),
    "gyro 6% long": lambda t: _actions(t, turn=_scaled(1.06)),
    "gyro 7% short": lambda t: _actions(t, turn=_scaled(0.93)),
    "gyro 9% long, wrapped": lambda t: _actions(t, turn=_scaled(1.09, wrap=True)),
    "gyro 5% short, feet": lambda t: _actions(t, turn=_scaled(0.95), travel=_feet),
}


def experience(seed: int) -> tuple[Tableau, list]:
    """The seed's tableau, read with odometry noise and recorded as a log records it, and its truth."""
    rng = np.random.default_rng(seed)
    if seed % 3 == 0:
        clean = examples.notched_rectangle(circuits=8 + seed % 5)
    else:
        clean = walk(random_world(rng, 4, 4, extra_edges=seed % 3, landmarks=0.4), 150 + 20 * (seed % 4), rng,
                     policy="explore")
    return with_odometry_noise(clean, 3.0, 1.2, rng, distance_sd=0.03), [s.truth for s in clean.steps]


def _dstates(tableau: Tableau):
    try:
        return Resolver(time_limit=20).resolve(tableau).dstate_of
    except BootmapError as e:
        print(f"    {type(e).__name__}: {e}", flush=True)
        return None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="54400-54439", help="seeds, e.g. 54400-54439 (default)")
    args = ap.parse_args(argv)
    seeds = parse_seeds(args.seeds)
    same = {name: 0 for name in VARIANTS}
    true = 0
    for seed in seeds:
        tableau, truth = experience(seed)
        written = _dstates(tableau)
        true += written is not None and dstate_accuracy(truth, written) == 1.0
        for name, variant in VARIANTS.items():
            dstates = _dstates(variant(tableau))
            ok = written is not None and dstates is not None and dstate_accuracy(written, dstates) == 1.0
            same[name] += ok
            if not ok:
                print(f"  seed {seed}, {name}: not the map of the tableau as written here", flush=True)
    print(f"{len(seeds)} seeds; the map as written here is the truth on {true}")
    targets = Targets()
    for name in VARIANTS:
        targets.check(f"maps as written here, {name}", same[name], "==", len(seeds), fmt="{}")
    return targets.exit_status()


if __name__ == "__main__":
    sys.exit(main())
