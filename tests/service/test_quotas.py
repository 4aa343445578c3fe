"""Fair share without a database write per request (bootmap.service.quotas).

The request limit is a sliding window kept in memory: at most the limit in any 60 s, a burst across a
minute boundary included (with an injected clock, and once against a server); servers share their counts
through the database. Solve leases count while their server's heartbeat is fresh. And a token's reads
go on while another connection holds SQLite's write lock for longer than the busy timeout.
"""

import math
import sqlite3
import time
from datetime import datetime, timedelta, timezone

import pytest
from hypothesis import given
from hypothesis import strategies as st
from service_helpers import Server, bearer, make_token
from sqlalchemy import text
from test_fair_share import wait_for

from bootmap import examples
from bootmap.service.quotas import RequestWindow, solve_retry_after
from bootmap.service.store import HeldLease, QuotaExceeded, SolvePlacesTaken, Store

SMALL = examples.notched_rectangle(circuits=2).to_dict()
BUSY_S = 1.0  # SQLite's busy timeout where a test holds the write lock longer
A, B = "a" * 32, "b" * 32  # two servers' ids


class Clock:
    def __init__(self, now: float):
        self.now = now

    def __call__(self) -> float:
        return self.now


# --- The window, in memory ----------------------------------------------------------------------------

def test_a_burst_across_a_minute_boundary_gets_no_more_than_the_limit():
    clock = Clock(119.0)  # a second before a minute turns: a fixed window would start again at 120
    window = RequestWindow(5, clock=clock)
    for _ in range(5):
        window.count(1)
        clock.now += 0.1  # 119.0, 119.1, ... 119.4
    clock.now = 120.5
    with pytest.raises(QuotaExceeded, match="BOOTMAP_TOKEN_REQUESTS_PER_MINUTE") as refused:
        window.count(1)
    assert refused.value.retry_after_s == 59  # the request of 119.0 leaves the window at 179.0
    window.count(2)  # another token's count is its own
    clock.now = 179.0
    window.count(1)  # room for one: the oldest has left
    with pytest.raises(QuotaExceeded) as refused:
        window.count(1)
    assert refused.value.retry_after_s == 1  # the next leaves at 179.1


@given(st.integers(1, 6), st.lists(st.floats(0, 300), max_size=60))
def test_no_60_s_ever_holds_more_than_the_limit_and_only_a_full_window_refuses(limit, times):
    clock = Clock(0.0)
    window = RequestWindow(limit, clock=clock)
    admitted: list[float] = []
    for t in sorted(times):
        clock.now = t
        try:
            window.count(7)
        except QuotaExceeded as e:
            counted = [a for a in admitted if a > t - 60]
            assert len(counted) == limit  # refused only when full
            assert e.retry_after_s == max(1, math.ceil(counted[0] + 60 - t))  # when the oldest leaves
        else:
            admitted.append(t)
    for start in admitted:
        assert sum(start <= a < start + 60 for a in admitted) <= limit


def test_windows_of_two_servers_share_a_tokens_limit():
    clock = Clock(1000.2)
    a, b = RequestWindow(5, clock=clock), RequestWindow(5, clock=clock)
    for _ in range(3):
        a.count(1)
    b.heard({1: [a.mine()[1]]})  # what a's beat writes, b's reads: three requests in second 1000
    b.count(1)
    b.count(1)
    with pytest.raises(QuotaExceeded) as refused:
        b.count(1)
    assert refused.value.retry_after_s == 60  # b's own two, at 1000.2, are the first to leave
    clock.now = 1060.5
    b.count(1)
    b.count(1)
    with pytest.raises(QuotaExceeded) as refused:
        b.count(1)
    assert refused.value.retry_after_s == 1  # a's three count until 1061, when the last that could be leaves
    clock.now = 1061.0
    b.count(1)


def test_the_retry_after_of_solve_places_names_when_one_may_free():
    now = datetime(2030, 1, 1, tzinfo=timezone.utc)
    running_here = HeldLease(now - timedelta(seconds=1), None)
    on_a_live_server = HeldLease(now - timedelta(seconds=2), now - timedelta(seconds=0.5))
    on_a_silent_server = HeldLease(now - timedelta(seconds=1), now - timedelta(seconds=2))
    assert solve_retry_after([running_here], solve_s=34, now=now) == 33  # when its solve must have ended
    assert solve_retry_after([running_here, on_a_live_server], solve_s=34, now=now) == 32
    assert solve_retry_after([running_here, on_a_silent_server], solve_s=34, now=now) == 1  # stale in 1 s
    assert solve_retry_after([HeldLease(now - timedelta(seconds=60), None)], solve_s=34, now=now) == 1


