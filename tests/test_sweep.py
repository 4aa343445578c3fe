"""bootmap sweep: a grid of real experiments on the local process pool and on a Dask LocalCluster,
streamed to disk, resumed, with failing cells recorded and bad sweep files refused by key."""

import csv
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from bootmap.errors import EXIT_INTERRUPTED, SweepError
from bootmap.experiments.world import run_experiment
from bootmap.proc import in_child
from bootmap.sim.world import load_world
from bootmap.experiments.sweep import TIMING_COLUMNS, DaskCluster, load_spec, loads_spec, run_sweep
from bootmap.experiments.sweep.cells import experiment_row
from hypothesis import given, settings
from hypothesis import strategies as st
from support.signals import ctrl_c_default

# Tiny cells: 3 circuits of the notched rectangle (24 images), about a second each.
TINY = """
name = "tiny"
[grid]
worlds = ["notched_rectangle"]
seeds = {seeds}
[[noise]]
name = "1x"
[[noise]]
name = "2x laser"
"laser.noise_sd" = 0.02
"laser.dropout" = 0.002
[run]
circuits = 3
time_limit = 10
cell_timeout = 120
"""


def tiny(seeds="[1, 2]", source="tiny.toml"):
    return loads_spec(TINY.format(seeds=seeds), source)


def deterministic(table):
    """The columns a cell determines (not its timings, nor which worker ran it)."""
    return [{k: v for k, v in row.items() if k not in TIMING_COLUMNS} for row in table]


