"""`bootmap serve` refuses bad settings and axioms before starting, with the setting named (exit 2)."""

import os
import subprocess
import sys


def serve(*args, **env):
    environ = {k: v for k, v in os.environ.items() if not k.startswith("BOOTMAP_")} | env
    return subprocess.run([sys.executable, "-m", "bootmap.cli", "serve", *args], capture_output=True, text=True,
                          env=environ, timeout=60)


def test_serve_is_a_sub_command_with_help():
    out = subprocess.run([sys.executable, "-m", "bootmap.cli", "serve", "--help"], capture_output=True, text=True)
    assert out.returncode == 0 and "--db" in out.stdout and "--axioms" in out.stdout and "BOOTMAP_" in out.stdout


def test_a_bad_setting_is_named(tmp_path):
    out = serve("--data-dir", str(tmp_path), BOOTMAP_MAX_STEPS="many")
    assert out.returncode == 2 and "max_steps (BOOTMAP_MAX_STEPS)" in out.stderr and "Traceback" not in out.stderr


def test_axioms_that_do_not_load_stop_the_start(tmp_path):
    (tmp_path / "asp").mkdir()
    (tmp_path / "asp" / "causal.lp").write_text("broken (\n")
    out = serve("--data-dir", str(tmp_path / "data"), "--axioms", str(tmp_path / "asp"))
    assert out.returncode == 2 and "causal.lp" in out.stderr and "does not parse" in out.stderr


def test_a_spool_dir_that_cannot_be_made_stops_the_start_naming_it(tmp_path):
    taken = tmp_path / "a-file"
    taken.write_text("not a directory")
    out = serve("--data-dir", str(tmp_path / "data"), BOOTMAP_SPOOL_DIR=str(taken / "spool"))
    assert out.returncode == 2 and "spool_dir (BOOTMAP_SPOOL_DIR)" in out.stderr and str(taken) in out.stderr
    assert "Traceback" not in out.stderr
