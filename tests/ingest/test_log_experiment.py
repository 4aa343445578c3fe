"""The experiment on a log, end to end: library and `bootmap experiment --log`, judged by the log's poses."""

import json
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bootmap.cli import main
from bootmap.errors import BadInput, LogError
from bootmap.experiments.evaluate import DESCRIPTORS
from bootmap.experiments.log import (LOCAL_MAP, LOCAL_MAP_IN_REACH, LOCAL_MAP_REANCHORED, LOCAL_MAP_VERIFIED,
                                     SCAN_MATCH, headline, place_recognition_along, place_recognition_method,
                                     run_log_experiment, visits_along)
from bootmap.ingest.ingest import read_log
from bootmap.ingest.places import PlaceDetector

from log_data import EXCERPT
from synthetic import ring_poses, ring_walls, write_drive_log, write_square_log


@pytest.fixture(scope="module")
def square(tmp_path_factory):
    return write_square_log(tmp_path_factory.mktemp("logs") / "square.log")


@pytest.fixture(scope="module")
def square_run(square, tmp_path_factory):
    out = tmp_path_factory.mktemp("square_report")
    return run_log_experiment(square, out_dir=out), out


def test_two_laps_of_a_square_give_its_map_by_hand(square_run):
    r, _ = square_run
    # 4 corners, each turned at twice: 16 dstates, 8 true ones (a corner and a heading), 4 places, 4 sides.
    assert (r["images"], r["truth"]["true_dstates"]) == (16, 8)
    m = r["map"]
    # By loop closing (the default): exact odometry puts every revisit on its first visit.
    assert (m["dstates"], m["places"], m["paths"]) == (8, 4, 4) and m["found_by"] == "loop closing"
    assert (m["true_dstates"], m["true_places"]) == (8, 4)
    assert m["dstate_accuracy"] == 1.0 and m["place_accuracy"] == 1.0
    assert m["every_visit_own_dstate_accuracy"] == 0.5  # each true dstate seen twice: half by renaming
    # Exact odometry: dead-reckoned places are the true ones.
    assert r["dead_reckoning"] == {"dstates": 8, "dstate_accuracy": 1.0}


def test_the_papers_fewest_dstates_give_the_square_too(square):
    r = run_log_experiment(square, mapper="fewest")
    m = r["map"]
    assert (m["dstates"], m["places"], m["paths"]) == (8, 4, 4)
    assert m["found_by"] == "fewest dstates" and m["proved_minimal"] and m["dstate_accuracy"] == 1.0


def test_an_unknown_mapper_is_refused(square):
    with pytest.raises(BadInput, match="unknown mapper 'guess'"):
        run_log_experiment(square, mapper="guess")


def test_the_square_meets_every_target_and_says_so(square_run):
    r, _ = square_run
    assert r["truth"]["corner_recall"]["recall"] == 1.0
    assert all(t["met"] for t in r["targets"].values())
    for d in ("raw", "shift"):
        n = r["nn_revisited"][d]
        assert (n["revisited"], n["ceiling"], n["revisited_visits"]) == (1.0, 1.0, 16)


def test_the_square_is_judged_as_slam_papers_judge_a_map(square_run):
    r, out = square_run
    b = r["baselines"]
    assert (b["map"], b["odometry_alone"], b["own_dstate"]) == (1.0, 1.0, 0.5)
    # Exact odometry ties the map: it beats a dstate per visit, not odometry alone, yet makes no error.
    assert not b["beats_baselines"] and b["error_ratio"] == 0.0 and b["target_met"]
    # Lap two closes every true dstate of lap one (8 pairs); each place's 4 visits make 4 closing pairs
    # (a turn's two ends, left in between by nothing, are not a closure).
    exact = {"precision": 1.0, "recall": 1.0}
    assert r["loop_closure"]["map"]["dstates"] == {"joins": 8, "true_joins": 8, "should_join": 8, **exact}
    assert r["loop_closure"]["map"]["places"] == {"joins": 16, "true_joins": 16, "should_join": 16, **exact}
    for d in DESCRIPTORS:  # a revisit reads its first visit's scan exactly
        p = r["place_recognition"][d]
        assert (p["visits"], p["revisits"], p["best_correct"]) == (16, 8, 8)
        assert p["recall_at_95_precision"] == p["recall_at_99_precision"] == 1.0
    perfect = r["perfect_odometry"]
    assert perfect["images"] == 16 and perfect["map"]["dstate_accuracy"] == 1.0
    for name in ("map_accuracy", "error_over_better_baseline", "loop_closure_precision",
                 "place_recognition_recall_at_95_precision", "perfect_odometry_map_accuracy"):
        assert r["targets"][name]["met"], name
    saved = json.loads((out / "results.json").read_text())
    assert {"baselines", "loop_closure", "place_recognition", "perfect_odometry"} <= saved.keys()
    report = (out / "report.md").read_text()
    assert "beats both: no" in report and "recall 100.0% at 95% precision" in report


