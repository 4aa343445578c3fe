"""A hostile tableau in the viewer, and the security headers, against a real uvicorn and real Chromium.

A user of a server that requires tokens publishes a tableau whose view labels are markup with script in
it, and puts an experiment run with a hostile name and world in the runs directory; an admin opens the
tableau in the viewer and hovers, clicks and opens everything that shows those strings. Nothing may run,
and the labels must show, as text. Behind that, the Content-Security-Policy stops inline script even
when markup does reach the page (defence in depth), and every kind of response carries the headers.
FastAPI's API docs keep working under a policy of their own (their CDN files are served by the test:
tests never reach the network).
"""

from __future__ import annotations

import base64
import hashlib
import json
import re
import shutil

import pytest
from service_helpers import CHROMIUM, REPO, SESSION_SETTINGS, Server, bearer, make_token

from bootmap import examples

pytest.importorskip("playwright.sync_api", reason="playwright not installed: pip install -e '.[dev]'")

pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="chromium not installed: apt-get install chromium")

# Each view label of the paper's world becomes markup that runs script if the page ever parses it as
# HTML: in an element (V0, V1), breaking out of a double- (V2) or single-quoted (V3) attribute. V0 takes
# the server over with the admin's token: it makes a new token. (200 characters: the longest label.)
TAKEOVER = ("<img src=x onerror=\"__pwned=1;fetch('/tokens',{method:'POST',headers:{Authorization:'Bearer '+"
            "sessionStorage['bootmap.token'],'Content-Type':'application/json'},"
            "body:JSON.stringify({name:'pwned'})})\">")
HOSTILE_VIEWS = {"V0": TAKEOVER, "V1": "<svg onload=__pwned=2><img src=x onerror=__pwned=2>",
                 "V2": "\"><img src=x onerror=__pwned=3><b x=\"", "V3": "'><img src=x onerror=__pwned=4><b x='"}
HOSTILE_RUN = "<img src=x onerror=__pwned=5>"
HOSTILE_WORLD = "<img src=x onerror=__pwned=6>"

POLICY_HEADERS = ("content-security-policy", "x-content-type-options", "x-frame-options", "referrer-policy")


def hostile_tableau() -> dict:
    doc = examples.notched_rectangle(circuits=2).to_dict()
    for step in doc["steps"]:
        step["view"] = HOSTILE_VIEWS[step["view"]]
    return doc


@pytest.fixture(scope="module")
def hostile_server(tmp_path_factory):
    """A server that requires tokens, with an admin, a user, the user's public hostile tableau and a
    hostile experiment run (one real figure)."""
    root = tmp_path_factory.mktemp("hostile_server")
    run = root / "runs" / HOSTILE_RUN
    run.mkdir(parents=True)
    (run / "results.json").write_text(json.dumps({"world": HOSTILE_WORLD, "seed": 1}))
    shutil.copy(REPO / "docs" / "viewer" / "map.png", run / "map.png")
    s = Server(root, require_tokens=True, runs_dir=root / "runs", **SESSION_SETTINGS)
    s.tokens = {"admin": make_token("root", admin=True, data_dir=s.data_dir),
                "user": make_token("mallory", data_dir=s.data_dir)}
    s.start()
    with s.client() as c:
        r = c.post("/tableaux", params={"public": "true"}, json=hostile_tableau(), headers=bearer(s.tokens["user"]))
        assert r.status_code == 201, r.text
        s.hostile_id = r.json()["id"]
    yield s
    s.stop()


@pytest.fixture
def admin_page(browser, hostile_server):
    """A tab whose sessionStorage holds the admin's token before any page script runs (as after the
    token dialog); the test fails if the page logs an error it did not expect (``allowed_errors``)."""
    context = browser.new_context(viewport={"width": 1280, "height": 1000})
    context.add_init_script(f"if (location.origin === {json.dumps(hostile_server.url)}) "
                            f"sessionStorage.setItem('bootmap.token', {json.dumps(hostile_server.tokens['admin'])})")
    tab = context.new_page()
    tab.errors, tab.allowed_errors, tab.posts = [], [], []
    tab.on("console", lambda m: m.type == "error" and tab.errors.append(m.text))
    tab.on("pageerror", lambda e: tab.errors.append(f"uncaught: {e}"))
    tab.on("request", lambda r: r.method != "GET" and tab.posts.append((r.method, r.url)))
    yield tab
    context.close()
    unexpected = [e for e in tab.errors if not any(a in e for a in tab.allowed_errors)]
    assert not unexpected, f"console errors: {unexpected}"


