"""The store is SQLAlchemy: a PostgreSQL URL works as well as the default SQLite file.

A throwaway PostgreSQL cluster (initdb + postgres from this machine's packages, on a private Unix
socket) serves one server process; a restart keeps the tableau and its map. Skipped, saying why, on a
machine without PostgreSQL's server binaries.
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
from service_helpers import Server

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