@pytest.fixture(scope="module")
def local(tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep") / "local"
    return run_sweep(tiny(), out, workers=2), out


def test_a_small_sweep_on_the_local_pool_runs_every_cell_as_the_experiment_does(local):
    result, out = local
    spec = tiny()
    assert [r["cell_id"] for r in result.table] == [c.id for c in spec.cells]  # grid order, every cell once
    assert result.ran == 4 and result.skipped == 0 and not result.failed
    # The pool's row for a cell is what the experiment gives when run here, directly.
    cell = spec.cells[3]  # seed 2 at twice the laser noise
    direct = run_experiment(load_world("notched_rectangle", dict(cell.noise.settings)), circuits=3, seed=2,
                            time_limit=10, learner=cell.learner)
    here = experiment_row(cell, direct)
    assert deterministic([result.table[3]]) == deterministic([here])
    assert result.table[3]["settings"] == {"laser.dropout": 0.002, "laser.noise_sd": 0.02}
    assert len({r["worker"] for r in result.table}) >= 1 and all(r["seconds"] > 0 for r in result.table)
    assert len(list((out / "simulations").glob("*.json.gz"))) == 4  # two seeds, two noise levels: four runs kept


def test_the_table_is_written_as_json_lines_and_csv_with_a_summary_and_figures(local):
    result, out = local
    lines = [json.loads(x) for x in (out / "results.jsonl").read_text().splitlines()]
    assert lines == result.table
    with (out / "results.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert [r["cell_id"] for r in rows] == [r["cell_id"] for r in result.table]
    assert [int(r["k"]) for r in rows] == [r["k"] for r in result.table]
    summary = (out / "summary.md").read_text()
    assert "| notched_rectangle | 1x | 2 | 0 |" in summary and "| notched_rectangle | 2x laser | 2 | 0 |" in summary
    for name in ("accuracy_vs_noise.png", "k_chosen.png", "map_exact.png", "learner_curves.png"):
        assert (out / name).stat().st_size > 5_000
    assert (out / "sweep.toml").read_text() == tiny().text


@pytest.mark.slow
def test_the_same_sweep_on_a_dask_local_cluster_gives_the_same_table(local, tmp_path):
    pytest.importorskip("distributed", reason="dask.distributed is not installed: pip install 'bootmap[dask]'")
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                      host="127.0.0.1") as cluster:
        result = run_sweep(tiny(), tmp_path / "dask", scheduler=cluster.scheduler_address)
    assert result.ran == 4 and not result.failed
    assert deterministic(result.table) == deterministic(local[0].table)
    assert {r["worker"] for r in result.table}.isdisjoint({r["worker"] for r in local[0].table})


@pytest.mark.slow
def test_resume_runs_only_the_cells_without_a_result(local, tmp_path):
    _, out = local
    shutil.copytree(out, tmp_path / "resumed")
    with (tmp_path / "resumed" / "results.jsonl").open("a") as f:
        f.write('{"cell_id": "notched_rect')  # the line being written when the sweep was interrupted
    before = {r["cell_id"]: r for r in local[0].table}
    result = run_sweep(tiny("[1, 2, 3]"), tmp_path / "resumed", workers=2, resume=True)
    assert result.skipped == 4 and result.ran == 2  # seed 3 at both noise levels
    assert [r["seed"] for r in result.table] == [1, 2, 3, 1, 2, 3]
    for row in result.table:
        if row["cell_id"] in before:  # taken from disk, not run again: the same worker and timings
            assert row == before[row["cell_id"]]
    assert len((tmp_path / "resumed" / "results.jsonl").read_text().splitlines()) == 6


def test_a_directory_with_results_is_not_overwritten_without_resume(local, tmp_path):
    shutil.copytree(local[1], tmp_path / "again")
    with pytest.raises(SweepError, match="--resume"):
        run_sweep(tiny(), tmp_path / "again", workers=1)


def test_a_failing_cell_is_recorded_with_its_error_and_the_sweep_goes_on(tmp_path):
    # A robot too slow to reach any dstate: the simulator gives up on it ("stuck"), in that cell only.
    spec = loads_spec(TINY.format(seeds="[1]").replace('name = "2x laser"', 'name = "stuck"')
                      .replace('"laser.noise_sd" = 0.02\n"laser.dropout" = 0.002', '"robot.max_speed" = 0.01'))
    result = run_sweep(spec, tmp_path / "out", workers=2)
    ok, stuck = result.table
    assert ok["status"] == "ok" and ok["k"] is not None
    assert stuck["status"] == "failed" and "SimulationError: stuck" in stuck["error"]
    assert stuck["all_checks"] is False and stuck["k"] is None
    assert "stuck" in (tmp_path / "out" / "summary.md").read_text()


def test_a_cell_over_its_time_is_stopped_and_recorded_as_timed_out():
    start = time.monotonic()
    outcome = in_child(lambda: time.sleep(30), timeout=0.5)
    assert outcome[0] == "timeout" and "0.5 s" in outcome[1]
    assert time.monotonic() - start < 5


def test_a_cell_that_raises_or_dies_is_a_failure_not_a_crash():
    kind, error = in_child(lambda: 1 / 0, timeout=30)
    assert kind == "failed" and error.startswith("ZeroDivisionError")
    kind, error = in_child(lambda: os._exit(3), timeout=30)
    assert kind == "failed" and "died without a result" in error
    assert in_child(lambda: {"x": [1, 2]}, timeout=30) == ("ok", {"x": [1, 2]})


@pytest.mark.parametrize("change, key", [
    (("worlds = [", "wrolds = ["), "tiny.toml: grid.wrolds: unknown key"),
    (("seeds = [1, 2]", 'seeds = "5-1"'), "tiny.toml: grid.seeds: the range '5-1' runs backwards"),
    (("seeds = [1, 2]", "seeds = [1, -2]"), "tiny.toml: grid.seeds: expected a list of seeds"),
    (('"notched_rectangle"]', '"notched_rectangle", "nowhere"]'), "tiny.toml: grid.worlds[1] (nowhere)"),
    (('"laser.noise_sd" = 0.02', '"laser.noise_sd" = -1'), "tiny.toml: noise[1] (2x laser): "),
    (('"laser.noise_sd" = 0.02', '"lasernoise" = 1'), 'tiny.toml: noise[1].lasernoise: expected a world field'),
    (("[run]", '[run]\nsteps = "many"'), "tiny.toml: run.steps: expected a whole number"),
    (("circuits = 3", "circuits = 0"), "tiny.toml: run.circuits: expected a whole number >= 1"),
    (("[grid]", '[grid]\nlearners = ["1-NN", "oracle"]'), "tiny.toml: grid.learners[1]: unknown learner 'oracle'"),
    (("[grid]", '[grid]\nlevels = ["causal,bogus"]'), "tiny.toml: grid.levels[0]: unknown level(s) bogus"),
    (("[grid]", '[grid]\nquantum = [0]'), "tiny.toml: grid.quantum[0]: expected \"learned\" or degrees"),
    (("cell_timeout = 120", "cell_timeout = 120\ncpus = 2"), "tiny.toml: run.cpus: unknown key"),
    (("[grid]", "[grdi]"), "tiny.toml: grdi: unknown key"),
])
def test_a_bad_sweep_file_is_refused_naming_the_key(change, key):
    text = TINY.format(seeds="[1, 2]").replace(*change)
    with pytest.raises(SweepError) as e:
        loads_spec(text, "tiny.toml")
    assert str(e.value).startswith(key), str(e.value)
    assert "laser.noise_sd" in str(e.value) if "noise[1] (2x laser)" in key else True


def test_the_command_exits_2_on_a_bad_sweep_file_and_1_when_a_cell_fails(tmp_path):
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    bad = tmp_path / "bad.toml"
    bad.write_text(TINY.format(seeds='"1,,2"'))
    run = subprocess.run([sys.executable, "-m", "bootmap.cli", "sweep", str(bad), "-o", str(tmp_path / "o")],
                         capture_output=True, text=True, env=env, timeout=120)
    assert run.returncode == 2 and f"bootmap sweep: error: {bad}: grid.seeds:" in run.stderr
    timeout = tmp_path / "timeout.toml"  # every cell over a 0.05 s budget
    timeout.write_text(TINY.format(seeds="[1]").replace("cell_timeout = 120", "cell_timeout = 0.05"))
    run = subprocess.run([sys.executable, "-m", "bootmap.cli", "sweep", str(timeout), "-o", str(tmp_path / "t"),
                          "--workers", "1", "--no-progress"], capture_output=True, text=True, env=env, timeout=120)
    assert run.returncode == 1, run.stderr
    assert "2 failed or timed out" in run.stdout and ": timeout: cell timeout" in run.stdout


def test_without_dask_the_scheduler_option_says_what_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # as if it were not installed
    with pytest.raises(SweepError, match=r"pip install 'bootmap\[dask\]'"):
        DaskCluster("tcp://127.0.0.1:8786")


def test_an_experiment_runs_with_one_blas_thread_and_gives_the_threads_back(monkeypatch):
    import bootmap.experiments.world as experiment
    from threadpoolctl import threadpool_info

    seen = []
    monkeypatch.setattr(experiment, "_run", lambda *a: seen.append([p["num_threads"] for p in threadpool_info()]))
    before = [p["num_threads"] for p in threadpool_info()]
    experiment.run_experiment("notched_rectangle", circuits=1)
    assert seen and set(seen[0]) == {1}
    assert [p["num_threads"] for p in threadpool_info()] == before


@settings(max_examples=20, deadline=None)
@given(seeds=st.lists(st.integers(0, 500), min_size=1, max_size=6, unique=True),
       levels=st.lists(st.floats(0.0, 0.05, allow_nan=False), min_size=1, max_size=3, unique=True),
       learners=st.lists(st.sampled_from(["1-NN", "3-NN", "linear SVM"]), min_size=1, max_size=3, unique=True))
def test_the_grid_is_every_combination_once_with_stable_ids(seeds, levels, learners):
    noise = "".join(f'[[noise]]\nname = "n{i}"\n"laser.noise_sd" = {x!r}\n' for i, x in enumerate(levels))
    text = (f"[grid]\nworlds = [\"notched_rectangle\"]\nseeds = {seeds}\nlearners = {json.dumps(learners)}\n"
            f"{noise}[run]\ncircuits = 2\n")
    cells = loads_spec(text).cells
    assert len(cells) == len(seeds) * len(levels) * len(learners)
    assert len({c.id for c in cells}) == len(cells)
    assert {(c.seed, c.noise.settings, c.learner) for c in cells} == \
        {(s, (("laser.noise_sd", x),), le) for s in seeds for x in levels for le in learners}
    assert [c.id for c in loads_spec(text).cells] == [c.id for c in cells]


@pytest.mark.slow
def test_a_log_is_an_axis_of_the_grid_beside_worlds(tmp_path, monkeypatch):
    # A robot's log (a synthetic CARMEN log of a square, truth known by hand) runs as `bootmap experiment
    # --log` does, one cell per seed, beside a world's cells; its row has the log's own figures.
    monkeypatch.syspath_prepend(str(Path(__file__).parent / "ingest"))
    from synthetic import write_square_log

    write_square_log(tmp_path / "square.log")
    text = TINY.format(seeds="[1]").replace('worlds = ["notched_rectangle"]',
                                            'worlds = ["notched_rectangle"]\nlogs = ["square.log"]')
    (tmp_path / "logs.toml").write_text(text)
    spec = load_spec(tmp_path / "logs.toml")
    assert [(c.world, c.noise.name, c.log is not None) for c in spec.cells] == [
        ("notched_rectangle", "1x", False), ("notched_rectangle", "2x laser", False), ("square.log", "as recorded", True)]
    result = run_sweep(spec, tmp_path / "out", workers=1)
    row = result.table[-1]
    assert (row["status"], row["error"], row["world"]) == ("ok", None, "square.log")
    assert (row["dstates"], row["places"], row["true_dstates"], row["dstate_accuracy"]) == (8, 4, 8, 1.0)
    assert row["map_exact"] and row["dead_reckoning_accuracy"] == 1.0 and row["ingest_s"] is not None
    # The world's cells are the experiment as before.
    assert deterministic(result.table[:2]) == deterministic(run_sweep(tiny("[1]"), tmp_path / "worlds", workers=1).table)


def test_a_log_that_is_not_there_is_refused_naming_the_key(tmp_path):
    text = TINY.format(seeds="[1]").replace('worlds = ["notched_rectangle"]', 'logs = ["nowhere.log"]')
    with pytest.raises(SweepError, match=r"grid\.logs\[0\] \(nowhere\.log\): no such log"):
        loads_spec(text, "logs.toml")


def _session(sid: int) -> list[int]:
    """The processes of a session (Linux /proc): a command, its workers and their children."""
    pids = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[3]) == sid and fields[0] != "Z":
                pids.append(int(entry.name))
    return pids


