"""Views benchmark: wall time of the k sweep (k = 1..12, k-means + M + U) on the 400 images x 180 values of
50 notched_rectangle circuits, and the k it chooses.

Run: ``.venv/bin/python bench/views_bench.py`` (targets: the sweep under 1 s on 2 cores;
from the paper, k = 4 chosen by M and 4 the largest k with U = 1). Each target is printed beside the
measured figure; the exit status is 1 if any is missed.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from bootmap.sim import simulate
from bootmap.views import ViewClusterer
from targets import Targets

SWEEP_MAX_S = 1.0
PAPER_K = 4  # the paper's notched rectangle: M picks 4 views, and 4 is the largest k with U = 1


def main() -> int:
    targets = Targets()
    tableau = simulate("notched_rectangle", policy="circuits", circuits=50, seed=1)
    images = np.array([s.image for s in tableau.steps], dtype=float)
    dstates = [s.truth for s in tableau.steps]
    ViewClusterer(k_max=2).fit(images[:20])  # warm up imports and thread pools
    start = time.perf_counter()
    model = ViewClusterer(k_max=12, max_range=8.0, random_state=0).fit(images, dstates)
    wall = time.perf_counter() - start
    print(f"k sweep 1..12 on {images.shape[0]} images x {images.shape[1]} values: {wall:.3f} s wall")
    print("M:", " ".join(f"{k}:{m:.3f}" for k, m in zip(model.ks_, model.internal_)))
    print("U:", " ".join(f"{k}:{u:.3f}" for k, u in zip(model.ks_, model.uncertainty_)))
    targets.check("k sweep, wall", wall, "<", SWEEP_MAX_S, fmt="{:.3f}", unit=" s")
    targets.check("chosen k (argmax M)", model.k_, "==", PAPER_K, fmt="{}")
    targets.check("largest k with U = 1", model.largest_k_with_u1_, "==", PAPER_K, fmt="{}")
    return targets.exit_status()


if __name__ == "__main__":
    sys.exit(main())
