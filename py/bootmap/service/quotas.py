"""Fair share between tokens, held in each server's memory and shared through the database every second.

A token is limited in two things, on all the servers of one database together (docs/service.md,
"Security"):

- Requests: at most ``token_requests_per_minute`` in any 60 s. :class:`RequestWindow` counts them in
  memory, so a request never writes the database: the times of this server's requests, plus what the
  other servers last wrote of theirs.
- Solve places: at most ``token_max_solves`` solves running or waiting. Each is a lease row naming the
  server that holds it (:meth:`Store.lease_solve`); another server's lease counts only while that
  server's heartbeat is fresh, so the places held by a server that died (kill -9 included) free within
  STALE_S of its last heartbeat.

:class:`Quotas` is one server's part: its window, its leases, and the beat, one background thread that
every BEAT_S writes the server's heartbeat and its changed request counts, reads the other servers'
fresh counts, and forgets servers silent for FORGET_S, in one short transaction
(:meth:`Store.heartbeat`). A locked or unreachable database only makes the beat log once and try again
at the next one; requests go on with the counts last heard.
"""

from __future__ import annotations

import json
import logging
import math
import os
import socket
import threading
import time
import uuid
from collections import Counter, deque
from datetime import datetime, timezone
from typing import Callable

from .store import HeldLease, QuotaExceeded, SolvePlacesTaken, Store

log = logging.getLogger("bootmap.service")

BEAT_S = 1.0  # how often a server writes its heartbeat and request counts and reads the others'
STALE_S = 3.0  # a server not heard from for this long is taken as gone: its leases and counts stop counting
FORGET_S = 60.0  # ... and for this long, its row, leases and counts are deleted
WINDOW_S = 60.0  # the request limit holds in any window this long


class RequestWindow:
    """At most ``limit`` requests per token in any ``window_s`` seconds, counted in memory.

    This server's requests are kept as their times, at most ``limit`` per token: a refused request is not
    counted, so a client that keeps retrying gets in as soon as there is room. The other servers' are what
    they last wrote (:meth:`mine` there, :meth:`heard` here): how many requests in each whole second; such
    a second counts until its last possible request leaves the window, so the others are never undercounted,
    only held up to a second longer. ``clock`` is wall-clock seconds, as the servers share them."""

    def __init__(self, limit: int, window_s: float = WINDOW_S, clock: Callable[[], float] = time.time):
        self.limit, self.window_s, self.clock = limit, window_s, clock
        self._mine: dict[int, deque[float]] = {}  # token id -> times of this server's counted requests
        self._elsewhere: dict[int, list[tuple[int, int]]] = {}  # token id -> (second, requests) on the others
        self._lock = threading.Lock()

    def count(self, token_id: int) -> None:
        """Count a request of the token now; if the window is full, QuotaExceeded (and it is not counted),
        with Retry-After when the oldest counted request leaves the window."""
        now = self.clock()
        with self._lock:
            mine = self._mine.setdefault(token_id, deque())
            while mine and mine[0] <= now - self.window_s:
                mine.popleft()
            others = [(second + 1 + self.window_s, n) for second, n in self._elsewhere.get(token_id, ())
                      if second + 1 + self.window_s > now]  # (when they leave the window, how many)
            total = len(mine) + sum(n for _, n in others)
            if total < self.limit:
                mine.append(now)
                return
            leaving = sorted([(t + self.window_s, 1) for t in mine] + others)
        wait = _seconds_until(leaving, total - self.limit + 1, now)
        raise QuotaExceeded(f"this token made {total} requests in the last {self.window_s:g} s, its limit "
                            f"(BOOTMAP_TOKEN_REQUESTS_PER_MINUTE, on all servers); retry in {wait} s", wait)

    def mine(self) -> dict[int, str]:
        """This server's requests still in the window, per token, as the other servers read them: JSON
        ``[[second, requests], ...]``. Tokens with none left are dropped from memory."""
        now = self.clock()
        out: dict[int, str] = {}
        with self._lock:
            tokens = list(self._mine)
        for token_id in tokens:  # the lock held for one token at a time: requests are counted meanwhile
            with self._lock:
                times = self._mine.get(token_id, deque())
                while times and times[0] <= now - self.window_s:
                    times.popleft()
                if not times:
                    self._mine.pop(token_id, None)
                    continue
                seconds = [math.floor(t) for t in times]
            out[token_id] = json.dumps(sorted(Counter(seconds).items()))
        return out

    def heard(self, elsewhere: dict[int, list[str]]) -> None:
        """The other servers' counts, as :meth:`mine` wrote them there (token id -> one text per server);
        they replace what was heard before."""
        parsed = {token_id: [(int(second), int(n)) for text in texts for second, n in json.loads(text)]
                  for token_id, texts in elsewhere.items()}
        with self._lock:
            self._elsewhere = parsed


def _seconds_until(leaving: list[tuple[float, int]], k: int, now: float) -> int:
    """Whole seconds (at least 1) until ``k`` requests have left the window; ``leaving`` is (when, how
    many), sorted."""
    gone = 0
    for at, n in leaving:
        gone += n
        if gone >= k:
            return max(1, math.ceil(at - now))
    return 1  # not reached: the window holds at least k requests


