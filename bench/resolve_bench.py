"""Resolver speed and accuracy beside AALpy's passive RPNI, on the same tableaux.

For each tableau: our resolve time (ground, solve, total), dstates found and accuracy against the truth
(best one-to-one renaming); then AALpy's RPNI (generalised state merging, Moore machine) learning from
the same steps with outputs = views, and outputs = views + heading: its states, accuracy and time.

Targets (docs/results/benchmarks.md): the paper's 401-step tableau resolved in under 0.1 s; 10,000 steps in under
10 s; our map always the true one (100% of time points on their true dstate, proved minimal, on every
tableau); no time-out (10 s) on the aliased 30-step walks; within 10 times RPNI's time where both are
right. Each is printed beside the measured figure; the exit status is 1 if any is missed.

Every family is also read by a robot: turns with noise of sd 3 degrees, travels' heading with 1.2 and
their length 3% off (support.noise), unrounded and recorded as a log records them (centimetres, tenths
of a degree): the same targets of accuracy hold for both.

Run: make bench   (or .venv/bin/python bench/resolve_bench.py [--quick] [--huge] [--search-map-levels]; --huge adds a
100,000-step walk: under 20 s and 1 GiB is its target; --search-map-levels grounds the topological level
with every search, as the resolver did before it was asked of each map found, for comparison)
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
import time

import numpy as np

from bootmap import examples
from bootmap.errors import SolveTimeout
from bootmap.mapping.motion import quantise
from bootmap.metrics import dstate_accuracy
from bootmap.mapping.resolver import Resolver
from bootmap.tableau import Tableau, Turn
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # tests/support: grid worlds, the checker
from support.check import tableau_headings
from support.gridworld import random_world, walk
from support.noise import LOGGED, with_odometry_noise
from huge_resolve import grid_walk
from targets import Targets


NO_METRICAL = ["causal", "topological"]
PAPER_MAX_S = 0.1  # the paper's 401-step tableau, resolved
LARGE_STEPS, LARGE_MAX_S = 10_000, 2.0  # the largest grid walk, resolved
# --huge: a 100,000-step walk resolved in a process of its own (bench/huge_resolve.py: its peak memory
# is the walk's and the resolve's)
HUGE_STEPS, HUGE_MAX_S, HUGE_MAX_MB = 100_000, 20.0, 1024.0
ALIASED_TIME_LIMIT_S = 10.0
RATIO_MAX = 3.0  # ours / RPNI where both find the true map (at 401, 2,001 and 5,001 steps)


def rpni(tableau: Tableau, with_heading: bool) -> tuple[list, float]:
    """AALpy GSM (RPNI) on the tableau as one Moore trace; the state it puts each time point in.

    Timed like our resolver, from the tableau to a state per time point: building the trace, learning,
    and running the learned machine along the trace."""
    from aalpy.learning_algs import run_GSM

    t0 = time.perf_counter()
    outs = list(zip(tableau.views, tableau_headings(tableau))) if with_heading else tableau.views
    ins = [f"turn{quantise(a.angle_deg, 15.0)}" if isinstance(a, Turn) else "travel" for a in tableau.actions]
    trace = [outs[0]] + list(zip(ins, outs[1:]))
    model = run_GSM([trace], output_behavior="moore", data_format="io_traces")
    model.reset_to_initial()
    states = [model.current_state.state_id]
    for i in ins:
        model.step(i)
        states.append(model.current_state.state_id)
    return states, time.perf_counter() - t0


def cases(quick: bool):
    yield "paper notched rectangle", examples.notched_rectangle(circuits=50)
    yield "paper, no metrical level", examples.notched_rectangle(circuits=50), NO_METRICAL
    sizes = (1_000,) if quick else (1_000, 5_000, 10_000)
    for n in sizes:
        yield f"5x5 grid, landmarks, {n} steps", grid_walk(n)
    n = 500 if quick else 2_000
    yield f"4x4 grid, no landmarks, {n} steps", aliased_grid_walk(n)
    yield from read_by_a_robot(quick)


def aliased_grid_walk(n: int) -> Tableau:
    rng = np.random.default_rng(3)
    return walk(random_world(rng, 4, 4, extra_edges=2, landmarks=0.0), n, rng, policy="explore")


#: Odometry's noise on the families read by a robot: turn sd, drift sd (degrees), length error (share).
ROBOT_NOISE = (3.0, 1.2, 0.03)


def read_by_a_robot(quick: bool):
    """The same walks again, as a robot's odometry reads them (:data:`ROBOT_NOISE`), unrounded and as
    logged; the same noise either way."""
    n = 500 if quick else 2_000
    families = [("paper", examples.notched_rectangle(circuits=50)), ("5x5 grid, 1000 steps", grid_walk(1_000)),
                (f"4x4 grid, no landmarks, {n} steps", aliased_grid_walk(n))]
    for name, clean in families:
        for how, rounding in (("unrounded", None), ("as logged", LOGGED)):
            yield f"{name}, noisy, {how}", with_odometry_noise(clean, *ROBOT_NOISE[:2], np.random.default_rng(11),
                                                                distance_sd=ROBOT_NOISE[2], rounding=rounding)


def aliased_walks(count: int):
    """Short walks on small grids without landmarks: heavy aliasing, and no headings to help."""
    for seed in range(count):
        rng = np.random.default_rng(seed)
        world = random_world(rng, 3 + seed % 2, 3 + (seed // 2) % 2, extra_edges=seed % 4, landmarks=0.0)
        yield walk(world, 30, rng, policy="random" if seed % 3 else "explore")


def aliasing_sweep(count: int, targets: Targets, defer: bool = True) -> None:
    resolver = Resolver(levels=NO_METRICAL, time_limit=ALIASED_TIME_LIMIT_S, defer_map_levels=defer)
    times, timeouts = [], 0
    for tableau in aliased_walks(count):
        t0 = time.perf_counter()
        try:
            resolver.resolve(tableau)
        except SolveTimeout:
            timeouts += 1
        times.append(time.perf_counter() - t0)
    q = np.percentile(times, [50, 90, 100])
    print(f"\n{count} aliased 30-step walks on 3x3/4x4 grids, no landmarks, levels causal+topological: "
          f"median {q[0]:.2f} s, p90 {q[1]:.2f} s, max {q[2]:.2f} s, time-outs (10 s) {timeouts}")
    targets.check(f"  time-outs ({ALIASED_TIME_LIMIT_S:.0f} s) on the aliased walks", timeouts, "==", 0, fmt="{}")


def ratio_where_both_are_right(targets: Targets, sizes=(50, 250, 625), runs: int = 30) -> None:
    """Ours against RPNI (views + heading) where both find the true map: the notched rectangle at
    several lengths, the two timed alternately, many times (milliseconds are noisy)."""
    print("\nwhere both are right (notched rectangle, views + heading for RPNI), medians of", runs, "alternating runs:")
    resolver = Resolver()
    for circuits in sizes:
        tableau = examples.notched_rectangle(circuits)
        truth = [s.truth for s in tableau.steps]
        ours, theirs = [], []
        for _ in range(runs + 3):
            t0 = time.perf_counter()
            cmap = resolver.resolve(tableau)
            ours.append(time.perf_counter() - t0)
            states, elapsed = rpni(tableau, with_heading=True)
            theirs.append(elapsed)
        assert dstate_accuracy(truth, cmap.dstate_of) == 1.0 and dstate_accuracy(truth, states) == 1.0
        o, r = np.median(ours[3:]), np.median(theirs[3:])
        print(f"  {len(tableau):>5} steps: ours {o * 1000:7.1f} ms, RPNI {r * 1000:6.1f} ms, ours / RPNI = {o / r:4.1f}")
        targets.check(f"  ours / RPNI, {len(tableau)} steps", o / r, "<=", RATIO_MAX, fmt="{:.1f}", unit="x")


def huge_row(targets: Targets, steps: int = HUGE_STEPS) -> None:
    """The walk of ``steps`` steps resolved in a child process; its figures against the targets."""
    import json
    import subprocess

    child = Path(__file__).with_name("huge_resolve.py")
    out = subprocess.run([sys.executable, str(child), str(steps)], capture_output=True, text=True, check=True)
    r = json.loads(out.stdout.strip().splitlines()[-1])
    print(f"\n5x5 grid, landmarks, {steps} steps: {r['dstates']} dstates, proved minimal {r['minimal']}, "
          f"{r['seconds']:.1f} s (ground {r['ground_s']:.1f}, solve {r['solve_s']:.1f}), peak memory "
          f"{r['peak_mb']:.0f} MiB (the tableau alone {r['walk_mb']:.0f})")
    targets.check(f"ours, {steps} steps: time", r["seconds"], "<", HUGE_MAX_S, fmt="{:.1f}", unit=" s")
    targets.check(f"ours, {steps} steps: peak memory", r["peak_mb"], "<", HUGE_MAX_MB, fmt="{:.0f}", unit=" MiB")
    targets.check(f"ours, {steps} steps: proved minimal", r["minimal"], "==", True, fmt="{}", bound_text="True")
    targets.check(f"ours, {steps} steps: accuracy", r["accuracy"], "==", 1.0, fmt="{:.1%}", bound_text="100%")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small tableaux only")
    ap.add_argument("--repeat", type=int, default=3, help="resolves per tableau; the median is printed")
    ap.add_argument("--huge", action="store_true", help=f"also a {HUGE_STEPS:,}-step walk (a minute or more, "
                    "over a GiB of memory)")
    ap.add_argument("--search-map-levels", action="store_true",
                    help="search with the levels that judge the map alone (the topological one) instead of "
                         "asking them of each map found: Resolver(defer_map_levels=False), for comparison")
    args = ap.parse_args(argv)
    head = (f"{'tableau':52} {'steps':>6} {'true':>5} | {'ours':>5} {'acc':>6} {'ground':>7} {'solve':>7} {'total':>7}"
            f" {'uniq':>5} | {'rpni(v)':>7} {'acc':>6} {'time':>7} | {'rpni(v+h)':>9} {'acc':>6} {'time':>7}")
    print(head)
    print("-" * len(head))
    targets, rows = Targets(), []
    for name, tableau, *levels in cases(args.quick):
        resolver = Resolver(levels=levels[0] if levels else None, time_limit=120,
                            defer_map_levels=not args.search_map_levels)
        truth = [s.truth for s in tableau.steps]
        runs = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            cmap = resolver.resolve(tableau)
            runs.append((time.perf_counter() - t0, cmap))
        total, cmap = sorted(runs, key=lambda r: r[0])[len(runs) // 2]
        v_states, v_time = rpni(tableau, with_heading=False)
        h_states, h_time = rpni(tableau, with_heading=True)
        print(f"{name:52} {len(tableau):>6} {len(set(truth)):>5} | {cmap.n_dstates:>5} "
              f"{dstate_accuracy(truth, cmap.dstate_of):>6.1%} {cmap.stats.ground_s:>7.3f} "
              f"{cmap.stats.solve_s:>7.3f} {total:>7.3f} {str(cmap.unique):>5} | "
              f"{len(set(v_states)):>7} {dstate_accuracy(truth, v_states):>6.1%} {v_time:>7.3f} | "
              f"{len(set(h_states)):>9} {dstate_accuracy(truth, h_states):>6.1%} {h_time:>7.3f}")
        sys.stdout.flush()
        rows.append((name, len(tableau), levels, cmap, dstate_accuracy(truth, cmap.dstate_of), total))
    print("\ntimes in seconds; accuracy = time points in their true dstate under the best one-to-one renaming;"
          "\n'true' = distinct true dstates visited; ours: median of", args.repeat, "resolves, proved minimal and"
          " (uniq) unique\n")
    for name, steps, levels, cmap, accuracy, total in rows:
        targets.check(f"ours, {name}: accuracy", accuracy, "==", 1.0, fmt="{:.1%}", bound_text="100%")
        targets.check(f"ours, {name}: proved minimal", cmap.minimal, "==", True, fmt="{}", bound_text="True")
        if name == "paper notched rectangle":
            targets.check(f"ours, {name}: time", total, "<", PAPER_MAX_S, fmt="{:.3f}", unit=" s")
        if steps == LARGE_STEPS:
            targets.check(f"ours, {name}: time", total, "<", LARGE_MAX_S, fmt="{:.1f}", unit=" s")
    aliasing_sweep(10 if args.quick else 40, targets, defer=not args.search_map_levels)
    ratio_where_both_are_right(targets, (50,) if args.quick else (50, 250, 625))
    if args.huge:
        huge_row(targets)
    return targets.exit_status()


if __name__ == "__main__":
    sys.exit(main())
