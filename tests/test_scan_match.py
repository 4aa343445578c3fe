"""Scan matching of laser images (bootmap.scan_match) with the real small_gicp, on hand ray-cast rooms."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bootmap.scan_match import Match, ScanMatcher
from bootmap.surfaces import image_points, surface_points
from support.raycast import CORRIDOR, ROOM, cast

MATCHER = ScanMatcher()


def relative(pa, pb):
    """The pose of ``pb`` in ``pa``'s frame."""
    c, s = math.cos(pa[2]), math.sin(pa[2])
    dx, dy = pb[0] - pa[0], pb[1] - pa[1]
    return c * dx + s * dy, -s * dx + c * dy, (pb[2] - pa[2] + math.pi) % (2 * math.pi) - math.pi


def angle_error(a, b):
    return abs((a - b + math.pi) % (2 * math.pi) - math.pi)


@pytest.mark.parametrize("shift", [(0.6, -0.3, math.radians(25)), (1.5, 0.8, math.radians(-70)),
                                   (-0.4, 0.5, math.radians(40))])
def test_a_scan_against_itself_moved_recovers_the_motion(shift):
    # The room seen again from a pose turned and shifted (views that overlap: the laser covers 180 degrees).
    pa = (2.5, 2.5, 0.3)
    c, s = math.cos(pa[2]), math.sin(pa[2])
    pb = (pa[0] + c * shift[0] - s * shift[1], pa[1] + s * shift[0] + c * shift[1], pa[2] + shift[2])
    a, b = cast(ROOM, pa), cast(ROOM, pb)
    m = MATCHER.match(a, b)
    want = relative(pa, pb)
    assert math.dist(m.transform[:2], want[:2]) < 0.05
    assert angle_error(m.transform[2], want[2]) < math.radians(1)
    # The same walls from a pose turned and shifted: what both saw lies on the other's surface.
    assert m.score > 0.5 and sum(m.refuted) <= 2


def test_a_scan_against_itself_scores_one():
    a = cast(ROOM, (3.0, 3.5, -0.4), noise_m=0.02)
    m = MATCHER.match(a, a)
    assert m.score > 0.98
    assert math.dist(m.transform[:2], (0, 0)) < 0.02 and angle_error(m.transform[2], 0) < math.radians(0.5)


def test_a_noisy_shifted_copy_scores_near_one():
    rng = np.random.default_rng(3)
    pa, pb = (2.0, 2.5, 0.0), (2.3, 2.6, 0.05)
    m = MATCHER.match(cast(ROOM, pa, noise_m=0.02, rng=rng), cast(ROOM, pb, noise_m=0.02, rng=rng))
    assert m.score > 0.9
    want = relative(pa, pb)
    assert math.dist(m.transform[:2], want[:2]) < 0.05 and angle_error(m.transform[2], want[2]) < math.radians(1)


def test_different_rooms_score_clearly_lower_than_a_shifted_copy():
    room, room_moved = cast(ROOM, (2.0, 3.0, 0.2)), cast(ROOM, (2.8, 3.4, 0.5))
    corridor = cast(CORRIDOR, (11.0, 4.0, math.pi / 2))
    same = MATCHER.match(room, room_moved).score
    other = max(MATCHER.match(room, corridor).score, MATCHER.match(corridor, room).score)
    assert same > 0.6
    assert other < same - 0.3


def test_scores_is_symmetric_with_the_matches_scores():
    images = np.array([cast(ROOM, (2.0, 3.0, 0.2)), cast(ROOM, (2.8, 3.4, 0.5)), cast(CORRIDOR, (11, 4, 1.5)),
                       np.full(180, 20.0)])
    S = MATCHER.scores(images)
    assert S.shape == (4, 4) and np.allclose(S, S.T)
    assert S[0, 1] == pytest.approx(MATCHER.match(images[0], images[1]).score)
    assert S[0, 1] > S[0, 2]
    assert (S[3] == 0).all()
    assert np.allclose(ScanMatcher(n_jobs=2).scores(images), S)


@pytest.mark.parametrize("empty", [np.full(180, 20.0), np.zeros(180), np.full(180, 25.0)])
def test_an_image_that_saw_nothing_scores_zero(empty):
    room = cast(ROOM, (2.0, 3.0, 0.2))
    for m in (MATCHER.match(room, empty), MATCHER.match(empty, room), MATCHER.match(empty, empty)):
        assert isinstance(m, Match) and m.score == 0.0
    assert MATCHER.scores([empty, empty]).tolist() == [[0.0, 0.0], [0.0, 0.0]]


