"""Recognition benchmark: supervised learners and clusterers on the paper's two worlds.

Run: ``.venv/bin/python bench/recognise_bench.py``. Simulates 50 notched_rectangle circuits and 100
taylor_hall dstates (seed 1), and for each prints the 1-NN online and CV accuracy at 90 images (paper:
about 90%, and 88% in Taylor Hall), 10-fold cross-validated accuracy (shuffled folds and training
subsets) of every learner at 30/60/90 training images with the mean fit time at 90, and the clusterers'
U(V|S) and adjusted Rand index at the paper's number of views and at one view per dstate. Labels are the
true dstates.

Targets, from the paper: 1-NN at 90 images (10-fold CV) at least 85% on both worlds (it reports about
90% and 88%); k-means at the paper's number of views removes all image variability (U(V|S) = 1). Each is
printed beside the measured figure; the exit status is 1 if any is missed.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from bootmap.recognise import compare_clusterers, compare_learners, learning_curve_cv, online_curve
from bootmap.experiments.world import NN_TARGET
from bootmap.sim import simulate
from targets import Targets

RUNS = (("notched_rectangle", {"policy": "circuits", "circuits": 50}, (4, 8)),
        ("taylor_hall", {"policy": "explore", "steps": 100}, (8, 20)))


def main() -> int:
    targets = Targets()
    for world, kw, ks in RUNS:
        tableau = simulate(world, seed=1, **kw)
        X = np.array([s.image for s in tableau.steps])
        y = np.array([s.truth for s in tableau.steps])
        print(f"{world}, seed 1: {len(y)} images, {len(set(y))} dstates\n")

        start = time.perf_counter()
        online = online_curve(X, y)
        t_online = time.perf_counter() - start
        start = time.perf_counter()
        cv = learning_curve_cv(X, y, random_state=0)
        t_cv = time.perf_counter() - start
        print(f"1-NN online accuracy after 90 images: {online[89]:.3f}  (after {len(y)}: {online[-1]:.3f}; "
              f"{t_online * 1e3:.1f} ms)")
        print(f"1-NN 10-fold CV accuracy at 90 images: {cv.at(90):.3f} +- {cv.std[cv.sizes == 90][0]:.3f}  "
              f"(curve over {len(cv.sizes)} sizes: {t_cv:.2f} s)")
        targets.check(f"{world}: 1-NN 10-fold CV accuracy at 90 images", cv.at(90), ">=", NN_TARGET, fmt="{:.3f}")
        print()

        rows = compare_learners(X, y, at=(30, 60, 90), random_state=0)
        print(f"{'learner':<12} {'acc@30':>7} {'acc@60':>7} {'acc@90':>7} {'fit ms @90':>11}")
        for r in rows:
            print(f"{r['learner']:<12} {r['acc@30']:7.3f} {r['acc@60']:7.3f} {r['acc@90']:7.3f} "
                  f"{r['fit_time'][-1] * 1e3:11.2f}")
        print()
        print(f"{'clusterer':<26} {'k':>2} {'U(V|S)':>7} {'ARI':>6} {'fit ms':>8}")
        paper_k = ks[0]
        for k in ks:
            for r in compare_clusterers(X, y, k=k, random_state=0):
                print(f"{r['clusterer']:<26} {k:>2} {r['U']:7.3f} {r['ari']:6.3f} {r['fit_time'] * 1e3:8.1f}")
                if k == paper_k and r["clusterer"] == "k-means":
                    kmeans_u = r["U"]
        targets.check(f"{world}: k-means U(V|S) at the paper's {paper_k} views", kmeans_u, "==", 1.0, fmt="{:.3f}",
                      bound_text="1")
        print()
    return targets.exit_status()


if __name__ == "__main__":
    sys.exit(main())
