"""The viewer's side of the service over HTTP (no browser): the page and its files, the layout resource
with its revision ETag, and the experiment runs' figures."""

import io

import pytest
from matplotlib.figure import Figure
from service_helpers import SESSION_SETTINGS, Server

from bootmap import examples


def test_the_page_and_its_modules_are_served_from_the_package(client):
    page = client.get("/")
    assert page.status_code == 200 and page.headers["content-type"].startswith("text/html")
    assert '<script type="module" src="/viewer/app.js">' in page.text
    for name in ("app.js", "api.js", "assert.js", "draw.js", "table.js", "why.js", "zoom.js"):
        r = client.get(f"/viewer/{name}")
        assert r.status_code == 200 and r.headers["content-type"].startswith("text/javascript"), name
    assert client.get("/viewer/viewer.css").headers["content-type"].startswith("text/css")


@pytest.mark.parametrize("name", ["nope.js", "..%2Fapp.py", "%2e%2e%2F__init__.py", "app.py", "APP.JS"])
def test_only_the_viewers_own_files_are_served(client, name):
    r = client.get(f"/viewer/{name}")
    assert r.status_code == 404, (name, r.status_code)
    assert r.headers["content-type"] == "application/problem+json"


def test_the_layout_of_the_paper_map_is_its_rectangle_and_carries_the_map(client, paper_id):
    r = client.get(f"/tableaux/{paper_id}/layout")
    assert r.status_code == 200, r.text
    d = r.json()
    assert d["id"] == paper_id and d["map"]["summary"]["places"] == 4
    assert d["layout"]["method"] == "metrical"
    assert {p: v["xy"] for p, v in d["layout"]["places"].items()} == {
        "P0": [0, 0], "P1": [0, -4], "P2": [-2, -4], "P3": [-2, 0]}
    assert set(d["layout"]["paths"]) == {"Pa0", "Pa1", "Pa2", "Pa3"}
    assert d["map"] == client.get(f"/tableaux/{paper_id}/map").json()


def test_the_layout_answers_304_until_an_append_makes_a_new_revision(client):
    tid = client.post("/tableaux", json=examples.notched_rectangle(circuits=1).to_dict()).json()["id"]
    first = client.get(f"/tableaux/{tid}/layout")
    etag = first.headers["etag"]
    same = client.get(f"/tableaux/{tid}/layout", headers={"If-None-Match": etag})
    assert same.status_code == 304 and same.content == b""
    r = client.post(f"/tableaux/{tid}/steps", json={"action": {"type": "turn", "angle_deg": -90},
                                                    "steps": [{"view": "V1"}]})
    assert r.status_code == 200, r.text
    changed = client.get(f"/tableaux/{tid}/layout", headers={"If-None-Match": etag})
    assert changed.status_code == 200 and changed.headers["etag"] != etag
    assert changed.json()["revision"] == 2 and len(changed.json()["map"]["steps"]) == 10


def test_the_layout_of_an_unknown_tableau_is_a_404_problem(client):
    r = client.get("/tableaux/999999/layout")
    assert r.status_code == 404 and r.headers["content-type"] == "application/problem+json"


def test_without_a_runs_directory_there_are_no_figures(client):
    assert client.get("/runs").json() == {"configured": False, "runs": []}
    r = client.get("/runs/figure", params={"run": "nr", "name": "views_M_U.png"})
    assert r.status_code == 404 and "--runs-dir" in r.json()["detail"]


def _png() -> bytes:
    fig = Figure(figsize=(2, 1))
    fig.add_subplot().plot([0, 1], [1, 0])
    out = io.BytesIO()
    fig.savefig(out, format="png")
    return out.getvalue()


@pytest.fixture(scope="module")
def runs_server(tmp_path_factory):
    runs = tmp_path_factory.mktemp("runs")
    for name, seed in (("nr", 1), ("th5/seed_2", 2)):
        (runs / name).mkdir(parents=True)
        (runs / name / "results.json").write_text(f'{{"world": "notched_rectangle", "seed": {seed}}}')
        (runs / name / "views_M_U.png").write_bytes(_png())
    (runs / "nr" / "notes.txt").write_text("not a figure")
    (runs / "stray").mkdir()
    (runs / "stray" / "picture.png").write_bytes(_png())  # no results.json: not a run
    s = Server(tmp_path_factory.mktemp("runs_server"), runs_dir=runs, **SESSION_SETTINGS).start()
    yield s
    s.stop()


def test_runs_are_listed_with_their_figures_and_only_those_are_served(runs_server):
    with runs_server.client() as c:
        listed = c.get("/runs").json()
        assert listed == {"configured": True, "runs": [
            {"name": "nr", "world": "notched_rectangle", "seed": 1, "figures": ["views_M_U.png"]},
            {"name": "th5/seed_2", "world": "notched_rectangle", "seed": 2, "figures": ["views_M_U.png"]}]}
        png = c.get("/runs/figure", params={"run": "th5/seed_2", "name": "views_M_U.png"})
        assert png.status_code == 200 and png.headers["content-type"] == "image/png"
        assert png.content.startswith(b"\x89PNG")
        for run, name in (("nr", "notes.txt"), ("stray", "picture.png"), ("nr/../stray", "picture.png"),
                          ("..", "results.json"), ("nr", "../th5/seed_2/views_M_U.png")):
            r = c.get("/runs/figure", params={"run": run, "name": name})
            assert r.status_code == 404, (run, name)
