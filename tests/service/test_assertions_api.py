"""A person's assertions through the service, on a real uvicorn server: POST/GET/DELETE
/tableaux/{id}/assertions, the map re-solved and stored with them, the clash as 409, owners only, kept
across a restart."""

from __future__ import annotations

import pytest
from service_helpers import PATIENT_SETTINGS, Server, bearer, make_token

from bootmap import examples


@pytest.fixture(scope="module")
def tokens_server(tmp_path_factory, server_axioms):
    s = Server(tmp_path_factory.mktemp("assertions_server"), axioms=server_axioms, require_tokens=True,
               **PATIENT_SETTINGS)
    tokens = {"alice": make_token("alice", data_dir=s.data_dir), "bob": make_token("bob", data_dir=s.data_dir)}
    s.start()
    yield s, tokens
    s.stop()


def _as(tokens_server, name: str):
    """A client of the server that sends ``name``'s token."""
    server, tokens = tokens_server
    with server.client() as c:
        c.headers.update(bearer(tokens[name]))
        yield c


@pytest.fixture
def alice(tokens_server):
    yield from _as(tokens_server, "alice")


@pytest.fixture
def bob(tokens_server):
    yield from _as(tokens_server, "bob")


def paper(client) -> int:
    """The paper's notched rectangle, two circuits (t0, t8 and t16 are S0), stored by ``client``."""
    r = client.post("/tableaux", json=examples.notched_rectangle(circuits=2).to_dict())
    assert r.status_code == 201, r.text
    return r.json()["id"]


def test_an_assertion_re_solves_the_map_says_what_changed_and_is_kept_with_who_and_when(alice):
    tid = paper(alice)
    r = alice.post(f"/tableaux/{tid}/assertions", json={"apart": ["S0", "t8"], "note": "two doors alike"})
    assert r.status_code == 201, r.text
    body = r.json()
    assert r.headers["location"] == f"/tableaux/{tid}/assertions/{body['assertion']['id']}"
    said = body["assertion"]
    assert (said["apart"], said["by"], said["note"], said["held"], said["soft"]) == (["t0", "t8"], "alice",
                                                                                     "two doors alike", True, False)
    assert body["diff"]["split"] == [{"was": "S0", "now": ["S0", "S8"]}] and body["diff"]["dstates"] == [8, 9]
    assert body["map"]["summary"]["dstates"] == 9 and body["map"]["revision"] == 2
    # stored: the map every read serves honours it, at the next revision
    m = alice.get(f"/tableaux/{tid}/map").json()
    assert m["summary"]["dstates"] == 9 and m["steps"][0]["dstate"] != m["steps"][8]["dstate"]
    assert alice.get(f"/tableaux/{tid}").json()["revision"] == 2
    listed = alice.get(f"/tableaux/{tid}/assertions").json()["assertions"]
    assert [a["apart"] for a in listed] == [["t0", "t8"]] and listed[0]["at"] == said["at"]
    # why: the map explained is the stored one, and the person's word is part of the proof
    why = alice.get(f"/tableaux/{tid}/why", params={"a": "t0", "b": "t8"}).json()
    assert why["verdict"] == "different" and "asserted_apart" in why["rules_cited"]
    # appending steps keeps the assertion in force
    steps = examples.notched_rectangle(circuits=3).to_dict()["steps"]
    r = alice.post(f"/tableaux/{tid}/steps", json={"action": steps[16]["action"], "steps": steps[17:]})
    assert r.status_code == 200, r.text
    assert r.json()["map"]["summary"]["dstates"] == 9
    # taking it back: the map as it was, and the diff says so
    r = alice.delete(f"/tableaux/{tid}/assertions/{said['id']}")
    assert r.status_code == 200, r.text
    assert r.json()["diff"]["joined"] == [{"now": "S0", "was": ["S0", "S8"]}] and r.json()["assertions"] == []
    assert alice.get(f"/tableaux/{tid}/map").json()["summary"]["dstates"] == 8
    assert alice.delete(f"/tableaux/{tid}/assertions/{said['id']}").status_code == 404


def test_assertions_the_experience_refutes_get_409_with_the_clash_and_nothing_is_stored(alice):
    tid = paper(alice)
    assert alice.post(f"/tableaux/{tid}/assertions", json={"apart": ["t1", "t9"]}).status_code == 201
    before = alice.get(f"/tableaux/{tid}/map").json()
    r = alice.post(f"/tableaux/{tid}/assertions", json={"same": ["t0", "t8"]})
    assert r.status_code == 409, r.text
    problem = r.json()
    assert r.headers["content-type"].startswith("application/problem+json")
    assert problem["type"].endswith("assertion-conflict")
    conflict = problem["conflict"]
    assert [list(a.values())[0] for a in conflict["assertions"]] == [["t0", "t8"], ["t1", "t9"]]
    assert {a["name"] for a in conflict["explanation"]["axioms"]} == {"one_value_per_feature"}
    assert {"told_apart_ahead", "asserted_apart"} <= set(conflict["explanation"]["rules_cited"])
    assert conflict["explanation"]["evidence"] == [0, 1, 8, 9]
    assert "one_value_per_feature (causal.lp:" in problem["text"]
    assert alice.get(f"/tableaux/{tid}/map").json() == before
    assert len(alice.get(f"/tableaux/{tid}/assertions").json()["assertions"]) == 1


