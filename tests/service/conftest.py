"""Fixtures: the session's server (a real uvicorn process), a client, the paper's tableau stored once.

The session server has small limits so that hostile inputs hit them quickly: 3 s solves, one solver and
one waiting solve, 4 MiB bodies, 10,000 steps. Its axioms are a private copy the axiom tests may edit.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from service_helpers import CHROMIUM, PATIENT_SETTINGS, REPO, serving

from bootmap import examples


@pytest.fixture(scope="session")
def server_axioms(tmp_path_factory) -> Path:
    dest = tmp_path_factory.mktemp("axioms") / "asp"
    shutil.copytree(REPO / "asp", dest)
    return dest


@pytest.fixture(scope="session")
def server(tmp_path_factory, server_axioms):
    yield from serving(tmp_path_factory.mktemp("server"), axioms=server_axioms, **PATIENT_SETTINGS)


@pytest.fixture(scope="session")
def client(server):
    with server.client() as c:
        yield c


@pytest.fixture(scope="session")
def paper_doc() -> dict:
    return examples.notched_rectangle(circuits=50).to_dict()


@pytest.fixture(scope="module")
def paper_id(client, paper_doc) -> int:
    """The paper's tableau, stored once for each module (on the server its ``client`` talks to)."""
    r = client.post("/tableaux", json=paper_doc)
    assert r.status_code == 201, r.text
    return r.json()["id"]


@pytest.fixture(scope="module")
def browser():
    """Headless chromium, one per test module (as root it needs --no-sandbox)."""
    sync_api = pytest.importorskip("playwright.sync_api", reason="playwright not installed: pip install -e '.[dev]'")
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"], headless=True)
        yield b
        b.close()
