"""Who may do what, against a real uvicorn on 127.0.0.1: tokens, owners, admins, hosts, other web sites.

``tokens_server`` requires tokens (as any server not on loopback does); the session's server runs in the
default loopback mode without tokens, where the Host and cross-site checks still hold.
"""

import os
import socket
import subprocess
import sys
import time
from urllib.parse import urlsplit

import pytest
from service_helpers import SESSION_SETTINGS, Server, bearer, make_token

from bootmap import examples
from bootmap.service.settings import Settings
from bootmap.tableau import FORMAT

PROBLEM = "application/problem+json"
SMALL = examples.notched_rectangle(circuits=2).to_dict()
MORE = {"action": {"type": "turn", "angle_deg": -90}, "steps": [{"view": "V1"}]}


@pytest.fixture(scope="module")
def tokens_server(tmp_path_factory, server_axioms):
    s = Server(tmp_path_factory.mktemp("tokens_server"), axioms=server_axioms, require_tokens=True,
               cors_origins="https://app.example", **SESSION_SETTINGS)
    tokens = {"admin": make_token("root", admin=True, data_dir=s.data_dir),
              "alice": make_token("alice", data_dir=s.data_dir), "bob": make_token("bob", data_dir=s.data_dir)}
    s.start()
    s.tokens = tokens
    yield s
    s.stop()


@pytest.fixture(scope="module")
def alices(tokens_server):
    """A tableau of alice's."""
    with tokens_server.client() as c:
        r = c.post("/tableaux", json=SMALL, headers=bearer(tokens_server.tokens["alice"]))
        assert r.status_code == 201, r.text
        return r.json()["id"]


def problem(r, status: int) -> dict:
    assert r.status_code == status, r.text
    assert r.headers["content-type"] == PROBLEM
    return r.json()


# --- Tokens -----------------------------------------------------------------------------------------

def test_token_create_prints_the_token_last_and_stores_only_its_hash(tmp_path):
    token = make_token("carol", data_dir=tmp_path)
    assert token.startswith("bm_") and len(token) > 40
    assert token.encode() not in (tmp_path / "bootmap.sqlite3").read_bytes()
    env = {k: v for k, v in os.environ.items() if not k.startswith("BOOTMAP_")}
    again = subprocess.run([sys.executable, "-m", "bootmap.cli", "token", "create", "carol", "--data-dir", str(tmp_path)],
                           capture_output=True, text=True, env=env)
    assert again.returncode == 2 and "'carol' exists already" in again.stderr
    bad = subprocess.run([sys.executable, "-m", "bootmap.cli", "token", "create", "a b", "--data-dir", str(tmp_path)],
                         capture_output=True, text=True, env=env)
    assert bad.returncode == 2 and "bad name" in bad.stderr


def _token_command(*args, data_dir) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if not k.startswith("BOOTMAP_")}
    return subprocess.run([sys.executable, "-m", "bootmap.cli", "token", *args, "--data-dir", str(data_dir)],
                          capture_output=True, text=True, env=env, timeout=60)


@pytest.mark.slow
def test_tokens_are_listed_without_their_secrets_and_a_revoked_one_is_refused_at_once(tmp_path, server_axioms):
    s = Server(tmp_path / "revoking", axioms=server_axioms, require_tokens=True, **SESSION_SETTINGS)
    dave, admin = make_token("dave", data_dir=s.data_dir), make_token("root", admin=True, data_dir=s.data_dir)
    s.start()
    try:
        with s.client() as c:
            r = c.post("/tableaux", json=SMALL, headers=bearer(dave))
            assert r.status_code == 201, r.text
            tableau = r.json()["id"]
            listed = _token_command("list", data_dir=s.data_dir)
            assert listed.returncode == 0, listed.stderr
            rows = {line.split()[0]: line.split() for line in listed.stdout.splitlines()[1:]}
            assert rows["dave"][1] == "user" and "1 tableau" in " ".join(rows["dave"])
            assert rows["root"][1] == "admin" and dave not in listed.stdout and admin not in listed.stdout
            revoked = _token_command("revoke", "dave", data_dir=s.data_dir)
            assert revoked.returncode == 0, revoked.stderr
            problem(c.get(f"/tableaux/{tableau}", headers=bearer(dave)), 401)
            assert c.get(f"/tableaux/{tableau}", headers=bearer(admin)).status_code == 200
            again = _token_command("revoke", "dave", data_dir=s.data_dir)
            assert again.returncode == 2 and "no token is named 'dave'" in again.stderr
            assert "dave" not in _token_command("list", data_dir=s.data_dir).stdout
    finally:
        s.stop()


