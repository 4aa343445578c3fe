"""The service's capabilities, over HTTP against a real uvicorn process: create, read, append, recognise,
minimal maps, axioms, health, schema; and a restart keeps everything."""

import os
import signal
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from service_helpers import Server

from bootmap import examples
from bootmap.mapping import Resolver
from bootmap.tableau import FORMAT, schema

PROBLEM = "application/problem+json"


def test_the_papers_tableau_gives_the_papers_map(client, paper_doc):
    r = client.post("/tableaux", json=paper_doc)
    assert r.status_code == 201, r.text
    created = r.json()
    assert r.headers["location"] == f"/tableaux/{created['id']}"
    summary = created["map"]["summary"]
    assert (summary["dstates"], summary["places"], summary["paths"]) == (8, 4, 4)
    assert summary["unique"] and summary["proved_minimal"] and created["steps"] == 401

    m = client.get(f"/tableaux/{created['id']}/map").json()
    assert m == created["map"]
    # The paper's table (6): S4 is not S0 (its place P2 is right of a path P0 is on); t8 is S0 again.
    assert m["steps"][4] == {"t": 4, "view": "V0", "dstate": "S4", "place": "P2", "path": "Pa2", "dir": "pos",
                             "action": "turn -90"}
    assert m["steps"][8]["dstate"] == "S0" and len(m["steps"]) == 401
    assert ["P2", "Pa1"] in m["right_of"] and ["P0", "Pa1"] in m["on"] and len(m["on"]) == 8
    text = client.get(f"/tableaux/{created['id']}/map/text").text
    assert text.startswith("8 dstates, 4 places, 4 paths; unique minimal map")
    assert "t4    V0    S4      P2     Pa2   pos  turn -90" in text
    stored = client.get(f"/tableaux/{created['id']}").json()
    assert stored["tableau"] == paper_doc and stored["revision"] == 1


def test_a_restart_keeps_every_tableau_and_map(tmp_path, paper_doc):
    server = Server(tmp_path).start()
    try:
        with server.client() as c:
            first = c.post("/tableaux", json=paper_doc).json()
            m = c.get(f"/tableaux/{first['id']}/map").json()
        server.stop()
        server.start()
        with server.client() as c:
            assert c.get(f"/tableaux/{first['id']}/map").json() == m
            assert c.get(f"/tableaux/{first['id']}").json()["tableau"] == paper_doc
            assert c.get("/tableaux").json()["total"] == 1
            second = c.post("/tableaux", json=paper_doc).json()
            assert second["id"] != first["id"]
    finally:
        server.stop()
    assert (tmp_path / "data" / "bootmap.sqlite3").is_file()


def _paper_images(n_values: int = 20) -> list[list[float]]:
    """Images for the paper's tableau: each view's mean scan plus a little noise (fixed seed)."""
    rng = np.random.default_rng(0)
    centres = rng.uniform(0.5, 4.5, (4, n_values))
    views = [int(s.view[1]) for s in examples.notched_rectangle(circuits=10).steps]
    return [list(map(float, centres[v] + rng.normal(0, 0.01, n_values))) for v in views]


@pytest.fixture(scope="module")
def images_only(client):
    """The paper's 10 circuits as images only, no view labels: the service clusters them."""
    steps = [s.to_dict() for s in examples.notched_rectangle(circuits=10).steps]
    images = _paper_images()
    for s, image in zip(steps, images):
        del s["view"]
        s["image"] = image
    r = client.post("/tableaux", json={"format": FORMAT, "steps": steps})
    assert r.status_code == 201, r.text
    return r.json(), images


def test_images_only_are_clustered_into_views_first(images_only):
    created, _ = images_only
    assert created["views_from_images"] == 4 and created["map"]["views_from_images"] == 4
    assert created["map"]["summary"]["dstates"] == 8 and created["map"]["summary"]["places"] == 4


def test_recognise_gives_the_nearest_dstate_and_its_distance(client, images_only):
    created, images = images_only
    rows = created["map"]["steps"]
    for t in (0, 5, 13):
        r = client.post(f"/tableaux/{created['id']}/recognise", json={"image": images[t]}).json()
        assert r["dstate"] == rows[t]["dstate"] and r["distance"] == pytest.approx(0, abs=1e-6)
        assert r["view"] == rows[t]["view"] and r["place"] == rows[t]["place"]
    far = client.post(f"/tableaux/{created['id']}/recognise", json={"image": [x + 1.0 for x in images[0]]}).json()
    assert far["distance"] == pytest.approx(np.sqrt(len(images[0])), rel=0.05)


