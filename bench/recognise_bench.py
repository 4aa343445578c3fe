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

``--laser``: recognition under a noisier laser instead. Both worlds on seeds 3000-3009 (no setting was
chosen on them; ``--seeds A-B`` for others) with the laser's range noise and drop-outs as shipped, doubled
and quadrupled; the despiked discriminant (:class:`bootmap.learners.DespikedDiscriminant`), the aligned
one (:class:`bootmap.learners.AlignedDiscriminant`), the nearest aligned mean
(:class:`bootmap.learners.AlignedNearestMean`) and the experiment's learner, which chooses between the last
two by inner folds (:class:`bootmap.learners.ChosenByFolds`), beside the paper's 1-NN, each by 10-fold CV at
90 images, true labels. Targets for the experiment's learner: at least 85% at twice the noise and 75% at
four times, in the mean over seeds, on both worlds. A run whose control law gets stuck is counted and left out.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from threadpoolctl import threadpool_limits

from bootmap.recognise import compare_clusterers, compare_learners, default_learners, learning_curve_cv, online_curve
from bootmap.experiments.world import NN_TARGET
from bootmap.sim import SimulationError, simulate
from bootmap.sim.world import load_world
from targets import Targets

LASER = (("1x", 0.01, 0.001, None), ("2x", 0.02, 0.002, 0.85), ("4x", 0.04, 0.004, 0.75))
LASER_SEEDS = range(3000, 3010)

RUNS = (("notched_rectangle", {"policy": "circuits", "circuits": 50}, (4, 8)),
        ("taylor_hall", {"policy": "explore", "steps": 100}, (8, 20)))


#: The learners of ``--laser``, by the name printed: the paper's nearest neighbour (None), the two discriminants,
#: the nearest aligned mean, and the experiment's learner, which chooses between those two by inner folds.
LASER_LEARNERS = ("1-NN", "despiked LDA", "aligned LDA", "aligned mean", "aligned by folds")


def laser_noise(targets: Targets, seeds=LASER_SEEDS) -> None:
    """Each of :data:`LASER_LEARNERS` at 90 images, per world and laser noise, over ``seeds``."""
    print(f"{'world':18} {'laser':>5} {'runs':>4} {'stuck':>5} | "
          + " | ".join(f"{name:>16} {'min':>4}" for name in LASER_LEARNERS))
    for world, kw, _ in RUNS:
        for name, noise_sd, dropout, target in LASER:
            spec = load_world(world, {"laser.noise_sd": noise_sd, "laser.dropout": dropout})
            scores, stuck = [], 0
            for seed in seeds:
                try:
                    tableau = simulate(spec, seed=seed, **kw)
                except SimulationError:
                    stuck += 1
                    continue
                X = np.array([s.image for s in tableau.steps])
                y = np.array([str(s.truth) for s in tableau.steps])
                learners = default_learners(seed)
                with threadpool_limits(1):
                    scores.append([learning_curve_cv(X, y, sizes=(90,), random_state=seed,
                                                     learner=None if learner == "1-NN" else learners[learner]).at(90)
                                   for learner in LASER_LEARNERS])
            a = np.array(scores)
            print(f"{world:18} {name:>5} {len(a):>4} {stuck:>5} | "
                  + " | ".join(f"{a[:, i].mean():>7.1%} +- {a[:, i].std():>4.1%} {a[:, i].min():>4.0%}"
                               for i in range(len(LASER_LEARNERS))), flush=True)
            if target is not None:
                targets.check(f"  {world}, {name} laser: {LASER_LEARNERS[-1]} at 90 images", a[:, -1].mean(), ">=",
                              target, fmt="{:.1%}", bound_text=f"{target:.0%}")


def main() -> int:
    targets = Targets()
    if "--laser" in sys.argv[1:]:
        seeds = LASER_SEEDS
        if "--seeds" in sys.argv[1:]:
            first, _, last = sys.argv[sys.argv.index("--seeds") + 1].partition("-")
            seeds = range(int(first), int(last or first) + 1)
        laser_noise(targets, seeds)
        return targets.exit_status()
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
        print(f"{'learner':<16} {'acc@30':>7} {'acc@60':>7} {'acc@90':>7} {'fit ms @90':>11}")
        for r in rows:
            print(f"{r['learner']:<16} {r['acc@30']:7.3f} {r['acc@60']:7.3f} {r['acc@90']:7.3f} "
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