def test_without_a_token_every_write_and_read_of_tableaux_is_401(tokens_server, alices):
    with tokens_server.client() as c:
        for method, path, body in [("POST", "/tableaux", SMALL), ("POST", f"/tableaux/{alices}/steps", MORE),
                                   ("DELETE", f"/tableaux/{alices}", None), ("POST", "/axioms/reload", None),
                                   ("GET", "/tableaux", None), ("GET", f"/tableaux/{alices}/map", None)]:
            r = c.request(method, path, json=body)
            assert problem(r, 401)["type"].endswith("/unauthorized") and r.headers["www-authenticate"] == "Bearer"
        wrong = c.get("/tableaux", headers=bearer("bm_" + "x" * 43))
        assert "not known" in problem(wrong, 401)["detail"]
        assert problem(c.get("/tableaux", headers={"Authorization": "Basic eDp5"}), 401)["detail"].startswith(
            "the Authorization header must be")
        assert c.get("/health").status_code == 200 and c.get("/openapi.json").status_code == 200
        tokens_required = c.get("/tableaux", headers=bearer(tokens_server.tokens["alice"]))
        assert tokens_required.status_code == 200


def test_another_owners_private_tableau_is_404_as_if_it_did_not_exist_and_nothing_changes(tokens_server, alices):
    alice, bob = bearer(tokens_server.tokens["alice"]), bearer(tokens_server.tokens["bob"])
    with tokens_server.client() as c:
        before = c.get(f"/tableaux/{alices}", headers=alice).json()
        for method, path, body in [("POST", f"/tableaux/{alices}/steps", MORE), ("DELETE", f"/tableaux/{alices}", None),
                                   ("GET", f"/tableaux/{alices}", None), ("GET", f"/tableaux/{alices}/map", None),
                                   ("GET", f"/tableaux/{alices}/map/text", None), ("GET", f"/tableaux/{alices}/maps", None),
                                   ("GET", f"/tableaux/{alices}/map/graph", None),
                                   ("GET", f"/tableaux/{alices}/why?a=0&b=4", None),
                                   ("PUT", f"/tableaux/{alices}/sharing", {"public": True})]:
            r = c.request(method, path, json=body, headers=bob)
            missing = c.request(method, path.replace(f"/{alices}", "/999999"), json=body, headers=bob)
            # The same answer as for an id that does not exist: nothing tells bob that alice's tableau does.
            assert problem(r, 404)["detail"] == problem(missing, 404)["detail"].replace("999999", str(alices))
        assert c.get(f"/tableaux/{alices}", headers=alice).json() == before
        assert alices not in [t["id"] for t in c.get("/tableaux", headers=bob).json()["items"]]
        assert alices in [t["id"] for t in c.get("/tableaux", headers=alice).json()["items"]]


def test_a_public_tableau_is_read_by_anyone_and_changed_by_its_owner_only(tokens_server):
    alice, bob = bearer(tokens_server.tokens["alice"]), bearer(tokens_server.tokens["bob"])
    with tokens_server.client() as c:
        tid = c.post("/tableaux", json=SMALL, headers=alice).json()["id"]
        assert c.put(f"/tableaux/{tid}/sharing", json={"public": True}, headers=alice).json() == {"public": True}
        assert c.get(f"/tableaux/{tid}/map", headers=bob).json()["summary"]["dstates"] == 8
        assert c.get(f"/tableaux/{tid}", headers=bob).json()["public"] is True
        problem(c.post(f"/tableaux/{tid}/steps", json=MORE, headers=bob), 403)
        assert c.post(f"/tableaux/{tid}/steps", json=MORE, headers=alice).status_code == 200


def test_owners_and_admins_delete(tokens_server):
    alice, admin = bearer(tokens_server.tokens["alice"]), bearer(tokens_server.tokens["admin"])
    with tokens_server.client() as c:
        first, second = (c.post("/tableaux", json=SMALL, headers=alice).json()["id"] for _ in range(2))
        assert c.delete(f"/tableaux/{first}", headers=alice).status_code == 204
        assert c.delete(f"/tableaux/{second}", headers=admin).status_code == 204
        for tid in (first, second):
            problem(c.get(f"/tableaux/{tid}/map", headers=alice), 404)
            problem(c.delete(f"/tableaux/{tid}", headers=alice), 404)