def test_recognise_names_the_wrong_image_length_and_a_tableau_without_images(client, images_only, paper_id):
    created, _ = images_only
    r = client.post(f"/tableaux/{created['id']}/recognise", json={"image": [1.0, 2.0]})
    assert r.status_code == 422 and r.json()["field"] == "image" and "have 20" in r.json()["detail"]
    r = client.post(f"/tableaux/{paper_id}/recognise", json={"image": [1.0]})
    assert r.status_code == 409 and r.headers["content-type"] == PROBLEM and "no images" in r.json()["detail"]


def test_images_can_be_appended_to_an_images_only_tableau(client):
    steps = [s.to_dict() for s in examples.notched_rectangle(circuits=2).steps]  # 17 steps
    images = _paper_images()[:17]
    for s, image in zip(steps, images):
        del s["view"]
        s["image"] = image
    action = steps[8].pop("action")
    created = client.post("/tableaux", json={"format": FORMAT, "steps": steps[:9]})
    assert created.status_code == 201, created.text
    created = created.json()
    r = client.post(f"/tableaux/{created['id']}/steps", json={"action": action, "steps": steps[9:]})
    assert r.status_code == 200, r.text
    assert r.json()["views_from_images"] == 4 and r.json()["map"]["summary"]["dstates"] == 8
    known = client.post(f"/tableaux/{created['id']}/recognise", json={"image": images[12]}).json()
    assert known["dstate"] == r.json()["map"]["steps"][12]["dstate"] and known["distance"] == pytest.approx(0, abs=1e-6)
    labelled = client.post(f"/tableaux/{created['id']}/steps", json={"action": action, "steps": [{"view": "V0"}]})
    assert labelled.status_code == 422 and labelled.json()["field"] == "steps[0]"
    short = client.post(f"/tableaux/{created['id']}/steps", json={"action": action, "steps": [{"image": [1.0]}]})
    assert short.status_code == 422 and short.json()["field"] == "steps[0].image", short.text


def test_appending_steps_extends_the_map(client):
    steps = [s.to_dict() for s in examples.notched_rectangle(circuits=3).steps]  # 25 steps
    first, rest = steps[:5], steps[5:]  # V0 V1 V2 V3 V0 | V1 ...
    action = first[-1].pop("action")
    created = client.post("/tableaux", json={"format": FORMAT, "steps": first}).json()
    assert created["map"]["summary"]["dstates"] == 5
    more = {"action": action, "steps": rest}
    r = client.post(f"/tableaux/{created['id']}/steps", json=more)
    assert r.status_code == 200, r.text
    appended = r.json()
    assert appended["revision"] == 2 and appended["steps"] == 25
    assert appended["map"]["summary"]["dstates"] == 8 and appended["map"]["revision"] == 2
    assert client.get(f"/tableaux/{created['id']}/map").json() == appended["map"]


def test_appending_step_by_step_keeps_the_map_a_fresh_solve_would_give(client):
    # Each append brings the map up to date, by extending the last one where the step repeats a known
    # transition (bootmap.mapping.stream): the map is the one the library resolves from scratch.
    full = examples.notched_rectangle(circuits=3)  # 25 steps
    steps = [s.to_dict() for s in full.steps]
    first = steps[:9]
    action = first[-1].pop("action")
    created = client.post("/tableaux", json={"format": FORMAT, "steps": first}).json()
    ways = []
    for n in range(10, len(steps) + 1):
        step = dict(steps[n - 1])
        following = step.pop("action", None)
        r = client.post(f"/tableaux/{created['id']}/steps", json={"action": action, "steps": [step]})
        assert r.status_code == 200, r.text
        action = following
        served = r.json()["map"]
        batch = Resolver().resolve(full.prefix(n)).to_dict()
        for key in ("summary", "steps", "dstates", "places", "paths", "alternatives"):
            assert served[key] == batch[key], (n, key)
        ways += [b["dstates"] for b in served["stats"]["bounds"]]
    # Some steps were not solved again (the stock axioms replayed, mapping/replay.py).
    assert "the last map extended by determinism (stock axioms replayed)" in ways


def test_a_bad_append_names_the_request_field_and_changes_nothing(client, paper_id):
    before = client.get(f"/tableaux/{paper_id}").json()
    bad = {"action": {"type": "turn", "angle_deg": -90},
           "steps": [{"view": "V1", "action": {"type": "travel", "distance_m": 4}}, {"image": [1.0]}]}
    r = client.post(f"/tableaux/{paper_id}/steps", json=bad)
    assert r.status_code == 422 and r.json()["field"] == "steps[1].view", r.text
    r = client.post(f"/tableaux/{paper_id}/steps", json={**bad, "steps": [{"view": "V1", "action": bad["action"]}]})
    assert r.status_code == 422 and r.json()["field"] == "steps[0].action"
    assert client.get(f"/tableaux/{paper_id}").json() == before
    r = client.post("/tableaux/999999/steps", json={**bad, "steps": [{"view": "V1"}]})
    assert r.status_code == 404 and r.headers["content-type"] == PROBLEM


