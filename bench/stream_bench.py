"""Streaming maps: latency per appended step on a long exploration, against a full resolve.

A random grid world is explored step by step; after each step the map is brought up to date by
``MapStream.update`` (extend by determinism, checked by the replay or clingo; place a new transition's
end where the axioms accept it at one dstate only; resolve only when neither stands, from the dstates the
last map proved). A full resolve of the same prefix is timed on every ``--resolve-every``-th step for
comparison.

Targets (printed beside the figures; the exit status is 1 if any is missed): per streamed step p50 under
10 ms, p99 under 100 ms, the slowest under 500 ms.

    .venv/bin/python bench/stream_bench.py --steps 2000
"""

from __future__ import annotations

import sys
from pathlib import Path

import argparse
import time

import numpy as np
from tqdm import tqdm

from bootmap.errors import SolveTimeout
from bootmap.mapping import Resolver
from bootmap.mapping.stream import MapStream
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # tests/support: grid worlds, the checker
from support.gridworld import random_world, walk
from targets import Targets

#: Per streamed step (seconds): p50, p99, the slowest.
TARGETS_S = {50: 0.010, 99: 0.100, 100: 0.500}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--size", type=int, nargs=2, default=(6, 5), metavar=("W", "H"))
    ap.add_argument("--resolve-every", type=int, default=100)
    args = ap.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    world = random_world(rng, *args.size, extra_edges=4, landmarks=0.4)
    tableau = walk(world, args.steps, rng, policy="explore")
    stream, resolver = MapStream(Resolver(time_limit=60)), Resolver(time_limit=60)
    streamed, full, timeouts = [], [], []
    cmap = None
    for n in tqdm(range(1, args.steps + 1), desc="steps", unit="step"):
        prefix = tableau.prefix(n)
        t0 = time.perf_counter()
        try:
            cmap = stream.update(prefix)
        except SolveTimeout:  # the full resolve behind it ran out of time: so would a batch resolve
            timeouts.append(n)
        streamed.append(time.perf_counter() - t0)
        if n % args.resolve_every == 0:
            t0 = time.perf_counter()
            try:
                resolver.resolve(prefix)
            except SolveTimeout:
                pass
            full.append(time.perf_counter() - t0)
    ms = lambda xs, q: 1000 * float(np.percentile(xs, q))
    print(f"{args.steps}-step exploration of a {args.size[0]}x{args.size[1]} grid world (seed {args.seed}): "
          f"{cmap.n_dstates} dstates, {cmap.n_places} places, {cmap.n_paths} paths"
          f"{f'; resolves timed out at {len(timeouts)} steps (first t={timeouts[0]})' if timeouts else ''}")
    print(f"streamed: p50 {ms(streamed, 50):.0f} ms, p99 {ms(streamed, 99):.0f} ms, max {ms(streamed, 100):.0f} ms; "
          f"{stream.extended_} steps extended the map, {stream.joined_} placed a new transition's end, "
          f"{stream.resolved_} resolved")
    late = streamed[len(streamed) // 2:]
    print(f"streamed, second half: p50 {ms(late, 50):.0f} ms, p99 {ms(late, 99):.0f} ms")
    print(f"full resolve per step (every {args.resolve_every}th prefix): p50 {ms(full, 50):.0f} ms, "
          f"p99 {ms(full, 99):.0f} ms")
    print()
    targets = Targets()
    for q, bound in TARGETS_S.items():
        name = "slowest" if q == 100 else f"p{q}"
        targets.check(f"streamed step, {name}", ms(streamed, q), "<", 1000 * bound, fmt="{:.0f}", unit=" ms")
    return targets.exit_status()


if __name__ == "__main__":
    sys.exit(main())