def test_only_an_admin_reloads_axioms_and_makes_tokens(tokens_server):
    with tokens_server.client() as c:
        r = c.post("/axioms/reload", headers=bearer(tokens_server.tokens["bob"]))
        assert "not one" in problem(r, 403)["detail"]
        reloaded = c.post("/axioms/reload", headers=bearer(tokens_server.tokens["admin"]))
        assert reloaded.status_code == 200 and reloaded.json()["theory"] == c.get("/axioms").json()["theory"]
        made = c.post("/tokens", json={"name": "dave"}, headers=bearer(tokens_server.tokens["admin"]))
        assert made.status_code == 201 and made.json()["admin"] is False
        assert c.get("/tableaux", headers=bearer(made.json()["token"])).status_code == 200  # honoured at once
        problem(c.post("/tokens", json={"name": "eve", "admin": True}, headers=bearer(made.json()["token"])), 403)
        problem(c.post("/tokens", json={"name": "dave"}, headers=bearer(tokens_server.tokens["admin"])), 409)
        # Revoked: refused at once; dave's tableau stays, for admins only.
        tid = c.post("/tableaux", json=SMALL, headers=bearer(made.json()["token"])).json()["id"]
        problem(c.delete("/tokens/dave", headers=bearer(made.json()["token"])), 403)
        assert c.delete("/tokens/dave", headers=bearer(tokens_server.tokens["admin"])).status_code == 204
        problem(c.get("/tableaux", headers=bearer(made.json()["token"])), 401)
        problem(c.delete("/tokens/dave", headers=bearer(tokens_server.tokens["admin"])), 404)
        assert c.get(f"/tableaux/{tid}", headers=bearer(tokens_server.tokens["admin"])).status_code == 200
        problem(c.get(f"/tableaux/{tid}", headers=bearer(tokens_server.tokens["alice"])), 404)


# --- Hosts and other web sites (the default loopback server, no tokens) ------------------------------

@pytest.mark.parametrize("host", ["evil.example", "evil.example:8000", "127.0.0.1.evil.example", "",
                                  "127.0.0.1:80@evil.example", "localhost:8000/x"])
def test_a_host_header_that_is_not_allowed_gets_400(client, host):
    for method, path in [("GET", "/health"), ("GET", "/tableaux/"), ("POST", "/axioms/reload")]:
        r = client.request(method, path, headers={"Host": host})
        assert problem(r, 400)["type"].endswith("/invalid-host") and "location" not in r.headers


def test_loopback_names_are_allowed_hosts(client):
    for host in ["127.0.0.1", "localhost:8000", "[::1]:8000"]:
        assert client.get("/health", headers={"Host": host}).status_code == 200


def test_a_cross_site_post_to_reload_fails(client, server):
    before = client.get("/axioms").json()["loaded"]
    for headers in [{"Origin": "http://evil.example"}, {"Origin": "null"}, {"Sec-Fetch-Site": "cross-site"},
                    {"Origin": "http://localhost:9999"}]:
        r = client.post("/axioms/reload", headers=headers)
        assert "another web site" in problem(r, 403)["detail"]
        problem(client.post("/tableaux", json=SMALL, headers=headers), 403)
    assert client.get("/axioms").json()["loaded"] == before  # nothing was reloaded
    same_site = client.post("/axioms/reload", headers={"Origin": server.url, "Sec-Fetch-Site": "same-origin"})
    assert same_site.status_code == 200


def test_cors_is_off_unless_configured(client):
    r = client.options("/tableaux", headers={"Origin": "http://evil.example", "Access-Control-Request-Method": "POST"})
    assert "access-control-allow-origin" not in r.headers


def test_a_configured_origin_may_call_from_a_browser(tokens_server):
    app = {"Origin": "https://app.example"}
    with tokens_server.client() as c:
        pre = c.options("/tableaux", headers={**app, "Access-Control-Request-Method": "POST",
                                              "Access-Control-Request-Headers": "authorization, content-type"})
        assert pre.status_code == 200 and pre.headers["access-control-allow-origin"] == "https://app.example"
        r = c.post("/tableaux", json=SMALL, headers={**app, **bearer(tokens_server.tokens["alice"])})
        assert r.status_code == 201 and r.headers["access-control-allow-origin"] == "https://app.example"
        other = c.post("/tableaux", json=SMALL, headers={"Origin": "https://elsewhere.example",
                                                         **bearer(tokens_server.tokens["alice"])})
        problem(other, 403)


def test_any_address_but_loopback_requires_tokens_and_named_hosts(tmp_path):
    assert not Settings(host="127.0.0.1").tokens_required and Settings(host="127.0.0.1", require_tokens=True).tokens_required
    assert Settings(host="0.0.0.0").tokens_required and Settings(host="192.168.1.5").tokens_required
    assert Settings(host="192.168.1.5").hosts[-1] == "192.168.1.5"
    env = {k: v for k, v in os.environ.items() if not k.startswith("BOOTMAP_")}
    out = subprocess.run([sys.executable, "-m", "bootmap.cli", "serve", "--host", "0.0.0.0", "--data-dir", str(tmp_path)],
                         capture_output=True, text=True, env=env, timeout=60)
    assert out.returncode == 2 and "BOOTMAP_ALLOWED_HOSTS" in out.stderr


