"""The benchmarks' target lines: a miss never reads as the bound it missed."""

import importlib.util
from pathlib import Path

_spec = importlib.util.spec_from_file_location("bench_targets", Path(__file__).resolve().parents[1] / "bench" / "targets.py")
targets = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(targets)


def test_a_miss_that_rounds_to_its_bound_is_shown_with_the_digits_that_tell_them_apart(capsys):
    t = targets.Targets()
    assert not t.check("recall", 70 / 88, ">=", 0.8, fmt="{:.2f}")
    assert t.check("recall", 0.8, ">=", 0.8, fmt="{:.2f}") and t.check("recall", 0.81, ">=", 0.8, fmt="{:.2f}")
    assert not t.check("seconds", 60.04, "<", 60.0, fmt="{:.1f}", unit=" s")
    out = capsys.readouterr().out.splitlines()
    assert out == ["recall: 0.795 (target >= 0.8: MISSED)", "recall: 0.80 (target >= 0.8: ok)",
                   "recall: 0.81 (target >= 0.8: ok)", "seconds: 60.04 s (target < 60 s: MISSED)"]
    assert t.exit_status() == 1
