"""The simulate and render sub-commands, registered on an argparse parser as cli.py does."""

import argparse
import json

import pytest


from bootmap.sim.commands import register
from bootmap.tableau import load


def _main(argv):
    parser = argparse.ArgumentParser(prog="bootmap")
    register(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    return args.handler(args)


def test_simulate_writes_a_valid_tableau(tmp_path, capsys):
    out = tmp_path / "run.json"
    code = _main(["simulate", "notched_rectangle", "--circuits", "2", "--seed", "1", "-o", str(out)])
    assert code == 0
    t = load(out)
    assert len(t) == 16 and t.meta["policy"] == "circuits"
    assert "16 dstate images from 8 true dstates" in capsys.readouterr().err


def test_simulate_to_stdout(capsys):
    assert _main(["simulate", "plus", "--steps", "3", "--no-progress"]) == 0
    assert len(json.loads(capsys.readouterr().out)["steps"]) == 3


def test_bad_world_file_exits_2_with_the_message_and_no_traceback(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text('format = "bootmap.world/1"\nname = "x"\n')
    assert _main(["simulate", str(bad), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "bad.toml: boundary: missing (required)" in err and "Traceback" not in err
    assert _main(["simulate", "nowhere_world"]) == 2


def test_render_world_and_run(tmp_path):
    run_file = tmp_path / "run.json"
    assert _main(["simulate", "notched_rectangle", "--circuits", "1", "--no-progress", "-o", str(run_file)]) == 0
    png = tmp_path / "w.png"
    assert _main(["render", "notched_rectangle", "--run", str(run_file), "--image", "1", "-o", str(png)]) == 0
    assert png.read_bytes()[:4] == b"\x89PNG"
    assert _main(["render", "taylor_hall", "-o", str(tmp_path / "t.png")]) == 0


def test_render_rejects_an_image_step_out_of_range(tmp_path, capsys):
    run_file = tmp_path / "run.json"
    _main(["simulate", "plus", "--steps", "2", "--no-progress", "-o", str(run_file)])
    assert _main(["render", "plus", "--run", str(run_file), "--image", "9", "-o", str(tmp_path / "x.png")]) == 2
    assert "--image 9" in capsys.readouterr().err


def test_simulate_set_overrides_a_world_field_and_a_bad_one_exits_2(tmp_path, capsys):
    quiet = ["--set", "motion_noise.turn_scale=0", "--set", "motion_noise.drift_deg_s=0",
             "--set", "motion_noise.slip_omega=0"]
    out = tmp_path / "run.json"
    assert _main(["simulate", "notched_rectangle", "--circuits", "1", "--seed", "1", "-o", str(out), *quiet]) == 0
    turns = [s.action.angle_deg for s in load(out).steps if s.action is not None and hasattr(s.action, "angle_deg")]
    assert turns and all(abs(a + 90) < 1.5 for a in turns)  # no turn-rate noise: turns read as made
    assert _main(["simulate", "notched_rectangle", "--set", "motion_noise.turn_scale=0.9", "--no-progress"]) == 2
    assert "motion_noise.turn_scale: must be <= 0.5, got 0.9" in capsys.readouterr().err
    with pytest.raises(SystemExit) as usage:  # argparse: a malformed setting is a usage error
        _main(["simulate", "notched_rectangle", "--set", "laser.noise_sd"])
    assert usage.value.code == 2
    assert "expected SECTION.FIELD=VALUE" in capsys.readouterr().err