def solve_retry_after(held: list[HeldLease], solve_s: float, now: datetime) -> int:
    """Seconds (at least 1) until one of the token's solve places is likely to free. A lease of a server
    that has missed a heartbeat frees when that heartbeat goes stale (the server is gone, or is taken as
    gone); any other when its solve reaches the time limit and kill grace (``solve_s``), if it started
    when the place was taken (one still waiting may take longer)."""
    def frees_in(lease: HeldLease) -> float:
        if lease.heartbeat_at is not None and (now - lease.heartbeat_at).total_seconds() > 1.5 * BEAT_S:
            return (lease.heartbeat_at - now).total_seconds() + STALE_S
        return (lease.started_at - now).total_seconds() + solve_s

    return max(1, math.ceil(min(frees_in(lease) for lease in held)))


class Quotas:
    """One server's part in the fair share: its request window, its solve leases, and the beat that shares
    them with the other servers on the database (a daemon thread, from :meth:`start` to :meth:`close`).

    ``solve_s`` is how long a solve may hold a solver (time limit plus kill grace): what a 429 for solves
    tells the client to wait when the places are held by live servers."""

    def __init__(self, store: Store, requests_per_minute: int, max_solves: int, solve_s: float):
        self.store, self.max_solves, self.solve_s = store, max_solves, solve_s
        self.server_id = uuid.uuid4().hex  # new at each start: a restarted server is a new one
        self.name = f"{socket.gethostname()} pid {os.getpid()}"
        self.requests = RequestWindow(requests_per_minute)
        self._written: dict[int, str] = {}  # the counts the last beat wrote, per token
        self._unreleased: list[int] = []  # leases whose release failed: the next beat deletes them
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._failing = False  # the last beat failed (logged once, until one succeeds)

    # --- The beat ------------------------------------------------------------------------------------

    def start(self) -> None:
        """Write the first heartbeat (so this server's leases count at once; an error here stops the
        start), then beat every BEAT_S in the background."""
        self.beat()
        self._thread = threading.Thread(target=self._run, name="bootmap-quotas", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(BEAT_S):
            try:
                self.beat()
            except Exception as e:  # locked, unreachable, anything: the server goes on, the beat tries again
                if not self._failing:
                    log.warning("the database did not take this server's heartbeat and request counts (%s); "
                                "trying again every %g s", e, BEAT_S)
                self._failing = True
            else:
                if self._failing:
                    log.info("the database takes this server's heartbeat again")
                self._failing = False

    def beat(self) -> None:
        """One beat: this server's heartbeat and changed request counts out, the other servers' fresh
        counts in; then the leases whose release failed are deleted."""
        mine = self.requests.mine()
        changed: dict[int, str | None] = {t: c for t, c in mine.items() if self._written.get(t) != c}
        changed.update({t: None for t in self._written if t not in mine})
        elsewhere = self.store.heartbeat(self.server_id, self.name, changed, STALE_S, FORGET_S)
        self._written = mine
        self.requests.heard(elsewhere)
        with self._lock:
            pending, self._unreleased = self._unreleased, []
        for i, lease in enumerate(pending):
            try:
                self.store.release_solve(lease)
            except Exception:
                with self._lock:
                    self._unreleased.extend(pending[i:])
                raise

    def close(self) -> None:
        """Stop the beat; this server's row, leases and counts leave the database (if it answers: else the
        other servers stop counting them within STALE_S)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(BEAT_S + self.store.busy_timeout_s + 5)
        try:
            self.store.remove_server(self.server_id)
        except Exception as e:
            log.warning("could not remove this server's heartbeat and solve leases from the database (%s); "
                        "the other servers stop counting them within %g s", e, STALE_S)

    # --- What requests call ---------------------------------------------------------------------------

    def count_request(self, token_id: int) -> None:
        """Count a request of the token (in memory); QuotaExceeded over the limit."""
        self.requests.count(token_id)

    def lease_solve(self, token_id: int) -> int:
        """Take one of the token's solve places (shared by every server on the database); the lease's id.
        None free: QuotaExceeded, with a Retry-After from :func:`solve_retry_after`."""
        try:
            return self.store.lease_solve(token_id, self.max_solves, self.server_id, STALE_S)
        except SolvePlacesTaken as e:
            wait = solve_retry_after(e.held, self.solve_s, datetime.now(timezone.utc))
            raise QuotaExceeded(f"this token has {len(e.held)} solves running or waiting, its limit "
                                f"(BOOTMAP_TOKEN_MAX_SOLVES); retry in {wait} s", wait) from None

    def release_solve(self, lease_id: int) -> None:
        """Give a solve place back; if the database does not take it now, the next beats try again (the
        request that held it is not failed for that)."""
        try:
            self.store.release_solve(lease_id)
        except Exception as e:
            log.warning("could not give back solve place %s (%s); the next heartbeat will", lease_id, e)
            with self._lock:
                self._unreleased.append(lease_id)