def test_every_minimal_map_is_listed_when_several_explain_the_experience(client):
    steps = [("A", "travel"), ("B", 90), ("B", -90), ("B", "travel"), ("B", 90), ("A", -90), ("A", 90), ("A", None)]
    doc = {"format": FORMAT, "steps": [
        {"view": v} | ({} if a is None else {"action": {"type": "travel", "distance_m": 2} if a == "travel"
                                                       else {"type": "turn", "angle_deg": a}}) for v, a in steps]}
    created = client.post("/tableaux", json=doc).json()
    summary = created["map"]["summary"]
    maps = client.get(f"/tableaux/{created['id']}/maps").json()
    assert not summary["unique"] and not maps["unique"], "this tableau has several minimal maps"
    assert len(maps["maps"]) == summary["minimal_maps"] >= 2
    assert maps["maps"][0]["dstate_of"] == [row["dstate"] for row in created["map"]["steps"]]
    assert all(m["dstates"] == summary["dstates"] for m in maps["maps"])
    assert len({tuple(m["dstate_of"]) for m in maps["maps"]}) == len(maps["maps"])


def test_axioms_list_files_and_rules_and_reload_after_an_edit(client, server_axioms, paper_doc):
    before = client.get("/axioms").json()
    topological = next(f for f in before["files"] if f["level"] == "topological")
    assert topological["file"] == "topological.lp" and any(r["name"] == "right_by_turn" for r in topological["rules"])

    (server_axioms / "daylight.lp").write_text("%! lit\nlit(T) :- view(T, _).\n")
    reloaded = client.post("/axioms/reload").json()
    assert "daylight" in reloaded["levels"] and reloaded["theory"] != before["theory"]
    assert client.post("/tableaux", json=paper_doc).json()["map"]["theory"] == reloaded["theory"]

    (server_axioms / "broken.lp").write_text("this is not ASP (\n")
    try:
        r = client.post("/axioms/reload")
        assert r.status_code == 422 and r.headers["content-type"] == PROBLEM
        assert "broken.lp" in r.json()["detail"] and "syntax error" in r.json()["detail"]
        assert str(server_axioms) in r.json()["detail"]  # the user's file, not the snapshot
        assert client.get("/axioms").json()["theory"] == reloaded["theory"]  # the old theory stays
        assert client.post("/tableaux", json=paper_doc).status_code == 201
    finally:
        (server_axioms / "broken.lp").unlink()
        (server_axioms / "daylight.lp").unlink()
    assert client.post("/axioms/reload").json()["theory"] == before["theory"]


def test_an_inconsistent_tableau_says_which_axiom_family_fails(client):
    doc = {"format": FORMAT, "steps": [{"view": "A", "action": {"type": "turn", "angle_deg": 180}},
                                       {"view": "B", "action": {"type": "turn", "angle_deg": 180}}, {"view": "C"}]}
    total = client.get("/tableaux").json()["total"]
    r = client.post("/tableaux", json=doc)
    assert r.status_code == 422 and r.headers["content-type"] == PROBLEM
    problem = r.json()
    assert problem["type"].endswith("/inconsistent-tableau") and problem["failing_levels"] == ["topological"]
    assert "no map satisfies the axioms" in problem["detail"] and "topological" in problem["detail"]
    assert client.get("/tableaux").json()["total"] == total  # nothing stored


def test_health_schema_and_docs(client):
    h = client.get("/health").json()
    assert h["status"] == "ok" and h["solvers"] == 1
    r = client.get("/schemas/tableau-1.schema.json")
    assert r.json() == schema() and r.headers["content-type"] == "application/schema+json"
    assert "swagger" in client.get("/docs").text.lower()
    paths = client.get("/openapi.json").json()["paths"]
    assert {"/tableaux", "/tableaux/{tableau_id}/map", "/tableaux/{tableau_id}/maps", "/tableaux/{tableau_id}/steps",
            "/tableaux/{tableau_id}/recognise", "/axioms", "/axioms/reload", "/health"} <= set(paths)


def test_head_is_answered_wherever_get_is(client, paper_id):
    for path in ["/health", f"/tableaux/{paper_id}/map", "/openapi.json"]:
        r = client.head(path)
        assert r.status_code == 200 and r.content == b"" and r.headers["content-type"] == client.get(path).headers[
            "content-type"]
    assert "HEAD" in client.delete("/health").headers["allow"]


