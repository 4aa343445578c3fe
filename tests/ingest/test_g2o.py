"""The g2o reader on the committed Killian excerpt, and on broken copies of it."""

import math
import random

import numpy as np
import pytest

from bootmap.errors import BadInput, LogError
from bootmap.ingest.g2o import read_g2o, read_g2o_text
from bootmap.ingest.scans import compose



def test_excerpt_has_one_scan_per_vertex_with_the_sick_layout(excerpt_scans):
    assert len(excerpt_scans) == 360
    first = excerpt_scans[0]
    assert len(first.ranges) == 180 and first.range_max == 50.0
    assert first.angle_min == pytest.approx(-math.pi / 2, abs=1e-6)
    assert first.angle_increment == pytest.approx(math.radians(1), abs=1e-6)
    assert first.ranges[:3].tolist() == [1.27, 1.32, 1.32]
    assert first.time == pytest.approx(1031745824.658)


def test_truth_is_the_vertex_and_odometry_starts_there(excerpt_scans):
    assert excerpt_scans[1].truth == (1.717, 37.352, -2.006596)
    assert excerpt_scans[0].odometry == excerpt_scans[0].truth == (1.96, 37.867, -2.01239)


def test_odometry_is_the_sequential_edges_dead_reckoned(excerpt_scans):
    # EDGE_SE2 0 1 0.569450 0.000409 0.005789: the first odometry step, composed onto vertex 0.
    expected = compose((1.96, 37.867, -2.01239), (0.569450, 0.000409, 0.005789))
    assert excerpt_scans[1].odometry == pytest.approx(expected)
    # 180 m on: odometry and truth part by a few metres (the wheels' drift), not by zero.
    last = excerpt_scans[-1]
    assert last.odometry[:2] == pytest.approx((-16.6595, 70.4972), abs=1e-3)
    assert math.dist(last.odometry[:2], last.truth[:2]) == pytest.approx(3.55, abs=0.01)


def test_edge_order_and_loop_closures_do_not_change_the_odometry(excerpt_lines, excerpt_scans):
    edges = [line for line in excerpt_lines if line.startswith("EDGE_SE2")]
    others = [line for line in excerpt_lines if not line.startswith("EDGE_SE2")]
    random.Random(7).shuffle(edges)
    wild_loop = "EDGE_SE2 5 300 99 99 3 500 0 0 500 0 5000"  # a loop closure the odometry must not use
    scans = read_g2o_text(others + edges + [wild_loop])
    np.testing.assert_allclose([s.odometry for s in scans], [s.odometry for s in excerpt_scans], atol=1e-12)


def _broken(lines, number, new):
    """The excerpt with line ``number`` (1-based) replaced."""
    out = list(lines)
    out[number - 1] = new
    return out


def _laser_line(lines):
    return next(i for i, line in enumerate(lines, 1) if line.startswith("ROBOTLASER1"))


def test_a_truncated_scan_line_is_refused_naming_the_line(excerpt_lines):
    n = _laser_line(excerpt_lines)
    cut = excerpt_lines[n - 1][:300]
    with pytest.raises(LogError, match=rf"^excerpt: line {n}: ROBOTLASER1 declares 180 beams but the line ends"):
        read_g2o_text(_broken(excerpt_lines, n, cut), "excerpt")


def test_a_wrong_beam_count_is_refused(excerpt_lines):
    n = _laser_line(excerpt_lines)
    tokens = excerpt_lines[n - 1].split()
    tokens[8] = "179"  # one beam fewer than the line holds
    with pytest.raises(LogError, match=rf"line {n}: after the 179 declared beams comes .1.\d+. where the number of remissions should be: a wrong beam count"):
        read_g2o_text(_broken(excerpt_lines, n, " ".join(tokens)), "excerpt")


def test_a_nan_range_is_refused_naming_the_line(excerpt_lines):
    n = _laser_line(excerpt_lines)
    tokens = excerpt_lines[n - 1].split()
    tokens[20] = "nan"
    with pytest.raises(LogError, match=rf"line {n}: a range reads 'nan', not a finite number"):
        read_g2o_text(_broken(excerpt_lines, n, " ".join(tokens)), "excerpt")


def test_a_missing_odometry_edge_breaks_the_chain(excerpt_lines):
    lines = [line for line in excerpt_lines if not line.startswith("EDGE_SE2 41 42 ")]
    with pytest.raises(LogError, match="no odometry edge 41 -> 42"):
        read_g2o_text(lines, "excerpt")


def test_a_file_without_scans_is_bad_input(tmp_path):
    path = tmp_path / "poses.g2o"
    path.write_text("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n")
    with pytest.raises(BadInput, match=f"{path}: no ROBOTLASER1 line"):
        read_g2o(path)


def test_the_whole_killian_log_from_rtb_data():
    pytest.importorskip("rtbdata")
    from bootmap.ingest.g2o import killian

    scans = killian()
    assert len(scans) == 3873
    drift = max(math.dist(s.odometry[:2], s.truth[:2]) for s in scans)
    assert 120 < drift < 130  # dead reckoning off by up to 126 m