def test_points_are_the_beams_that_saw_something():
    image = np.full(180, 20.0)
    image[0], image[90], image[179] = 1.0, 2.0, 3.0
    pts = image_points(image)
    assert pts.shape == (3, 2)
    assert np.allclose(pts[0], (0, -1), atol=1e-9) and np.allclose(pts[2], (0, 3), atol=1e-9)
    # A wall face on at 2 m: consecutive returns 3.5 cm apart are joined and sampled every 5 cm at most.
    wall = surface_points(np.full(180, 2.0))
    gaps = np.linalg.norm(np.diff(wall[np.argsort(np.arctan2(wall[:, 1], wall[:, 0]))], axis=0), axis=1)
    assert gaps.max() <= 0.05 + 1e-9


poses = st.tuples(st.floats(0.8, 7.2), st.floats(0.8, 4.2), st.floats(-math.pi, math.pi))


@settings(max_examples=15, deadline=None)
@given(pa=poses, pb=poses, noise=st.sampled_from([0.0, 0.02]))
def test_score_in_unit_interval_and_matching_symmetric(pa, pb, noise):
    rng = np.random.default_rng(0)
    a, b = cast(ROOM, pa, noise_m=noise, rng=rng), cast(ROOM, pb, noise_m=noise, rng=rng)
    ab, ba = MATCHER.match(a, b), MATCHER.match(b, a)
    assert 0.0 <= ab.score <= 1.0
    assert ab.score == pytest.approx(ba.score, abs=1e-9)
    assert ab.inliers == ba.inliers[::-1] and ab.points == ba.points[::-1]
    # The two transforms are each other's inverse: composing them is no motion.
    x, y, t = ab.transform
    c, s = math.cos(t), math.sin(t)
    u, v, w = ba.transform
    assert math.hypot(x + c * u - s * v, y + s * u + c * v) < 1e-6 and angle_error(t + w, 0.0) < 1e-6


@settings(max_examples=12, deadline=None)
@given(pa=poses, pb=poses, radius=st.sampled_from([1.0, 2.0, 3.0]))
def test_a_match_never_puts_its_visits_farther_apart_than_a_place(pa, pb, radius):
    # A match says the two visits are one place: its motion stays within the place radius, or it is no match.
    m = ScanMatcher(place_radius_m=radius).match(cast(ROOM, pa), cast(ROOM, pb))
    assert math.hypot(*m.transform[:2]) <= radius + 1e-9 or m.score == 0.0


def test_the_room_seen_from_beyond_the_place_radius_is_no_match():
    # The same walls from 1.7 m away: one place within a 3 m radius; within 1 m, ICP (first reach 1 m)
    # slides the search's best shift on to the true motion, beyond that radius: no match.
    pa, pb = (2.0, 2.5, 0.3), (3.6, 3.0, 0.5)
    a, b = cast(ROOM, pa), cast(ROOM, pb)
    wide = ScanMatcher(place_radius_m=3.0).match(a, b)
    assert wide.score > 0.5 and math.dist(wide.transform[:2], relative(pa, pb)[:2]) < 0.05
    narrow = ScanMatcher(place_radius_m=1.0).match(a, b)
    assert narrow.score == 0.0


@pytest.mark.parametrize("turn_deg", [150.0, -100.0, 180.0])
def test_images_all_round_match_from_any_heading(turn_deg):
    """Images of 360 beams (a place's local map is rendered so): the room seen from a pose turned half
    round and shifted is aligned and scores near one, where two 180-degree scans would share no wall."""
    matcher = ScanMatcher(fov_deg=360.0)
    pa = (2.5, 2.5, 0.3)
    pb = (3.1, 2.2, pa[2] + math.radians(turn_deg))
    a, b = cast(ROOM, pa, beams=360, fov_deg=360), cast(ROOM, pb, beams=360, fov_deg=360)
    m = matcher.match(a, b)
    want = relative(pa, pb)
    assert math.dist(m.transform[:2], want[:2]) < 0.05 and angle_error(m.transform[2], want[2]) < math.radians(1)
    assert m.score > 0.9 and sum(m.refuted) <= 2
    # Another room all round scores clearly lower.
    assert matcher.match(a, cast(CORRIDOR, (5.0, 1.0, 0.0), beams=360, fov_deg=360)).score < m.score - 0.3


