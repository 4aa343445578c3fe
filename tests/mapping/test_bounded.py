"""Time limits hold on the command line: resolutions run in a child process stopped after the limit."""

import json
import subprocess
import sys
import time
from dataclasses import dataclass

import pytest

from bootmap.errors import InconsistentTableau, SolveTimeout
from bootmap.examples import notched_rectangle
from bootmap.mapping import Resolver
from bootmap.mapping.bounded import GRACE_S, resolve_within
from bootmap.tableau import Step, Tableau, Turn


def test_bootmap_map_on_a_hard_tableau_returns_within_the_limit(tmp_path):
    # 5,000 steps, one view everywhere: no view tells any two time points apart.
    steps = [{"view": "A", "action": {"type": "travel", "distance_m": 2}} for _ in range(4999)] + [{"view": "A"}]
    path = tmp_path / "hard.json"
    path.write_text(json.dumps({"format": "bootmap.tableau/1", "steps": steps}))
    start = time.monotonic()
    out = subprocess.run([sys.executable, "-m", "bootmap.cli", "map", str(path), "--time-limit", "5"],
                         capture_output=True, text=True, timeout=60)
    elapsed = time.monotonic() - start
    assert elapsed < 5 + GRACE_S + 1.5, elapsed  # the promised bound: 8 s for a limit of 5
    assert out.returncode in (0, 1) and "Traceback" not in out.stderr
    if out.returncode == 1:
        assert "time limit of 5 s" in out.stderr


@dataclass(frozen=True)
class GroundsForever:
    """Stands in for a resolver stuck in a grounding clingo cannot interrupt."""

    time_limit: float = 0.5

    def resolve(self, tableau):
        time.sleep(60)


def test_a_resolution_that_overruns_is_stopped_at_the_limit_plus_grace():
    start = time.monotonic()
    with pytest.raises(SolveTimeout) as e:
        resolve_within(GroundsForever(), notched_rectangle(1), grace_s=0.5)
    assert time.monotonic() - start < 3
    assert e.value.stage == "grounding" and e.value.time_limit_s == 0.5 and "stopped at 1 s" in str(e.value)


def test_answers_come_back_from_the_child_as_they_are():
    paper = notched_rectangle(3)
    cmap = resolve_within(Resolver(time_limit=30), paper)
    assert cmap.dstate_of == Resolver().resolve(paper).dstate_of and cmap.unique
    around_twice = Tableau((Step("A", Turn(180.0)), Step("B", Turn(180.0)), Step("C")))
    with pytest.raises(InconsistentTableau) as e:
        resolve_within(Resolver(time_limit=30), around_twice)
    assert e.value.failing_levels == ["topological"] and e.value.diagnosed
    with pytest.raises(SolveTimeout) as t:
        resolve_within(Resolver(levels=["causal", "topological"], time_limit=0.0), notched_rectangle(50))
    # Stopped in the first try (one dstate per view): its four views are proved; once that failed, five.
    assert (t.value.stage, t.value.lower_bound) in {("one dstate per class", 4), ("the lower bounds", 5)}


def test_any_work_is_stopped_the_same_way_and_bootmap_why_uses_it(tmp_path, capsys):
    from bootmap.cli import main
    from bootmap.mapping.bounded import run_within

    start = time.monotonic()
    with pytest.raises(SolveTimeout, match="stopped at 0.6 s"):
        run_within(lambda: time.sleep(60), 0.3, grace_s=0.3)
    assert time.monotonic() - start < 2
    assert run_within(lambda: {"answer": 42}, 5) == {"answer": 42}
    path = tmp_path / "paper.json"
    path.write_text(notched_rectangle(3).dumps())
    assert main(["why", str(path), "S0", "S4", "--levels", "causal,topological", "--time-limit", "30"]) == 0
    assert "on_path_no_side" in capsys.readouterr().out