# --- Heartbeats, counts and leases in the store ---------------------------------------------------------

def two_servers(tmp_path) -> tuple[Store, Store, int]:
    url = f"sqlite:///{tmp_path / 'db.sqlite3'}"
    a, b = Store(url), Store(url)  # two engines on one file, as two server processes have
    token = a.add_token("alice", "d" * 64, admin=False).id
    a.heartbeat(A, "server a", {}, 3, 60)
    b.heartbeat(B, "server b", {}, 3, 60)
    return a, b, token


def test_a_solve_lease_counts_while_its_servers_heartbeat_is_fresh(tmp_path):
    a, b, token = two_servers(tmp_path)
    a.lease_solve(token, 2, A, stale_s=3)
    a.lease_solve(token, 2, A, stale_s=3)
    with pytest.raises(SolvePlacesTaken) as taken:
        b.lease_solve(token, 2, B, stale_s=3)
    assert [h.heartbeat_at is not None for h in taken.value.held] == [True, True]  # held on another server
    with pytest.raises(SolvePlacesTaken) as taken:
        a.lease_solve(token, 2, A, stale_s=0)  # a server's own leases count whatever its heartbeat
    assert [h.heartbeat_at for h in taken.value.held] == [None, None]

    time.sleep(0.05)
    lease = b.lease_solve(token, 2, B, stale_s=0.01)  # a not heard from for longer: its leases are not counted
    b.release_solve(lease)
    a.remove_server(A)  # a clean stop: its leases go
    b.lease_solve(token, 2, B, stale_s=3)
    b.lease_solve(token, 2, B, stale_s=3)
    with pytest.raises(SolvePlacesTaken):
        b.lease_solve(token, 2, B, stale_s=3)


def test_heartbeats_share_request_counts_and_forget_silent_servers(tmp_path):
    a, b, token = two_servers(tmp_path)
    a.heartbeat(A, "server a", {token: "[[100, 3]]", 999: "[[100, 1]]"}, 3, 60)  # 999: a revoked token
    assert b.heartbeat(B, "server b", {}, 3, 60) == {token: ["[[100, 3]]"]}
    assert a.heartbeat(A, "server a", {}, 3, 60) == {}  # a server's own are not read back
    a.heartbeat(A, "server a", {token: None}, 3, 60)  # none left in its window
    assert b.heartbeat(B, "server b", {}, 3, 60) == {}

    a.heartbeat(A, "server a", {token: "[[101, 1]]"}, 3, 60)
    a.lease_solve(token, 4, A, stale_s=3)
    time.sleep(0.05)
    assert b.heartbeat(B, "server b", {}, stale_s=0.01, forget_s=60) == {}  # a is stale: not counted
    assert b.heartbeat(B, "server b", {}, stale_s=3, forget_s=60) == {token: ["[[101, 1]]"]}
    b.heartbeat(B, "server b", {}, stale_s=3, forget_s=0.01)  # a is silent for longer: forgotten
    with b.engine.connect() as conn:
        assert conn.execute(text("SELECT id FROM servers")).scalars().all() == [B]
        assert conn.execute(text("SELECT count(*) FROM solve_leases")).scalar() == 0
        assert conn.execute(text("SELECT count(*) FROM request_counts")).scalar() == 0


