"""The bootmap command, run as a user runs it: exit codes, help, text and JSON maps."""

import json
import math
import signal
import subprocess
import sys

import pytest

from bootmap import examples
from bootmap.errors import EXIT_INTERRUPTED
from support.signals import ctrl_c_default


def bootmap(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "bootmap.cli", *map(str, args)], capture_output=True,
                          text=True, cwd=cwd, timeout=120)


@pytest.fixture
def paper_file(tmp_path):
    path = tmp_path / "paper.json"
    path.write_text(examples.notched_rectangle(circuits=50).dumps())
    return path


def test_help_explains_every_sub_command():
    out = bootmap("--help")
    assert out.returncode == 0
    for cmd in ("map", "why", "axioms", "schema", "demo", "experiment", "serve"):
        assert cmd in out.stdout
    sub = bootmap("map", "--help")
    assert "--levels" in sub.stdout and "--time-limit" in sub.stdout and "--format" in sub.stdout


def test_map_prints_the_annotated_tableau(paper_file):
    out = bootmap("map", paper_file)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("8 dstates, 4 places, 4 paths; unique minimal map")
    assert "t4    V0    S4      P2     Pa2   pos  turn -90" in out.stdout
    assert "t400  V0    S0" in out.stdout


def test_map_json_is_machine_readable(paper_file):
    out = bootmap("map", paper_file, "--format", "json", "--levels", "causal,topological")
    data = json.loads(out.stdout)
    assert data["summary"]["dstates"] == 8 and data["summary"]["unique"] is True
    assert data["summary"]["levels"] == ["causal", "topological"]
    assert data["steps"][4]["dstate"] == "S4"


