"""Work that ends by a deadline for sure: run in a forked child, killed if it runs over.

clingo cannot interrupt a grounding, and a large or hostile tableau can ground for longer than any time
limit; an experiment can get stuck. So the command line resolves, and a sweep runs each cell, in a child
forked for the work and killed at its deadline; whatever the child built (clingo's groundings included)
dies with it. The work's value comes back pickled through a pipe.

``os.fork`` rather than ``multiprocessing``: Dask's worker processes are daemons, which ``multiprocessing``
forbids to have children; and the work is inherited, so nothing is pickled on the way in.
"""

from __future__ import annotations

import os
import pickle
import select
import signal
import time
import traceback
from typing import Callable


def in_child(work: Callable[[], object], timeout: float) -> tuple:
    """``work()`` in a forked child, killed ``timeout`` seconds on -> ``("ok", value)``, ``("failed",
    error)`` or ``("timeout", message)``. Where the platform cannot fork, ``work()`` runs here, unbounded."""
    if not hasattr(os, "fork"):
        try:
            return "ok", work()
        except Exception as e:
            return "failed", f"{type(e).__name__}: {e}"
    read_fd, write_fd = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: do the work, send the outcome, leave without running the parent's exit code
        os.close(read_fd)
        _die_with_parent()
        _child(work, write_fd)
    os.close(write_fd)
    finished = False
    try:
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


def _die_with_parent() -> None:
    """Where Linux allows it, have the kernel kill this process when the one that forked it dies (a sweep's
    worker terminated at Ctrl-C, or killed): no orphan goes on grounding for nobody."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        PR_SET_PDEATHSIG = 1
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
    except (OSError, AttributeError):  # not Linux, or no prctl: the deadline still ends the child
        pass


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