def _open(page, server):
    page.goto(f"{server.url}/?tableau={server.hostile_id}")
    page.wait_for_selector("body[data-drawn]", state="attached", timeout=20_000)


def test_hostile_view_labels_and_run_names_show_as_text_and_run_nothing(admin_page, hostile_server):
    page = admin_page
    _open(page, hostile_server)
    # Hover every place, a path and a dstate; click two dstates (the why panel); open the hostile run.
    hovered, made = [], []
    for hub in page.locator("#map [data-place] .hub").all():
        hub.hover(force=True)
        hovered.append(page.locator("#hover").inner_text())
        made.append(page.locator("#hover *:not(b):not(br)").count())  # elements other than the name and breaks
    page.locator("#map .path .hit").first.hover(force=True)
    path_hover = page.locator("#hover").inner_text()
    page.locator("#map .dstate circle").first.hover(force=True)
    dstates = page.locator("#map .dstate circle")
    dstates.nth(0).click()
    dstates.nth(1).click()
    page.wait_for_selector("body[data-why]:not([data-why=asking])", state="attached", timeout=20_000)
    summary = page.locator("#runs-panel summary").first
    summary.click()
    page.wait_for_function("() => [...document.querySelectorAll('#runs figure img')].length === 1 && "
                           "document.querySelector('#runs figure img').complete && "
                           "document.querySelector('#runs figure img').naturalWidth > 0")
    page.wait_for_timeout(500)  # time for a handler's request, had one run

    # No script ran, the page sent nothing but GETs, and no token 'pwned' was made (the name is free).
    assert page.evaluate("typeof window.__pwned") == "undefined"
    assert page.posts == []
    with hostile_server.client() as c:
        r = c.post("/tokens", json={"name": "pwned"}, headers=bearer(hostile_server.tokens["admin"]))
        assert r.status_code == 201, r.text
        assert c.delete("/tokens/pwned", headers=bearer(hostile_server.tokens["admin"])).status_code == 204
    # Each hostile label showed in a place's hover text, as text: no element was made of it.
    for label in HOSTILE_VIEWS.values():
        assert any(label in text for text in hovered), (label, hovered)
    assert made == [0] * len(hovered)
    assert path_hover.startswith("Pa") and "right of it:" in path_hover
    # The table and the why panel show them as text too; the runs list shows the run's name and world.
    assert set(page.locator("#tableau tbody td:nth-child(2)").all_inner_texts()) == set(HOSTILE_VIEWS.values())
    assert page.locator("body").get_attribute("data-why") in ("different", "same", "undecided")
    assert summary.inner_text() == f"{HOSTILE_RUN} — {HOSTILE_WORLD}, seed 1 (1 figures)"
    assert page.locator("body img:not(#runs figure img)").count() == 0


def test_markup_put_into_the_page_runs_no_inline_handler_and_no_eval(admin_page, hostile_server):
    # Defence in depth: were a hostile string ever parsed as HTML, the policy still runs none of it.
    page = admin_page
    page.allowed_errors += ["Content Security Policy", "401"]  # chromium logs the refusal and the image's 401
    _open(page, hostile_server)
    page.evaluate("""() => {
        document.addEventListener('securitypolicyviolation', (e) => { window.__violated = e.violatedDirective; });
        document.body.insertAdjacentHTML('beforeend', '<img id=probe src=x onerror="window.__csp=1">');
        document.getElementById('probe').addEventListener('error', () => { window.__failed = 1; });
    }""")
    page.wait_for_function("() => window.__failed === 1 && window.__violated !== undefined")
    assert page.evaluate("typeof window.__csp") == "undefined"  # the image failed, its handler did not run
    assert page.evaluate("window.__violated").startswith("script-src")
    # eval from the page's own task (Playwright's evaluate itself is exempt from the page's policy).
    page.evaluate("() => setTimeout(() => { try { window.__eval = eval('1 + 1'); } "
                  "catch (e) { window.__eval = e.name; } })")
    page.wait_for_function("() => window.__eval !== undefined")
    assert page.evaluate("window.__eval") == "EvalError"


