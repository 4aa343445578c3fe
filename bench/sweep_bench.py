"""Cells per minute: a sweep on the local process pool against the serial loop (the target).

The cells are the paper's notched rectangle, the paper's run (``--circuits``, default 50: 400 images) over
``--seeds`` (default 1-60: a sweep long enough that starting the workers and writing the report, about
5 CPU-seconds in all, are not most of what is measured; with 20 cells of 20 circuits they were a quarter). The serial loop is what a researcher ran before sweeps: one process running
``run_experiment`` seed after seed (``bootmap experiment --seeds``), timed from its first cell. The pool is
``run_sweep`` with ``--workers`` (default 2), timed whole: starting the workers, forking every cell,
writing the table, summary and figures. The two alternate ``--repeat`` times (default 2), so a change in
the machine's load hits both; the ratio is taken between the medians. Target on this 2-core machine:
at least 1.8x the serial loop's cells per minute. Both tables must agree (the sweep is the same
experiment), and that is checked too.

``--old-threads N`` also times the serial loop on N seeds with the BLAS/OpenMP threading as it was
before sweeps (every thread pool at its default size): what a busy core did to one experiment.

Run: .venv/bin/python bench/sweep_bench.py [--seeds 1-60] [--circuits 50] [--workers 2] [--repeat 2] [--old-threads 4]
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import sys
import tempfile
import time
import warnings

from bootmap.arguments import seeds as parse_seeds
from bootmap.experiments.world import run_experiment
from bootmap.experiments.sweep import TIMING_COLUMNS, loads_spec, run_sweep
from bootmap.experiments.sweep.cells import experiment_row
from targets import Targets

SPEEDUP_TARGET = 1.8

SPEC = """
name = "bench"
[grid]
worlds = ["notched_rectangle"]
seeds = {seeds}
[run]
circuits = {circuits}
time_limit = 20
"""


def cpu_seconds() -> float:
    """CPU time of this process and of its children that have ended (the pool's workers, once it is shut
    down, with the cells they forked and waited for)."""
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def serial(spec, blas_threads: int | None = 1) -> tuple[float, float, list[dict]]:
    """Every cell in this process, one after another: wall seconds, CPU seconds and rows."""
    rows = []
    start, cpu = time.perf_counter(), cpu_seconds()
    for cell in spec.cells:
        r = run_experiment(cell.world, circuits=cell.circuits, seed=cell.seed, time_limit=cell.time_limit,
                           blas_threads=blas_threads)
        rows.append(experiment_row(cell, r))
    return time.perf_counter() - start, cpu_seconds() - cpu, rows


def pooled(spec, workers: int) -> tuple[float, float, list[dict]]:
    with tempfile.TemporaryDirectory() as out:
        start, cpu = time.perf_counter(), cpu_seconds()
        result = run_sweep(spec, out, workers=workers)
        seconds = time.perf_counter() - start
        print(f"          (pool: {result.seconds:.1f} s from starting the workers to the last cell's row; "
              f"then the table, summary and figures)", flush=True)
        return seconds, cpu_seconds() - cpu, result.table


def same(a: list[dict], b: list[dict]) -> bool:
    drop = set(TIMING_COLUMNS) | {"curve"}
    return [{k: v for k, v in r.items() if k not in drop} for r in a] == \
        [{k: v for k, v in r.items() if k not in drop} for r in b]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=parse_seeds, default=parse_seeds("1-60"))
    parser.add_argument("--circuits", type=int, default=50)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--old-threads", type=int, default=0, metavar="N")
    args = parser.parse_args()
    warnings.filterwarnings("ignore")
    spec = loads_spec(SPEC.format(seeds=args.seeds, circuits=args.circuits), "bench")
    n = len(spec.cells)
    print(f"{n} cells: notched_rectangle, {args.circuits} circuits, seeds {args.seeds[0]}-{args.seeds[-1]}; "
          f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at the start", flush=True)
    serial(loads_spec(SPEC.format(seeds=[0], circuits=2), "warm-up"))  # imports, caches: not the loop's cost
    times, cpu = {"serial": [], "pool": []}, {"serial": [], "pool": []}
    tables = {}
    for i in range(args.repeat):
        for name, run in (("serial", lambda: serial(spec)), ("pool", lambda: pooled(spec, args.workers))):
            seconds, cpu_s, tables[name] = run()
            times[name].append(seconds)
            cpu[name].append(cpu_s)
            print(f"  run {i + 1}: {name:6} {seconds:6.1f} s  {n / seconds * 60:6.1f} cells/min  "
                  f"CPU {cpu_s / n:5.2f} s/cell  load average {os.getloadavg()[0]:.2f}", flush=True)
    rate = {k: n / statistics.median(v) * 60 for k, v in times.items()}
    per_cell = {k: statistics.median(v) / n for k, v in cpu.items()}
    print(f"serial loop:          {rate['serial']:6.1f} cells/min, CPU {per_cell['serial']:.2f} s a cell "
          f"(medians of {args.repeat})")
    print(f"local pool, {args.workers} workers: {rate['pool']:6.1f} cells/min, CPU {per_cell['pool']:.2f} s a cell "
          f"(workers' start, warm-up and report included)")
    if args.old_threads:
        few = loads_spec(SPEC.format(seeds=args.seeds[:args.old_threads], circuits=args.circuits), "old")
        seconds, _, _ = serial(few, blas_threads=None)
        print(f"serial loop, default BLAS/OpenMP threads (as before sweeps), {args.old_threads} cells: "
              f"{args.old_threads / seconds * 60:6.1f} cells/min")
    print(f"load average at the end: {os.getloadavg()[0]:.2f} (other jobs on this machine count in it)")
    targets = Targets()
    targets.check(f"pool of {args.workers} / serial loop, cells per minute", rate["pool"] / rate["serial"], ">=",
                  SPEEDUP_TARGET, fmt="{:.2f}", unit="x")
    targets.check("the pool's table is the serial loop's", int(same(tables["serial"], tables["pool"])), "==", 1,
                  fmt="{}", bound_text="1 (same)")
    return targets.exit_status()


if __name__ == "__main__":
    sys.exit(main())
