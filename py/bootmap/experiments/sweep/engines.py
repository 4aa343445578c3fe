"""Where a sweep's cells run: a process pool on this machine, or a Dask distributed cluster.

Both take cells and yield their rows as they finish (in any order), so the sweep can write each row to
disk at once. Neither is home-made: :class:`LocalPool` is ``concurrent.futures.ProcessPoolExecutor``,
:class:`DaskCluster` a ``dask.distributed.Client``. Each worker caps BLAS and OpenMP at one thread
(threadpoolctl in every experiment; environment variables for what a cell starts), so N workers use N
cores and do not fight over them.
"""

from __future__ import annotations

import os
import signal
from collections.abc import Iterable, Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed

from ...errors import BootmapError, SweepError
from ...proc import preloaded_context
from .cells import failed_row, run_cell
from .spec import Cell

THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS")
DASK_HINT = "pip install 'bootmap[dask]'"


def one_thread_per_worker() -> None:
    """A worker's initializer: BLAS and OpenMP pools of one thread (for what the cells start; every
    experiment also caps its own pools with threadpoolctl); Ctrl-C left to the sweep (a terminal sends it
    to every process of the command, and the sweep stops its workers itself); then one tiny experiment, so
    that what the first experiment of a process pays once (lazy imports, reading the axioms) is paid here
    and inherited by every cell's forked child, rather than paid again in each (about 0.2 s a cell)."""
    for var in THREAD_VARIABLES:
        os.environ[var] = "1"
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    from ..world import run_experiment

    run_experiment("notched_rectangle", circuits=2, seed=0, time_limit=10.0)


#: What every worker imports, loaded once by the process that starts them (2 s of it scikit-learn and scipy).
PRELOAD = ["bootmap.experiments.world"]


class LocalPool:
    """``workers`` processes on this machine (default: one per core).

    Workers are not forked from the sweep's own process: one that has already used OpenMP (a test run, a
    notebook) would pass a broken thread pool on to forked children. They are forked from a forkserver
    that has imported what a cell needs (:data:`PRELOAD`, :func:`bootmap.proc.preloaded_context`), so
    that the imports are paid once rather than by every worker (spawned workers each took 2 s of them).
    The forkserver lives as long as the sweep's process and serves its later pools too."""

    def __init__(self, workers: int | None = None):
        self.workers = workers or os.cpu_count() or 1

    def __str__(self) -> str:
        return f"local pool of {self.workers} worker(s)"

    def run(self, cells: Iterable[Cell]) -> Iterator[dict]:
        context = preloaded_context(PRELOAD)
        with ProcessPoolExecutor(self.workers, mp_context=context, initializer=one_thread_per_worker) as pool:
            futures = {pool.submit(run_cell, cell): cell for cell in cells}
            try:
                for future in as_completed(futures):
                    yield _row(future, futures[future])
            finally:  # interrupted (Ctrl-C, or the caller stopped reading): stop the cells at work rather
                # than wait for them; the pool, broken, then fails those not started, which nobody reads.
                # (Not cancelled first: Python 3.11's executor then fails a cancelled one and its thread
                # raises InvalidStateError, which prints a traceback at Ctrl-C.)
                if not all(f.done() for f in futures):
                    _stop_workers(pool)


def _stop_workers(pool: ProcessPoolExecutor) -> None:
    """Terminate the pool's worker processes (a cell's forked child dies with its worker:
    :func:`bootmap.proc.in_child`)."""
    for process in list(getattr(pool, "_processes", {}).values()):  # the executor keeps no public list
        if process.is_alive():
            process.terminate()


class DaskCluster:
    """The cells as tasks of a Dask distributed cluster at ``address`` (``tcp://HOST:PORT``).

    The workers need bootmap installed; each cell carries its world file's text, so they need no worlds.
    Start them with one thread each, e.g. ``dask worker tcp://HOST:8786 --nworkers 4 --nthreads 1``:
    each cell then has a core, as on the local pool."""

    def __init__(self, address: str, connect_timeout_s: float = 10.0):
        try:
            from distributed import Client  # noqa: F401
        except ModuleNotFoundError:
            raise SweepError(f"running on a Dask cluster needs dask.distributed: {DASK_HINT}", "--scheduler") from None
        self.address = address
        self.connect_timeout_s = connect_timeout_s

    def __str__(self) -> str:
        return f"Dask cluster at {self.address}"

    def run(self, cells: Iterable[Cell]) -> Iterator[dict]:
        from distributed import Client, as_completed as dask_completed

        try:
            client = Client(self.address, timeout=f"{self.connect_timeout_s}s")
        except (OSError, TimeoutError) as e:
            raise BootmapError(f"cannot reach the Dask scheduler at {self.address}: {e}") from None
        with client:
            client.run(one_thread_per_worker)  # the workers' own processes, before any cell
            cells = list(cells)
            # pure=False: a cell is a run, not a value to deduplicate; its key names it in Dask's logs.
            futures = client.map(run_cell, cells, pure=False, key=[f"bootmap-cell-{c.id}" for c in cells])
            by_future = dict(zip(futures, cells))
            try:
                for future in dask_completed(futures):
                    yield _row(future, by_future[future])
            finally:
                client.cancel([f for f in futures if not f.done()])


def _row(future, cell: Cell) -> dict:
    """The row a finished task returned; a task that could not run at all (a worker process lost, say)
    is a failed cell, not the end of the sweep."""
    try:
        return future.result()
    except Exception as e:  # noqa: BLE001
        return failed_row(cell, "failed", f"the worker lost the cell: {type(e).__name__}: {e}")


def engine(workers: int | None = None, scheduler: str | None = None):
    """The engine a sweep runs on: Dask when a scheduler address is given (or ``BOOTMAP_DASK_SCHEDULER``
    is set), else the local pool."""
    scheduler = scheduler or os.environ.get("BOOTMAP_DASK_SCHEDULER") or None
    if scheduler:
        return DaskCluster(scheduler)
    return LocalPool(workers)
