"""Odometry noise against the map: learned action types beside a fixed 15-degree quantum and RPNI.

600-step explorations of random 20-place grid worlds (5 x 4, landmarks on 40% of the places), read with
turn noise of sd 0-12 degrees and travel drift of sd 0-4 degrees (bootmap.testing.noise); for each level,
3 seeds. Ours (action types learned, the default), ours with ``--quantum 15`` (the rounding used before),
and AALpy's RPNI with views + dead-reckoned heading (rounded to 15 degrees, as bench/resolve_bench.py
feeds it), all against the truth: dstates found, time points on their true dstate (best one-to-one
renaming), seconds.

Targets (issue 12): the true map on every tableau up to 10 degrees of turn noise, each in under 5 s.
Writes docs/noise_sweep.png. Run: .venv/bin/python bench/noise_bench.py
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from bootmap.errors import SolveTimeout
from bootmap.mapping.resolver import Resolver
from bootmap.metrics import dstate_accuracy
from bootmap.testing.check import true_partition
from bootmap.testing.gridworld import random_world, walk
from bootmap.testing.noise import with_odometry_noise
from resolve_bench import rpni
from targets import Targets

TURN_SD = (0, 3, 6, 10, 12)
SEEDS = (21, 22, 23)
STEPS = 600
EXACT_UP_TO_DEG, MAX_S = 10, 5.0
FIGURE = Path(__file__).resolve().parents[1] / "docs" / "noise_sweep.png"


def tableaux(turn_sd: float):
    for seed in SEEDS:
        rng = np.random.default_rng(seed)
        world = random_world(rng, 5, 4, extra_edges=4, landmarks=0.4)
        yield seed, with_odometry_noise(walk(world, STEPS, rng, policy="explore"), turn_sd,
                                        min(4.0, turn_sd / 2.5), rng)


def run(resolver: Resolver, tableau) -> tuple[int | None, float, float]:
    truth = true_partition(tableau)
    t0 = time.perf_counter()
    try:
        cmap = resolver.resolve(tableau)
    except SolveTimeout as e:
        best = e.best_map
        return (None if best is None else best.n_dstates), \
            (0.0 if best is None else dstate_accuracy(truth, best.dstate_of)), time.perf_counter() - t0
    return cmap.n_dstates, dstate_accuracy(truth, cmap.dstate_of), time.perf_counter() - t0


def main() -> int:
    targets = Targets()
    learned, fixed = Resolver(time_limit=30), Resolver(quantum_deg=15, time_limit=10)
    print(f"{'turn sd':>7} {'drift':>5} {'seed':>4} {'true':>4} | {'ours':>5} {'acc':>6} {'s':>5} | "
          f"{'q=15':>5} {'acc':>6} {'s':>5} | {'rpni':>5} {'acc':>6} {'s':>5}")
    rows = []
    for sd in TURN_SD:
        for seed, tableau in tableaux(sd):
            truth = true_partition(tableau)
            ours, q15 = run(learned, tableau), run(fixed, tableau)
            states, rpni_s = rpni(tableau, with_heading=True)
            theirs = (len(set(states)), dstate_accuracy(truth, states), rpni_s)
            rows.append((sd, ours, q15, theirs))
            cells = [f"{'-' if n is None else n:>5} {acc:>6.1%} {s:>5.2f}" for n, acc, s in (ours, q15, theirs)]
            print(f"{sd:>7} {min(4.0, sd / 2.5):>5.1f} {seed:>4} {len(set(truth)):>4} | " + " | ".join(cells))
            if sd <= EXACT_UP_TO_DEG:
                targets.check(f"  ours, turn sd {sd}, seed {seed}: time points right", ours[1], "==", 1.0,
                              fmt="{:.1%}", bound_text="100%")
                targets.check(f"  ours, turn sd {sd}, seed {seed}: seconds", ours[2], "<", MAX_S, fmt="{:.2f}")
    print("\n'-': no map within the time limit (q=15: 10 s); accuracy then of the best map found, if any")
    _figure(rows)
    return targets.exit_status()


def _figure(rows) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.5))
    for i, (label, style) in enumerate((("ours (learned action types)", "o-"), ("ours, --quantum 15", "s--"),
                                        ("RPNI, views + heading", "^:"))):
        means = [np.mean([r[1 + i][1] for r in rows if r[0] == sd]) for sd in TURN_SD]
        ax.plot(TURN_SD, means, style, label=label)
    ax.set_xlabel("turn noise, sd (degrees); travel drift sd = min(4, turn / 2.5)")
    ax.set_ylabel("time points on their true dstate")
    ax.set_ylim(0, 1.05)
    ax.set_title(f"{STEPS}-step explorations of 20-place grid worlds, {len(SEEDS)} seeds")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(FIGURE, dpi=110)
    plt.close(fig)
    print(f"figure: {FIGURE.relative_to(FIGURE.parents[1])}")


if __name__ == "__main__":
    sys.exit(main())
