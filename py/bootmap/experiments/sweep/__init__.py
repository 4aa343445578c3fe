"""Sweeps: many experiments at once (``bootmap sweep SPEC.toml -o DIR``), on this machine or a Dask cluster.

A sweep file (:mod:`.spec`) names a grid - worlds, seeds, noise levels, view clusterers, learners,
resolver options; each cell is one run of :func:`bootmap.experiments.world.run_experiment` (:mod:`.cells`). The
cells run on a local process pool or a Dask distributed cluster (:mod:`.engines`); each row is written to
``DIR/results.jsonl`` as its cell finishes (:mod:`.store`), so ``resume=True`` picks up an interrupted
sweep; at the end come ``results.csv``, ``summary.md`` and figures (:mod:`.report`). Cells that differ
only in what they do with a run (clusterer, learner, levels, action typing) share its simulation, kept in
``DIR/simulations`` (:mod:`bootmap.experiments.runs`).
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path

from .cells import COLUMNS, TIMING_COLUMNS, run_cell
from .engines import DaskCluster, LocalPool, engine
from .report import FIGURES, summary_text, write_figures
from .spec import Cell, Noise, SweepSpec, load_spec, loads_spec
from .store import ResultStore

__all__ = ["COLUMNS", "TIMING_COLUMNS", "Cell", "DaskCluster", "LocalPool", "Noise", "SweepResult", "SweepSpec",
           "load_spec", "loads_spec", "run_cell", "run_sweep"]


@dataclass
class SweepResult:
    """What a sweep did: ``table`` (one row per cell, grid order), how many cells ``ran`` now and how many
    were ``skipped`` as already done (``resume``), the wall time, and the output directory."""

    table: list[dict]
    ran: int
    skipped: int
    seconds: float
    out_dir: Path

    @property
    def failed(self) -> list[dict]:
        return [r for r in self.table if r["status"] != "ok"]


def run_sweep(spec: SweepSpec | str | Path, out_dir: str | Path, workers: int | None = None,
              scheduler: str | None = None, resume: bool = False, retry_failed: bool = False,
              progress: bool = False) -> SweepResult:
    """Run every cell of ``spec`` not already in ``out_dir`` (with ``resume``) and write the results.

    ``scheduler`` (``tcp://HOST:PORT``, or ``$BOOTMAP_DASK_SCHEDULER``) runs the cells on a Dask cluster;
    otherwise a pool of ``workers`` processes (default one per core) runs them here. ``progress`` shows a
    bar with the time left on stderr. A cell that fails or times out is a row with its error; the sweep
    goes on. Raises :class:`~bootmap.errors.SweepError` for a bad sweep file or an output directory that
    holds results already (without ``resume``)."""
    spec = spec if isinstance(spec, SweepSpec) else load_spec(spec)
    store = ResultStore(out_dir)
    runner = engine(workers, scheduler)
    done = store.open(spec, resume, retry_failed)
    runs = str(store.dir / RUNS_DIR)
    todo = first_of_each_run([replace(c, runs_dir=runs) for c in spec.cells if c.id not in done])
    rows = dict(done)
    start = time.perf_counter()
    bar = _bar(len(todo), progress)
    try:
        for row in runner.run(todo):
            store.append(row)  # on disk before anything else: an interruption loses only running cells
            rows[row["cell_id"]] = row
            bar.update(1)
            if row["status"] != "ok":
                bar.set_postfix_str(f"{sum(r['status'] != 'ok' for r in rows.values())} failed")
    finally:
        bar.close()
    seconds = time.perf_counter() - start
    table = store.finish(spec, rows)
    how = (f"{len(table)} cells on a {runner}: {len(todo)} run in {seconds:.1f} s"
           + (f" ({len(todo) / seconds * 60:.1f} cells/min)" if todo and seconds > 0 else "")
           + (f", {len(done)} done before (resumed)" if done else "") + f"; sweep file {spec.source}.")
    (store.dir / "summary.md").write_text(summary_text(spec.name, table, how))
    if table:
        write_figures(table, store.dir)
    return SweepResult(table, len(todo), len(done), seconds, store.dir)


#: Where a sweep's output directory keeps the simulated runs its cells share.
RUNS_DIR = "simulations"


def first_of_each_run(cells: list[Cell]) -> list[Cell]:
    """The cells in the order they are started: the first cell of each simulated run before any second
    one, and so on, so that a cell starts once the cell that simulates its run has had a head start (in
    grid order, the learners of one run sit side by side: on two workers both would simulate it)."""
    seen: dict[tuple, int] = {}
    rank = []
    for c in cells:
        rank.append(seen.get(c.run, 0))
        seen[c.run] = rank[-1] + 1
    return [c for _, _, c in sorted(zip(rank, range(len(cells)), cells), key=lambda x: x[:2])]


def _bar(total: int, progress: bool):
    from tqdm import tqdm

    # tqdm's estimate of the time left is the mean time per finished cell times the cells left.
    return tqdm(total=total, unit="cell", desc="cells", file=sys.stderr, disable=not progress, dynamic_ncols=True)
