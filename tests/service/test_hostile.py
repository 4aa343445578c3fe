"""Hostile input: each gets a clear 4xx (problem details naming what to fix) and stored data stays intact.

The session server's limits: 4 MiB bodies, 10,000 steps, 512 values per image, 3 s solves.
"""

import json
import socket
from urllib.parse import urlsplit

import pytest

from bootmap.tableau import FORMAT

PROBLEM = "application/problem+json"
TURN = {"type": "turn", "angle_deg": -90}


@pytest.fixture(autouse=True)
def stored_data_intact(client, paper_id):
    """Around every test here: the paper's tableau and map are exactly as stored, before and after."""
    before = client.get(f"/tableaux/{paper_id}").text, client.get(f"/tableaux/{paper_id}/map").text
    yield
    assert (client.get(f"/tableaux/{paper_id}").text, client.get(f"/tableaux/{paper_id}/map").text) == before


def refused(client, status: int, *args, **kw) -> dict:
    """Send a request that must be refused with ``status``, store nothing, and say why as problem details."""
    total = client.get("/tableaux").json()["total"]
    r = client.request(*args, **kw)
    assert r.status_code == status, r.text
    assert r.headers["content-type"] == PROBLEM
    problem = r.json()
    assert problem["status"] == status and problem["detail"] and problem["type"].startswith("https://")
    assert client.get("/tableaux").json()["total"] == total
    return problem


def tableau(*steps, **extra) -> dict:
    return {"format": FORMAT, "steps": list(steps), **extra}


def post_raw(client, body: bytes, **kw) -> dict:
    return refused(client, kw.pop("status", 400), "POST", "/tableaux", content=body,
                   headers={"content-type": "application/json"})


# --- Client data never becomes program text --------------------------------------------------------

def test_asp_syntax_in_labels_is_only_ever_a_label(client, tmp_path):
    marker = tmp_path / "pwned"
    labels = [f'a"). #script (python) import os; os.system("touch {marker}") #end. b("',
              '#include "/etc/passwd".', "x :- not x.", "#program base.", "%* comment", "V0\n:- view(_, _)."]
    steps = [{"view": v, "action": TURN} for v in labels] + [{"view": labels[0]}]
    r = client.post("/tableaux", json=tableau(*steps))
    assert r.status_code == 201, r.text
    m = r.json()["map"]
    assert [row["view"] for row in m["steps"]] == labels + [labels[0]]
    assert {d["view"] for d in m["dstates"].values()} == set(labels)
    assert not marker.exists()


def test_nul_in_a_label_is_refused_not_cut_short(client):
    """clingo holds C strings: "a\\u0000b" and "a\\u0000c" would both reach it as "a"."""
    problem = refused(client, 422, "POST", "/tableaux", json=tableau({"view": "a\x00b", "action": TURN},
                                                                      {"view": "a\x00c"}))
    assert problem["field"] == "steps[0].view" and "NUL" in problem["detail"]


@pytest.mark.parametrize("field", ["axioms", "levels", "script", "program"])
def test_no_field_can_name_axioms_a_program_or_a_file(client, field):
    problem = refused(client, 422, "POST", "/tableaux", json=tableau({"view": "a"}, **{field: "/etc/passwd"}))
    assert problem["field"] == field and "unknown field" in problem["detail"]


# --- Size -------------------------------------------------------------------------------------------

def test_a_100_mb_body_is_refused_before_it_is_read(server, client):
    """Content-Length says 100 MB: the 413 comes back while the client has sent only the first 64 KiB."""
    url = urlsplit(server.url)
    with socket.create_connection((url.hostname, url.port), timeout=10) as s:
        s.sendall(b"POST /tableaux HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
                  b"Content-Length: %d\r\n\r\n" % (100 * 2**20) + b"[" * 65536)
        reply = b""
        while not reply.endswith(b"}"):  # the headers and the problem document may come in two packets
            chunk = s.recv(65536)
            assert chunk, f"connection closed after {reply!r}"
            reply += chunk
    reply = reply.decode()
    assert reply.startswith("HTTP/1.1 413") and PROBLEM in reply
    assert "larger than this server's limit of 4194304 bytes" in reply


def test_a_streamed_100_mb_body_is_cut_off_at_the_limit(client):
    chunks = (b"x" * 2**20 for _ in range(100))  # chunked: no Content-Length to check beforehand
    problem = refused(client, 413, "POST", "/tableaux", content=chunks, headers={"content-type": "application/json"})
    assert problem["limit_bytes"] == 4 * 2**20


def test_a_million_steps_are_refused(client):
    body = json.dumps(tableau(*[{"view": "A", "action": TURN}] * 999_999, {"view": "A"})).encode()
    assert len(body) > 4 * 2**20
    post_raw(client, body, status=413)