def test_without_the_perfect_odometry_run_its_target_is_left_out(square):
    r = run_log_experiment(square, perfect_odometry=False)
    assert r["perfect_odometry"] is None and "perfect_odometry_map_accuracy" not in r["targets"]
    assert r["targets"]["loop_closure_precision"]["met"]


def test_views_beat_shuffled_truth_on_the_square(square_run):
    v = square_run[0]["views"]
    assert (v["k"], v["k_by_M"], v["criterion"]) == (8, 8, "M") and not v["M_degenerate"]
    assert v["U"][7] == 1.0 and v["U_shuffled"][7] < 0.9


def test_the_report_has_its_figures(square_run):
    r, out = square_run
    for name in ("results.json", "report.md", "views_M_U.png", "trajectory.png", "topological_map.png",
                 "learning_curves.png", "precision_recall.png"):
        assert (out / name).stat().st_size > 0, name
    assert json.loads((out / "results.json").read_text())["map"]["dstates"] == 8
    assert "visits in their true dstate: 100.0%" in (out / "report.md").read_text()


def test_the_excerpt_runs_end_to_end_from_the_command_line(tmp_path, capsys):
    assert main(["experiment", "--log", str(EXCERPT), "-o", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "360 scans, 16 dstates chosen; turns at 8 of 8 corners; truth: 16 true dstates" in out
    # No true dstate of the excerpt is seen twice: nothing to recognise, and the output says so.
    assert "nearest neighbour (raw scans): no true dstate is seen twice" in out
    r = json.loads((tmp_path / "results.json").read_text())
    assert r["views"]["k_by_M"] == 1 and r["views"]["criterion"] == "davies-bouldin"
    assert r["map"]["dstates"] >= r["map"]["true_dstates"] - 2
    # The excerpt's corners are right angles, read within a few degrees: no action is taken as mistyped.
    assert r["map"]["retyped_steps"] == []


@pytest.mark.parametrize("argv, message", [
    (["--log", "no/such.log"], "no/such.log: no such file or directory"),
    (["--log", str(EXCERPT), "--seeds", "1,2"], "--seeds: for the simulated experiment"),
    (["notched_rectangle", "--log", str(EXCERPT)], "give a world or --log, not both"),
    ([], "give a world (e.g. taylor_hall) or a robot's log"),
])
def test_bad_input_exits_2_naming_it(argv, message, capsys):
    assert main(["experiment", *argv]) == 2
    assert message in capsys.readouterr().err


@pytest.fixture
def bare(tmp_path, square):
    """The square's log without its true poses."""
    path = tmp_path / "bare.log"
    path.write_text("".join(line + "\n" for line in square.read_text().splitlines() if not line.startswith("TRUEPOS")))
    return path


def test_a_log_without_true_poses_has_nothing_to_evaluate(bare):
    with pytest.raises(LogError, match="no true poses"):
        run_log_experiment(bare)


def test_an_unknown_view_criterion_is_refused(square):
    with pytest.raises(BadInput, match="unknown view criterion 'silhouette'"):
        run_log_experiment(square, view_criterion="silhouette")


def test_places_the_laser_shows_are_revisited_lap_after_lap_and_scan_matching_recognises_them(tmp_path):
    """Two laps of a ring corridor, ray-cast: its four corners are the places the laser shows (the way
    ahead closes, one opens to the side), each turned at on both laps; exact odometry closes the loop,
    and scan matching finds each corner's first visit from its second."""
    log = write_drive_log(tmp_path / "ring.log", ring_walls(), ring_poses(laps=2))
    r = run_log_experiment(log, places=PlaceDetector(), perfect_odometry=False)
    assert r["dstates_at"] == "places"
    # 4 corners x 2 laps, a turn each: 16 dstates chosen, 8 true (a corner and a heading).
    assert (r["images"], r["truth"]["true_dstates"]) == (16, 8)
    assert r["map"]["dstate_accuracy"] == 1.0 and r["loop_closure"]["map"]["dstates"]["precision"] == 1.0
    matched = r["place_recognition"][SCAN_MATCH]
    assert matched["revisits"] == 8 and matched["recall_at_95_precision"] >= 0.75
    # So does matching the corners' local maps, rendered all round (bootmap.ingest.local_maps).
    local = r["place_recognition"][LOCAL_MAP]
    assert local["revisits"] == 8 and local["recall_at_95_precision"] >= 0.75
    # Searched within odometry's reach, no fewer of them: exact odometry rules out no true revisit.
    reached = r["place_recognition"][LOCAL_MAP_IN_REACH]
    assert (reached["revisits"], reached["queries"]) == (8, local["queries"])
    assert reached["recall_at_95_precision"] >= local["recall_at_95_precision"]
    # Verified by their surroundings, the same revisits, each found; and so within the reach of dead
    # reckoning re-anchored at the loops the map closed before each visit (the method judged).
    verified = r["place_recognition"][LOCAL_MAP_VERIFIED]
    assert (verified["revisits"], verified["queries"]) == (8, local["queries"])
    assert verified["best_correct"] == 8 and verified["recall_at_95_precision"] >= 0.75
    reanchored = r["place_recognition"][LOCAL_MAP_REANCHORED]
    assert place_recognition_method(r)[0] == LOCAL_MAP_REANCHORED
    assert (reanchored["revisits"], reanchored["queries"], reanchored["best_correct"]) == (8, local["queries"], 8)
    assert reanchored["recall_at_95_precision"] >= 0.75
    # The headline names each method as it is, the judged one as such; only the raw descriptors are scans.
    lines = "\n".join(headline(r))
    assert "place recognition (local map re-anchored, the one judged;" in lines
    assert "place recognition (raw scans;" in lines and "local map in reach;" in lines
    # The raw scans of a corner's two visits, a few centimetres apart, are told apart less well.
    assert matched["average_precision"] >= max(r["place_recognition"][d]["average_precision"] for d in DESCRIPTORS)


def test_why_on_a_logs_map_shows_what_the_laser_says_beside_odometry(tmp_path):
    """`bootmap why` on a log's loop-closed map: a join proposed by odometry also shows the two scans'
    match once aligned; so does a pair odometry keeps apart, where the laser would join them. A tableau
    that does not say what laser took its images shows none."""
    from dataclasses import replace

    from bootmap.ingest.ingest import ingest
    from bootmap.mapping.loops import LoopCloser
    from bootmap.tableau import Tableau

    log = write_drive_log(tmp_path / "ring.log", ring_walls(), ring_poses(laps=2))
    tableau = ingest(log)
    tableau = tableau.with_views(["corridor"] * len(tableau))  # views say nothing: odometry and the laser
    closer = LoopCloser()
    cmap = closer.resolve(tableau)
    second = len(tableau) // 2  # the first corner again, on the second lap
    assert cmap.dstate_of[0] == cmap.dstate_of[second]
    same = closer.explain(tableau, 0, second)
    (join,) = [j for j in same.joins if j.startswith(f"t0 = t{second}: proposed")]
    score = float(re.search(r"their scans, aligned, score (\d\.\d\d)", join).group(1))
    assert score > 0.9 and "0.0 m apart)" in join
    # The second lap's odometry 30 m off: odometry keeps them apart, and the laser says what it would.
    shifted = Tableau(tuple(s if t < second else replace(s, odometry=(s.odometry[0] + 30.0, *s.odometry[1:]))
                            for t, s in enumerate(tableau.steps)), tableau.world, dict(tableau.meta))
    apart = closer.explain(shifted, 0, second)
    assert apart.verdict == "different" and "more than odometry may drift" in apart.sentence
    assert re.search(r"their scans, aligned, score (0\.9\d|1\.00)", apart.sentence)
    # Kept apart by their headings, the laser is not asked.
    assert "scan" not in closer.explain(tableau, 0, 1).sentence
    # Without the laser's description, no scan match is claimed.
    bare = Tableau(tableau.steps, tableau.world, {k: v for k, v in tableau.meta.items() if k != "laser"})
    assert not any("scan" in j for j in closer.explain(bare, 0, second).joins)


def test_dstates_at_places_is_for_logs_only(capsys):
    assert main(["experiment", "notched_rectangle", "--dstates", "places"]) == 2
    assert "--dstates: for an experiment on a robot's log" in capsys.readouterr().err


def test_no_calibrate_is_for_logs_only(capsys):
    assert main(["experiment", "notched_rectangle", "--no-calibrate"]) == 2
    assert "--no-calibrate: for an experiment on a robot's log" in capsys.readouterr().err


def test_a_log_ingested_as_recorded_keeps_its_odometry(tmp_path, capsys):
    # --no-calibrate: no calibration looked for, none recorded; by default it is looked for and recorded
    log = write_drive_log(tmp_path / "ring.log", ring_walls(), ring_poses(laps=1))
    assert main(["ingest", str(log), "-o", str(tmp_path / "as_recorded.json"), "--no-calibrate", "--no-progress"]) == 0
    assert main(["ingest", str(log), "-o", str(tmp_path / "calibrated.json"), "--no-progress"]) == 0
    as_recorded = json.loads((tmp_path / "as_recorded.json").read_text())["meta"]
    calibrated = json.loads((tmp_path / "calibrated.json").read_text())["meta"]
    assert "calibration" not in as_recorded["odometry"]  # the building's axis is recorded either way
    assert as_recorded["odometry"]["axis_deg"] == calibrated["odometry"]["axis_deg"]
    # the drive's odometry is exact: the laser finds no drift worth taking out
    assert calibrated["odometry"]["calibration"]["applied"] is False
    assert "calibrated by the laser" not in capsys.readouterr().err


def test_place_recognition_is_judged_by_a_method_fixed_beforehand_not_by_the_best_descriptor():
    from bootmap.experiments.log import RECOGNITION_PREFERENCE, best_place_recognition, place_recognition_method

    def figures(recall):
        return {"recall_at_95_precision": recall}

    measured = {"place_recognition": {d: figures(1.0) for d in DESCRIPTORS}}
    measured["place_recognition"][LOCAL_MAP_IN_REACH] = figures(0.2)
    # The local maps within loop closing's reach are judged, though a scan descriptor did better here
    assert place_recognition_method(measured) == (LOCAL_MAP_IN_REACH, figures(0.2))
    assert best_place_recognition(measured)[1] == figures(1.0)
    # Without scan matching, the first scan descriptor in the fixed order
    scans_only = {"place_recognition": {d: figures(0.1 * i) for i, d in enumerate(DESCRIPTORS)}}
    first = next(d for d in RECOGNITION_PREFERENCE if d in DESCRIPTORS)
    assert place_recognition_method(scans_only)[0] == first


@pytest.mark.slow
def test_place_recognition_along_the_drive_finds_the_second_lap_where_it_was_on_the_first(tmp_path):
    """Two laps of the ring corridor, a visit every 3 m: the visits of the second lap revisit the first,
    odometry (exact here) allows the true match, and scan matching the local maps, verified by their
    surroundings, puts each at the right place; the first lap has nothing earlier to revisit."""
    log = write_drive_log(tmp_path / "ring.log", ring_walls(), ring_poses(laps=2))
    r = place_recognition_along(log, every_m=3.0)
    assert r["verified"] and r["reanchored"]
    # A corridor of one width looks alike all along it: matched place by place, a visit's look-alikes a few
    # metres on outscore it; verified by its surroundings (the corners 6 m on), every revisit is found.
    plain = place_recognition_along(log, every_m=3.0, verify=False)
    assert (plain["revisits"], plain["queries"]) == (r["revisits"], r["queries"])
    assert r["best_correct"] == r["revisits"] > plain["best_correct"]
    assert r["recall_at_95_precision"] >= 0.9 > plain["recall_at_95_precision"] + 0.5
    scans = read_log(log)
    visits = visits_along(scans, 3.0)
    assert r["visits"] == len(visits) and r["every_m"] == 3.0
    lap = len(visits) // 2
    assert lap - 3 <= r["revisits"] <= r["queries"] <= len(visits)
    assert r["best_correct"] >= 0.75 * r["revisits"]
    assert 0.0 <= r["recall_at_99_precision"] <= r["recall_at_95_precision"] <= r["best_correct"] / r["revisits"]


@settings(max_examples=25, deadline=None)
@given(steps=st.lists(st.floats(0.0, 3.0), min_size=1, max_size=60), every=st.sampled_from([0.5, 2.0, 5.0]))
def test_visits_along_are_every_so_many_metres_of_the_drive(steps, every):
    from bootmap.ingest.scans import Scan

    x = np.concatenate([[0.0], np.cumsum(steps)])
    scans = [Scan(float(k), np.full(3, 5.0), -1.0, 1.0, 20.0, (float(v), 0.0, 0.0)) for k, v in enumerate(x)]
    taken = visits_along(scans, every)
    assert taken[0] == 0 and taken == sorted(set(taken))
    gaps = np.diff(x[taken])
    assert (gaps >= every - 1e-9).all()
    # None is skipped: between two taken scans, every scan before the second was under every_m on.
    for a, b in zip(taken, taken[1:]):
        assert (x[a:b] - x[a] < every - 1e-9).all()


def test_place_recognition_along_refuses_what_it_cannot_judge(square, bare):
    with pytest.raises(BadInput, match="every_m > 0"):
        place_recognition_along(square, every_m=0.0)
    with pytest.raises(LogError, match="bare.log: the log has no true poses"):
        place_recognition_along(bare)


def test_bootmap_ingest_gives_the_lasers_place_matches_and_loop_closing_weighs_them(tmp_path, capsys):
    """`bootmap ingest` writes each visit's place matches with the earlier visits (meta.place_matches): on
    two laps of the ring corridor, every corner's second visit matches its first. Where odometry cannot
    join them (the second lap 5 m off, beyond a near proposal after 70 m; the views all different, so no
    retraced context), the matches do, and `bootmap why` says so; without them the laps stay apart."""
    from dataclasses import replace

    from bootmap.mapping.loops import LoopCloser
    from bootmap.tableau import Tableau, load

    log = write_drive_log(tmp_path / "ring.log", ring_walls(), ring_poses(laps=2))
    out = tmp_path / "ring.json"
    assert main(["ingest", str(log), "-o", str(out), "--no-progress"]) == 0
    tableau = load(out)
    said = f"; {len(tableau.meta['place_matches'])} place matches between visits"
    assert said in capsys.readouterr().err
    second = len(tableau) // 2
    matches = {(m["a"], m["b"]): m["score"] for m in tableau.meta["place_matches"]}
    assert all(matches.get((t, t + second), 0) > 0.9 for t in range(second))  # each corner, both ends
    assert all(a < b for a, b in matches)
    shifted = Tableau(tuple(replace(s, view=f"v{t}", odometry=(s.odometry[0] + (5.0 if t >= second else 0.0),
                                                                *s.odometry[1:]))
                            for t, s in enumerate(tableau.steps)), tableau.world, dict(tableau.meta))
    cmap = LoopCloser().resolve(shifted)
    assert all(cmap.dstate_of[t] == cmap.dstate_of[t + second] for t in range(second))
    why = LoopCloser().explain(shifted, 0, second)
    assert any(f"t0 = t{second}: proposed (recognised): the laser matches their places" in j for j in why.joins)
    blind = Tableau(shifted.steps, shifted.world, {k: v for k, v in shifted.meta.items() if k != "place_matches"})
    assert LoopCloser().resolve(blind).n_dstates == len(tableau)
    assert main(["ingest", str(log), "-o", str(out), "--no-progress", "--no-place-matches"]) == 0
    assert "place_matches" not in load(out).meta and "matching the places" not in capsys.readouterr().err
    # With progress shown, the place matching (the longest part) says what it is doing before it starts.
    assert main(["ingest", str(log), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert err.index(f"matching the places of {len(tableau)} dstates") < err.index("place matches between visits")
