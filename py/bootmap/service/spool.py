"""Where a server writes request bodies as they arrive: a directory of its own, which it holds by a lock.

A posted tableau is written to a file here and read by an intake process, so the server never holds it
whole; the file is removed when the request ends. A server killed outright (kill -9, the machine's OOM
killer) cannot remove its files, so each server's spool is a directory ``bootmap-spool-*`` holding a
``lock`` file the server keeps locked (``flock``) while it runs. The kernel drops that lock when the
process dies, however it dies; a server starting on the same parent directory removes every spool whose
lock it can take, i.e. whose server is gone. Spools of running servers are never touched: their locks are
held. A spool is made under a hidden name and renamed once locked, so a starting server never sees one
half made.
"""

from __future__ import annotations

import fcntl
import os
import shutil
import tempfile
from pathlib import Path

PREFIX = "bootmap-spool-"
LOCK = "lock"


class Spool:
    """This server's spool directory; ``Spool.open(parent)`` sweeps the dead servers' spools first."""

    def __init__(self, directory: Path, lock_fd: int):
        self.directory, self._lock_fd = directory, lock_fd

    @classmethod
    def open(cls, parent: Path | None = None) -> "Spool":
        parent = Path(parent) if parent is not None else Path(tempfile.gettempdir())
        parent.mkdir(parents=True, exist_ok=True)
        sweep(parent)
        partial = Path(tempfile.mkdtemp(dir=parent, prefix="." + PREFIX))
        fd = os.open(partial / LOCK, os.O_RDWR | os.O_CREAT, 0o600)
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # a new file: nobody else can hold it
        directory = parent / partial.name[1:]
        partial.rename(directory)
        return cls(directory, fd)

    def new_file(self) -> tuple[int, Path]:
        """A new empty file in the spool: its open descriptor and its path."""
        fd, name = tempfile.mkstemp(dir=self.directory, prefix="body-")
        return fd, Path(name)

    def close(self) -> None:
        """Remove the spool (a request still writing to it fails, as the server is stopping)."""
        shutil.rmtree(self.directory, ignore_errors=True)
        os.close(self._lock_fd)


def sweep(parent: Path) -> list[Path]:
    """Remove the spools under ``parent`` whose server is gone (their lock is free); return them."""
    removed = []
    for directory in parent.glob(PREFIX + "*"):
        try:
            fd = os.open(directory / LOCK, os.O_RDWR)
        except OSError:  # no lock (not made by Spool.open), a file of that name, no permission: not ours
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:  # its server is running
            continue
        else:
            shutil.rmtree(directory, ignore_errors=True)
            removed.append(directory)
        finally:
            os.close(fd)
    return removed
