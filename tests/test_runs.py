"""Simulated runs kept on disk and read back: the same tableau to the last bit, simulated once for the
experiments (a sweep's cells) that share it, and never read back for another world, noise, length, seed."""

import gzip
import json
from types import SimpleNamespace

from hypothesis import given, settings
from hypothesis import strategies as st

import bootmap.experiments.world as experiment
from bootmap.experiments.runs import RunStore, run_key
from bootmap.experiments.sweep import first_of_each_run, loads_spec
from bootmap.experiments.sweep.cells import _experiment_row
from bootmap.sim import simulate
from bootmap.sim.world import load_world

from test_sweep import TINY, deterministic


def test_a_stored_run_reads_back_as_the_same_tableau(tmp_path):
    world = load_world("taylor_hall")
    made = simulate(world, policy="explore", steps=12, seed=4)
    store = RunStore(tmp_path / "runs")
    assert store.simulated(world, "explore", 50, 12, 4, lambda: made) is made
    (stored,) = (tmp_path / "runs").glob("*.json.gz")
    assert json.loads(gzip.open(stored, "rt").read())["steps"][3]["image"] == list(made.steps[3].image)
    back = store.simulated(world, "explore", 50, 12, 4, lambda: 1 / 0)  # read back: never simulated again
    assert back == made and back is not made
    stored.write_bytes(stored.read_bytes()[:1000])  # a file cut short (a full disk, a killed writer) ...
    assert store.simulated(world, "explore", 50, 12, 4, lambda: made) is made  # ... is simulated again
    assert store.simulated(world, "explore", 50, 12, 4, lambda: 1 / 0) == made  # and stored whole


def test_runs_differ_by_world_noise_policy_length_and_seed_but_not_by_where_the_world_lies():
    world = load_world("notched_rectangle")
    key = run_key(world, "circuits", 3, None, 1)
    others = [run_key(load_world("notched_rectangle", {"laser.noise_sd": 0.02}), "circuits", 3, None, 1),
              run_key(load_world("taylor_hall"), "circuits", 3, None, 1),
              run_key(world, "random", 3, None, 1), run_key(world, "circuits", 4, None, 1),
              run_key(world, "circuits", 3, 24, 1), run_key(world, "circuits", 3, None, 2)]
    assert key not in others and len(set(others)) == len(others)
    from dataclasses import replace

    assert run_key(replace(world, source="elsewhere/notched_rectangle.toml"), "circuits", 3, None, 1) == key


def test_cells_that_differ_only_in_the_learner_simulate_their_run_once(tmp_path, monkeypatch):
    spec = loads_spec(TINY.format(seeds="[1]").replace("[grid]", '[grid]\nlearners = ["1-NN", "despiked LDA"]'))
    cells = [c for c in spec.cells if c.noise.name == "1x"]
    assert [c.learner for c in cells] == ["1-NN", "despiked LDA"] and cells[0].run == cells[1].run
    alone = [_experiment_row(c) for c in cells]  # no store: each simulates
    made = []
    real = experiment.simulate
    monkeypatch.setattr(experiment, "simulate", lambda *a, **k: made.append(1) or real(*a, **k))
    from dataclasses import replace

    shared = [_experiment_row(replace(c, runs_dir=str(tmp_path / "runs"))) for c in cells]
    assert len(made) == 1 and len(list((tmp_path / "runs").glob("*.json.gz"))) == 1
    assert deterministic(shared) == deterministic(alone)  # the run read back gives the same experiment
    assert cells[0].id == replace(cells[0], runs_dir="anywhere").id  # where runs are kept is no parameter


@settings(max_examples=60, deadline=None)
@given(st.lists(st.integers(0, 4), max_size=30))
def test_the_start_order_is_a_permutation_that_keeps_each_runs_cells_in_grid_order(runs):
    # Cells stand in by their run (anything with .run and an identity): every cell once; within a run, grid
    # order; and the k-th cell of any run starts before the (k+1)-th cell of any run.
    cells = [SimpleNamespace(run=r, index=i) for i, r in enumerate(runs)]
    order = first_of_each_run(cells)
    assert sorted(c.index for c in order) == list(range(len(cells)))
    rank = {c.index: sum(d.run == c.run for d in cells[:c.index]) for c in cells}
    assert [rank[c.index] for c in order] == sorted(rank[c.index] for c in order)
    for r in set(runs):
        assert [c.index for c in order if c.run == r] == [c.index for c in cells if c.run == r]


def test_the_first_cell_of_each_run_starts_before_any_second_one():
    spec = loads_spec(TINY.format(seeds="[1, 2]").replace("[grid]", '[grid]\nlearners = ["1-NN", "3-NN"]'))
    order = first_of_each_run(list(spec.cells))
    assert sorted(c.id for c in order) == sorted(c.id for c in spec.cells)
    runs = [c.run for c in order]
    assert len(set(runs[:4])) == 4 and runs[4:] == runs[:4]  # four runs, each started once before its second cell
