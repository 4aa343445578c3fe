"""Grid worlds: construction, local geometry, walks, and the oracle property (the true map obeys the axioms)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bootmap.tableau import Tableau, Travel, Turn
from support.check import check_map, true_partition
from support.gridworld import (TRAVEL, TURN_AROUND, GridWorld, neighbour, random_world,
                                       truth_id, walk)

T_JUNCTION = """
+-+-+
  |
  +
"""


def parse_truth(truth: str) -> tuple[tuple[int, int], int]:
    node, heading = truth.split(":")
    x, y = node.split(",")
    return (int(x), int(y)), int(heading)


# -- hand-written worlds --------------------------------------------------------------------------

def test_ascii_t_junction():
    w = GridWorld.from_ascii(T_JUNCTION)
    assert w.nodes == {(0, 1), (1, 1), (2, 1), (1, 0)}
    assert w.edges == {((0, 1), (1, 1)), ((1, 1), (2, 1)), ((1, 0), (1, 1))}
    # At the junction, facing each way: left, front, right, back.
    assert [w.view(((1, 1), h)) for h in (0, 90, 180, 270)] == [".FRB", "L.RB", "LF.B", "LFR."]
    assert w.view(((0, 1), 0)) == ".F.." and w.view(((1, 0), 90)) == ".F.."


def test_ascii_landmarks_and_round_trip():
    text = "A-+\n| |\n+-B"
    w = GridWorld.from_ascii(text)
    assert w.landmarks == {(0, 1): "A", (1, 0): "B"}
    assert w.view(((0, 1), 0)) == ".FR./A"
    assert w.to_ascii() == text
    assert GridWorld.from_ascii(w.to_ascii()) == w


def test_from_edges_matches_ascii():
    w = GridWorld.from_edges([((0, 1), (1, 1)), ((2, 1), (1, 1)), ((1, 1), (1, 0))])
    assert w == GridWorld.from_ascii(T_JUNCTION)


@pytest.mark.parametrize("edges", [[((0, 0), (2, 0))], [((0, 0), (1, 1))]])
def test_from_edges_rejects_non_unit_edges(edges):
    with pytest.raises(ValueError, match="4-neighbours"):
        GridWorld.from_edges(edges)


def test_ascii_rejects_misplaced_symbols():
    with pytest.raises(ValueError, match="lattice"):
        GridWorld.from_ascii("+--+")


def test_actions_only_turn_towards_open_sides():
    w = GridWorld.from_ascii(T_JUNCTION)
    assert w.actions(((1, 1), 0)) == ["right", TURN_AROUND, TRAVEL]        # left is a wall
    assert w.actions(((0, 1), 180)) == [TURN_AROUND]                        # dead end, facing the wall
    with pytest.raises(ValueError, match="wall"):
        w.step(((0, 1), 180), TRAVEL)
    assert w.step(((1, 1), 0), "right") == ((1, 1), 270)
    assert w.step(((1, 1), 270), TRAVEL) == ((1, 0), 270)


# -- random worlds --------------------------------------------------------------------------------

@settings(max_examples=50, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), width=st.integers(1, 6), height=st.integers(2, 6),
       extra=st.integers(0, 6), keep=st.sampled_from([1.0, 0.8, 0.5]))
def test_random_world_is_a_connected_grid_subgraph(seed, width, height, extra, keep):
    w = random_world(np.random.default_rng(seed), width, height, extra_edges=extra, keep=keep)
    assert w.is_connected()
    assert all(0 <= x < width and 0 <= y < height for x, y in w.nodes)
    assert len(w.nodes) == max(2, round(keep * width * height))
    # A spanning tree has n - 1 edges; the extra ones close loops (as many as the grid allows).
    assert len(w.nodes) - 1 <= len(w.edges) <= len(w.nodes) - 1 + extra


def test_random_world_is_deterministic():
    a = random_world(np.random.default_rng(7), 5, 4, extra_edges=3, landmarks=0.3)
    b = random_world(np.random.default_rng(7), 5, 4, extra_edges=3, landmarks=0.3)
    c = random_world(np.random.default_rng(8), 5, 4, extra_edges=3, landmarks=0.3)
    assert a == b and a != c


def test_bends_turn_frames_without_changing_the_graph():
    # Frames are drawn last: the same generator gives the same nodes, edges and landmarks with bends.
    plain = random_world(np.random.default_rng(7), 5, 4, extra_edges=3, landmarks=0.3)
    bent = random_world(np.random.default_rng(7), 5, 4, extra_edges=3, landmarks=0.3, bends=0.5)
    assert (bent.nodes, bent.edges, bent.landmarks) == (plain.nodes, plain.edges, plain.landmarks)
    assert plain.frames == {} and len(bent.frames) == 10
    assert all(a % 15 == 0 and -180 < a <= 180 and a != 0 for a in bent.frames.values())


def test_frames_off_the_quantum_are_refused():
    with pytest.raises(ValueError, match="multiple of 15"):
        GridWorld.from_ascii("+-+").with_frames({(1, 0): 10})


def test_landmark_fraction():
    w = random_world(np.random.default_rng(3), 4, 5, landmarks=0.25, letters="XY")
    assert len(w.landmarks) == 5 and set(w.landmarks.values()) <= {"X", "Y"}


# -- walks ----------------------------------------------------------------------------------------

def small_world(seed=1):
    return random_world(np.random.default_rng(seed), 4, 4, extra_edges=2, landmarks=0.2)


@pytest.mark.parametrize("policy", ["random", "explore"])
def test_walk_is_deterministic(policy):
    w = small_world()
    a = walk(w, 50, np.random.default_rng(5), policy=policy)
    b = walk(w, 50, np.random.default_rng(5), policy=policy)
    c = walk(w, 50, np.random.default_rng(6), policy=policy)
    assert a.to_dict() == b.to_dict() and a.to_dict() != c.to_dict()
    assert len(a) == 50 and a.meta["policy"] == policy


@pytest.mark.parametrize("policy", ["random", "explore"])
@pytest.mark.parametrize("bends", [0.0, 0.5])
def test_walk_steps_are_consistent_with_the_world(policy, bends):
    w = random_world(np.random.default_rng(2), 4, 4, extra_edges=2, landmarks=0.2, bends=bends)
    t = walk(w, 120, np.random.default_rng(0), policy=policy)
    states = [parse_truth(s.truth) for s in t.steps]
    frame = {n: w.frames.get(n, 0) for n in w.nodes}
    for step, state in zip(t.steps, states):
        assert step.view == w.view(state) and step.truth == truth_id(state)
        # The pose faces the node's heading turned by the node's frame.
        plane = math.radians(state[1] + frame[state[0]]) % (2 * math.pi)
        assert step.pose == pytest.approx((state[0][0] * 2.0, state[0][1] * 2.0, plane))
    bent = 0
    for (node, h), (node2, h2), a in zip(states, states[1:], t.actions):
        if isinstance(a, Travel):
            assert w.is_open(node, h) and node2 == neighbour(node, h) and h2 == h
            # A travel turns the robot in the plane by the difference of the two frames.
            assert a.distance_m == 2.0 and (a.heading_change_deg - frame[node2] + frame[node]) % 360 == 0
            assert -180 < a.heading_change_deg <= 180
            bent += a.heading_change_deg != 0
        else:
            assert node2 == node and (h + a.angle_deg - h2) % 360 == 0
            assert a.angle_deg == 180 or w.is_open(node, h2)
    assert (bent > 0) == (bends > 0)


@pytest.mark.parametrize("policy", ["random", "explore"])
def test_walk_never_turns_twice_in_a_row_when_it_can_travel(policy):
    w = small_world(3)
    t = walk(w, 200, np.random.default_rng(1), policy=policy)
    states = [parse_truth(s.truth) for s in t.steps]
    for i in range(1, len(t.actions)):
        if isinstance(t.actions[i - 1], Turn) and isinstance(t.actions[i], Turn):
            assert not w.is_open(*states[i])


def test_explore_visits_every_corridor_end_of_a_t_junction():
    w = GridWorld.from_ascii(T_JUNCTION)
    t = walk(w, 40, np.random.default_rng(0), policy="explore")
    visited = {parse_truth(s.truth) for s in t.steps}
    assert {(n, h) for n in w.nodes for h in w.open_headings(n)} <= visited


def test_explore_covers_more_than_random():
    w = random_world(np.random.default_rng(11), 5, 5, extra_edges=3)
    seen = {p: len({s.truth for s in walk(w, 150, np.random.default_rng(2), policy=p).steps})
            for p in ("random", "explore")}
    assert seen["explore"] > seen["random"]


def test_walk_rejects_unknown_policy():
    with pytest.raises(ValueError, match="policy"):
        walk(small_world(), 10, np.random.default_rng(0), policy="wander")


def test_walk_tableau_survives_json():
    t = walk(small_world(), 30, np.random.default_rng(0))
    assert Tableau.loads(t.dumps()).to_dict() == t.to_dict()


# -- the oracle property ---------------------------------------------------------------------------

@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), width=st.integers(2, 6), height=st.integers(2, 6),
       extra=st.integers(0, 5), landmarks=st.sampled_from([0.0, 0.2, 1.0]),
       keep=st.sampled_from([1.0, 0.7]), n=st.integers(1, 150),
       policy=st.sampled_from(["random", "explore"]), bends=st.sampled_from([0.0, 0.5, 1.0]))
def test_true_map_satisfies_every_axiom(seed, width, height, extra, landmarks, keep, n, policy, bends):
    # Bent corridors keep the world a plane figure, so its true map still satisfies every axiom.
    rng = np.random.default_rng(seed)
    w = random_world(rng, width, height, extra_edges=extra, landmarks=landmarks, keep=keep, bends=bends)
    t = walk(w, n, rng, policy=policy)
    assert check_map(t, true_partition(t)) == []


def test_docstring_examples():
    import doctest

    import support.gridworld

    assert doctest.testmod(support.gridworld).failed == 0
