"""Child processes: work that ends by a deadline for sure, and long-lived helpers that start cheaply.

Work that ends by a deadline for sure (:func:`in_child`): run in a forked child, killed if it runs over.

clingo cannot interrupt a grounding, and a large or hostile tableau can ground for longer than any time
limit; an experiment can get stuck. So the command line resolves, and a sweep runs each cell, in a child
forked for the work and killed at its deadline; whatever the child built (clingo's groundings included)
dies with it. The work's value comes back pickled through a pipe.

``os.fork`` rather than ``multiprocessing``: Dask's worker processes are daemons, which ``multiprocessing``
forbids to have children; and the work is inherited, so nothing is pickled on the way in.
"""

from __future__ import annotations

import multiprocessing
import os
import pickle
import select
import signal
import time
import traceback
from typing import Callable, Sequence


def in_child(work: Callable[[], object], timeout: float) -> tuple:
    """``work()`` in a forked child, killed ``timeout`` seconds on -> ``("ok", value)``, ``("failed",
    error)`` or ``("timeout", message)``. Where the platform cannot fork, ``work()`` runs here, unbounded."""
    if not hasattr(os, "fork"):
        try:
            return "ok", work()
        except Exception as e:
            return "failed", f"{type(e).__name__}: {e}"
    read_fd, write_fd = os.pipe()
    # Ctrl-C is held back over the fork: arriving in the child before it is inside _child, its
    # KeyboardInterrupt would unwind into the parent's code in the child (a sweep's worker loop, say),
    # which would go on as a second copy of the parent, holding its pipes.
    held = _hold_interrupts()
    parent = os.getpid()
    pid = os.fork()
    if pid == 0:  # the child: do the work, send the outcome, leave without running the parent's exit code
        try:
            os.close(read_fd)
            _die_with_parent(parent)
            _release_interrupts(held)  # from here a Ctrl-C is the work's outcome (_child catches it)
            _child(work, write_fd)
        finally:
            os._exit(1)
    os.close(write_fd)
    finished = False
    try:
        _release_interrupts(held)  # (inside the try: a Ctrl-C held back until now still stops the child)
        data, finished = _read_until(read_fd, time.monotonic() + timeout)
    finally:
        os.close(read_fd)
        # Over its time (or we are interrupted): stop it. Done: it has nothing left to do but free what it
        # built, which can take seconds after a large grounding; it is stopped rather than waited for.
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
    if not finished:
        return "timeout", f"no result within {timeout:g} s; stopped"
    if not data:
        return "failed", "the process died without a result (killed for memory, or a crash in C code)"
    return pickle.loads(data)


def _die_with_parent(parent: int) -> None:
    """Where Linux allows it, have the kernel kill this process when the one that forked it (``parent``)
    dies (a sweep's worker terminated at Ctrl-C, or killed): no orphan goes on grounding for nobody. A
    parent that died before the kernel was asked has already handed this process on: it ends at once."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        PR_SET_PDEATHSIG = 1
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
    except (OSError, AttributeError):  # not Linux, or no prctl: the deadline still ends the child
        pass
    if os.getppid() != parent:
        os._exit(1)


def _hold_interrupts():
    """Block SIGINT in this thread (where signals can be blocked): the mask to restore, or None."""
    if not hasattr(signal, "pthread_sigmask"):
        return None
    return signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})


def _release_interrupts(held) -> None:
    """Restore the signal mask :func:`_hold_interrupts` changed (a SIGINT held back is delivered now)."""
    if held is not None:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)


def _child(work: Callable[[], object], write_fd: int) -> None:
    try:
        try:
            payload = pickle.dumps(("ok", work()))
        except BaseException as e:  # noqa: BLE001  (anything, a bug included, is the work's outcome)
            payload = pickle.dumps(("failed", f"{type(e).__name__}: {e}\n{traceback.format_exc(limit=6)}"))
        with os.fdopen(write_fd, "wb") as pipe:
            pipe.write(payload)
    finally:
        os._exit(0)


def _read_until(fd: int, deadline: float) -> tuple[bytes, bool]:
    """Everything written to ``fd`` until the writer closes it (-> finished) or the deadline passes."""
    chunks = []
    while True:
        left = deadline - time.monotonic()
        if left <= 0 or not select.select([fd], [], [], left)[0]:
            return b"".join(chunks), False
        chunk = os.read(fd, 1 << 16)
        if not chunk:
            return b"".join(chunks), True
        chunks.append(chunk)


def in_processes(work: Callable[..., list], jobs: int, shared: tuple, items: list, *per_item: list | None) -> list:
    """``work(*shared, items, *per_item)``, one value per item, in ``jobs`` processes: the items (and each
    ``per_item`` list beside them, or None) cut into ``4 * jobs`` strided chunks, each chunk's values put back
    in the items' order. In this process where ``jobs`` is 1 or there are fewer than two items. (Many
    independent pieces of work alike in cost, such as pairs of scans to match.)"""
    if jobs == 1 or len(items) < 2:
        return work(*shared, items, *per_item)
    from concurrent.futures import ProcessPoolExecutor

    parts = jobs * 4
    chunks = [[items[k::parts]] + [None if extra is None else extra[k::parts] for extra in per_item]
              for k in range(parts)]
    with ProcessPoolExecutor(jobs) as pool:
        done = list(pool.map(_unpacked, [work] * parts, [shared] * parts, chunks))
    values: list = [None] * len(items)
    for k, part in enumerate(done):
        values[k::parts] = part
    return values


def _unpacked(work: Callable[..., list], shared: tuple, chunk: list) -> list:
    return work(*shared, *chunk)


def preloaded_context(modules: Sequence[str]):
    """A multiprocessing context whose processes start with ``modules`` already imported.

    Long-lived helper processes (a sweep's workers, the service's solvers and intake processes) are not
    forked from their parent, which may have threads (a server) or an OpenMP pool (a test run, a notebook)
    that a forked child would inherit broken. Spawned, each imported what it needs for itself (a second
    or two of CPU each, again for every solver replaced after a kill). They are forked from
    multiprocessing's *forkserver* instead: a fresh, single-threaded process that imports ``modules``
    once and forks every helper from there. Its forked children's parent is the forkserver, which ends
    when the process that started it ends (see :func:`parent_gone`).

    The forkserver is one per process and reads its preload list once, at its start: every caller in
    one process should name every module its helpers need. Where the platform has no forkserver, the
    processes are spawned and import for themselves."""
    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(list(modules))  # (no effect once this process's forkserver is running)
    return context


def parent_gone(owner_pid: int, first_parent: int) -> bool:
    """Whether the process that started this one (``owner_pid``) is gone.

    ``first_parent`` is this process's parent as it started (``os.getppid()`` then): the owner itself
    (spawned) or the owner's forkserver (:func:`preloaded_context`), which ends with the owner. Either
    way, the owner's end changes this process's parent (it is handed to init or a subreaper); and a
    process whose parent was already neither when it started (the owner died before it ran) has lost
    its owner too."""
    parent = os.getppid()
    if parent != first_parent:
        return True
    if first_parent == owner_pid:
        return False
    try:  # started by the forkserver: the owner must still be there
        os.kill(owner_pid, 0)
    except ProcessLookupError:
        return True
    except PermissionError:  # there, owned by another user (it cannot be ours, but it is alive)
        return False
    return False