def test_a_database_of_the_previous_version_opens(tmp_path):
    """Its solve leases and request counts (a TTL, a fixed minute) are dropped and made afresh."""
    path = tmp_path / "old.sqlite3"
    with sqlite3.connect(path) as conn:
        conn.executescript("""
            CREATE TABLE tokens (id INTEGER NOT NULL, name VARCHAR(100) NOT NULL, digest VARCHAR(64) NOT NULL,
                admin BOOLEAN NOT NULL, created_at DATETIME NOT NULL, touched_at DATETIME, PRIMARY KEY (id),
                UNIQUE (name), UNIQUE (digest));
            CREATE TABLE solve_leases (id INTEGER NOT NULL, token_id INTEGER NOT NULL, expires_at DATETIME NOT NULL,
                PRIMARY KEY (id), FOREIGN KEY(token_id) REFERENCES tokens (id) ON DELETE CASCADE);
            CREATE TABLE request_counts (token_id INTEGER NOT NULL, minute BIGINT NOT NULL, count INTEGER NOT NULL,
                PRIMARY KEY (token_id, minute), FOREIGN KEY(token_id) REFERENCES tokens (id) ON DELETE CASCADE);
            INSERT INTO tokens VALUES (1, 'alice', 'dddd', 0, '2025-01-01 00:00:00', NULL);
            INSERT INTO solve_leases VALUES (1, 1, '2099-01-01 00:00:00');
            INSERT INTO request_counts VALUES (1, 29000000, 5);
        """)
    store = Store(f"sqlite:///{path}")
    assert store.token_by_digest("dddd").name == "alice"
    store.heartbeat(A, "server a", {1: "[[100, 1]]"}, 3, 60)
    store.release_solve(store.lease_solve(1, 1, A, stale_s=3))  # the old lease is gone with its table
    store.lease_solve(1, 1, A, stale_s=3)
    store.close()


# --- Against a server -------------------------------------------------------------------------------

@pytest.mark.slow
def test_a_tokens_reads_go_on_while_another_connection_holds_the_write_lock(tmp_path):
    """A request writes nothing: reads with a token are answered while the database cannot be written
    for longer than SQLite's busy timeout (each once waited for it and failed, 500 'database is locked';
    the timeout set to 1 s here, held 3 s). The server's heartbeat fails meanwhile, says so once, and
    takes again after."""
    server = Server(tmp_path, require_tokens=True, sqlite_busy_timeout_s=BUSY_S).start()
    headers = bearer(make_token("alice", data_dir=server.data_dir))
    try:
        with server.client() as c:
            created = c.post("/tableaux", json=SMALL, headers=headers)
            assert created.status_code == 201, created.text
            paths = ("/tableaux", f"/tableaux/{created.json()['id']}/map")

            lock = sqlite3.connect(server.data_dir / "bootmap.sqlite3", isolation_level=None)
            lock.execute("BEGIN IMMEDIATE")
            locked, slowest, answered = time.monotonic(), 0.0, 0
            try:
                while time.monotonic() - locked < 3 * BUSY_S:
                    for path in paths:
                        t0 = time.monotonic()
                        r = c.get(path, headers=headers)
                        slowest = max(slowest, time.monotonic() - t0)
                        assert r.status_code == 200, r.text
                        assert time.monotonic() - t0 < 3 * BUSY_S, f"{path} took {time.monotonic() - t0:.1f} s"
                        answered += 1
                    assert c.get("/health").status_code == 200
                    time.sleep(0.2)
            finally:
                lock.execute("ROLLBACK")
                lock.close()
            unlocked = datetime.now(timezone.utc)
            print(f"{answered} reads answered during the {3 * BUSY_S:.0f} s lock, the slowest in {slowest:.3f} s")
            wait_for(lambda: last_heartbeat(server) > unlocked, timeout=15)  # the beat goes on
            assert server.log.read_text().count("did not take this server's heartbeat") == 1
            assert c.post("/tableaux", json=SMALL, headers=headers).status_code == 201  # writes again
    finally:
        server.stop()


def test_the_busy_timeout_set_is_the_one_each_sqlite_connection_waits(tmp_path):
    store = Store(f"sqlite:///{tmp_path / 'db.sqlite3'}", busy_timeout_s=2.5)
    with store.engine.connect() as conn:
        assert conn.exec_driver_sql("PRAGMA busy_timeout").scalar() == 2500
    with Store(f"sqlite:///{tmp_path / 'db.sqlite3'}").engine.connect() as conn:  # the default: 10 s
        assert conn.exec_driver_sql("PRAGMA busy_timeout").scalar() == 10_000


def last_heartbeat(server) -> datetime:
    with sqlite3.connect(server.data_dir / "bootmap.sqlite3") as conn:
        (beat,) = conn.execute("SELECT heartbeat_at FROM servers").fetchone()  # UTC, as the store writes it
    return datetime.fromisoformat(beat).replace(tzinfo=timezone.utc)
