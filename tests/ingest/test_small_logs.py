"""Logs however small, and files that are no log: a result, or exit 2 naming the file and what is missing.

The logs are the synthetic square (tests/ingest/synthetic.py) as a gmapping-corrected CARMEN log, gzip
compressed, cut to a few scans: before its first turn there is no dstate; once it has turned, two.
"""

import gzip
import json

import numpy as np
import pytest

from bootmap.cli import main
from bootmap.errors import BadInput, LogError
from bootmap.experiments.log import run_log_experiment
from bootmap.experiments.world import recognition_section
from bootmap.recognise import TooFewImages, fitting_sizes, learning_curve_cv, online_curve
from bootmap.views import ViewClusterer, davies_bouldin_k

from synthetic import corrected_lines, square_poses, write_corrected_log


def test_every_cut_of_a_log_gives_a_result_or_a_clear_refusal(tmp_path):
    outcomes = {}
    for n in range(1, 13):
        log = write_corrected_log(tmp_path / f"square-{n}.log.gz", n)
        try:
            r = run_log_experiment(log)
        except (LogError, BadInput) as e:
            assert str(log) in str(e)
            outcomes[n] = "refused"
        else:
            assert r["scans"] == n and r["images"] >= 2
            outcomes[n] = "ran"
    # The turn starts at the 5th scan, 15 degrees a scan: once it has turned 45 degrees or more (the 9th),
    # its two ends are dstates; before, there is none.
    assert [n for n, o in outcomes.items() if o == "ran"] == [9, 10, 11, 12]


@pytest.mark.parametrize("scans, message", [
    (1, "1 scan: a log needs at least 2 to have any motion"),
    (6, "the odometry turns nowhere in 6 scans (no heading change of 45 degrees or more"),
])
def test_too_few_scans_exit_2_naming_the_file(tmp_path, capsys, scans, message):
    log = write_corrected_log(tmp_path / "short.log.gz", scans)
    for argv in (["experiment", "--log", str(log), "-o", str(tmp_path / "out")],
                 ["ingest", str(log), "--no-progress", "-o", str(tmp_path / "t.json")]):
        assert main(argv) == 2
        assert f"{log}: {message}" in capsys.readouterr().err


def test_two_dstates_run_and_say_what_they_could_not_compute(tmp_path, capsys):
    log = write_corrected_log(tmp_path / "turn.log.gz", 12)
    out = tmp_path / "out"
    assert main(["experiment", "--log", str(log), "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    r = json.loads((out / "results.json").read_text())
    v, rec = r["views"], r["recognition"]
    assert r["images"] == 2 and v["ks"] == [1, 2] and v["k_by_davies_bouldin"] is None
    assert v["k_note"].startswith("k capped at 2, below k_max 12: 2 images")
    assert "no k by Davies-Bouldin" in v["k_note"] and v["k_note"] in printed
    assert rec["cv_sizes"] == [] and rec["cv_at_90"] is None and len(rec["online_accuracy"]) == 2
    assert rec["cv_note"] == "no learning curve: 2 images: 10-fold cross-validation needs at least 10"
    assert (out / "report.md").stat().st_size > 0 and (out / "learning_curves.png").stat().st_size > 0


def _truncated_gzip(path):
    whole = gzip.compress("\n".join(corrected_lines(square_poses()[:40])).encode())
    path.write_bytes(whole[:len(whole) // 2])


@pytest.mark.parametrize("name, write, message", [
    ("empty.log", lambda p: p.write_bytes(b""), "the file is empty: no laser scan"),
    ("empty.log.gz", lambda p: p.write_bytes(gzip.compress(b"")), "the file is empty: no laser scan"),
    ("cut.log.gz", _truncated_gzip, "the gzip stream ends early: a truncated file"),
    ("damaged.log.gz", lambda p: p.write_bytes(b"\x1f\x8b\x08\x00\x00\x00\x00\x00\x00\x03" + bytes(range(256)) * 4),
     "corrupt gzip data"),
    ("binary.log", lambda p: p.write_bytes(bytes(range(256)) * 8), "binary data, not a CARMEN log"),
    ("odom.log.gz", lambda p: p.write_bytes(gzip.compress(b"PARAM a 1 h 0\nODOM 0 0 0 0 0 0 1.0 h 1.0\n")),
     "no laser scan: none of its 2 records is a FLASER, ROBOTLASER1 or RAWLASER1 line"),
])
def test_a_file_that_is_no_log_exits_2_saying_why(tmp_path, capsys, name, write, message):
    log = tmp_path / name
    write(log)
    for argv in (["experiment", "--log", str(log), "-o", str(tmp_path / "out")],
                 ["ingest", str(log), "--no-progress"]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert f"{log}: {message}" in err and "Traceback" not in err


@pytest.mark.parametrize("n", [2, 3, 4, 5])
def test_davies_bouldin_with_k_max_at_or_above_the_images(n):
    x = np.arange(n, dtype=float)[:, None] ** 2  # n distinct images
    clusterer = ViewClusterer(k_max=n + 3).fit(x)
    assert clusterer.ks_.tolist() == list(range(1, n + 1))
    k, scores = davies_bouldin_k(clusterer, x)
    # Undefined at one cluster and at a cluster per image; defined between.
    assert scores[0] is None and scores[-1] is None
    assert all(s is not None and s >= 0 for s in scores[1:-1])
    assert k == (None if n < 3 else 1 + int(np.argmin(scores[1:-1])) + 1)


def test_davies_bouldin_when_images_repeat():
    x = np.array([[0.0], [0.0], [1.0], [1.0]])  # two distinct images: k capped at 2
    clusterer = ViewClusterer(k_max=12).fit(x)
    assert clusterer.ks_.tolist() == [1, 2]
    assert davies_bouldin_k(clusterer, x) == (2, [None, 0.0])


@pytest.mark.parametrize("n, needed", [(0, 10), (5, 10), (11, 12)])
def test_too_few_images_for_a_learning_curve_are_named(n, needed):
    x, y = np.arange(2 * n, dtype=float).reshape(n, 2), np.arange(n) % 2
    with pytest.raises(TooFewImages, match=f"^{n} images: ") as caught:
        learning_curve_cv(x, y)
    assert (caught.value.images, caught.value.needed) == (n, needed)
    assert isinstance(caught.value, ValueError)


def test_the_fewest_images_for_a_learning_curve_give_one():
    assert fitting_sizes(12).tolist() == [10]
    x = np.repeat(np.eye(3), 4, axis=0)
    curve = learning_curve_cv(x, np.repeat([0, 1, 2], 4), random_state=0)
    assert curve.sizes.tolist() == [10] and curve.scores.shape == (1, 10)


@pytest.mark.parametrize("n", [1, 2, 11])
def test_recognition_with_too_few_images_reports_none_and_why(n):
    x = np.arange(n, dtype=float)[:, None]
    labels = [f"S{i % 3}" for i in range(n)]
    rec = recognition_section(x, labels)
    assert rec["online_accuracy"] == online_curve(x, labels).tolist()
    assert (rec["cv_sizes"], rec["cv_mean"], rec["cv_at_90"], rec["learner_cv_at_90"]) == ([], [], None, None)
    assert rec["cv_note"].startswith(f"no learning curve: {n} images: ")


def test_recognition_with_enough_images_has_no_note():
    x = np.arange(12, dtype=float)[:, None]
    rec = recognition_section(x, [f"S{i % 3}" for i in range(12)])
    assert rec["cv_note"] is None and rec["cv_sizes"] == [10]
