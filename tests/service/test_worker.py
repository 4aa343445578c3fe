"""Solver processes: stopped for sure at the deadline, capped in memory, and replaced afterwards."""

import subprocess
import sys
from pathlib import Path

import pytest

from bootmap import examples
from bootmap.mapping.theory import default_axioms_dir
from bootmap.errors import SolveTimeout
from bootmap.service.worker import SolveJob, SolverKilled, SolverPool
from bootmap.tableau import Tableau

AXIOMS = str(default_axioms_dir())


def one_view(n: int) -> Tableau:
    """n time points that all look alike, joined by travels: a hard solve that grounds for a long time."""
    steps = [{"view": "V", "action": {"type": "travel", "distance_m": 1.0}}] * (n - 1) + [{"view": "V"}]
    return Tableau.from_dict({"format": "bootmap.tableau/1", "steps": steps})


def test_a_solver_busy_past_the_deadline_is_killed_and_replaced():
    pool = SolverPool(1, memory_mb=2048, kill_grace_s=0)
    try:
        first = pool._workers[0]
        # Validating and grounding 10,000 steps takes over a second: only the kill can end it at 0.1 s.
        with pytest.raises(SolverKilled, match="still busy"):
            pool.solve(SolveJob(one_view(10_000).to_dict(), AXIOMS, time_limit_s=0.1))
        assert not first.process.is_alive()
        solved = pool.solve(SolveJob(examples.notched_rectangle().to_dict(), AXIOMS, time_limit_s=30))
        assert solved.map["summary"]["dstates"] == 8 and pool.alive() == 1
    finally:
        pool.close()


def test_the_resolvers_own_time_limit_ends_a_slow_solve_first():
    pool = SolverPool(1, memory_mb=2048, kill_grace_s=10)
    try:
        with pytest.raises(SolveTimeout, match="time limit of 1") as e:
            pool.solve(SolveJob(one_view(2_000).to_dict(), AXIOMS, time_limit_s=1))
        assert not isinstance(e.value, SolverKilled) and e.value.lower_bound >= 1
    finally:
        pool.close()


MEMORY_CAP = """
import sys
from bootmap import examples
from bootmap.service.worker import SolveJob, SolverOutOfMemory, SolverPool
sys.path.insert(0, {here!r})
from test_worker import AXIOMS, one_view

pool = SolverPool(1, memory_mb=256, kill_grace_s=0)  # the smallest cap the settings allow
try:
    try:
        pool.solve(SolveJob(one_view(5_000).to_dict(), AXIOMS, time_limit_s=60))
        print("solved over the cap")
    except SolverOutOfMemory as e:
        print("out of memory:", e)
    solved = pool.solve(SolveJob(examples.notched_rectangle().to_dict(), AXIOMS, time_limit_s=30))
    print("then", solved.map["summary"]["dstates"], "dstates")
finally:
    pool.close()
"""


def test_a_solve_over_the_memory_cap_fails_cleanly_and_the_solver_goes_on():
    # In a process of its own: solvers are forked from their process's forkserver, and the modules it
    # preloaded count against their cap; in a test worker, another module's sweep may have started it.
    run = subprocess.run([sys.executable, "-c", MEMORY_CAP.format(here=str(Path(__file__).parent))],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    said = run.stdout.splitlines()
    assert said[0].startswith("out of memory: the solve needed more than this server's solver memory of 256 MiB")
    assert said[1] == "then 8 dstates"