def test_more_steps_than_the_limit_are_refused_by_count(client):
    problem = refused(client, 422, "POST", "/tableaux", json=tableau(*[{"view": "A", "action": TURN}] * 10_000,
                                                                      {"view": "A"}))
    assert problem["field"] == "steps" and "10001 steps" in problem["detail"] and "10000" in problem["detail"]


def test_an_append_that_takes_a_tableau_past_the_step_limit_is_refused_by_its_total(client):
    created = client.post("/tableaux", json=tableau({"view": "A", "action": TURN}, {"view": "B"}))
    assert created.status_code == 201, created.text
    tid = created.json()["id"]
    try:
        # 9,999 new steps are within the limit of 10,000; with the 2 stored, the tableau would have 10,001.
        problem = refused(client, 422, "POST", f"/tableaux/{tid}/steps",
                          json={"action": TURN, "steps": [{"view": "A", "action": TURN}] * 9_998 + [{"view": "A"}]})
        assert problem["field"] == "steps" and "10001 steps" in problem["detail"] and "10000" in problem["detail"]
        assert client.get(f"/tableaux/{tid}").json()["revision"] == 1
    finally:
        assert client.delete(f"/tableaux/{tid}").status_code == 204


def test_an_image_longer_than_the_limit_is_refused(client):
    problem = refused(client, 422, "POST", "/tableaux", json=tableau({"image": [1.0] * 513}))
    assert problem["field"] == "steps[0].image" and "512" in problem["detail"]


# --- Malformed JSON ---------------------------------------------------------------------------------

def test_deeply_nested_json_is_refused(client):
    assert "nested too deeply" in post_raw(client, b"[" * 100_000 + b"]" * 100_000)["detail"]
    meta = json.dumps(tableau({"view": "a"}, meta={"a": json.loads("[" * 400 + "]" * 400)}))
    problem = refused(client, 422, "POST", "/tableaux", content=meta, headers={"content-type": "application/json"})
    assert problem["field"].startswith("meta.a") and "nested too deeply" in problem["detail"]


def test_malformed_json_says_where(client):
    assert post_raw(client, b'{"format": "bootmap.tableau/1", "steps": [}')["detail"] == \
        "not valid JSON: Expecting value at line 1 column 43"
    assert "not UTF-8" in post_raw(client, b'{"format": "\xff"}')["detail"]
    assert "4300 digits" in post_raw(client, b'{"format": ' + b"9" * 5000 + b"}")["detail"]
    lone = post_raw(client, b'{"format": "bootmap.tableau/1", "steps": [{"view": "\\ud800"}]}')
    assert lone["detail"].startswith("steps[0].view: a lone UTF-16 surrogate")


def test_json_that_is_not_sent_as_json_is_refused(client):
    problem = refused(client, 415, "POST", "/tableaux", content=json.dumps(tableau({"view": "a"})),
                      headers={"content-type": "text/plain"})
    assert "Content-Type: application/json" in problem["detail"]


# --- Numbers ----------------------------------------------------------------------------------------

@pytest.mark.parametrize("literal", ["NaN", "Infinity", "-Infinity", "1e400"])
def test_non_finite_numbers_are_refused_with_the_field(client, literal):
    body = '{"format": "bootmap.tableau/1", "steps": [{"view": "a", "action": {"type": "turn", "angle_deg": %s}}, ' \
           '{"view": "b"}]}' % literal
    problem = post_raw(client, body.encode(), status=422)
    assert problem["field"] == "steps[0].action.angle_deg" and "not a finite number" in problem["detail"]


@pytest.mark.parametrize("action, field, words", [
    ({"type": "travel", "distance_m": -3}, "steps[0].action.distance_m", "greater than 0"),
    ({"type": "travel", "distance_m": 0}, "steps[0].action.distance_m", "greater than 0"),
    ({"type": "travel", "distance_m": 1e300}, "steps[0].action.distance_m", "less than or equal to 100000"),
    ({"type": "turn", "angle_deg": 1e9}, "steps[0].action.angle_deg", "less than or equal to 360"),
    ({"type": "turn", "angle_deg": False}, "steps[0].action.angle_deg", "valid number"),
    ({"type": "turn", "angle_deg": "90"}, "steps[0].action.angle_deg", "valid number"),
    ({"type": "travel", "distance_m": 2, "heading_change_deg": -720}, "steps[0].action.heading_change_deg", "-360"),
    ({"type": "fly", "distance_m": 2}, "steps[0].action", "unknown action type 'fly'"),
])
def test_absurd_numbers_and_types_are_refused_with_the_field(client, action, field, words):
    problem = refused(client, 422, "POST", "/tableaux", json=tableau({"view": "a", "action": action}, {"view": "b"}))
    assert problem["field"] == field and words in problem["detail"]