def test_axioms_name_their_directory_not_the_servers_path(client, server_axioms):
    listing = client.get("/axioms").text
    assert client.get("/axioms").json()["directory"] == server_axioms.name and str(server_axioms.parent) not in listing


def test_a_script_in_an_axiom_file_is_refused_with_clingos_reason(client, server_axioms):
    before = client.get("/axioms").json()["theory"]
    (server_axioms / "sneaky.lp").write_text('#script (python)\nimport os\n#end.\n')
    try:
        r = client.post("/axioms/reload")
        assert r.status_code == 422 and "sneaky.lp" in r.json()["detail"]
        assert "python support not available" in r.json()["detail"]
    finally:
        (server_axioms / "sneaky.lp").unlink()
    assert client.get("/axioms").json()["theory"] == before


def test_a_solver_that_dies_is_logged_where_the_problem_says(client, server):
    """Kill the solver in the middle of a hard solve: 500 solver-crashed, and the log line it points to."""
    from test_limits import ONE_VIEW, _solves, _wait_for

    result = {}
    thread = threading.Thread(target=lambda: result.update(r=server.client().post("/tableaux", json=ONE_VIEW)))
    thread.start()
    _wait_for(lambda: _solves(client)[0] == 1)
    time.sleep(0.3)
    solver = _solver_pids(server.process.pid)
    assert len(solver) == 1, solver
    os.kill(solver[0], signal.SIGKILL)
    thread.join(30)
    problem = result["r"].json()
    assert result["r"].status_code == 500 and problem["type"].endswith("/solver-crashed")
    assert "server log" in problem["detail"]
    assert f"solver process {solver[0]} died during a solve (exit code -9)" in server.log.read_text()
    _wait_for(lambda: client.get("/health").json()["solvers"] == 1, timeout=30)


def _solver_pids(server: int, memory_mb: int = 2048) -> list[int]:
    """The server's solver processes: the processes under it (children of its forkserver) whose address
    space is capped at the solvers' memory (the intake processes have another cap, multiprocessing's
    resource tracker and the forkserver none)."""
    found, todo = [], [server]
    while todo:
        for task in Path(f"/proc/{todo.pop()}/task").iterdir():
            children = [int(p) for p in (task / "children").read_text().split()]
            found += children
            todo += children
    cap = ["Max", "address", "space", str(memory_mb * 2**20)]
    return [p for p in found if any(line.split()[:4] == cap for line in Path(f"/proc/{p}/limits").open())]


def test_unknown_routes_and_methods_are_problems_too(client):
    r = client.get("/nowhere")
    assert r.status_code == 404 and r.headers["content-type"] == PROBLEM and "/docs" in r.json()["detail"]
    r = client.delete("/tableaux")
    assert r.status_code == 405 and r.headers["allow"] == "GET, HEAD, POST"


def test_a_logs_tableau_is_mapped_by_loop_closing(client):
    # Laps of a square whose corners all look alike, from a log (the robot drove through dstates):
    # the fewest dstates would merge what only odometry tells apart, so the service closes loops.
    steps, x, y = [], 0, 0
    for _ in range(3):
        for dx, dy in ((6, 0), (0, 6), (-6, 0), (0, -6)):
            steps.append({"view": "corner", "odometry": [x, y, 0], "action": {"type": "travel", "distance_m": 6}})
            x, y = x + dx, y + dy
            steps.append({"view": "corner", "odometry": [x, y, 0], "action": {"type": "turn", "angle_deg": 90}})
    steps.append({"view": "corner", "odometry": [x, y, 0]})
    doc = {"format": "bootmap.tableau/1", "steps": steps, "meta": {"passes_through": True}}
    created = client.post("/tableaux", json=doc)
    assert created.status_code == 201, created.text
    m = client.get(f"/tableaux/{created.json()['id']}/map").json()
    assert m["summary"]["found_by"] == "loop closing" and m["summary"]["dstates"] == 8
    assert m["summary"]["places"] == 4 and not m["summary"]["proved_minimal"]
    # ... and asked why, it explains that map: the join that made two laps' corners one dstate.
    why = client.get(f"/tableaux/{created.json()['id']}/why", params={"a": "t0", "b": "t8"})
    assert why.status_code == 200, why.text
    e = why.json()
    assert e["verdict"] == "same" and e["found_by"] == "loop closing"
    assert e["joins"] == ["t0 = t8: proposed (near): dead reckoning puts them 0.0 m apart after 24 m driven "
                          "(within 3.2 m)"]
