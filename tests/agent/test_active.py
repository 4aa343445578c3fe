"""Active mapping in the simulator: the robot explores and rehearses until its own map is unique and true."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bootmap.cli import main
from bootmap.mapping.rehearsal import Rehearsal
from bootmap.mapping.resolver import Resolver
from bootmap.metrics import dstate_accuracy
from bootmap.sim import Explore, RandomWalk, Simulation
from bootmap.agent.active import Active, decision_of
from bootmap.sim.world import load_world
from bootmap.tableau import Step, Tableau
from bootmap.views import OnlineViews


def _active_run(name, seed, **kwargs):
    world = load_world(name)
    policy = Active(max_range=world.laser.range_max, **kwargs)
    result = Simulation(world).reset(seed).run(policy)
    return world, policy, result


def _assert_true_map(world, policy, result):
    m = policy.map_
    truth = [s.truth for s in result.tableau.steps]
    assert policy.complete_ and m.unique and m.minimal
    assert (m.n_dstates, m.n_places, m.n_paths) == (world.truth_dstates, len(world.places), len(world.paths))
    assert dstate_accuracy(truth, m.dstate_of) == 1.0  # no true dstates merged, none split
    assert result.contacts == 0


def test_active_maps_the_loop_world_with_its_five_paths():
    """The fixed explorer's map keeps the east corridor's two directions as two paths; the active robot
    turns around on a path its map knows one way only, and rehearses while maps disagree."""
    world, policy, result = _active_run("loop", seed=1)
    _assert_true_map(world, policy, result)
    assert policy.map_.n_paths == 5 and policy.turnarounds_ >= 1 and policy.rehearsals_ >= 1
    # Where two maps disagreed at the spur junction, the robot travelled straight on through it.
    at_junction = [actions for t, actions in policy.plans_ if result.tableau.steps[t].truth in ("T:E", "T:W")]
    assert ["travel"] in [a[:1] for a in at_junction]


def test_active_keeps_taylor_hall_20_dstates_7_places_4_paths():
    world, policy, result = _active_run("taylor_hall", seed=1)
    _assert_true_map(world, policy, result)
    assert (policy.map_.n_dstates, policy.map_.n_places, policy.map_.n_paths) == (20, 7, 4)


def test_active_maps_the_aliased_plus_world_truly_and_stops_by_itself():
    world, policy, result = _active_run("plus", seed=2)
    _assert_true_map(world, policy, result)
    assert len(result.tableau) < policy.max_steps


def test_the_map_is_current_after_every_step_and_matches_a_fresh_resolve():
    _, policy, result = _active_run("plus", seed=0)
    fresh = Resolver(quantum_deg=90).resolve(policy.tableau_)
    assert fresh.dstate_of == policy.map_.dstate_of and len(policy.tableau_) == len(result.tableau)
    assert [s.action for s in policy.tableau_.steps] == [s.action for s in result.tableau.steps]


def test_active_is_deterministic_for_a_seed():
    a = _active_run("plus", seed=5)[2].tableau.dumps()
    b = _active_run("plus", seed=5)[2].tableau.dumps()
    assert a == b


def test_active_stops_at_its_step_cap():
    world, policy, result = _active_run("loop", seed=0, max_steps=6)
    assert len(result.tableau) == 6 and not policy.complete_


class _Replay:
    """Replays decisions, then stops: with the same seed, the simulation repeats a run exactly."""

    junctions, follow = True, "centre"

    def __init__(self, decisions):
        self.decisions = list(decisions)

    def reset(self, rng):
        self.queue = list(self.decisions)

    def decide(self, obs):
        return self.queue.pop(0) if self.queue else None


class _Recording(Explore):
    def reset(self, rng):
        super().reset(rng)
        self.decisions = []

    def decide(self, obs):
        d = super().decide(obs)
        self.decisions.append(d)
        return d


def _labelled(tableau, world):
    views = OnlineViews(max_range=world.laser.range_max).labels([s.image for s in tableau.steps])
    return Tableau(tuple(Step(v, s.action) for v, s in zip(views, tableau.steps)))


def test_a_rehearsal_plan_carried_out_in_the_simulator_makes_an_ambiguous_map_unique():
    """14 steps of the loop leave two minimal maps; the simulated robot carries out the plan from there
    (same seed, same first 14 steps) and its map of the longer experience is unique."""
    world, resolver = load_world("loop"), Resolver(quantum_deg=90)
    explorer = _Recording()
    first = Simulation(world).reset(0).run(explorer, n_steps=14).tableau
    before = resolver.resolve(_labelled(first, world))
    assert not before.unique
    plan = Rehearsal(resolver).plan(_labelled(first, world), cmap=before)
    assert plan.kind in ("distinguish", "partial", "test") and plan.actions
    replay = _Replay(explorer.decisions[:13] + [decision_of(a) for a in plan.actions])
    after = Simulation(world).reset(0).run(replay).tableau
    assert [s.image for s in after.steps[:14]] == [s.image for s in first.steps]
    labelled = _labelled(after, world)
    cmap = resolver.resolve(labelled)
    assert cmap.unique
    # What the robot saw refutes some hypothesis (a view it predicted did not show) and not all of them.
    seen = [s.view for s in labelled.steps[14:]]
    refuted = [any(p is not None and p != v for p, v in zip(h["predicts"], seen)) for h in plan.hypotheses]
    assert any(refuted) and not all(refuted)


def test_random_walk_is_seeded_and_physically_honest():
    world = load_world("plus")
    a = Simulation(world).reset(3).run(RandomWalk(), n_steps=15)
    b = Simulation(world).reset(3).run(RandomWalk(), n_steps=15)
    assert a.tableau.dumps() == b.tableau.dumps() and a.contacts == 0
    assert world.in_free_space(a.trajectory[:, :2], tolerance=0.0).all()


def test_decision_of_reads_plan_actions_and_rejects_others():
    assert decision_of("travel").kind == "travel"
    d = decision_of("turn -90")
    assert d.kind == "turn" and math.isclose(d.angle, -math.pi / 2)
    with pytest.raises(ValueError, match="jump"):
        decision_of("jump 3")


def test_bad_parameters_are_refused_with_their_name():
    with pytest.raises(ValueError, match="max_steps"):
        Active(max_steps=1)
    with pytest.raises(ValueError, match="view_threshold"):
        Active(view_threshold=0)
    with pytest.raises(ValueError, match="threshold"):
        OnlineViews(threshold=-1)


def test_bad_option_values_exit_2(capsys):
    assert main(["simulate", "plus", "--policy", "random", "--no-progress"]) == 2
    assert "--steps" in capsys.readouterr().err
    with pytest.raises(SystemExit) as e:
        main(["simulate", "plus", "--policy", "wander"])
    assert e.value.code == 2
    assert main(["experiment", "loop", "--policy", "active", "--circuits", "2"]) == 2
    assert "circuits" in capsys.readouterr().err


@settings(max_examples=60, deadline=None)
@given(st.lists(st.lists(st.floats(0, 8), min_size=4, max_size=4), min_size=1, max_size=30),
       st.floats(0.05, 3))
def test_online_views_label_each_image_once_and_for_good(images, threshold):
    """A label never changes as more images come; an image is within the threshold of its view's
    prototype; prototypes of different views are at least the threshold apart."""
    ov = OnlineViews(threshold=threshold)
    labels = [ov.label(x) for x in images]
    again = OnlineViews(threshold=threshold).labels(images[:len(images) // 2])
    assert labels[:len(again)] == again
    protos = np.array(ov.prototypes_)
    for x, v in zip(images, labels):
        assert np.mean(np.abs(protos[int(v[1:])] - x)) < threshold or any(np.array_equal(p, x) for p in protos)
    for i in range(len(protos)):
        for j in range(i):
            assert np.mean(np.abs(protos[i] - protos[j])) >= threshold
