"""Streaming maps (issue 14): the map after every appended step equals a fresh resolve of the same steps."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from bootmap.tableau import Tableau

from bootmap.examples import notched_rectangle
from bootmap.mapping import Resolver
from bootmap.mapping.stream import MapStream
from bootmap.testing.gridworld import random_world, walk


def same_map(a, b) -> bool:
    """Two maps say the same (their solver figures aside)."""
    da, db = a.to_dict(), b.to_dict()
    da.pop("stats"), db.pop("stats")
    return da == db


def streamed_equals_batch(tableau, every: int = 1):
    stream, resolver = MapStream(Resolver(time_limit=30)), Resolver(time_limit=30)
    for n in range(1, len(tableau) + 1):
        streamed = stream.update(tableau.prefix(n))
        if n % every == 0 or n == len(tableau):
            batch = resolver.resolve(tableau.prefix(n))
            assert same_map(streamed, batch), f"prefix of {n} time points"
    return stream


def test_the_papers_tableau_streamed_step_by_step_is_the_papers_map():
    stream = streamed_equals_batch(notched_rectangle(6))
    assert stream.map_.n_dstates == 8 and stream.map_.unique
    assert stream.extended_ > stream.resolved_  # most steps repeat a known transition


@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 10_000), policy=st.sampled_from(["random", "explore"]))
def test_streaming_equals_batch_on_every_prefix_of_a_random_walk(seed, policy):
    rng = np.random.default_rng(seed)
    world = random_world(rng, 3, 3, extra_edges=1, landmarks=0.3)
    stream = streamed_equals_batch(walk(world, 60, rng, policy=policy))
    assert stream.extended_ + stream.resolved_ == 60


@pytest.mark.slow
def test_streaming_equals_batch_on_a_long_exploration():
    rng = np.random.default_rng(7)
    world = random_world(rng, 4, 4, extra_edges=2, landmarks=0.5)
    stream = streamed_equals_batch(walk(world, 240, rng, policy="explore"), every=8)
    assert stream.extended_ > 120


def test_a_step_that_breaks_the_map_is_resolved_again():
    # A walk whose map was unique gets a step that contradicts it: the same action from the same
    # dstate leads to another view. The stream must not keep the old partition.
    full = notched_rectangle(3)
    doc = full.to_dict()
    doc["steps"][-1]["view"] = "V9"
    broken = Tableau.from_dict(doc)
    stream = MapStream(Resolver(time_limit=30, misreads=False))
    stream.update(full.prefix(len(full) - 1))
    cmap = stream.update(broken)
    assert (stream.extended_, stream.resolved_) == (0, 2)
    assert same_map(cmap, Resolver(time_limit=30, misreads=False).resolve(broken))
    assert cmap.n_dstates > 8
