"""Dead reckoning re-anchored at the joins made (bootmap.mapping.loops.anchoring): the shortest ways through
the drive and the joins, checked against a plain search of the whole graph."""

import heapq

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bootmap.mapping.loops.anchoring import Anchoring


def searched(along, xy, groups, jump):
    """Every pair's shortest way and its displacement by Dijkstra over every time point (the reference)."""
    n = len(along)
    edges = {t: [] for t in range(n)}
    for t in range(n - 1):
        edges[t].append((t + 1, along[t + 1] - along[t], xy[t + 1] - xy[t]))
        edges[t + 1].append((t, along[t + 1] - along[t], xy[t] - xy[t + 1]))
    for g in groups:
        for a in g:
            edges[a] += [(b, jump, np.zeros(2)) for b in g if b != a]
    R, V = np.full((n, n), np.inf), np.zeros((n, n, 2))
    for s in range(n):
        R[s, s], heap = 0.0, [(0.0, s)]
        while heap:
            d, u = heapq.heappop(heap)
            if d > R[s, u]:
                continue
            for v, w, dv in edges[u]:
                if d + w < R[s, v]:
                    R[s, v], V[s, v] = d + w, V[s, u] + dv
                    heapq.heappush(heap, (d + w, v))
    return R, V


@st.composite
def drives(draw):
    n = draw(st.integers(2, 24))
    # a turn on the spot drives nowhere: hops of no length are drawn too
    hops = draw(st.lists(st.one_of(st.just(0.0), st.floats(0.5, 60.0)), min_size=n - 1, max_size=n - 1))
    along = np.concatenate([[0.0], np.cumsum(hops)])
    xy = np.array(draw(st.lists(st.tuples(st.floats(-200, 200), st.floats(-200, 200)), min_size=n, max_size=n)))
    labels = draw(st.lists(st.integers(0, max(1, n // 3)), min_size=n, max_size=n))  # a partition of the points
    groups = [[t for t in range(n) if labels[t] == g] for g in set(labels)]
    jump = draw(st.floats(1.0, 150.0))
    return along, xy, groups, jump


@settings(max_examples=60, deadline=None)
@given(drives())
def test_the_shortest_ways_through_drive_and_joins_are_those_a_full_search_finds(drive):
    along, xy, groups, jump = drive
    driven, displacement = Anchoring(along, xy, groups, jump).rows(range(len(along)))
    R, V = searched(along, xy, groups, jump)
    assert np.allclose(driven, R, atol=1e-6)
    assert np.allclose(driven, driven.T)
    assert np.all(driven <= np.abs(along[:, None] - along[None, :]) + 1e-9)  # never longer than the drive
    for g in groups:
        for x in g:
            for y in g:
                assert driven[x, y] <= jump + 1e-9
    # where two ways tie, either displacement is right: compare where the shortest way is the only one
    unique = _unique_ways(along, groups, jump, R)
    assert np.allclose(displacement[unique], V[unique], atol=1e-6)
    assert np.allclose(displacement[unique], -displacement.transpose(1, 0, 2)[unique], atol=1e-6)
    # rows asked a few at a time are the rows asked all at once
    assert all(np.allclose(Anchoring(along, xy, groups, jump).rows([t])[0][0], driven[t]) for t in range(len(along)))


def _unique_ways(along, groups, jump, R):
    """Pairs whose shortest way is the only one (no other within a millimetre): their displacement is
    defined. A way to t is unique when one edge into t lies on a shortest way, from a point whose way is."""
    n = len(along)
    into = {t: [(u, abs(along[t] - along[u])) for u in (t - 1, t + 1) if 0 <= u < n] for t in range(n)}
    for g in groups:
        for t in g:
            into[t] += [(u, jump) for u in g if u != t]
    out = np.zeros((n, n), dtype=bool)
    for s in range(n):
        out[s, s] = True
        for t in sorted(range(n), key=lambda t: R[s, t]):
            if t != s:
                on = [u for u, w in into[t] if abs(R[s, u] + w - R[s, t]) < 1e-3]
                out[s, t] = len(on) == 1 and out[s, on[0]]
    return out & out.T


def test_without_joins_the_drive_is_its_own_way():
    along = np.array([0.0, 5, 12, 30])
    xy = np.array([[0, 0], [5, 0], [5, 7], [20, 7.0]])
    driven, displacement = Anchoring(along, xy, [[0], [1], [2], [3]], jump_m=10.0).rows(range(4))
    assert np.allclose(driven, np.abs(along[:, None] - along[None, :]))
    assert np.allclose(displacement, xy[None, :, :] - xy[:, None, :])


def test_a_join_shortens_the_way_and_moves_nothing():
    # a 400 m loop closed where it began (t0 = t4); t3 lies 100 m before the closure
    along = np.array([0.0, 100, 200, 300, 400])
    xy = np.array([[0, 0], [100, 0], [100, 100], [0, 100], [0, 3.0]])  # 3 m of drift round the loop
    a = Anchoring(along, xy, [[0, 4]], jump_m=50.0)
    metres, displacement = a.way(0, 3)
    assert metres == pytest.approx(150.0) and np.allclose(displacement, [0, 97])
    assert a.way(1, 3)[0] == pytest.approx(200.0)  # the drive is shorter than the way through the join
    with pytest.raises(ValueError, match="jump_m"):
        Anchoring(along, xy, [[0, 4]], jump_m=0.0)
    with pytest.raises(ValueError, match="4 positions for 5 time points"):
        Anchoring(along, xy[:4], [], jump_m=10.0)
