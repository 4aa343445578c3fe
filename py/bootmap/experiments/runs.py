"""Simulated runs kept on disk, so that experiments that differ only in what they do with a run simulate
it once.

A sweep's grid crosses the world, its noise and the seed (what the robot experiences) with the clusterer,
the learner, the levels and the action typing (what is done with the experience). Cells that share the
first three share one simulated run: the first to need it simulates it and stores its tableau here, the
others read it back (a run of the paper's room is 4-6 s of a cell's 7-10 s; a grid of two learners
simulated each run twice). A run is found by a key made of everything that decides it: the world as
loaded (its noise settings included), the policy, its length, the seed, and the code (bootmap's version
and its source files), so that a run simulated by other code is never read back.

Stored as the tableau's JSON (gzipped), which gives back the same tableau: images, actions, truth and
poses to the last bit. Written to a temporary file and renamed, so that two processes that simulate the
same run at once leave one whole file.
"""

from __future__ import annotations

import gzip
import hashlib
import json
import os
import pickle
import tempfile
from dataclasses import replace
from functools import lru_cache
from pathlib import Path
from typing import Callable

from ..errors import BootmapError
from ..sim.world import World
from ..tableau import Tableau


class RunStore:
    """Simulated runs in ``directory``, one gzipped tableau per run (created when first needed).

    Examples
    --------
    >>> import tempfile
    >>> from bootmap.sim import simulate
    >>> from bootmap.sim.world import load_world
    >>> store, world = RunStore(tempfile.mkdtemp()), load_world("notched_rectangle")
    >>> first = store.simulated(world, "circuits", 1, None, 3, lambda: simulate(world, circuits=1, seed=3))
    >>> again = store.simulated(world, "circuits", 1, None, 3, lambda: None)  # read back, not simulated
    >>> again == first
    True
    """

    def __init__(self, directory: str | os.PathLike):
        self.directory = Path(directory)

    def simulated(self, world: World, policy: str, circuits: int | None, steps: int | None, seed: int,
                  simulate: Callable[[], Tableau]) -> Tableau:
        """The run of ``world`` with this policy, length and seed: read back if stored, else ``simulate()``
        and stored."""
        path = self.directory / f"{run_key(world, policy, circuits, steps, seed)}.json.gz"
        if path.exists():
            try:
                with gzip.open(path, "rt", encoding="utf-8") as f:
                    return Tableau.from_dict(json.load(f), source=str(path))
            except (OSError, EOFError, ValueError, BootmapError):  # cut short or damaged: simulated again
                pass
        tableau = simulate()
        self.directory.mkdir(parents=True, exist_ok=True)
        fd, temporary = tempfile.mkstemp(dir=self.directory, suffix=".tmp")
        try:
            with os.fdopen(fd, "wb") as raw, gzip.open(raw, "wt", encoding="utf-8", compresslevel=1) as f:
                json.dump(tableau.to_dict(), f)
            os.replace(temporary, path)
        except BaseException:
            Path(temporary).unlink(missing_ok=True)
            raise
        return tableau


def run_key(world: World, policy: str, circuits: int | None, steps: int | None, seed: int) -> str:
    """What decides a simulated run, as a hex digest: the world as loaded (not where its file lies), the
    policy, its length, the seed and the code."""
    decided = (_code(), replace(world, source=""), policy, circuits, steps, seed)
    return hashlib.sha1(pickle.dumps(decided, protocol=4)).hexdigest()


@lru_cache(maxsize=1)
def _code() -> str:
    """bootmap's version and a digest of its source files (the simulator reads the walls, the surfaces and
    the policies' maps from modules of its own and others: all of them, rather than a list to keep)."""
    from .. import __version__

    package = Path(__file__).resolve().parents[1]
    digest = hashlib.sha1(__version__.encode())
    for path in sorted(package.rglob("*.py")):
        digest.update(path.relative_to(package).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()
