"""Rehearsal over HTTP (a real uvicorn process): the plan `bootmap rehearse` prints, as JSON."""

import numpy as np

from bootmap.mapping.rehearsal import Rehearsal
from bootmap.tableau import Tableau
from support.gridworld import random_world, walk


def ambiguous_walk_doc() -> dict:
    # A 30-step random walk of a 4x3 grid world that leaves two minimal maps (tests/mapping/test_rehearsal.py).
    rng = np.random.default_rng(170)
    world = random_world(rng, 4, 3, extra_edges=2, landmarks=0.0)
    return walk(world, 30, rng, policy="random").to_dict()


def test_a_unique_map_has_nothing_to_rehearse(client, paper_id):
    r = client.get(f"/tableaux/{paper_id}/rehearsal")
    assert r.status_code == 200, r.text
    assert (r.json()["kind"], r.json()["actions"]) == ("nothing", [])


def test_the_plan_is_the_one_bootmap_rehearse_makes(client):
    doc = ambiguous_walk_doc()
    created = client.post("/tableaux", json=doc)
    assert created.status_code == 201, created.text
    r = client.get(f"/tableaux/{created.json()['id']}/rehearsal", params={"max_length": 6})
    assert r.status_code == 200, r.text
    plan = r.json()
    local = Rehearsal(max_length=6).plan(Tableau.from_dict(doc))
    assert plan["kind"] == local.kind != "nothing"
    assert plan["actions"] == local.actions and plan["hypotheses"] == local.hypotheses
    assert "The minimal maps disagree" in plan["text"]


def test_bad_rehearsal_requests_are_clear_problems(client, paper_id):
    assert client.get(f"/tableaux/{paper_id}/rehearsal", params={"max_length": 0}).status_code == 422
    assert client.get("/tableaux/999999/rehearsal").status_code == 404
