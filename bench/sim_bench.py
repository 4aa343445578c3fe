"""Simulator benchmark: simulated seconds per wall second, wall time for 50 notched-rectangle circuits,
and microseconds per 180-beam laser scan against 100 wall segments.

Run: ``.venv/bin/python bench/sim_bench.py`` (targets: 50 circuits under 3 s wall; a scan
against 100 segments under 100 us). Each target is printed beside the measured figure; the exit status
is 1 if any is missed.
"""

from __future__ import annotations

import math
import sys
import time

import numpy as np

from bootmap.sim import run
from bootmap.sim.laser import Scene, SweepCaster, build_space, cast_reference
from bootmap.sim.world import load_world
from targets import Targets

CIRCUITS_MAX_S = 3.0  # 50 notched_rectangle circuits, wall time
SCAN_MAX_US = 100.0  # one 180-beam scan against 100 segments, the sweep caster


def per_call_us(fn, repeat: int) -> float:
    fn()
    start = time.perf_counter()
    for _ in range(repeat):
        fn()
    return (time.perf_counter() - start) / repeat * 1e6


def office_segments(n: int, rng: np.random.Generator) -> np.ndarray:
    """n wall segments 0.3-2 m long, scattered over 20 m x 20 m around the sensor."""
    start = rng.uniform(-10, 10, (n, 2))
    angle = rng.uniform(0, 2 * math.pi, n)
    length = rng.uniform(0.3, 2.0, n)
    end = start + length[:, None] * np.column_stack([np.cos(angle), np.sin(angle)])
    return np.hstack([start, end])


def main() -> int:
    targets = Targets()
    run("notched_rectangle", circuits=1, seed=0)  # warm up imports and caches
    result = run("notched_rectangle", circuits=50, seed=1)
    print(f"50 notched_rectangle circuits: {result.wall_time:.2f} s wall, {result.sim_time:.0f} s simulated, "
          f"{len(result.tableau)} dstates")
    targets.check("  50 notched_rectangle circuits, wall", result.wall_time, "<", CIRCUITS_MAX_S, fmt="{:.2f}",
                  unit=" s")
    print(f"simulated seconds per wall second: {result.sim_time / result.wall_time:.0f}")
    taylor = run("taylor_hall", policy="explore", seed=1)
    print(f"taylor_hall exploration: {taylor.wall_time:.2f} s wall, {taylor.sim_time:.0f} s simulated, "
          f"{taylor.sim_time / taylor.wall_time:.0f} sim s per wall s")

    angles = np.linspace(-math.pi / 2, math.pi / 2, 180)
    scene = Scene(office_segments(100, np.random.default_rng(0)), np.zeros((0, 3)))
    caster = SweepCaster(angles, 8.0)
    space = build_space(scene)
    fast = per_call_us(lambda: caster.cast(scene, 0.1, 0.2, 0.3), 3000)
    ref = per_call_us(lambda: cast_reference(space, angles, 8.0, 0.1, 0.2, 0.3), 100)
    print(f"180-beam scan, 100 segments: sweep caster {fast:.0f} us, pymunk segment_query_first {ref:.0f} us")
    targets.check("  180-beam scan, 100 segments, sweep caster", fast, "<", SCAN_MAX_US, fmt="{:.0f}", unit=" us")
    w = load_world("taylor_hall")
    hall = Scene.of_world(w)
    hall_caster = SweepCaster(w.laser.angles, w.laser.range_max)
    print(f"180-beam scan in taylor_hall ({len(hall.segments)} segments, {len(hall.discs)} discs): "
          f"{per_call_us(lambda: hall_caster.cast(hall, 30.0, 1.2, 0.0), 3000):.0f} us")
    return targets.exit_status()


if __name__ == "__main__":
    sys.exit(main())
