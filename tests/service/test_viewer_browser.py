"""The viewer in a real headless browser: Debian's chromium driven by Playwright, against a real uvicorn.

The system's chromium is launched by path (``playwright install`` downloads a browser of its own, which
this project never does); as root it needs ``--no-sandbox``. Without chromium these tests skip and say
how to get it. Every test fails if the page logged an error to the console.

With ``BOOTMAP_SCREENSHOTS=1`` the tests write the README's screenshots to docs/viewer/.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from service_helpers import CHROMIUM, REPO, SESSION_SETTINGS, Server, bearer, make_token

from bootmap import examples
from support.gridworld import random_world, walk

pytest.importorskip("playwright.sync_api", reason="playwright not installed: pip install -e '.[dev]'")

SHOTS = REPO / "docs" / "viewer" if os.environ.get("BOOTMAP_SCREENSHOTS") == "1" else None
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="chromium not installed: apt-get install chromium")


@pytest.fixture(scope="module")
def runs_dir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("runs")


@pytest.fixture(scope="module")
def viewer_server(tmp_path_factory, runs_dir):
    """A server of the module's own, with a runs directory (empty until a test runs an experiment). Its
    solves have a generous time limit: what the viewer shows must not depend on how busy the machine is
    (the paper's map on the causal and topological levels, and a proof on it, take about a second alone
    and more than the session's 3 s under a loaded test run)."""
    s = Server(tmp_path_factory.mktemp("viewer_server"), runs_dir=runs_dir,
               **{**SESSION_SETTINGS, "solve_time_limit_s": 60}).start()
    yield s
    s.stop()


@pytest.fixture(scope="module")
def paper(viewer_server) -> int:
    with viewer_server.client() as c:
        r = c.post("/tableaux", json=examples.notched_rectangle(circuits=50).to_dict())
        assert r.status_code == 201, r.text
        return r.json()["id"]


@pytest.fixture
def page(browser):
    """A fresh tab; the test fails if the page logs a console error or throws (``page.allowed_errors``
    lists the messages a test expects)."""
    context = browser.new_context(viewport={"width": 1280, "height": 1000})
    tab = context.new_page()
    tab.errors, tab.allowed_errors = [], []
    tab.on("console", lambda m: m.type == "error" and tab.errors.append(m.text))
    tab.on("pageerror", lambda e: tab.errors.append(f"uncaught: {e}"))
    yield tab
    context.close()
    unexpected = [e for e in tab.errors if not any(a in e for a in tab.allowed_errors)]
    assert not unexpected, f"console errors: {unexpected}"


def _open(page, server, tableau_id, levels=None):
    query = f"?tableau={tableau_id}" + (f"&levels={levels}" if levels else "")
    page.goto(server.url + "/" + query)
    page.wait_for_selector("body[data-drawn]", state="attached", timeout=20_000)


def _shot(page, name, full_page=False):
    if SHOTS is not None:
        SHOTS.mkdir(parents=True, exist_ok=True)
        if name != "map.png":  # the map's picture shows a path's hover box; the others none
            page.mouse.move(0, 0)
        page.screenshot(path=str(SHOTS / name), full_page=full_page)


def test_the_paper_map_shows_4_places_and_4_paths_and_hovering_a_path_shows_its_sides(page, viewer_server, paper):
    _open(page, viewer_server, paper)
    assert page.locator("#map .place").count() == 4
    assert page.locator("#map .path").count() == 4
    assert page.locator("#map .dstate").count() == 8
    assert page.locator("#tableau tbody tr").count() == 401
    assert "8 dstates, 4 places, 4 paths" in page.locator("#summary").inner_text()
    # P2 is right of Pa1 facing pos (the map's right_of): hovering Pa1 colours it and says so.
    # force: a straight path's box is a line (no area), which Playwright counts as not visible.
    page.locator('#map .path[data-path="Pa1"] .hit').hover(force=True)
    assert page.locator('#map .place.right-of').evaluate_all("ns => ns.map(n => n.dataset.place)") == ["P2"]
    assert "right of it: P2" in page.locator("#hover").inner_text()
    _shot(page, "map.png")


def test_clicking_S0_and_S4_shows_the_proof_by_on_path_no_side_on_t0_to_t4(page, viewer_server, paper):
    _open(page, viewer_server, paper, levels="causal,topological")
    page.locator('#map .dstate[data-dstate="S0"] circle').click()
    assert page.locator("#map .dstate.lit").evaluate_all("ns => ns.map(n => n.dataset.dstate)") == ["S0"]
    page.locator('#map .dstate[data-dstate="S4"] circle').click()
    page.wait_for_selector("body[data-why=different]", state="attached", timeout=60_000)
    why = page.locator("#why").inner_text()
    assert "DIFFERENT" in why and "levels causal,topological" in why
    assert page.locator("#why .axioms .rule").all_inner_texts() == ["on_path_no_side"]
    assert "topological.lp:" in page.locator("#why .axioms").inner_text()
    assert page.locator("#tableau tr.evidence").evaluate_all("rs => rs.map(r => r.dataset.t)") == [
        "0", "1", "2", "3", "4"]
    # The rule chain names each rule with its file and line.
    chain = page.locator("#why .proof").inner_text()
    assert "turn_link" in chain and "causal.lp:" in chain
    _shot(page, "why.png", full_page=True)


def test_clicking_a_time_point_lights_its_dstate(page, viewer_server, paper):
    _open(page, viewer_server, paper)
    page.locator('#tableau tbody tr[data-t="13"]').click()  # t13 is S5 (13 mod 8)
    assert page.locator("#map .dstate.lit").evaluate_all("ns => ns.map(n => n.dataset.dstate)") == ["S5"]


def test_appended_steps_show_up_without_a_reload_beside_the_true_trajectory(page, viewer_server):
    # A walk through a random grid world with landmarks (true poses on every step): its first 40 steps
    # are posted, the page opened, then the next 20 appended through the API.
    rng = np.random.default_rng(3)
    steps = walk(random_world(rng, 3, 3, extra_edges=1, landmarks=1.0), 60, rng, policy="explore").to_dict()["steps"]
    first = [*steps[:39], {k: v for k, v in steps[39].items() if k != "action"}]
    with viewer_server.client() as c:
        r = c.post("/tableaux", json={"format": "bootmap.tableau/1", "steps": first})
        assert r.status_code == 201, r.text
        tid = r.json()["id"]
        _open(page, viewer_server, tid)
        assert page.locator("#tableau tbody tr").count() == 40
        assert page.locator("#truth-panel").is_visible() and page.locator("#trajectory polyline").count() == 1
        page.evaluate("window.__sameDocument = true")
        r = c.post(f"/tableaux/{tid}/steps", json={"action": steps[39]["action"], "steps": steps[40:]})
        assert r.status_code == 200, r.text
        places = r.json()["map"]["summary"]["places"]
    page.wait_for_selector('body[data-drawn="2"]', state="attached", timeout=10_000)
    assert page.evaluate("window.__sameDocument") is True
    assert page.locator("#tableau tbody tr").count() == 60
    assert page.locator("#map .place").count() == places
    assert "revision 2" in page.locator("#summary").inner_text()
    # The trajectory drawn has a point per step: 60 now.
    assert len(page.locator("#trajectory polyline").get_attribute("points").split()) == 60
    _shot(page, "live.png")


def test_the_experiments_figures_are_viewable(page, viewer_server, runs_dir, paper):
    from bootmap.experiments.world import run_experiment

    run_experiment("notched_rectangle", circuits=2, seed=1, out_dir=runs_dir / "nr")  # a real run: 3-5 s
    _open(page, viewer_server, paper)
    page.locator("#runs-panel summary").first.click()
    # A function, not an expression: Playwright evaluates an expression with eval, which the page's
    # Content-Security-Policy refuses.
    page.wait_for_function("() => document.querySelectorAll('#runs img').length >= 3 && "
                           "[...document.querySelectorAll('#runs img')].every(i => i.complete && i.naturalWidth > 0)")
    names = page.locator("#runs figcaption").all_inner_texts()
    assert {"views_M_U.png", "learning_curves.png", "world_map.png"} <= set(names)
    assert "notched_rectangle, seed 1" in page.locator("#runs summary").first.inner_text()


def test_on_a_server_that_needs_tokens_the_page_asks_once_and_sends_it_on_every_request(page, tmp_path_factory):
    # A real server with tokens required: the page and its files load without one; the first data request
    # answers 401, the page asks, and every later request carries "Authorization: Bearer".
    s = Server(tmp_path_factory.mktemp("tokens_viewer"), require_tokens=True, **SESSION_SETTINGS).start()
    try:
        token = make_token("viewer", data_dir=s.data_dir)
        with s.client() as c:
            r = c.post("/tableaux", json=examples.notched_rectangle(circuits=2).to_dict(), headers=bearer(token))
            assert r.status_code == 201, r.text
            tid = r.json()["id"]
        sent = []
        page.allowed_errors.append("401")  # chromium logs the refused request itself
        page.on("request", lambda r: sent.append((r.url, r.headers.get("authorization"))))
        page.goto(f"{s.url}/?tableau={tid}")
        page.locator("#token-dialog").wait_for()
        assert "needs an API token" in page.locator("#token-reason").inner_text()
        before = len(sent)
        page.locator("#token-input").fill(token)
        page.locator("#token-ok").click()
        page.wait_for_selector("body[data-drawn]", state="attached", timeout=20_000)
        assert page.locator("#map .place").count() == 4
        page.wait_for_timeout(1500)  # a poll of the layout, with the token too
        api = [(url, auth) for url, auth in sent[before:] if "/viewer/" not in url]
        assert any("/tableaux?limit=" in url for url, _ in api) and any("/layout" in url for url, _ in api)
        assert all(auth == f"Bearer {token}" for _, auth in api), api
        assert all(auth is None for url, auth in sent[:before])
        assert page.evaluate("sessionStorage.getItem('bootmap.token')") == token
    finally:
        page.goto("about:blank")  # stop the page's polling first: a poll of a stopped server is a console error
        s.stop()


# ---------------------------------------------------------------------------------------------------
# A map at a real log's scale: zoom, pan, fit, labels readable, clicks on dstates, downloads
# ---------------------------------------------------------------------------------------------------

HOME = [0.0, 0.0, 640.0, 460.0]  # the whole map: draw.js's WIDTH and HEIGHT


@pytest.fixture(scope="module")
def big(viewer_server) -> int:
    """A 700-step exploration of a random 6x6 grid world with loops: 36 places and over 100 dstates,
    about the size of a real log's map (MIT's Killian Court: 38 places, 80 dstates). Solved in a second."""
    rng = np.random.default_rng(5)
    doc = walk(random_world(rng, 6, 6, extra_edges=4, landmarks=0.5), 700, rng, policy="explore").to_dict()
    with viewer_server.client() as c:
        r = c.post("/tableaux", json=doc)
        assert r.status_code == 201, r.text
        assert r.json()["map"]["summary"]["places"] >= 30
        return r.json()["id"]


def _view(page) -> list[float]:
    return [float(v) for v in page.locator("#map").get_attribute("viewBox").split()]


def _to_map(page, x, y) -> list[float]:
    """The map point (SVG user units) under the client point (x, y)."""
    return page.evaluate("([x, y]) => { const p = new DOMPoint(x, y).matrixTransform("
                         "document.getElementById('map').getScreenCTM().inverse()); return [p.x, p.y]; }", [x, y])


def _to_screen(page, x, y) -> list[float]:
    return page.evaluate("([x, y]) => { const p = new DOMPoint(x, y).matrixTransform("
                         "document.getElementById('map').getScreenCTM()); return [p.x, p.y]; }", [x, y])


def test_the_wheel_zooms_about_the_pointer_a_drag_pans_and_fit_shows_the_whole_map_again(page, viewer_server, big):
    _open(page, viewer_server, big)
    assert page.locator("#map .place").count() >= 30
    assert _view(page) == HOME
    box = page.locator("#map").bounding_box()
    px, py = box["x"] + 0.3 * box["width"], box["y"] + 0.4 * box["height"]
    under = _to_map(page, px, py)
    page.mouse.move(px, py)
    page.mouse.wheel(0, -300)  # away from the user: zoom in
    for _ in range(50):  # the wheel event is dispatched, not awaited
        if _view(page) != HOME:
            break
        page.wait_for_timeout(50)
    zoomed = _view(page)
    assert zoomed[2] < HOME[2] * 0.8 and zoomed[3] < HOME[3] * 0.8
    assert abs(zoomed[2] / zoomed[3] - HOME[2] / HOME[3]) < 1e-3  # as much across as up
    sx, sy = _to_screen(page, *under)  # the point that was under the pointer still is
    assert abs(sx - px) < 3 and abs(sy - py) < 3, (sx, sy, px, py)

    # A drag pans: the map follows the pointer, the view moves the other way by as many map units.
    scale = box["width"] / zoomed[2]
    page.mouse.down()
    page.mouse.move(px + 80, py + 40, steps=8)
    page.mouse.up()
    panned = _view(page)
    assert panned[2:] == zoomed[2:]
    assert abs((zoomed[0] - panned[0]) * scale - 80) < 3 and abs((zoomed[1] - panned[1]) * scale - 40) < 3
    assert page.locator("#map .dstate.lit").count() == 0  # the drag ended on the map, clicked nothing

    page.locator("#zoom-fit").click()
    assert _view(page) == HOME
    # The buttons, the keys (with the map focused) and a double-click on the background.
    page.locator("#zoom-in").click()
    assert _view(page)[2] < HOME[2]
    page.locator("#zoom-out").click()
    page.locator("#zoom-out").click()
    assert _view(page)[2] > HOME[2]
    page.locator("#map").focus()
    page.keyboard.press("0")
    assert _view(page) == HOME
    page.keyboard.press("+")
    page.keyboard.press("+")
    assert _view(page)[2] < HOME[2] * 0.7
    x = _view(page)[0]
    page.keyboard.press("ArrowLeft")  # shows more of the left
    assert _view(page)[0] < x
    page.mouse.dblclick(box["x"] + 3, box["y"] + 3)  # a corner: background
    assert _view(page) == HOME


@pytest.mark.parametrize("width", [500, 1280])
def test_place_labels_are_at_least_11_px_on_screen_whatever_the_window_or_the_zoom(page, viewer_server, big, width):
    page.set_viewport_size({"width": width, "height": 900})
    _open(page, viewer_server, big)
    measure = ("() => { const svg = document.getElementById('map'), k = svg.getScreenCTM().a;"
               " return [...svg.querySelectorAll('.place-label')].map(t =>"
               " [parseFloat(getComputedStyle(t).fontSize) * k, t.getBoundingClientRect().height]); }")
    for action in ["fit", "zoom-out", "zoom-out", "zoom-out", "zoom-fit", "zoom-in", "zoom-in", "zoom-in", "zoom-in"]:
        if action != "fit":
            page.locator(f"#{action}").click()
        sizes = page.evaluate(measure)
        assert len(sizes) >= 30
        assert min(font for font, _ in sizes) >= 11, (action, min(sizes))
        assert min(height for _, height in sizes) >= 11, (action, min(sizes))
    # Zoomed in, the map's circles grow on screen while the labels keep their size; crowded dstate
    # labels show once they have room.
    assert _view(page)[2] < HOME[2] / 2
    assert page.locator("#map .dstate.crowded").count() < page.locator("#map .dstate").count()


def test_a_click_on_a_dstate_where_it_lies_on_its_place_circle_selects_the_dstate(page, viewer_server, big):
    _open(page, viewer_server, big)
    # A point inside both a dstate's circle and its place's (the dstate's edge nearest the place's centre),
    # in client coordinates; the place's circle is drawn first, the dstate above it.
    found = page.evaluate("""() => {
      const svg = document.getElementById('map'), ctm = svg.getScreenCTM();
      for (const fan of svg.querySelectorAll('.dstates .fan')) {
        const hub = svg.querySelector(`.place[data-place="${CSS.escape(fan.dataset.of)}"] .hub circle`);
        if (!hub) continue;
        const hx = +hub.getAttribute('cx'), hy = +hub.getAttribute('cy'), hr = +hub.getAttribute('r');
        for (const c of fan.querySelectorAll('.dstate circle')) {
          const x = +c.getAttribute('cx'), y = +c.getAttribute('cy'), r = +c.getAttribute('r');
          const d = Math.hypot(x - hx, y - hy);
          if (d === 0 || d - (r - 1.5) > hr - 1.5) continue;  // not on the place's circle
          const t = (r - 1.5) / d, p = new DOMPoint(x + (hx - x) * t, y + (hy - y) * t).matrixTransform(ctm);
          return { dstate: c.parentNode.dataset.dstate, place: fan.dataset.of, x: p.x, y: p.y };
        }
      }
      return null; }""")
    assert found is not None, "no dstate lies on its place's circle"
    page.mouse.click(found["x"], found["y"])
    assert page.locator("#map .dstate.lit").evaluate_all("ns => ns.map(n => n.dataset.dstate)") == [found["dstate"]]
    assert found["dstate"] in page.locator("#selection").inner_text()
    # The place stays unfolded: the click was not the place's.
    assert page.locator(f'#map .place[data-place="{found["place"]}"]').get_attribute("class") == "place unfolded"


def test_the_map_downloads_as_a_standalone_svg_and_as_the_apis_json(page, viewer_server, big):
    import json
    import xml.etree.ElementTree as ET

    _open(page, viewer_server, big)
    page.locator("#zoom-in").click()  # the drawing as it is: zoomed
    view = page.locator("#map").get_attribute("viewBox")
    with page.expect_download() as got:
        page.locator("#save-svg").click()
    svg = got.value
    assert svg.suggested_filename == f"bootmap-tableau-{big}-rev1-map.svg"
    root = ET.parse(svg.path()).getroot()
    ns = "{http://www.w3.org/2000/svg}"
    assert root.tag == f"{ns}svg" and root.get("viewBox") == view
    assert root.get("width") == "640" and root.get("height") == "460"
    places = root.findall(f".//{ns}g[@class='places']/{ns}g")
    assert len(places) == page.locator("#map .place").count() >= 30
    assert len(root.findall(f".//{ns}circle")) == page.locator("#map circle").count()
    style = root.find(f"{ns}style").text  # the page's rules, in the file: it renders on its own
    assert ".hub circle" in style and ".path .line" in style and "--path" in style

    with page.expect_download() as got:
        page.locator("#save-json").click()
    assert got.value.suggested_filename == f"bootmap-tableau-{big}-rev1-map.json"
    saved = json.loads(Path(got.value.path()).read_text())
    with viewer_server.client() as c:
        served = c.get(f"/tableaux/{big}/map").json()
    assert saved == served
    assert len(saved["dstates"]) == served["summary"]["dstates"] > 100


@pytest.fixture(scope="module")
def killian(viewer_server) -> int:
    """The MIT Killian Court log's tableau, as `bootmap ingest killian --no-place-matches` writes it: 98
    visits, mapped by the server by loop closing (the odometry as recorded: on Killian the calibration
    leaves it so, tests/ingest/test_killian_readme.py)."""
    pytest.importorskip("rtbdata")
    from bootmap.ingest.ingest import log_tableau, read_log

    with viewer_server.client() as c:
        r = c.post("/tableaux", json=log_tableau(read_log("killian"), calibrate=False).to_dict())
        assert r.status_code == 201, r.text
        return r.json()["id"]


@pytest.mark.slow
def test_a_real_logs_map_is_decluttered_and_readable_once_zoomed(page, viewer_server, killian):
    """Killian's 80-odd dstates at 38 places: the whole map shows its places' names and hides the dstate
    labels that have no room; zoomed in on the densest part, they show, and every label stays as large
    on screen."""
    page.set_viewport_size({"width": 1400, "height": 900})
    _open(page, viewer_server, killian)
    dstates = page.locator("#map .dstate").count()
    assert page.locator("#map .place").count() >= 30 and dstates >= 70
    crowded_at_fit = page.locator("#map .dstate.crowded").count()
    assert crowded_at_fit > dstates / 2
    shots = REPO / "docs" / "logs" if SHOTS is not None else None
    if shots is not None:
        page.mouse.move(0, 0)
        page.screenshot(path=str(shots / "killian_viewer.png"))
    # Zoom in on the densest places: the place circle with the most others within 80 px on screen.
    centres = np.array(page.evaluate(
        "() => [...document.querySelectorAll('#map .place circle')].map(c => {"
        " const r = c.getBoundingClientRect(); return [r.x + r.width / 2, r.y + r.height / 2]; })"))
    near = (np.hypot(*(centres[:, None, :] - centres[None, :, :]).transpose(2, 0, 1)) < 80).sum(axis=1)
    x, y = centres[int(np.argmax(near))]
    page.mouse.move(x, y)
    home = _view(page)
    box = page.locator("#map").bounding_box()

    def places_in_view() -> int:
        return page.evaluate(
            "([x0, y0, x1, y1]) => [...document.querySelectorAll('#map .place circle')].filter(c => {"
            " const r = c.getBoundingClientRect(), x = r.x + r.width / 2, y = r.y + r.height / 2;"
            " return x > x0 && x < x1 && y > y0 && y < y1; }).length",
            [box["x"], box["y"], box["x"] + box["width"], box["y"] + box["height"]])

    def wheel(times: int) -> None:
        for _ in range(times):
            page.mouse.wheel(0, -300)
            page.wait_for_timeout(100)

    wheel(3)  # about six times closer: the dense part fills the view, its places' names all readable
    page.wait_for_function(f"() => document.getElementById('map').viewBox.baseVal.width < {home[2] / 3}",
                           timeout=10_000)
    assert places_in_view() >= 5
    if shots is not None:
        page.mouse.move(0, 0)
        page.screenshot(path=str(shots / "killian_viewer_zoomed.png"))
        page.mouse.move(x, y)
    wheel(3)  # closer still: the dstates' labels that had no room show
    page.wait_for_function(f"() => document.querySelectorAll('#map .dstate.crowded').length < {crowded_at_fit}",
                           timeout=10_000)
    assert places_in_view() >= 1
    sizes = page.evaluate("() => { const svg = document.getElementById('map'), k = svg.getScreenCTM().a;"
                          " return [...svg.querySelectorAll('.place-label')].map(t =>"
                          " parseFloat(getComputedStyle(t).fontSize) * k); }")
    assert min(sizes) >= 11


# --- A person in the loop: same place / not the same, what changed, the clash, the list ------------------

@pytest.fixture
def two_laps(viewer_server) -> int:
    """The paper's notched rectangle, two circuits (t0, t8 and t16 are S0): a tableau of the test's own."""
    with viewer_server.client() as c:
        r = c.post("/tableaux", json=examples.notched_rectangle(circuits=2).to_dict())
        assert r.status_code == 201, r.text
        return r.json()["id"]


def _pick_rows(page, *ts):
    for t in ts:
        page.locator(f'#tableau tbody tr[data-t="{t}"]').click()


def test_not_the_same_splits_the_dstate_lights_what_changed_and_lists_the_assertion_to_take_back(page, viewer_server,
                                                                                               two_laps):
    _open(page, viewer_server, two_laps)
    assert page.locator("#assert-apart").is_disabled()
    page.wait_for_selector("body[data-listed]", state="attached", timeout=20_000)  # fetched after the map
    assert page.locator("#assertions li.none").count() == 1  # the owner's (here, the local user's) list
    _pick_rows(page, 0, 8)  # both S0
    assert page.locator("#assert-apart").is_enabled()
    page.locator("#assert-apart").click()
    page.wait_for_selector("body[data-asserted=changed]", state="attached", timeout=60_000)
    assert "9 dstates" in page.locator("#summary").inner_text()
    assert "dstate S0 split: now S0, S8" in page.locator("#asserted").inner_text()
    page.wait_for_selector('#map .dstate.changed[data-dstate="S8"]', state="attached")
    assert sorted(page.locator("#map .dstate.changed").evaluate_all("ns => ns.map(n => n.dataset.dstate)")) == [
        "S0", "S8"]
    assert page.locator("#assertions li code").all_inner_texts() == ["apart(t0, t8)"]
    _shot(page, "assert.png", full_page=True)
    # taking it back: the map as it was
    page.locator("#assertions button.remove").click()
    page.wait_for_selector("body[data-asserted=removed]", state="attached", timeout=60_000)
    assert "8 dstates" in page.locator("#summary").inner_text()
    assert "dstates S0 + S8 joined: now S0" in page.locator("#asserted").inner_text()
    assert page.locator("#assertions li.none").count() == 1


def test_same_place_that_the_experience_refutes_shows_the_clash_with_its_proof(page, viewer_server, two_laps):
    page.allowed_errors = ["409 (Conflict)"]  # the browser logs the service's refusal; the page shows why
    _open(page, viewer_server, two_laps)
    _pick_rows(page, 1, 9)
    page.locator("#assert-apart").click()
    page.wait_for_selector("body[data-asserted=changed]", state="attached", timeout=60_000)
    _pick_rows(page, 0, 8)
    page.locator("#assert-same").click()
    page.wait_for_selector("body[data-asserted=conflict]", state="attached", timeout=60_000)
    text = page.locator("#asserted").inner_text()
    assert "No map honours that" in text and "same(t0, t8) and apart(t1, t9)" in text
    assert page.locator("#asserted .axioms .rule").all_inner_texts() == ["one_value_per_feature"]
    assert "causal.lp:" in page.locator("#asserted .axioms").inner_text()
    assert page.locator("#tableau tr.evidence").evaluate_all("rs => rs.map(r => r.dataset.t)") == ["0", "1", "8", "9"]
    assert page.locator("#assertions li code").all_inner_texts() == ["apart(t1, t9)"]  # nothing stored


def test_not_the_same_that_the_axioms_refute_shows_the_clash_with_its_proof(page, viewer_server):
    # There and back again: turned around twice on the spot, the robot is where it was, facing the same way.
    from bootmap.tableau import Step, Tableau, Travel, Turn
    there_and_back = Tableau(tuple(Step(v, a) for v, a in
                                   [("A", Turn(180.0)), ("B", Turn(180.0)), ("A", Travel(1.0)), ("C", None)]))
    with viewer_server.client() as c:
        r = c.post("/tableaux", json=there_and_back.to_dict())
        assert r.status_code == 201, r.text
        tableau_id = r.json()["id"]
    page.allowed_errors = ["409 (Conflict)"]
    _open(page, viewer_server, tableau_id)
    _pick_rows(page, 0, 2)
    page.locator("#assert-apart").click()
    page.wait_for_selector("body[data-asserted=conflict]", state="attached", timeout=60_000)
    text = page.locator("#asserted").inner_text()
    assert "No map honours that" in text and "apart(t0, t2)" in text and "cannot be different dstates" in text
    assert "one_dstate_per_place_and_direction" in page.locator("#asserted .axioms .rule").all_inner_texts()
    assert "topological.lp:" in page.locator("#asserted .axioms").inner_text()
    assert "supposing t0 and t2 are different dstates" in text
    assert page.locator("#tableau tr.evidence").evaluate_all("rs => rs.map(r => r.dataset.t)") == ["0", "1", "2"]


def test_a_list_of_assertions_fetched_before_an_assertion_and_answered_after_it_does_not_hide_it(page, viewer_server,
                                                                                                 two_laps):
    # The page fetches the tableau's assertions once the map is drawn; hold that answer (the list as it was:
    # empty) back until a "not the same" has been made and listed: the late, older list must not replace it.
    held = []

    def hold(route):
        if route.request.method == "GET":
            held.append((route, route.fetch()))
        else:
            route.continue_()

    page.route(f"**/tableaux/{two_laps}/assertions", hold)
    _open(page, viewer_server, two_laps)
    _pick_rows(page, 0, 8)
    page.locator("#assert-apart").click()
    page.wait_for_selector("body[data-asserted=changed]", state="attached", timeout=60_000)
    assert page.locator("#assertions li code").all_inner_texts() == ["apart(t0, t8)"]
    assert len(held) == 1 and held[0][1].json()["assertions"] == []
    held[0][0].fulfill(response=held[0][1])
    page.wait_for_timeout(500)  # the held answer arrives and is read (a margin, not the subject)
    assert page.locator("#assertions li code").all_inner_texts() == ["apart(t0, t8)"]


def test_dstates_the_minimal_maps_disagree_on_are_drawn_dashed(page, viewer_server):
    # A short exploration of a random grid world that leaves two minimal maps (seed 20023: 20 steps).
    rng = np.random.default_rng(20023)
    world = random_world(rng, int(rng.integers(3, 5)), int(rng.integers(3, 5)), extra_edges=int(rng.integers(0, 4)),
                         landmarks=0.2)
    tableau = walk(world, int(rng.integers(8, 30)), rng, policy="explore")
    with viewer_server.client() as c:
        r = c.post("/tableaux", json=tableau.to_dict())
        assert r.status_code == 201, r.text
        tid, m = r.json()["id"], r.json()["map"]
    assert m["confidence"]["minimal_maps"] == 2
    unsettled = sorted(d for d, x in m["confidence"]["dstates"].items() if x["in_maps"] < x["of"])
    assert unsettled
    _open(page, viewer_server, tid)
    assert sorted(page.locator("#map .dstate.unsettled").evaluate_all("ns => ns.map(n => n.dataset.dstate)")) == \
        unsettled
    assert "of time points at a dstate they all agree on" in page.locator("#summary").inner_text()