def test_an_image_all_round_is_read_all_round():
    """At 360 degrees the beams wrap: the returns of a circle of radius 2 are 2 m away all round, and its
    surface closes between the last beam and the first (no gap behind the robot)."""
    circle = np.full(360, 2.0)
    points = image_points(circle, fov_deg=360)
    assert np.allclose(np.hypot(points[:, 0], points[:, 1]), 2.0)
    assert np.allclose(np.degrees(np.arctan2(points[[0, 90, 180, 270], 1], points[[0, 90, 180, 270], 0])),
                       [-180.0, -90.0, 0.0, 90.0])
    surface = surface_points(circle, fov_deg=360, resolution_m=0.01)
    behind = surface[(surface[:, 0] < 0) & (np.abs(surface[:, 1]) < 0.02)]
    assert len(behind) >= 2  # samples between beam 359 (+179 degrees) and beam 0 (-180)


def _places():
    """Three visits each to a room and to a corridor's bend, from poses a little apart: each visit's
    revisits are the other two of its place."""
    rooms = [cast(ROOM, p) for p in ((2.0, 3.0, 0.2), (2.6, 3.3, 0.45), (1.8, 2.5, -0.1))]
    bends = [cast(CORRIDOR, p) for p in ((11.0, 4.0, 1.5), (11.2, 5.0, 1.7), (10.8, 3.2, 1.3))]
    return np.array([rooms[0], bends[0], rooms[1], bends[1], rooms[2], bends[2]])


def test_a_shortlist_verifies_each_images_likeliest_matches_and_no_other():
    images = _places()
    full = MATCHER.scores(images)
    short = ScanMatcher(shortlist=2).scores(images)
    # Each visit's two most alike by the correlative search are its own place's other visits: those pairs
    # are matched in full, the pairs across the two places are not (0: not verified).
    same_place = np.equal.outer(np.arange(6) % 2, np.arange(6) % 2)
    assert np.allclose(short[same_place], full[same_place])
    assert (short[~same_place] == 0).all() and (full[~same_place] > 0).any()
    assert np.allclose(ScanMatcher(shortlist=2, n_jobs=2).scores(images), short)
    # A shortlist as long as the others are many is every pair.
    assert np.allclose(ScanMatcher(shortlist=5).scores(images), full)


@settings(max_examples=8, deadline=None)
@given(k=st.integers(1, 4), order=st.permutations(range(6)))
def test_a_shortlist_is_the_full_scores_of_at_least_k_partners_per_image(k, order):
    images = _places()[list(order)]
    full, short = MATCHER.scores(images), ScanMatcher(shortlist=k).scores(images)
    verified = np.isclose(short, full)
    # A score is the full match's or 0 (not verified); symmetric; every image has k partners verified.
    assert (verified | (short == 0)).all() and np.allclose(short, short.T)
    assert ((verified & ~np.eye(6, dtype=bool)).sum(axis=1) >= k).all()


@settings(max_examples=8, deadline=None)
@given(mask=st.lists(st.booleans(), min_size=36, max_size=36), k=st.sampled_from([None, 2]))
def test_only_the_allowed_pairs_are_scored_and_they_as_in_full(mask, k):
    images = _places()
    allowed = np.array(mask).reshape(6, 6)
    either = (allowed | allowed.T) & ~np.eye(6, dtype=bool)
    matcher = ScanMatcher(shortlist=k)
    full, some = matcher.scores(images), matcher.scores(images, allowed=allowed)
    # A pair neither way allowed scores 0; an allowed one its full match's score, or 0 off a shortlist.
    assert (some[~either & ~np.eye(6, dtype=bool)] == 0).all()
    exact = ScanMatcher().scores(images)
    assert (np.isclose(some, exact) | (some == 0))[either].all()
    if k is None:
        assert np.allclose(some[either], full[either])


def test_allowed_pairs_must_be_one_per_pair_of_images():
    with pytest.raises(ValueError, match="allowed has shape"):
        MATCHER.scores(_places(), allowed=np.ones((5, 5), dtype=bool))
