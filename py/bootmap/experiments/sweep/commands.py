"""The ``sweep`` sub-command; :func:`register` adds it to the ``bootmap`` command.

``bootmap sweep SPEC.toml -o DIR`` runs a grid of experiments on a local process pool (``--workers``) or
a Dask cluster (``--scheduler tcp://HOST:PORT`` or ``$BOOTMAP_DASK_SCHEDULER``). Exit codes: 0 every cell
ran (whatever its checks say: the table reports them), 1 a cell failed or timed out, or the cluster
cannot be reached, 2 a bad sweep file or an output directory that holds another sweep.
"""

from __future__ import annotations

import argparse
import sys

from ... import arguments
from ...errors import EXIT_FAILURE, EXIT_INTERRUPTED, EXIT_OK


def register(subparsers) -> None:
    """Add ``sweep`` to an ``argparse`` sub-parsers object."""
    p = subparsers.add_parser(
        "sweep", help="run a grid of experiments (worlds x seeds x noise x ...) on this machine or a Dask cluster",
        description="Run every cell of a sweep file's grid (worlds, seeds, noise levels, view clusterers, "
                    "learners, resolver levels and quantum) as one experiment each, on a process pool here or "
                    "on a Dask distributed cluster. Writes DIR/results.jsonl as cells finish (so --resume can "
                    "go on after an interruption), then DIR/results.csv, DIR/summary.md and figures. A cell "
                    "that fails or times out is recorded with its error and the sweep goes on. Sweep files: "
                    "sweeps/*.toml; the format is in bootmap.experiments.sweep.spec.")
    p.add_argument("spec", help="sweep file (TOML)")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output directory")
    p.add_argument("--workers", type=arguments.count("workers"), metavar="N",
                   help="processes on this machine (default: one per core)")
    p.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                   help="run on this Dask scheduler instead (default: $BOOTMAP_DASK_SCHEDULER, else locally); "
                        "needs pip install 'bootmap[dask]'")
    p.add_argument("--resume", action="store_true",
                   help="go on with the sweep in DIR: run only the cells it has no result for")
    p.add_argument("--retry-failed", action="store_true",
                   help="resume, and run the failed and timed-out cells again too")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(handler=cmd_sweep)


def cmd_sweep(args: argparse.Namespace) -> int:
    from . import run_sweep

    try:
        result = run_sweep(args.spec, args.output, workers=args.workers, scheduler=args.scheduler,
                           resume=args.resume or args.retry_failed, retry_failed=args.retry_failed,
                           progress=not args.no_progress)
    except KeyboardInterrupt:
        print(f"bootmap sweep: interrupted; the cells that finished are in {args.output}/results.jsonl, and "
              f"`bootmap sweep {args.spec} -o {args.output} --resume` goes on", file=sys.stderr)
        return EXIT_INTERRUPTED
    table = result.table
    exact = sum(bool(r["map_exact"]) for r in table)
    print(f"{len(table)} cells ({result.ran} run now, {result.skipped} done before) in {result.seconds:.1f} s; "
          f"map exact in {exact}; every check of the paper in {sum(bool(r['all_checks']) for r in table)}; "
          f"{len(result.failed)} failed or timed out")
    for r in result.failed:
        print(f"  {r['cell_id']}: {r['status']}: {str(r['error']).splitlines()[0]}")
    print(f"table: {result.out_dir}/results.csv; summary: {result.out_dir}/summary.md")
    return EXIT_FAILURE if result.failed else EXIT_OK
