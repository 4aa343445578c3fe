"""Hard solves end cleanly and never stall the server; over the bound of solves, a 503 with Retry-After.

This module's server has one solver, one waiting place and a 3 s time limit (kill at 4 s): the time limit
is its subject. A tableau of one view repeated 5,000 times (all travels) is a hard solve: it ends by the
time limit, not by a map.
"""

import threading
import time

import pytest

from bootmap.tableau import FORMAT
from service_helpers import SESSION_SETTINGS, serving

ONE_VIEW = {"format": FORMAT, "steps": [{"view": "V", "action": {"type": "travel", "distance_m": 1.0}}] * 4999
            + [{"view": "V"}]}


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    yield from serving(tmp_path_factory.mktemp("limits_server"), **SESSION_SETTINGS)


@pytest.fixture(scope="module")
def client(server):
    with server.client() as c:
        yield c


def test_hard_solves_time_out_cleanly_without_stalling_the_server(client, server, paper_doc, paper_id):
    outcomes: list = []

    def post_hard():
        with server.client() as c:
            t0 = time.monotonic()
            r = c.post("/tableaux", json=ONE_VIEW)
            outcomes.append((r, time.monotonic() - t0))

    total = client.get("/tableaux").json()["total"]
    posters = [threading.Thread(target=post_hard) for _ in range(2)]
    for p in posters:
        p.start()
    _wait_for(lambda: _solves(client) == (1, 1))

    # One solving, one waiting: the line is full. A third solve is refused without waiting for a place in
    # the line (the line is still full after the answer), saying when to retry.
    busy = client.post("/tableaux", json=paper_doc)
    assert busy.status_code == 503 and _solves(client) != (0, 0)
    assert busy.headers["retry-after"] == "3" and busy.headers["content-type"] == "application/problem+json"
    assert busy.json()["type"].endswith("/solvers-busy")

    # Meanwhile every other request is answered while a solve runs (solves run off the event loop): a read
    # answered with a solve still running after it. Whether it is fast is the machine's business, not this
    # test's (the solves' own limit is what bounds how long this loop runs).
    answered_during_a_solve = 0
    while any(p.is_alive() for p in posters):
        assert client.get(f"/tableaux/{paper_id}/map").status_code == 200
        health = client.get("/health")
        assert health.status_code == 200
        answered_during_a_solve += health.json()["solves_running"] == 1
        time.sleep(0.1)
    assert answered_during_a_solve >= 1

    for r, seconds in outcomes:
        assert r.status_code == 422 and r.json()["type"].endswith("/solve-timeout"), r.text
        assert "time limit" in r.json()["detail"] and seconds < 2 * (3 + 1) + 3  # its own solve and the one before
    assert client.get("/tableaux").json()["total"] == total
    assert client.post("/tableaux", json=paper_doc).status_code == 201  # the solver is back


def _solves(client) -> tuple[int, int]:
    h = client.get("/health").json()
    return h["solves_running"], h["solves_waiting"]


def _wait_for(condition, timeout: float = 10) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, "timed out waiting"
        time.sleep(0.02)
