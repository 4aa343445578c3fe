"""From a log to a tableau, through the library and through `bootmap ingest`."""

import json
from collections import Counter

import pytest

from bootmap.cli import main
from bootmap.logs import ingest
from bootmap.logs.ingest import log_tableau
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
    t = ingest("killian")
    recall = t.meta["truth"]["corner_recall"]
    assert len(t) == 98 and recall["corners"] == 55 and recall["found"] == 53
    seen = Counter(s.truth for s in t.steps)
    assert len(seen) == 69 and sum(n == 1 for n in seen.values()) == 45