def test_without_tokens_on_loopback_the_local_user_does_everything(client):
    created = client.post("/tableaux", json={"format": FORMAT, "steps": [{"view": "a"}]})
    assert created.status_code == 201
    assert client.delete(f"/tableaux/{created.json()['id']}").status_code == 204


def test_a_body_is_never_read_for_a_token_the_server_does_not_know(tokens_server):
    """Eight connections announce 4 MiB bodies (all the body memory the server lends at once), send one
    byte and trickle: with a made-up token each is answered 401 at once, before its body, so it holds
    nothing, and an honest post goes through meanwhile (before, the bodies were read first: every POST
    waited for the trickles' 20 s body time-out)."""
    url = urlsplit(tokens_server.url)
    trickles = []
    for path in ["/tokens", "/tableaux/1/sharing", "/tableaux/1/recognise", "/tableaux"] * 2:
        sock = socket.create_connection((url.hostname, url.port), timeout=5)
        sock.sendall(f"POST {path} HTTP/1.1\r\nHost: 127.0.0.1\r\nAuthorization: Bearer bm_{'x' * 43}\r\n"
                     f"Content-Type: application/json\r\nContent-Length: {4 * 2**20}\r\n\r\n{{".encode())
        trickles.append(sock)
    for sock in trickles:
        assert sock.recv(65536).startswith(b"HTTP/1.1 401"), "answered before the body"
    t0 = time.monotonic()
    with tokens_server.client() as c:
        assert c.post("/tableaux", json=SMALL, headers=bearer(tokens_server.tokens["alice"])).status_code == 201
    assert time.monotonic() - t0 < 10
    for sock in trickles:
        sock.close()


@pytest.mark.parametrize("headers", [{"Sec-Fetch-Site": "cross-site"}, {"Origin": "http://evil.example"}])
def test_a_page_elsewhere_cannot_start_a_solve_with_a_get(client, paper_id, headers):
    for path in [f"/tableaux/{paper_id}/why?a=0&b=4", f"/tableaux/{paper_id}/rehearsal"]:
        assert "start a solve" in problem(client.get(path, headers=headers), 403)["detail"]
    assert client.get(f"/tableaux/{paper_id}/map", headers=headers).status_code == 200  # reading is fine


def test_an_https_origin_is_not_this_http_server(client, server):
    host = urlsplit(server.url).netloc
    problem(client.post("/axioms/reload", headers={"Origin": f"https://{host}"}), 403)
    assert client.post("/axioms/reload", headers={"Origin": f"http://{host}"}).status_code == 200


# --- Every route, classified: who may call it --------------------------------------------------------

OPEN, TOKEN, READ, WRITE, ADMIN = "open", "needs a token", "owner, admin or public", "owner or admin", "admin only"
#: (method, path) -> (class, how to call it: the path filled in, and the request's other arguments). A
#: request is valid, so that it reaches the check (a body or query FastAPI refuses is refused first).
ROUTES = {
    ("GET", "/openapi.json"): (OPEN, {}), ("GET", "/docs"): (OPEN, {}), ("GET", "/redoc"): (OPEN, {}),
    ("GET", "/docs/oauth2-redirect"): (OPEN, {}), ("GET", "/health"): (OPEN, {}), ("GET", "/"): (OPEN, {}),
    ("GET", "/schemas/tableau-1.schema.json"): (OPEN, {}), ("GET", "/axioms"): (OPEN, {}),
    ("GET", "/viewer/{name}"): (OPEN, {"path": "/viewer/app.js"}),
    ("POST", "/tableaux"): (TOKEN, {"json": {}}),  # refused as invalid (422) once the token is accepted
    ("GET", "/tableaux"): (TOKEN, {}), ("GET", "/runs"): (TOKEN, {}),
    ("GET", "/runs/figure"): (TOKEN, {"params": {"run": "none", "name": "none.png"}}),
    ("GET", "/tableaux/{tableau_id}"): (READ, {}), ("GET", "/tableaux/{tableau_id}/map"): (READ, {}),
    ("GET", "/tableaux/{tableau_id}/map/text"): (READ, {}), ("GET", "/tableaux/{tableau_id}/maps"): (READ, {}),
    ("GET", "/tableaux/{tableau_id}/map/graph"): (READ, {"params": {"format": "dot"}}),
    ("GET", "/tableaux/{tableau_id}/layout"): (READ, {}),
    ("GET", "/tableaux/{tableau_id}/why"): (READ, {"params": {"a": "S0", "b": "S4"}}),
    ("GET", "/tableaux/{tableau_id}/rehearsal"): (READ, {"params": {"max_length": 2}}),
    ("POST", "/tableaux/{tableau_id}/recognise"): (READ, {"json": {"image": [0.0]}}),
    ("DELETE", "/tableaux/{tableau_id}"): (WRITE, {}),
    ("PUT", "/tableaux/{tableau_id}/sharing"): (WRITE, {"json": {"public": False}}),
    ("POST", "/tableaux/{tableau_id}/steps"): (WRITE, {"json": MORE}),
    # a person's assertions are their owner's, to read as to change
    ("GET", "/tableaux/{tableau_id}/assertions"): (WRITE, {}),
    ("POST", "/tableaux/{tableau_id}/assertions"): (WRITE, {"json": {"apart": [0, 1]}}),
    ("DELETE", "/tableaux/{tableau_id}/assertions/{assertion_id}"): (
        WRITE, {"path": "/tableaux/{tableau_id}/assertions/1"}),
    ("POST", "/axioms/reload"): (ADMIN, {}), ("POST", "/tokens"): (ADMIN, {"json": {"name": "mallory"}}),
    ("DELETE", "/tokens/{name}"): (ADMIN, {"path": "/tokens/bob"}),
}