@pytest.mark.parametrize("body, status, field", [
    ({"same": ["t0", "t99"]}, 422, "same[1]"),
    ({"apart": ["t3", 3]}, 422, "apart"),
    ({"same": ["S0", "S99"]}, 422, "same[1]"),
    ({"same": ["t0"]}, 422, "same"),
    ({"same": ["t0", "t8"], "apart": ["t1", "t9"]}, 422, ""),
    ({"same": ["t0", "t8"], "colour": "red"}, 422, "colour"),
    ({"apart": ["t0", "t8"], "soft": True, "cost": 0}, 422, "cost"),
])
def test_bad_assertions_name_the_field(alice, body, status, field):
    tid = paper(alice)
    r = alice.post(f"/tableaux/{tid}/assertions", json=body)
    assert r.status_code == status, r.text
    assert r.json()["detail"].startswith(f"{field}: " if field else "") and r.json().get("field", "") == field
    assert alice.get(f"/tableaux/{tid}/assertions").json()["assertions"] == []


def test_malformed_json_is_400(alice):
    tid = paper(alice)
    r = alice.post(f"/tableaux/{tid}/assertions", content=b'{"same": ["t0", "t8"]',
                   headers={"Content-Type": "application/json"})
    assert r.status_code == 400 and "Malformed JSON" in r.json()["title"]


def test_only_the_owner_reads_or_changes_assertions(alice, bob):
    tid = paper(alice)
    said = alice.post(f"/tableaux/{tid}/assertions", json={"apart": ["t0", "t8"]}).json()["assertion"]
    for r in (bob.get(f"/tableaux/{tid}/assertions"), bob.post(f"/tableaux/{tid}/assertions", json={"same": [1, 9]}),
              bob.delete(f"/tableaux/{tid}/assertions/{said['id']}")):
        assert r.status_code == 404  # a private tableau: as if it did not exist
    assert alice.put(f"/tableaux/{tid}/sharing", json={"public": True}).status_code == 200
    assert bob.get(f"/tableaux/{tid}/map").status_code == 200  # the map is public now ...
    for r in (bob.get(f"/tableaux/{tid}/assertions"), bob.post(f"/tableaux/{tid}/assertions", json={"same": [1, 9]}),
              bob.delete(f"/tableaux/{tid}/assertions/{said['id']}")):
        assert r.status_code == 403  # ... its assertions are its owner's
    assert len(alice.get(f"/tableaux/{tid}/assertions").json()["assertions"]) == 1


@pytest.mark.slow
def test_assertions_and_the_map_they_made_survive_a_restart(tmp_path):
    server = Server(tmp_path, **PATIENT_SETTINGS).start()
    try:
        with server.client() as c:
            tid = paper(c)
            soft = c.post(f"/tableaux/{tid}/assertions", json={"apart": [0, 8], "soft": True, "cost": 9}).json()
            assert soft["assertion"]["held"] and soft["map"]["summary"]["dstates"] == 9
            cheap = c.post(f"/tableaux/{tid}/assertions", json={"same": [1, 2], "soft": True}).json()
            assert not cheap["assertion"]["held"]  # views differ: no map joins them; a soft one is broken
            listed, m = c.get(f"/tableaux/{tid}/assertions").json(), c.get(f"/tableaux/{tid}/map").json()
        server.stop()
        server.start()
        with server.client() as c:
            assert c.get(f"/tableaux/{tid}/assertions").json() == listed
            assert c.get(f"/tableaux/{tid}/map").json() == m
            c.delete(f"/tableaux/{tid}")
            assert c.get(f"/tableaux/{tid}/assertions").status_code == 404
    finally:
        server.stop()


def test_steps_that_contradict_an_assertion_are_refused_with_the_clash(alice):
    tid = paper(alice)
    assert alice.post(f"/tableaux/{tid}/assertions", json={"same": ["t8", "t16"]}).status_code == 201
    # From t16 (one dstate with t8, a person said) the same turn now shows a view t9 never showed.
    r = alice.post(f"/tableaux/{tid}/steps", json={"action": {"type": "turn", "angle_deg": -90},
                                                   "steps": [{"view": "V9"}]})
    assert r.status_code == 409, r.text
    conflict = r.json()["conflict"]
    assert [list(a.values())[0] for a in conflict["assertions"]] == [["t8", "t16"]]
    assert 17 in conflict["explanation"]["evidence"] and 9 in conflict["explanation"]["evidence"]
    assert alice.get(f"/tableaux/{tid}").json()["steps"] == 17  # the append is not stored
