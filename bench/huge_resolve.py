"""One long walk resolved in a process of its own: its time and peak memory (the resolve bench's --huge row).

The process imports what resolving needs (the resolver, clingo, numpy) and the grid walk, and nothing the
resolve bench's other rows do (scikit-learn's metrics for the accuracy, AALpy for RPNI: 85 MiB more): its
peak memory is the walk's and the resolve's. The accuracy against the walk's truth is worked out after the
peak is read.

Run: .venv/bin/python bench/huge_resolve.py [STEPS]   (prints one JSON line; resolve_bench.py --huge reads it)
"""

from __future__ import annotations

import json
import resource
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # tests/support: grid worlds
from bootmap.mapping.resolver import Resolver
from support.gridworld import random_world, walk


def grid_walk(n: int):
    """The resolve bench's 5x5 grid walk with landmarks (the same seed)."""
    rng = np.random.default_rng(7)
    return walk(random_world(rng, 5, 5, extra_edges=3, landmarks=0.3), n, rng, policy="explore")


def peak_mib() -> float:
    """This process's peak resident memory so far (MiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def huge(steps: int) -> dict:
    """Resolve the walk of ``steps`` steps: its time, dstates, whether proved minimal, the share of time
    points in their true dstate, and the peak memory (MiB) with the walk alone and after resolving."""
    tableau = grid_walk(steps)
    before = peak_mib()
    t0 = time.perf_counter()
    cmap = Resolver(time_limit=600).resolve(tableau)
    seconds = time.perf_counter() - t0
    peak = peak_mib()
    from bootmap.metrics import dstate_accuracy  # (scikit-learn: after the peak is read)

    accuracy = dstate_accuracy([s.truth for s in tableau.steps], cmap.dstate_of)
    return {"steps": steps, "seconds": seconds, "dstates": cmap.n_dstates, "minimal": cmap.minimal,
            "accuracy": accuracy, "ground_s": cmap.stats.ground_s, "solve_s": cmap.stats.solve_s,
            "walk_mb": before, "peak_mb": peak}


if __name__ == "__main__":
    print(json.dumps(huge(int(sys.argv[1]) if len(sys.argv) > 1 else 100_000)))