def test_a_tableau_read_from_standard_input_as_dash(paper_file):
    # `bootmap simulate WORLD | bootmap map -`: "-" names standard input, and bad input there is named too.
    run = subprocess.run([sys.executable, "-m", "bootmap.cli", "map", "-", "--levels", "causal,topological"],
                         input=paper_file.read_text(), capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert run.stdout.startswith("8 dstates, 4 places, 4 paths")
    bad = subprocess.run([sys.executable, "-m", "bootmap.cli", "why", "-", "t0", "t4"], input="{}",
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "stdin: (top level): 'format' is a required property" in bad.stderr


def test_bad_tableau_exits_2_with_the_place_named(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "bootmap.tableau/1", "steps": [{"view": "a", "action": {"type": "fly"}}, {"view": "b"}]}')
    out = bootmap("map", bad)
    assert out.returncode == 2
    assert "bad.json: steps[0].action.type: unknown action type 'fly'" in out.stderr
    assert "Traceback" not in out.stderr


def test_unknown_level_exits_2(paper_file):
    out = bootmap("map", paper_file, "--levels", "causal,astrology")
    assert out.returncode == 2 and "unknown level(s) astrology" in out.stderr


def test_time_out_exits_1_and_says_so(paper_file):
    out = bootmap("map", paper_file, "--levels", "causal,topological", "--time-limit", "0")
    assert out.returncode == 1 and "time limit" in out.stderr and "Traceback" not in out.stderr


def test_inconsistent_tableau_exits_1(tmp_path):
    path = tmp_path / "t.json"
    path.write_text(json.dumps({"format": "bootmap.tableau/1", "steps": [
        {"view": "A", "action": {"type": "turn", "angle_deg": 180}},
        {"view": "B", "action": {"type": "turn", "angle_deg": 180}}, {"view": "C"}]}))
    out = bootmap("map", path)
    assert out.returncode == 1 and "no map satisfies the axioms" in out.stderr


def test_axioms_lists_named_rules_with_file_and_line():
    out = bootmap("axioms")
    assert out.returncode == 0
    assert any(line.split()[:2] == ["topological", "right_by_turn"] and "topological.lp:" in line
               for line in out.stdout.splitlines())


def test_schema_prints_the_json_schema():
    out = bootmap("schema")
    assert json.loads(out.stdout)["title"].startswith("bootmap tableau")


def test_map_of_a_simulated_run_clusters_its_images_first(tmp_path):
    run = tmp_path / "run.json"
    sim = bootmap("simulate", "notched_rectangle", "--policy", "circuits", "--circuits", "10", "--seed", "1", "-o", run)
    assert sim.returncode == 0, sim.stderr
    out = bootmap("map", run)
    assert out.returncode == 0, out.stderr
    assert "clustered 80 images into 4 views" in out.stderr
    assert out.stdout.startswith("8 dstates, 4 places, 4 paths")


def test_a_sub_command_is_hidden_only_when_a_third_party_package_is_missing(monkeypatch, capsys):
    # The service needs fastapi; without it `serve` is left out and the rest of the command works. Any
    # other import error (a bug in bootmap itself) surfaces instead of silently dropping the command.
    import importlib

    from bootmap import cli

    real = importlib.import_module

    def missing(name):
        def fake(module, *args):
            if module == "bootmap.service.commands":
                raise ModuleNotFoundError(f"No module named {name!r}", name=name)
            return real(module, *args)
        return fake

    monkeypatch.setattr(importlib, "import_module", missing("fastapi"))
    parser = cli.build_parser()
    commands = parser._subparsers._group_actions[0].choices
    assert "serve" not in commands and {"map", "why", "simulate"} <= set(commands)
    monkeypatch.setattr(importlib, "import_module", missing("bootmap.service.nowhere"))
    with pytest.raises(ModuleNotFoundError, match="bootmap.service.nowhere"):
        cli.build_parser()


def test_map_of_images_takes_a_view_with_a_single_image_as_a_misread(tmp_path, capsys):
    # One image of a run corrupted (a passer-by fills the scan): clustering gives it a view of its own.
    # The map does not make it a dstate of its own: it names the step as a misread.
    from bootmap.cli import main
    from bootmap.sim import simulate
    from bootmap.sim.world import load_world

    run = simulate(load_world("notched_rectangle"), circuits=10, seed=3).to_dict()
    run["steps"][37]["image"] = [0.3] * len(run["steps"][37]["image"])
    path = tmp_path / "run.json"
    path.write_text(json.dumps(run))
    assert main(["map", str(path), "--time-limit", "20", "--format", "json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert [s["t"] for s in result["suspect_steps"]] == [37]
    assert result["summary"]["dstates"] == len({s["truth"] for s in run["steps"]})


def test_map_closes_loops_from_odometry_when_asked(tmp_path):
    # Three laps of a square whose corners all look alike, with the robot's odometry at every step.
    steps, x, y, heading = [], 0.0, 0.0, 0
    for _ in range(3):
        for _ in range(4):
            steps.append({"view": "corner", "odometry": [x, y, 0], "action": {"type": "travel", "distance_m": 6}})
            x, y = x + 6 * round(math.cos(math.radians(heading))), y + 6 * round(math.sin(math.radians(heading)))
            steps.append({"view": "corner", "odometry": [x, y, 0], "action": {"type": "turn", "angle_deg": 90}})
            heading += 90
    steps.append({"view": "corner", "odometry": [x, y, 0]})
    path = tmp_path / "laps.json"
    path.write_text(json.dumps({"format": "bootmap.tableau/1", "steps": steps}))
    out = bootmap("map", path, "--map", "loops")
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("8 dstates, 4 places, 4 paths; loop-closed from odometry, every axiom holds")
    data = json.loads(bootmap("map", path, "--map", "loops", "--format", "json").stdout)
    assert data["summary"]["found_by"] == "loop closing" and data["summary"]["proved_minimal"] is False
    # By default the fewest dstates, unless the tableau says the robot drove through dstates (a log).
    assert json.loads(bootmap("map", path, "--format", "json").stdout)["summary"]["found_by"] == "fewest dstates"
    path.write_text(json.dumps({"format": "bootmap.tableau/1", "steps": steps, "meta": {"passes_through": True}}))
    assert json.loads(bootmap("map", path, "--format", "json").stdout)["summary"]["found_by"] == "loop closing"


def test_why_explains_the_loop_closed_map_of_a_log(tmp_path):
    steps = []
    for _ in range(2):
        for corner in range(4):
            steps += [{"view": "corner", "action": {"type": "travel", "distance_m": 6}},
                      {"view": "corner", "action": {"type": "turn", "angle_deg": 90}}]
    path = tmp_path / "log.json"
    path.write_text(json.dumps({"format": "bootmap.tableau/1", "steps": steps + [{"view": "corner"}],
                                "meta": {"passes_through": True}}))
    out = bootmap("why", path, "t0", "t8")
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("t0 (S0) vs t8 (S0): same (loop-closed map)")
    assert "proposed (near): dead reckoning puts them 0.0 m apart after 24 m driven (within 3.2 m)" in out.stdout
    one = bootmap("why", path, "t3")
    assert one.returncode == 2 and "ask why about two time points" in one.stderr


def _interrupted(args, ready: bytes, cwd) -> tuple[int, str]:
    """Start ``bootmap args``, wait until it has written ``ready`` to stderr (it is at work), press Ctrl-C
    (SIGINT), and return its exit code and everything it wrote to stderr."""
    proc = subprocess.Popen([sys.executable, "-m", "bootmap.cli", *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, cwd=cwd, preexec_fn=ctrl_c_default)
    seen = b""
    while ready not in seen:
        chunk = proc.stderr.read1(4096)
        if not chunk:
            break
        seen += chunk
    proc.send_signal(signal.SIGINT)
    _, rest = proc.communicate(timeout=120)
    return proc.returncode, (seen + rest).decode(errors="replace")


@pytest.mark.parametrize("command", [["simulate", "notched_rectangle", "--circuits", "3000", "-o", "run.json"],
                                     ["experiment", "notched_rectangle", "--circuits", "3000", "-o", "out"]])
def test_ctrl_c_stops_a_long_run_saying_so_without_a_traceback(tmp_path, command):
    code, err = _interrupted(command, b"dstate/s", tmp_path)
    assert code == EXIT_INTERRUPTED, err[-2000:]
    assert "bootmap: interrupted" in err and "Traceback" not in err and "KeyboardInterrupt" not in err


@pytest.mark.parametrize("command", [["map", "{paper}"], ["why", "{paper}", "S0", "S4"], ["rehearse", "{paper}"]])
def test_answers_go_to_a_file_with_o_as_they_would_to_stdout(tmp_path, paper_file, command):
    args = [a.format(paper=paper_file) for a in command]
    printed = bootmap(*args, "--format", "json")
    assert printed.returncode == 0, printed.stderr
    out = tmp_path / "answer.json"
    written = bootmap(*args, "--format", "json", "-o", out)
    assert written.returncode == 0 and written.stdout == ""
    strip = lambda d: {k: v for k, v in d.items() if k not in ("seconds", "stats")}  # noqa: E731
    assert strip(json.loads(out.read_text())) == strip(json.loads(printed.stdout))


def test_o_into_a_missing_folder_fails_with_exit_1_and_bad_input_writes_nothing(tmp_path, paper_file):
    r = bootmap("map", paper_file, "-o", tmp_path / "no" / "such" / "map.txt")
    assert r.returncode == 1 and "cannot write" in r.stderr and "Traceback" not in r.stderr
    bad = tmp_path / "bad.json"
    bad.write_text("{")
    r = bootmap("map", bad, "-o", tmp_path / "map.txt")
    assert r.returncode == 2 and not (tmp_path / "map.txt").exists()


def test_no_progress_leaves_stderr_quiet(tmp_path):
    r = bootmap("experiment", "notched_rectangle", "--circuits", "3", "--no-progress", "-o", tmp_path / "out")
    assert "dstate/s" not in r.stderr and "%|" not in r.stderr