def _described(pids: list[int]) -> list[str]:
    """Each process with its command line."""
    out = []
    for pid in pids:
        try:
            line = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
        except OSError:
            continue
        out.append(f"{pid}: {line[:160]}")
    return out


def _until(condition, seconds: float) -> bool:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.2)
    return condition()


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads processes from Linux's /proc")
def test_ctrl_c_stops_a_sweep_and_its_workers_and_says_how_to_resume(tmp_path):
    spec = tmp_path / "long.toml"
    spec.write_text(TINY.format(seeds="[1, 2, 3, 4, 5, 6]").replace("circuits = 3", "circuits = 400"))
    proc = subprocess.Popen([sys.executable, "-m", "bootmap.cli", "sweep", str(spec), "-o", str(tmp_path / "out"),
                             "--workers", "2", "--no-progress"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True, preexec_fn=ctrl_c_default)
    try:
        # At work: the command, multiprocessing's resource tracker and forkserver, the two workers the
        # forkserver forked, and a child each worker forked for the cell it runs.
        assert _until(lambda: len(_session(proc.pid)) >= 7, 120), _described(_session(proc.pid))
        os.killpg(proc.pid, signal.SIGINT)  # as a terminal sends Ctrl-C: to every process of the command
        try:
            _, err = proc.communicate(timeout=60)
        except subprocess.TimeoutExpired:  # something still holds the command's output: say what
            raise AssertionError(f"exit code {proc.poll()}; still running: {_described(_session(proc.pid))}")
    finally:
        if _session(proc.pid):
            os.killpg(proc.pid, signal.SIGKILL)
    err = err.decode(errors="replace")
    assert proc.returncode == EXIT_INTERRUPTED, err[-3000:]
    assert "interrupted" in err and "--resume" in err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err
    assert _until(lambda: not _session(proc.pid), 15), f"left running: {_session(proc.pid)}"


def test_every_shipped_sweep_file_reads():
    from pathlib import Path

    from bootmap.experiments.sweep.spec import load_spec

    files = sorted((Path(__file__).resolve().parents[1] / "sweeps").glob("*.toml"))
    assert files
    for f in files:
        assert load_spec(f).cells, f
