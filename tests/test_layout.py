"""The map's drawing (bootmap.layout): places where the robot's travels put them, the same every time."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from bootmap import examples
from bootmap.layout import layout
from bootmap.mapping import Deadline, Resolver
from bootmap.metrics import dstate_accuracy
from bootmap.tableau import Step, Tableau, Travel, Turn
from support.gridworld import random_world, walk


def _drawn(tableau: Tableau, levels=None) -> dict:
    cmap = Resolver(levels=levels).resolve(tableau, Deadline.after(20)).to_dict()
    return layout(cmap, tableau.to_dict())


def test_the_paper_room_is_drawn_as_its_rectangle_with_dstates_towards_their_headings():
    drawn = _drawn(examples.notched_rectangle(circuits=3))
    assert drawn["method"] == "metrical" and drawn["closure_rms_m"] < 1e-6
    xy = {p: drawn["places"][p]["xy"] for p in drawn["places"]}
    assert xy == {"P0": [0, 0], "P1": [0, -4], "P2": [-2, -4], "P3": [-2, 0]}
    assert drawn["places"]["P0"]["dstates"] == ["S0", "S1"]
    # S0 faces 0 degrees (+x), S1 after the right turn faces 270 (-y): each sits off P0 that way.
    s0, s1 = drawn["dstates"]["S0"]["xy"], drawn["dstates"]["S1"]["xy"]
    assert s0[0] > 0 and abs(s0[1]) < 1e-9 and s1[1] < 0 and abs(s1[0]) < 1e-9
    assert drawn["paths"]["Pa1"] == {"places": ["P0", "P1"], "points": [[0, 0], [0, -4]]}
    assert drawn["trajectory"] is None  # the hand-made tableau has no poses


def test_without_the_metrical_level_the_places_are_laid_out_by_travel_distance_and_the_same_each_time():
    tableau = examples.notched_rectangle(circuits=2)
    first, again = (_drawn(tableau, ["causal", "topological"]) for _ in range(2))
    assert first == again
    assert first["method"] == "graph" and first["closure_rms_m"] is None
    xy = {p: np.array(v["xy"]) for p, v in first["places"].items()}
    # Neighbours along the room's sides are nearer than the diagonal opposites, as the travels say.
    assert np.linalg.norm(xy["P0"] - xy["P1"]) < np.linalg.norm(xy["P0"] - xy["P2"])
    assert len({tuple(v) for v in map(tuple, xy.values())}) == 4


def test_travels_that_do_not_close_fall_back_to_the_graph_layout():
    # A "room" whose third side is 1 m where the first is 4 m: the headings say rectangle, the lengths
    # cannot close it (3 m short), so the metrical fit is refused and the residual reported.
    cycle = [Turn(-90.0), Travel(4.0), Turn(-90.0), Travel(2.0), Turn(-90.0), Travel(1.0), Turn(-90.0), Travel(2.0)]
    steps = [Step(view=f"V{t % 8}", action=cycle[t % 8]) for t in range(16)] + [Step(view="V0")]
    drawn = _drawn(Tableau(tuple(steps), "open room"))
    assert drawn["method"] == "graph" and drawn["closure_rms_m"] > 0.4
    assert len(drawn["places"]) == 4


def test_travels_that_do_not_close_are_drawn_at_the_robots_odometry_when_the_steps_carry_it():
    # The same open room, now with the robot's own dead-reckoned pose at each step (a log's): each place
    # at the mean of its visits' odometry, in the frame of the first step (turned so it faces along x).
    cycle = [Turn(-90.0), Travel(4.0), Turn(-90.0), Travel(2.0), Turn(-90.0), Travel(1.0), Turn(-90.0), Travel(2.0)]
    corners = [(10, 5), (10, 5), (10, 1), (10, 1), (8, 1), (8, 1), (8, 4), (8, 4)]  # facing north at first
    steps = [Step(view=f"V{t % 8}", action=cycle[t % 8], odometry=(*corners[t % 8], math.pi / 2))
             for t in range(16)] + [Step(view="V0", odometry=(10, 5, math.pi / 2))]
    drawn = _drawn(Tableau(tuple(steps), "open room, with odometry"))
    assert drawn["method"] == "odometry"
    xy = {p: v["xy"] for p, v in drawn["places"].items()}
    assert xy == {"P0": [0.0, 0.0], "P1": [-4.0, 0.0], "P2": [-4.0, 2.0], "P3": [-1.0, 2.0]}


def test_poses_give_the_true_trajectory_in_their_own_frame():
    rng = np.random.default_rng(7)
    world = random_world(rng, 3, 3, extra_edges=1, landmarks=1.0)
    tableau = walk(world, 40, rng, policy="explore")
    drawn = _drawn(tableau)
    assert drawn["trajectory"] == [[round(s.pose[0], 4), round(s.pose[1], 4)] for s in tableau.steps]


@settings(max_examples=8, deadline=None)
@given(st.integers(0, 10_000), st.floats(0.5, 5.0))
def test_places_sit_where_the_world_has_them_up_to_the_robots_starting_frame(seed, cell):
    # Exploring walks of random grid worlds whose nodes carry landmarks: the resolver finds the true
    # map; its layout must be the world's nodes, turned so that the first heading is 0 and moved so
    # that the first place is at the origin.
    rng = np.random.default_rng(seed)
    world = random_world(rng, 3, 3, extra_edges=1, landmarks=1.0, letters="ABCDEFGHI", cell_m=cell)
    tableau = walk(world, 50, rng, policy="explore")
    cmap = Resolver().resolve(tableau, Deadline.after(20))
    if dstate_accuracy(cmap.dstate_of, [s.truth for s in tableau.steps]) < 1.0:
        return  # an aliased walk whose minimal map is not the world: nothing to compare with
    drawn = layout(cmap.to_dict(), tableau.to_dict())
    assert drawn["method"] == "metrical" and drawn["closure_rms_m"] < 1e-6
    x0, y0, theta0 = tableau.steps[0].pose
    turn = np.array([[math.cos(-theta0), -math.sin(-theta0)], [math.sin(-theta0), math.cos(-theta0)]])
    for t, row in enumerate(cmap.to_dict()["steps"]):
        x, y, _ = tableau.steps[t].pose
        expected = turn @ np.array([x - x0, y - y0])
        assert np.allclose(drawn["places"][row["place"]]["xy"], expected, atol=1e-3), (t, row["place"])


def test_a_map_of_one_place_is_drawn_at_the_origin_with_its_dstates_around_it():
    # Turns only: one place, three dstates facing 0, 90 and 180 degrees; no travel to lay anything out by.
    steps = [Step(view="a", action=Turn(90.0)), Step(view="b", action=Turn(90.0)), Step(view="c")]
    drawn = _drawn(Tableau(tuple(steps), "one place"))
    assert drawn["method"] == "graph" and list(drawn["places"]) == ["P0"]
    assert drawn["places"]["P0"] == {"xy": [0, 0], "dstates": ["S0", "S1", "S2"]}
    assert [drawn["dstates"][d]["xy"] for d in ("S0", "S1", "S2")] == [[0.22, 0], [0, 0.22], [-0.22, 0]]
    assert drawn["bounds"] == [-0.22, 0, 0.22, 0.22]
