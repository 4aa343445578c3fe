"""The resolver against the truth, on random walks through random grid worlds.

A grid world is geometric, so its true map (one dstate per node and heading) satisfies every axiom.
The resolver returns a *minimal* map that satisfies them, so for every tableau:

* the map passes the independent re-check :func:`support.check.check_map`;
* it has at least one dstate per distinct view (one view per dstate), and with the metrical level at
  least one per distinct (view, heading) pair (one heading per dstate);
* it has no more dstates than the true dstates the walk visited (the truth is a map; the minimal map is
  no larger).

The same holds with the levels causal + topological and causal + metrical. Some worlds bend their
corridors (frames turned by multiples of 15 degrees), so travels change the heading and the metrical
level must add those changes up right. Worlds are kept small (3x3 to 4x4 grids, 20 to 80 steps) so that
a resolution usually takes well under a second. Without the metrical
level the search is much harder (views alias and nothing tells headings apart), so those walks are
shorter (20 to 40 steps) and have more landmarks. A resolution that runs out of time proves nothing
either way: the example is rejected (and counted in hypothesis' statistics) rather than failed.
"""

import numpy as np
from hypothesis import HealthCheck, event, given, note, reject, settings
from hypothesis import strategies as st

from bootmap.errors import SolveTimeout
from bootmap.mapping.resolver import Resolver
from support.check import check_map, tableau_headings, true_partition
from support.gridworld import random_world, walk

LEVEL_SETS = {
    "all": ("causal", "topological", "metrical"),
    "causal+topological": ("causal", "topological"),
    "causal+metrical": ("causal", "metrical"),
}
TIME_LIMIT_S = 10.0


@st.composite
def grid_walks(draw, max_steps=80, landmarks=(0.0, 0.2, 0.5)):
    """A random tableau from a random small grid world (and the world, for the failure report)."""
    seed = draw(st.integers(0, 2**32 - 1), label="seed")
    width, height = draw(st.integers(3, 4), label="width"), draw(st.integers(3, 4), label="height")
    extra = draw(st.integers(0, 3), label="extra_edges")
    landmarks = draw(st.sampled_from(landmarks), label="landmarks")
    # Some worlds bend their corridors, so that travels change the heading too.
    bends = draw(st.sampled_from([0.0, 0.3, 1.0]), label="bends")
    n_steps = draw(st.integers(20, max_steps), label="n_steps")
    policy = draw(st.sampled_from(["random", "explore"]), label="policy")
    rng = np.random.default_rng(seed)
    world = random_world(rng, width, height, extra_edges=extra, landmarks=landmarks, bends=bends)
    return world, walk(world, n_steps, rng, policy=policy)


def view_heading_pairs(tableau) -> int:
    return len(set(zip(tableau.views, tableau_headings(tableau))))


def check_resolution(level_set: str, world, tableau) -> None:
    levels = LEVEL_SETS[level_set]
    note(f"world:\n{world.to_ascii()}\nlandmarks: {dict(world.landmarks)}\nframes: {dict(world.frames)}")
    note(f"tableau: {tableau.dumps()}")
    try:
        resolved = Resolver(levels=list(levels), time_limit=TIME_LIMIT_S).resolve(tableau)
    except SolveTimeout:
        event("resolver timed out")
        reject()
    note(f"resolved: {resolved.dstate_of}")
    assert check_map(tableau, resolved.dstate_of, levels) == []
    n = resolved.n_dstates
    assert n == len(set(resolved.dstate_of))
    assert n >= len(set(tableau.views))
    if "metrical" in levels:
        assert n >= view_heading_pairs(tableau)
    assert n <= len(set(true_partition(tableau)))


def _settings(n):
    return settings(max_examples=n, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@_settings(15)
@given(grid_walks())
def test_resolved_map_is_valid_and_between_views_and_truth(world_and_walk):
    check_resolution("all", *world_and_walk)


@_settings(10)
@given(grid_walks(max_steps=40, landmarks=(0.5, 1.0)))
def test_same_without_metrical_level(world_and_walk):
    check_resolution("causal+topological", *world_and_walk)


@_settings(30)
@given(grid_walks())
def test_same_without_topological_level(world_and_walk):
    check_resolution("causal+metrical", *world_and_walk)
