"""Evaluation against a log's poses: hand-checkable cases for the map, the views and nearest neighbour."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bootmap.experiments.evaluate import dead_reckoned_dstates, nn_on_revisits, shift_tolerant_distances, shuffled_uncertainty
from bootmap.views import ViewClusterer, davies_bouldin_k

from synthetic import pattern


def _turned(scan: np.ndarray, beams: int) -> np.ndarray:
    """The scan a robot turned by ``beams`` degrees reads: shifted, the new edge beams unseen (repeated)."""
    out = np.roll(scan, beams)
    if beams > 0:
        out[:beams] = scan[0]
    elif beams < 0:
        out[beams:] = scan[-1]
    return out


@settings(max_examples=30, deadline=None)
@given(shift=st.integers(-10, 10), corner=st.integers(0, 3), sector=st.integers(0, 3))
def test_a_turned_scan_matches_its_original_under_the_shift_tolerant_distance(shift, corner, sector):
    scans = np.stack([pattern(c, s) for c in range(4) for s in range(4)])
    original = scans[4 * corner + sector]
    d = shift_tolerant_distances(_turned(original, shift)[None], scans)[0]
    assert int(np.argmin(d)) == 4 * corner + sector
    assert d[4 * corner + sector] == pytest.approx(0.0, abs=1e-12)


def test_raw_distance_misses_a_turned_scan_that_the_shift_tolerant_one_finds():
    # Visits 0 and 1 are one true dstate, 1 turned by 6 beams; 2, another dstate, lies half-way between
    # them beam by beam, so it is each one's raw nearest neighbour.
    base = np.linspace(1.0, 8.0, 180) ** 1.3
    turned = _turned(base, 6)
    images = np.stack([base, turned, (base + turned) / 2])
    truth = ["P0:N", "P0:N", "P1:N"]
    raw, shift = nn_on_revisits(images, truth, "raw"), nn_on_revisits(images, truth, "shift")
    assert (raw["revisited"], shift["revisited"]) == (0.0, 1.0)
    assert raw["revisited_visits"] == 2 and raw["revisited_dstates"] == 1
    assert shift["ceiling"] == pytest.approx(2 / 3) and shift["all_visits"] == pytest.approx(2 / 3)


def test_no_dstate_seen_twice_has_nothing_to_recognise():
    r = nn_on_revisits(np.eye(3), ["a", "b", "c"])
    assert r["revisited"] is None and r["ceiling"] == 0.0 and r["all_visits"] == 0.0


def test_an_unknown_descriptor_is_named():
    with pytest.raises(ValueError, match="unknown scan descriptor 'sift'"):
        nn_on_revisits(np.eye(3), ["a", "a", "b"], "sift")


def test_views_that_copy_the_truth_beat_the_shuffled_baseline():
    truth = [f"S{i % 6}" for i in range(60)]
    assert shuffled_uncertainty(truth, truth) < 0.2  # six views of 60 visits: by chance U is small


def test_davies_bouldin_finds_the_clusters_where_m_picks_fewer():
    # Three tight groups of very different spreads: M's 1/(k * SSE) is dominated by the widest group.
    rng = np.random.default_rng(0)
    x = np.concatenate([rng.normal(0, 3.0, (30, 5)), rng.normal(40, 0.1, (30, 5)), rng.normal(80, 0.1, (30, 5))])
    model = ViewClusterer(k_max=6).fit(x)
    k, scores = davies_bouldin_k(model, x)
    assert k == 3 and scores[0] is None and len(scores) == 6


def test_dead_reckoned_dstates_join_close_visits_and_each_turns_two_ends():
    # Two turns at one corner (odometry 1 m apart), then a turn 20 m away; headings east then north.
    odometry = [(0, 0, 0), (0.5, 0.5, 1.57), (20, 0, 0), (20, 0.5, 1.57), (1, 0, 0), (1, 0.5, 1.57)]
    track = [(x, 0, 0) for x in range(30)]
    assert dead_reckoned_dstates(odometry, track) == ["P0:E", "P0:N", "P1:E", "P1:N", "P0:E", "P0:N"]