def app_routes() -> set[tuple[str, str]]:
    from bootmap.service.app import create_app

    def flat(routes):
        for r in routes:
            if hasattr(r, "original_router"):  # an included router
                yield from flat(r.original_router.routes)
            else:
                yield r
    return {(m, r.path) for r in flat(create_app(Settings()).routes) for m in r.methods - {"HEAD"}}


def call(c, method: str, path: str, how: dict, tableau_id: int | None = None, token: str | None = None):
    how = dict(how)
    url = how.pop("path", path).replace("{tableau_id}", str(tableau_id))
    return c.request(method, url, headers=bearer(token) if token else {}, **how)


@pytest.fixture(scope="module")
def alices_public(tokens_server):
    with tokens_server.client() as c:
        r = c.post("/tableaux", params={"public": "true"}, json=SMALL, headers=bearer(tokens_server.tokens["alice"]))
        assert r.status_code == 201, r.text
        return r.json()["id"]


def test_every_route_of_the_service_is_classified():
    assert app_routes() == set(ROUTES), "a route without a class (or a class for no route): classify it in ROUTES"


def test_without_a_token_only_the_open_routes_answer(tokens_server, alices):
    with tokens_server.client() as c:
        for (method, path), (kind, how) in ROUTES.items():
            r = call(c, method, path, how, alices)
            if kind == OPEN:
                assert r.status_code == 200, (method, path, r.status_code)
            else:
                assert problem(r, 401)["status"] == 401, (method, path)


def test_another_tokens_private_tableau_is_missing_on_every_tableau_route(tokens_server, alices):
    bob = tokens_server.tokens["bob"]
    with tokens_server.client() as c:
        for (method, path), (kind, how) in ROUTES.items():
            if kind in (READ, WRITE):
                assert problem(call(c, method, path, how, alices, bob), 404)["status"] == 404, (method, path)
        assert c.get(f"/tableaux/{alices}", headers=bearer(tokens_server.tokens["alice"])).status_code == 200


def test_a_public_tableau_is_readable_by_any_token_and_writable_only_by_its_owner(tokens_server, alices_public):
    bob = tokens_server.tokens["bob"]
    with tokens_server.client() as c:
        for (method, path), (kind, how) in ROUTES.items():
            r = call(c, method, path, how, alices_public, bob)
            if kind == READ:
                assert r.status_code not in (401, 403, 404), (method, path, r.text)
            elif kind == WRITE:
                assert problem(r, 403)["status"] == 403, (method, path)
        assert c.get(f"/tableaux/{alices_public}", headers=bearer(bob)).json()["revision"] == 1


def test_admin_routes_refuse_a_user_token_and_token_routes_accept_one(tokens_server):
    alice = tokens_server.tokens["alice"]
    with tokens_server.client() as c:
        for (method, path), (kind, how) in ROUTES.items():
            r = call(c, method, path, how, token=alice)
            if kind == ADMIN:
                assert problem(r, 403)["status"] == 403, (method, path)
            elif kind == TOKEN:
                assert r.status_code not in (401, 403), (method, path, r.text)
