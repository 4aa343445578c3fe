"""From a log to a tableau, through the library and through `bootmap ingest`."""

import json
from collections import Counter

import pytest

from bootmap.cli import main
from bootmap.ingest.ingest import ingest
from bootmap.ingest.ingest import log_tableau, read_log
from bootmap.tableau import Tableau, Travel, Turn, load

from log_data import EXCERPT


def test_the_excerpt_becomes_a_tableau_of_turns_and_travels(excerpt_scans):
    t = log_tableau(excerpt_scans)
    assert len(t) == 16
    assert [type(a) for a in t.actions] == [Turn, Travel] * 7 + [Turn]
    assert t.actions[0] == Turn(-89.0) and t.actions[1].distance_m == pytest.approx(47.23)
    assert all(len(s.image) == 180 and max(s.image) <= 20.0 for s in t.steps)
    assert t.steps[0].pose == pytest.approx(excerpt_scans[18].truth, abs=1e-4)  # the true pose, for evaluation
    assert t.meta["laser"]["range_max"] == 20.0 and t.meta["dstates"]["scans"][:2] == [18, 25]


def test_truth_puts_each_turn_at_one_place_and_headings_in_the_buildings_frame(excerpt_scans):
    t = log_tableau(excerpt_scans)
    truth = [s.truth for s in t.steps]
    places = [x.split(":")[0] for x in truth]
    assert places[0::2] == places[1::2]  # a turn's two ends
    assert truth[:4] == ["P0:S", "P0:W", "P1:W", "P1:N"]
    assert len(set(truth)) == 16 and t.meta["truth"]["corner_recall"]["recall"] == 1.0


def test_the_tableau_round_trips_through_json(excerpt_scans):
    t = log_tableau(excerpt_scans)
    back = Tableau.loads(t.dumps())
    assert back.steps == t.steps


def test_bootmap_ingest_writes_the_run(tmp_path, capsys):
    out = tmp_path / "run.json"
    assert main(["ingest", str(EXCERPT), "-o", str(out), "--no-progress"]) == 0
    assert len(load(out)) == 16
    assert "16 dstates from 360 scans" in capsys.readouterr().err


def test_bootmap_ingest_exits_2_on_a_bad_log(tmp_path, capsys):
    bad = tmp_path / "bad.g2o"
    bad.write_text("VERTEX_SE2 0 0 0 0\nROBOTLASER1 0 -1.57 3.14 0.0174 50 0.1 0 180 1 2\n")
    assert main(["ingest", str(bad), "-o", str(tmp_path / "x.json"), "--no-progress"]) == 2
    assert f"{bad}: line 2: ROBOTLASER1 declares 180 beams" in capsys.readouterr().err


def test_a_straight_run_has_no_dstates(excerpt_scans):
    with pytest.raises(Exception, match="turns nowhere"):
        log_tableau(excerpt_scans[30:110])


def test_killian_whole_log_truth():
    pytest.importorskip("rtbdata")
    # Killian's odometry drifts less than the calibration's bound, which leaves it as recorded (tested with
    # the experiment, tests/ingest/test_killian_readme.py): the same tableau, without reading the drift.
    t = log_tableau(read_log("killian"), calibrate=False)
    recall = t.meta["truth"]["corner_recall"]
    assert len(t) == 98 and recall["corners"] == 55 and recall["found"] == 53
    seen = Counter(s.truth for s in t.steps)
    assert len(seen) == 75 and sum(n == 1 for n in seen.values()) == 53
    # No travel starts and ends at one true place (the SSH: a travel leaves its place).
    places = [s.truth.split(":")[0] for s in t.steps]
    assert all(places[k] != places[k + 1] for k, a in enumerate(t.actions) if isinstance(a, Travel))
    # The robot's own odometry at every dstate, the flag that it drove through dstates, and a true path
    # thinned to fit what the service takes as a tableau's meta (64 KiB by default).
    assert all(s.odometry is not None for s in t.steps) and t.meta["passes_through"] is True
    assert 100 < len(t.meta["trajectory"]) < 3873 and len(json.dumps(t.meta)) < 64 * 1024


def _corridor_log():
    """Scans of a robot that turns, drives 20 m down a corridor (walls 1 m off) past a side corridor on
    its left at 10 m, and turns again: poses exact, and the true poses the same."""
    import math

    import numpy as np

    from bootmap.ingest.scans import Scan

    angles = np.radians(np.arange(-90, 90, 1.0))
    poses = [(0.0, 0.0, math.radians(-90 + 15 * k)) for k in range(7)]  # a left turn on the spot
    poses += [(0.25 * k, 0.0, 0.0) for k in range(1, 81)]
    poses += [(20.0, 0.0, math.radians(15 * k)) for k in range(1, 7)]
    scans = []
    for i, (x, y, h) in enumerate(poses):
        with np.errstate(divide="ignore"):
            ranges = np.minimum(1.0 / np.abs(np.sin(angles)), 30.0)
        if h == 0.0 and 8.75 <= x <= 11.25:
            ranges[angles > np.radians(60)] = 12.0  # the side corridor, open to the left
        scans.append(Scan(0.1 * i, ranges, float(angles[0]), math.radians(1.0), 30.0, (x, y, h), (x, y, h)))
    return scans


def test_junctions_passed_are_dstates_when_asked_for():
    from bootmap.ingest.dstates import JunctionDetector

    scans = _corridor_log()
    turns_only = log_tableau(scans)
    assert [type(a) for a in turns_only.actions] == [Turn, Travel, Turn]
    t = log_tableau(scans, junctions=JunctionDetector())
    assert [type(a) for a in t.actions] == [Turn, Travel, Travel, Turn]
    pass_step = t.steps[2]
    assert pass_step.pose[0] == pytest.approx(10.0, abs=0.3)
    # the two travels add up to the one they cut, and the pass is a place of its own
    assert t.actions[1].distance_m + t.actions[2].distance_m == pytest.approx(turns_only.actions[1].distance_m)
    places = [s.truth.split(":")[0] for s in t.steps]
    assert places[0] == places[1] and places[3] == places[4] and len(set(places)) == 3
    assert t.meta["dstates"]["passes"] == [t.meta["dstates"]["scans"][2]]
    assert Tableau.loads(t.dumps()).steps == t.steps  # the pass's scan index is a plain int in the JSON


def test_bootmap_ingest_junctions_records_its_detector_and_experiment_on_a_world_refuses_it(tmp_path, capsys):
    out = tmp_path / "run.json"
    assert main(["ingest", str(EXCERPT), "-o", str(out), "--no-progress", "--junctions"]) == 0
    meta = load(out).meta["dstates"]
    assert meta["junctions"]["min_width_m"] == 1.5 and set(meta["passes"]) <= set(meta["scans"])
    assert main(["experiment", "notched_rectangle", "--junctions"]) == 2
    assert "--junctions: for an experiment on a robot's log" in capsys.readouterr().err
