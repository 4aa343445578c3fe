"""Rehearsal: the shortest actions whose outcome the minimal maps predict differently."""

import itertools
import json
import subprocess
import sys

import numpy as np
import pytest

from bootmap.examples import notched_rectangle
from bootmap.mapping import Resolver
from bootmap.mapping.rehearsal import Rehearsal
from bootmap.tableau import Step, Tableau, Travel, Turn
from support.gridworld import random_world, scripted, walk

# The plan's actions as the grid world names them.
WORLD_ACTION = {"turn -90": "right", "turn +90": "left", "turn +180": "around", "travel": "travel"}

# 30-step random walks of 4x3 grid worlds (seeds found by a search over 0-300) that leave two or more
# minimal maps: some are told apart at once, some only by testing or exploring first.
AMBIGUOUS = [2, 3, 80, 159, 170, 191, 236, 273]


def ambiguous_walk(seed: int):
    rng = np.random.default_rng(seed)
    world = random_world(rng, 4, 3, extra_edges=2, landmarks=0.0)
    return world, walk(world, 30, rng, policy="random")


def _state(truth: str):
    xy, heading = truth.split(":")
    return tuple(int(v) for v in xy.split(",")), int(heading)


def executed(world, tableau: Tableau, actions: list[str]) -> Tableau:
    """The tableau with the plan's actions carried out in the world (the robot's new experience)."""
    start = _state(tableau.steps[-1].truth)
    more = scripted(world, start, [WORLD_ACTION[a] for a in actions]).to_dict()["steps"]
    doc = tableau.to_dict()
    doc["steps"][-1]["action"] = more[0]["action"]
    return Tableau.from_dict({**doc, "steps": doc["steps"] + more[1:]})


def test_a_plan_that_tells_the_maps_apart_leaves_every_time_point_settled():
    # t4 may be t0's dstate or t2's: travelling on from t4 shows which (B after t0, C after t2).
    tableau = Tableau(tuple(Step(v, Travel(1.0) if i < 4 else None) for i, v in enumerate("ABACA")))
    plan = Rehearsal(Resolver(levels=["causal"])).plan(tableau)
    assert (plan.kind, plan.actions, plan.settled_now, plan.settled_after) == ("distinguish", ["travel"], 0.4, 1.0)
    assert "40% now, at least 100% after these actions" in plan.to_text()


def test_a_unique_map_has_nothing_to_rehearse():
    plan = Rehearsal().plan(notched_rectangle(3))
    assert (plan.kind, plan.actions) == ("nothing", [])
    assert plan.to_text().startswith("Nothing to rehearse")


@pytest.mark.parametrize("seed", AMBIGUOUS)
def test_no_shorter_sequence_tells_the_maps_apart(seed):
    # Brute force over every sequence of the experienced actions, each map predicting the plain way
    # (follow its transitions; no prediction once it has never seen the action taken there), the robot
    # taking only actions it has taken before from every view it may be seeing.
    world, tableau = ambiguous_walk(seed)
    cmap = Resolver(time_limit=20).resolve(tableau)
    assert not cmap.unique
    plan = Rehearsal(max_length=5).plan(tableau, cmap)
    maps = [cmap.dstate_of] + cmap.alternatives
    # the map's confidence now, and at worst after the plan: fewer maps left can only agree on more
    assert plan.settled_now == cmap.confidence.settled < 1.0
    assert plan.settled_now <= plan.settled_after <= 1.0
    steps = tableau.steps
    actions = [_word(s.action) for s in steps]
    words = sorted({a for a in actions if a})
    taken = {}
    for t in range(len(steps) - 1):
        taken.setdefault(steps[t].view, set()).add(actions[t])
    nexts = [{(m[t], actions[t]): m[t + 1] for t in range(len(m) - 1)} for m in maps]
    views = [{m[t]: steps[t].view for t in range(len(m))} for m in maps]

    def predictions(seq):
        """Per map, the views it predicts along seq; None if the robot could not take seq."""
        at, out = [m[-1] for m in maps], [[] for _ in maps]
        for a in seq:
            seen = {views[i][d] for i, d in enumerate(at) if d is not None}
            can = set.intersection(*(taken.get(v, set()) for v in seen)) if seen else set()
            if a not in (can or words):
                return None
            at = [nexts[i].get((d, a)) if d is not None else None for i, d in enumerate(at)]
            for i, d in enumerate(at):
                out[i].append(views[i].get(d))
        return out

    def tells_all_apart(seq):
        seen = predictions(seq)
        return seen is not None and all(any(None not in (x, y) and x != y for x, y in zip(p, q))
                                        for p, q in itertools.combinations(seen, 2))

    shortest = next((n for n in range(1, 6) for seq in itertools.product(words, repeat=n)
                     if tells_all_apart(seq)), None)
    if plan.kind == "distinguish":
        assert tells_all_apart(plan.actions)
    assert len(plan.actions) == shortest if shortest else plan.kind != "distinguish"
    # What the plan says each map predicts is what the map predicts.
    assert [h["predicts"] for h in plan.hypotheses] == predictions(plan.actions)
    assert [h["at"] for h in plan.hypotheses] == [m[-1] for m in maps]


def _word(action) -> str | None:
    if action is None:
        return None
    return f"turn {round(action.angle_deg):+d}" if isinstance(action, Turn) else "travel"


@pytest.mark.parametrize("seed", [3, 159, 170])
def test_carrying_out_plans_makes_the_map_unique(seed):
    world, tableau = ambiguous_walk(seed)
    cmap = Resolver(time_limit=20).resolve(tableau)
    for _ in range(6):
        plan = Rehearsal().plan(tableau, cmap)
        if plan.kind == "nothing":
            break
        before = len(cmap.alternatives) + 1
        tableau = executed(world, tableau, plan.actions)
        cmap = Resolver(time_limit=20).resolve(tableau)
        if plan.kind == "distinguish":  # whatever was seen refuted all but one of the maps
            assert cmap.unique or len(cmap.alternatives) + 1 < before
    assert cmap.unique


def test_bootmap_rehearse_prints_the_plan(tmp_path):
    _, tableau = ambiguous_walk(170)
    path = tmp_path / "walk.json"
    path.write_text(json.dumps(tableau.to_dict()))
    run = lambda *a: subprocess.run([sys.executable, "-m", "bootmap.cli", "rehearse", str(path), *a],
                                    capture_output=True, text=True, timeout=120)
    text = run()
    assert text.returncode == 0, text.stderr
    assert "The minimal maps disagree" in text.stdout and "map 1: now at" in text.stdout
    out = json.loads(run("--format", "json").stdout)
    assert out["kind"] in ("distinguish", "partial", "test", "explore") and out["actions"]
    assert len(out["hypotheses"]) >= 2
    assert run("--max-length", "0").returncode == 2
