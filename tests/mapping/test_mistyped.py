"""Mistyped actions: a reading far from its learned type is abduced as the neighbouring type, at a cost,
and the map names it (the Killian log's 45- and 60-degree corners read on a 90-degree grid)."""

import numpy as np
import pytest

from bootmap.examples import notched_rectangle
from bootmap.mapping import Resolver
from bootmap.mapping.motion import MotionPrimitives, type_suspects
from bootmap.mapping.resolver import MISTYPE_COST
from bootmap.metrics import dstate_accuracy
from bootmap.tableau import Turn
from support.check import check_map, true_partition
from support.gridworld import random_world, walk
from support.noise import LOGGED, ROUNDINGS, with_mistyped_action, with_odometry_noise


def exploration(seed: int, turn_sd: float = 3.0, steps: int = 600, rounding=LOGGED):
    """600 steps exploring a 20-place grid world, turns read with noise (as tests/mapping/test_misreads.py
    makes them), recorded as a log records them (or unrounded)."""
    rng = np.random.default_rng(seed)
    world = random_world(rng, 5, 4, extra_edges=4, landmarks=0.4)
    return with_odometry_noise(walk(world, steps, rng, policy="explore"), turn_sd, turn_sd / 2, rng,
                               rounding=rounding), rng


def learned(tableau):
    m = MotionPrimitives().fit(tableau.actions)
    return m.angles_, m.grid_deg_


@pytest.mark.parametrize("rounding", ROUNDINGS, ids=["logged", "unrounded"])
@pytest.mark.parametrize("seed", [21, 22])
def test_a_mistyped_turn_is_named_and_the_map_is_the_truth(seed, rounding):
    clean, rng = exploration(seed, rounding=rounding)
    tableau, at = with_mistyped_action(clean, rng, rounding=rounding)
    angles, grid = learned(tableau)
    truth_angle = clean.steps[at].action.angle_deg
    # The learned types take the misread turn for another action: that is what the resolver has to undo.
    assert abs(((angles[at] - truth_angle) + 180) % 360 - 180) >= 45
    cmap = Resolver(time_limit=60).resolve(tableau)
    truth = true_partition(tableau)
    assert [s["t"] for s in cmap.retyped_steps] == [at]
    step = cmap.retyped_steps[0]
    assert step["learned_deg"] == angles[at] and step["cost"] == MISTYPE_COST
    assert abs(((step["abduced_deg"] - truth_angle) + 180) % 360 - 180) < 10  # retyped as the turn it was
    assert cmap.n_dstates == len(set(truth)) and dstate_accuracy(truth, cmap.dstate_of) == 1.0
    assert cmap.minimal
    # Independently of clingo: the map satisfies every axiom on the turns as the robot really made them.
    assert check_map(clean, cmap.dstate_of, cmap.levels, quantum_deg=90) == []
    assert "actions taken as mistyped: t%d" % at in cmap.to_text()
    assert cmap.to_dict()["retyped_steps"] == cmap.retyped_steps


def test_without_retyping_the_mistyped_turn_costs_dstates():
    """The same tableau read with its learned types alone: the theory proves more dstates than the truth
    has (the heading after the turn is wrong for every later time point)."""
    clean, rng = exploration(21)
    tableau, _ = with_mistyped_action(clean, rng)
    from bootmap.mapping.grounding import Deadline
    from bootmap.mapping.search import Search

    search = Search(Resolver(retype=False), tableau, Deadline.after(60))
    assert search.retyping.proved_with(search.state.angles) > len(set(true_partition(tableau))) + 1


def test_clean_and_noisy_readings_have_no_suspects():
    clean = notched_rectangle(20)
    assert type_suspects(clean.actions, *learned(clean)) == []
    for seed in (30, 31, 32):
        noisy, _ = exploration(seed, turn_sd=6.0)
        assert type_suspects(noisy.actions, *learned(noisy)) == []


def test_a_clean_map_retypes_nothing():
    cmap = Resolver().resolve(notched_rectangle(10))
    assert cmap.retyped_steps == [] and cmap.n_dstates == 8 and cmap.unique


def noisy_rectangle(seed: int):
    """The paper's tableau read by a real robot (turns off by 3 degrees), with one turn mistyped."""
    rng = np.random.default_rng(seed)
    return with_mistyped_action(with_odometry_noise(notched_rectangle(12), 3.0, 1.5, rng), rng)


def test_suspects_are_far_from_their_type_and_offer_the_neighbour():
    tableau, at = noisy_rectangle(4)
    suspects = type_suspects(tableau.actions, *learned(tableau))
    assert [s.t for s in suspects] == [at]
    read = tableau.steps[at].action.angle_deg
    s = suspects[0]
    assert s.kind == "turn" and isinstance(tableau.steps[at].action, Turn) and s.measured == pytest.approx(read)
    # The two grid angles either side of the reading: the type it was learned as, and the other.
    assert {s.angle, s.alternative} <= {90, -90, 0, 180} and s.angle != s.alternative


def test_retyping_can_be_switched_off():
    tableau, at = noisy_rectangle(4)
    assert [s["t"] for s in Resolver().resolve(tableau).retyped_steps] == [at]
    exact = Resolver(retype=False, time_limit=30).resolve(tableau)
    assert exact.retyped_steps == [] and exact.n_dstates > 8


def test_why_reads_the_actions_as_the_map_typed_them():
    """The explainer states its evidence with the actions as the map typed them, and says two visits of
    one dstate on either side of the mistyped turn are one dstate."""
    from bootmap.mapping.explain import Explainer, _Question
    from bootmap.mapping.grounding import Deadline

    tableau, at = noisy_rectangle(4)
    explainer = Explainer(time_limit=60)
    cmap = explainer.resolver.resolve(tableau)
    explainer.remember(tableau, cmap)
    question = _Question(explainer, tableau, Deadline.after(60), cmap)
    assert question.angles[at] == cmap.retyped_steps[0]["abduced_deg"] != learned(tableau)[0][at]
    d = cmap.dstate_of[at - 1]
    b = max(b for b in range(at + 1, len(tableau)) if cmap.dstate_of[b] == d)
    assert explainer.explain(tableau, at - 1, b).verdict == "same"
