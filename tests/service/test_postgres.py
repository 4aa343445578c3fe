"""The store is SQLAlchemy: a PostgreSQL URL works as well as the default SQLite file.

A throwaway PostgreSQL cluster (initdb + postgres from this machine's packages, on a private Unix
socket) serves one server process, where a restart keeps the tableau and its map; then two server
processes at once, which share tokens, ownership, quotas and appends through it. Skipped, saying why, on
a machine without PostgreSQL's server binaries.
"""

from __future__ import annotations

import os
import pwd
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import pytest
import threading

from service_helpers import Server, bearer, make_token
from test_limits import ONE_VIEW, _wait_for

from bootmap import examples

pytest.importorskip("psycopg", reason="the PostgreSQL driver (psycopg) is not installed")
INITDB = shutil.which("initdb") or next(iter(sorted(Path("/usr/lib/postgresql").glob("*/bin/initdb"))), None)
pytestmark = pytest.mark.skipif(INITDB is None, reason="PostgreSQL's server binaries (initdb) are not installed")


def _as_owner(user: str | None):
    """PostgreSQL refuses to run as root: run its programs as its own user then."""
    if user is None:
        return {}
    entry = pwd.getpwnam(user)
    return {"user": entry.pw_uid, "group": entry.pw_gid}


@pytest.fixture()
def postgres_url():
    bin_dir = Path(INITDB).resolve().parent
    user = "postgres" if os.geteuid() == 0 else None
    # Not under pytest's tmp_path: PostgreSQL's own user must be able to reach it.
    root = Path(tempfile.mkdtemp(prefix="bootmap-pg-"))
    if user:
        shutil.chown(root, user)
    run = _as_owner(user)
    data, socket = root / "data", root
    subprocess.run([bin_dir / "initdb", "-D", data, "-U", "bootmap", "--auth=trust", "-E", "UTF8"],
                   check=True, capture_output=True, **run)
    server = subprocess.Popen([bin_dir / "postgres", "-D", data, "-k", socket, "-c", "listen_addresses=",
                               "-p", "5499"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, **run)
    try:
        deadline = time.monotonic() + 30
        while not (socket / ".s.PGSQL.5499").exists():
            assert time.monotonic() < deadline and server.poll() is None, "PostgreSQL did not start"
            time.sleep(0.1)
        subprocess.run([bin_dir / "createdb", "-h", socket, "-p", "5499", "-U", "bootmap", "bootmap"],
                       check=True, capture_output=True, **run)
        yield f"postgresql+psycopg://bootmap@/bootmap?host={socket}&port=5499"
    finally:
        server.terminate()
        server.wait(30)
        shutil.rmtree(root, ignore_errors=True)


def test_a_postgresql_store_keeps_tableaux_and_maps_across_a_restart(tmp_path, postgres_url):
    doc = examples.notched_rectangle(circuits=10).to_dict()
    (tmp_path / "service").mkdir()
    server = Server(tmp_path / "service", db=postgres_url).start()
    try:
        with server.client() as c:
            created = c.post("/tableaux", json=doc)
            assert created.status_code == 201, created.text
            tid = created.json()["id"]
            summary = created.json()["map"]["summary"]
            assert (summary["dstates"], summary["places"], summary["paths"]) == (8, 4, 4)
        server.stop()
        server.start()
        with server.client() as c:
            assert c.get(f"/tableaux/{tid}/map").json() == created.json()["map"]
            assert c.get(f"/tableaux/{tid}").json()["tableau"] == doc
    finally:
        server.stop()
    assert not (tmp_path / "service" / "data" / "bootmap.sqlite3").exists()  # it really used PostgreSQL


@pytest.mark.slow
def test_two_servers_on_one_postgresql_share_tokens_quotas_and_appends(tmp_path, postgres_url):
    """Scaled out: two `bootmap serve` processes on two loopback ports, one database, no state of their own."""
    settings = {"db": postgres_url, "require_tokens": True, "token_max_solves": 1, "solve_time_limit_s": 3,
                "solve_kill_grace_s": 1}
    root = make_token("root", admin=True, db=postgres_url)  # made with the CLI, straight into the database
    servers = []
    for name in ("a", "b"):
        (tmp_path / name).mkdir()
        servers.append(Server(tmp_path / name, **settings).start())
    a, b = (s.client() for s in servers)
    try:
        assert servers[0].url != servers[1].url
        # A token made through one server is honoured by the other.
        made = a.post("/tokens", json={"name": "alice"}, headers=bearer(root))
        assert made.status_code == 201, made.text
        alice = bearer(made.json()["token"])
        assert b.get("/tableaux", headers=alice).status_code == 200
        # Ownership holds across servers: alice's tableau, stored through a, is hers on b.
        mallory = bearer(make_token("mallory", db=postgres_url))
        tid = a.post("/tableaux", json=examples.notched_rectangle(circuits=50).to_dict(), headers=alice).json()["id"]
        assert b.get(f"/tableaux/{tid}/map", headers=alice).json()["summary"]["dstates"] == 8
        assert b.post(f"/tableaux/{tid}/steps", json=MORE, headers=mallory).status_code == 404

        # A quota is shared: alice's one solve place, taken by a hard solve on a, is taken on b too.
        hard = threading.Thread(target=lambda: a.post("/tableaux", json=ONE_VIEW, headers=alice))
        hard.start()
        _wait_for(lambda: a.get("/health").json()["solves_running"] == 1)
        over = b.post("/tableaux", json=examples.notched_rectangle(circuits=2).to_dict(), headers=alice)
        assert over.status_code == 429 and over.headers["retry-after"] and "TOKEN_MAX_SOLVES" in over.json()["detail"]
        hard.join()
        assert b.post("/tableaux", json=examples.notched_rectangle(circuits=2).to_dict(), headers=alice).status_code == 201

        # Two appends racing through different servers (alice's and an admin's, each within its one solve
        # place): one is stored, the other is told to retry (409). (If one finishes before the other
        # reads, both are stored, one after the other: never lost.)
        outcomes = []
        for _ in range(3):
            revision = a.get(f"/tableaux/{tid}", headers=alice).json()["revision"]
            statuses = _race([lambda: a.post(f"/tableaux/{tid}/steps", json=MORE, headers=alice),
                              lambda: b.post(f"/tableaux/{tid}/steps", json=MORE, headers=bearer(root))])
            now = b.get(f"/tableaux/{tid}", headers=alice).json()["revision"]
            assert (sorted(statuses), now) in [([200, 409], revision + 1), ([200, 200], revision + 2)], statuses
            outcomes.append(sorted(statuses))
            if sorted(statuses) == [200, 409]:
                break
        assert [200, 409] in outcomes
    finally:
        a.close()
        b.close()
        for s in servers:
            s.stop()


# One more circuit of the notched rectangle from its last view (V0): appended once or twice, one after the
# other, the map is the same 8 dstates (a partial circuit appended twice would contradict the first).
MORE = {"action": {"type": "turn", "angle_deg": -90},
        "steps": [{"view": "V1", "action": {"type": "travel", "distance_m": 4}},
                  {"view": "V2", "action": {"type": "turn", "angle_deg": -90}},
                  {"view": "V3", "action": {"type": "travel", "distance_m": 2}},
                  {"view": "V0"}]}


def _race(calls) -> list[int]:
    """Start the calls at the same moment, in threads; their status codes."""
    barrier, statuses = threading.Barrier(len(calls)), []

    def run(call):
        barrier.wait()
        statuses.append(call().status_code)

    threads = [threading.Thread(target=run, args=(c,)) for c in calls]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    return statuses