def test_an_absurd_laser_range_in_meta_is_refused(client):
    steps = [{"image": [1.0, 2.0], "action": TURN}, {"image": [2.0, 1.0]}]
    problem = refused(client, 422, "POST", "/tableaux", json=tableau(*steps, meta={"laser": {"range_max": -1}}))
    assert problem["field"] == "meta.laser.range_max"


def test_an_integer_truth_too_large_for_a_float_is_refused(client):
    body = b'{"format": "bootmap.tableau/1", "steps": [{"view": "a", "truth": ' + b"9" * 4000 + b"}]}"
    problem = post_raw(client, body, status=422)
    assert problem["field"] == "steps[0].truth" and "more than a float can hold" in problem["detail"]
    assert client.post("/tableaux", json=tableau({"view": "a", "truth": 2**60})).status_code == 201


@pytest.mark.parametrize("value", [1.7e308, -1.7e308, 1e10])
def test_image_values_beyond_1e9_are_refused_so_distances_stay_finite(client, paper_id, value):
    problem = refused(client, 422, "POST", "/tableaux", json=tableau({"image": [value, 1.0], "action": TURN},
                                                                      {"image": [1.0, 2.0]}))
    assert problem["field"] == "steps[0].image[0]" and "1000000000" in problem["detail"]
    problem = refused(client, 422, "POST", f"/tableaux/{paper_id}/recognise", json={"image": [value]})
    assert problem["field"] == "image[0]"


def test_images_at_the_bound_are_clustered_and_recognised_with_finite_distances(client):
    steps = [{"image": [1e9 if t % 2 else -1e9, 0.0], "action": TURN} for t in range(7)] + [{"image": [-1e9, 0.0]}]
    r = client.post("/tableaux", json=tableau(*steps))
    assert r.status_code == 201, r.text
    far = client.post(f"/tableaux/{r.json()['id']}/recognise", json={"image": [0.0, 1e9]}).json()
    assert far["distance"] == pytest.approx(2**0.5 * 1e9)


@pytest.mark.parametrize("path, status", [("/tableaux/0", 422), ("/tableaux/-1", 422), (f"/tableaux/{2**63}", 422),
                                          ("/tableaux/1e3", 422), ("/tableaux/999999", 404), ("/tableaux/+1", 422),
                                          ("/tableaux/01", 422), ("/tableaux/%201", 422), ("/tableaux/1_0", 422)])
def test_absurd_ids_are_refused(client, path, status):
    refused(client, status, "GET", path)


# --- Bodies that mean different things to different JSON readers ------------------------------------

ONE = '{"format": "bootmap.tableau/1", "steps": [{"view": "a"}]}'


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-le", "utf-32"])
def test_a_body_in_another_encoding_than_utf8_is_400(client, encoding):
    problem = post_raw(client, ONE.encode(encoding))  # json.loads(bytes) would have read it
    assert problem["type"].endswith("/malformed-json")
    assert "not UTF-8" in problem["detail"] or "not valid JSON" in problem["detail"]


def test_a_key_given_twice_is_400_not_last_one_wins(client):
    body = b'{"format": "bootmap.tableau/1", "steps": [{"view": "a", "view": "b"}]}'
    assert "'view' appears twice" in post_raw(client, body)["detail"]


@pytest.mark.parametrize("field, value", [("world", "w" * 201), ("world", "a\u0000b"),
                                          ("steps[0].truth", "t" * 201), ("steps[0].truth", "S\u00000")])
def test_world_and_truth_are_short_text_without_nul(client, field, value):
    doc = tableau({"view": "a"})
    if field == "world":
        doc["world"] = value
    else:
        doc["steps"][0]["truth"] = value
    problem = refused(client, 422, "POST", "/tableaux", json=doc)
    assert problem["field"] == field


def test_an_integer_beyond_64_bits_in_meta_is_refused(client):
    body = ('{"format": "bootmap.tableau/1", "meta": {"seeds": [1, ' + "9" * 4000 + ']}, '
            '"steps": [{"view": "a"}]}').encode()
    problem = post_raw(client, body, status=422)
    assert problem["field"] == "meta.seeds[1]" and "beyond 64 bits" in problem["detail"]
    assert client.post("/tableaux", json=tableau({"view": "a"}, meta={"seed": 2**63 - 1})).status_code == 201


def test_path_parameters_publish_their_bounds_as_openapi_does(client):
    spec = client.get("/openapi.json").json()
    for path, operations in spec["paths"].items():
        for operation in operations.values():
            for parameter in operation.get("parameters", []):
                schema = parameter["schema"]
                assert not {"ge", "le", "gt", "lt"} & set(schema), (path, parameter["name"], schema)
    read = spec["paths"]["/tableaux/{tableau_id}"]["get"]["parameters"][0]["schema"]
    assert read["minimum"] == 1 and read["maximum"] == 2**63 - 1
