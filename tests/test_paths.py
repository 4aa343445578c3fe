"""Paths thinned for drawing: every point stays within the tolerance of the thinned path, and the ends stay."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from bootmap.paths import simplify


def _distance_to_polyline(points: np.ndarray, line: np.ndarray) -> np.ndarray:
    a, b = line[:-1], line[1:]
    ab = b - a
    span = np.maximum((ab * ab).sum(axis=1), 1e-12)
    t = np.clip(((points[:, None, :] - a[None]) * ab[None]).sum(axis=2) / span, 0.0, 1.0)
    gap = points[:, None, :] - a[None] - t[..., None] * ab[None]
    return np.hypot(gap[..., 0], gap[..., 1]).min(axis=1)


@settings(max_examples=80, deadline=None)
@given(steps=st.lists(st.tuples(st.floats(-1, 1), st.floats(-1, 1)), min_size=2, max_size=200),
       tolerance=st.sampled_from([0.001, 0.02, 0.1, 0.5]))
def test_every_point_stays_within_the_tolerance_and_the_ends_are_kept(steps, tolerance):
    xy = np.cumsum(np.array(steps), axis=0)
    keep = simplify(xy, tolerance)
    assert keep[0] == 0 and keep[-1] == len(xy) - 1 and np.all(np.diff(keep) > 0)
    if len(keep) >= 2:
        assert _distance_to_polyline(xy, xy[keep]).max() <= tolerance + 1e-9


def test_a_straight_run_is_its_two_ends():
    xy = np.column_stack([np.linspace(0, 10, 500), np.zeros(500)])
    assert simplify(xy, 0.01).tolist() == [0, 499]


def test_a_path_of_fewer_than_three_points_is_kept_whole():
    for n in range(3):
        assert simplify(np.zeros((n, 2)), 0.1).tolist() == list(range(n))
