"""Solver processes: stopped for sure at the deadline, capped in memory, and replaced afterwards."""

import pytest

from bootmap import examples
from bootmap.mapping.theory import default_axioms_dir
from bootmap.errors import SolveTimeout
from bootmap.service.worker import SolveJob, SolverKilled, SolverOutOfMemory, SolverPool
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


def test_a_solve_over_the_memory_cap_fails_cleanly_and_the_solver_goes_on():
    pool = SolverPool(1, memory_mb=150, kill_grace_s=0)
    try:
        with pytest.raises(SolverOutOfMemory, match="150 MiB"):
            pool.solve(SolveJob(one_view(5_000).to_dict(), AXIOMS, time_limit_s=60))
        solved = pool.solve(SolveJob(examples.notched_rectangle().to_dict(), AXIOMS, time_limit_s=30))
        assert solved.map["summary"]["dstates"] == 8
    finally:
        pool.close()