def test_api_docs_run_their_inline_script_and_cdn_files_under_their_own_policy(browser, hostile_server):
    # The CDN's files are served by the test (tests never reach the network); the browser still checks
    # every one against the page's policy before asking for it.
    context = browser.new_context()
    page = context.new_page()
    errors = []
    page.on("console", lambda m: m.type == "error" and errors.append(m.text))
    page.on("pageerror", lambda e: errors.append(f"uncaught: {e}"))
    stub = ("window.SwaggerUIBundle = (config) => { window.__swagger = config.url; return {}; };"
            "SwaggerUIBundle.presets = {apis: {}}; SwaggerUIBundle.SwaggerUIStandalonePreset = {};")

    def cdn(route):
        url = route.request.url
        if url.endswith(".js"):
            route.fulfill(body=stub, content_type="text/javascript")
        elif url.endswith(".css"):
            route.fulfill(body="#swagger-ui { min-height: 1px; }", content_type="text/css")
        else:  # the icon
            route.fulfill(status=204)

    page.route("https://**/*", cdn)
    try:
        page.goto(f"{hostile_server.url}/docs")
        page.wait_for_function("() => window.__swagger !== undefined")
        assert page.evaluate("window.__swagger") == "/openapi.json"
        assert page.evaluate("getComputedStyle(document.getElementById('swagger-ui')).minHeight") == "1px"
        assert errors == []
    finally:
        context.close()


# --- The headers on every kind of response ---------------------------------------------------------

def big_tableau() -> dict:
    """Over 256 KiB stored (views and 512-value images): read back in chunks, a streamed response."""
    doc = examples.notched_rectangle(circuits=8).to_dict()
    for i, step in enumerate(doc["steps"]):
        step["image"] = [round(1 + (i * 512 + j) * 1e-7, 12) for j in range(512)]
    return doc


@pytest.fixture(scope="module")
def responses(hostile_server) -> dict:
    """Every kind of response the service gives, each fetched once."""
    admin = bearer(hostile_server.tokens["admin"])
    with hostile_server.client() as c:
        r = c.post("/tableaux", json=big_tableau(), headers=admin)
        assert r.status_code == 201, r.text
        big = r.json()["id"]
        layout = c.get(f"/tableaux/{hostile_server.hostile_id}/layout", headers=admin)
        assert layout.status_code == 200
        with c.stream("GET", f"/tableaux/{big}", headers=admin) as streamed:
            streamed.read()
        return {
            "health": (c.get("/health"), 200),
            "problem 404": (c.get("/tableaux/999999", headers=admin), 404),
            "guard 401": (c.get("/tableaux"), 401),
            "guard 400 (host)": (c.get("/health", headers={"Host": "evil.example"}), 400),
            "viewer file": (c.get("/viewer/app.js"), 200),
            "viewer page": (c.get("/"), 200),
            "layout 304": (c.get(f"/tableaux/{hostile_server.hostile_id}/layout",
                                 headers={**admin, "If-None-Match": layout.headers["etag"]}), 304),
            "streamed tableau": (streamed, 200),
            "docs": (c.get("/docs"), 200),
        }


@pytest.mark.parametrize("kind", ["health", "problem 404", "guard 401", "guard 400 (host)", "viewer file",
                                  "viewer page", "layout 304", "streamed tableau", "docs"])
def test_every_kind_of_response_carries_the_security_headers(responses, kind):
    r, status = responses[kind]
    assert r.status_code == status
    assert all(name in r.headers for name in POLICY_HEADERS), dict(r.headers)
    assert r.headers["x-content-type-options"] == "nosniff"
    assert r.headers["x-frame-options"] == "DENY"
    assert r.headers["referrer-policy"] == "no-referrer"
    policy = directives(r.headers["content-security-policy"])
    assert policy["frame-ancestors"] == ["'none'"] and policy["default-src"] == ["'none'"]
    assert "'unsafe-inline'" not in policy["script-src"] and "'unsafe-eval'" not in policy["script-src"]
    if kind == "streamed tableau":  # really streamed: chunked, no length known beforehand
        assert r.headers.get("transfer-encoding") == "chunked" and "content-length" not in r.headers
    if kind != "docs":
        assert policy["script-src"] == ["'self'"]


def test_the_docs_policy_allows_its_cdn_script_and_its_inline_script_by_hash_only(responses):
    docs, _ = responses["docs"]
    inline = re.findall(r"<script>(.*?)</script>", docs.text, re.DOTALL)
    assert len(inline) == 1
    digest = base64.b64encode(hashlib.sha256(inline[0].encode()).digest()).decode()
    cdn = re.findall(r"<script src=\"([^\"]+)\"", docs.text)
    assert cdn and all(url.startswith("https://cdn.jsdelivr.net/") for url in cdn)
    assert directives(docs.headers["content-security-policy"])["script-src"] == [f"'sha256-{digest}'", *cdn]
    api = directives(responses["health"][0].headers["content-security-policy"])
    assert api["script-src"] == ["'self'"] and f"'sha256-{digest}'" not in str(api)


def directives(policy: str) -> dict[str, list[str]]:
    return {d.split()[0]: d.split()[1:] for d in (part.strip() for part in policy.split(";")) if d}
