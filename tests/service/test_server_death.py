"""A server killed outright (kill -9) leaves nothing behind, against real uvicorn servers on 127.0.0.1.

Its solve leases stop counting once its heartbeat is stale (3 s), so a token whose solve places it held
gets them back on another server within seconds; its solver and intake processes notice that their
parent is gone and end (a solver in the middle of a solve too), and multiprocessing's resource tracker
with them; the bodies it was reading are removed by the next server started on its spool directory. Bounds are generous (5 s for
what takes about 3 s) and nothing depends on how busy the machine is but how long things take.
"""

import os
import signal
import time
from pathlib import Path

from service_helpers import Server, bearer, make_token
from test_fair_share import hang_up_later, solves, wait_for

from bootmap import examples

SMALL = examples.notched_rectangle(circuits=2).to_dict()


def descendants(pid: int) -> dict[int, str]:
    """The processes below ``pid`` (children of any of its threads, recursively): pid -> start time
    (field 22 of /proc/PID/stat, so that a reused pid is not mistaken for one of them)."""
    found: dict[int, str] = {}
    todo = [pid]
    while todo:
        parent = todo.pop()
        for task in Path(f"/proc/{parent}/task").glob("*"):
            try:
                children = (task / "children").read_text().split()
            except OSError:  # the thread ended meanwhile
                continue
            for child in map(int, children):
                if child not in found and (start := _start_time(child)) is not None:
                    found[child] = start
                    todo.append(child)
    return found


def _stat(pid: int) -> list[str] | None:
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    return text[text.rindex(")") + 2:].split()  # after "pid (name) ": state is field 3, start time 22


def _start_time(pid: int) -> str | None:
    fields = _stat(pid)
    return None if fields is None else fields[19]


def alive(pid: int, start: str) -> bool:
    """Still running (a zombie waiting to be reaped holds nothing: it counts as gone)."""
    fields = _stat(pid)
    return fields is not None and fields[19] == start and fields[0] != "Z"


def cmdline(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace").strip()
    except OSError:
        return "?"


def test_a_killed_server_frees_its_tokens_solve_places_and_leaves_no_process_behind(tmp_path):
    """Two servers on one SQLite file; the token's two solve places are taken by hard solves on a (30 s
    each), which is then killed. Before, its leases kept the token at 429 for a minute and more (their
    TTL), and its intake processes and multiprocessing's resource tracker ran on for good. Now b takes
    the token's post within seconds, and every process a started (its solvers, one of them busy, its
    intake processes, the resource tracker) ends."""
    db = str(tmp_path / "shared.sqlite3")
    settings = {"db": db, "require_tokens": True, "token_max_solves": 2, "max_concurrent_solves": 1,
                "max_queued_solves": 2, "solve_time_limit_s": 30, "solve_kill_grace_s": 2,
                "spool_dir": str(tmp_path / "spool")}
    token = make_token("alice", db=db)
    servers = []
    for name in ("a", "b"):
        (tmp_path / name).mkdir()
        servers.append(Server(tmp_path / name, **settings).start())
    a, b = servers
    flood, left_behind = [], {}
    try:
        with a.client() as ca, b.client() as cb:
            flood = [hang_up_later(a, token) for _ in range(2)]
            wait_for(lambda: solves(ca) == (1, 1))  # both places taken on a: one solving, one waiting
            over = cb.post("/tableaux", json=SMALL, headers=bearer(token))
            assert over.status_code == 429 and "BOOTMAP_TOKEN_MAX_SOLVES" in over.json()["detail"], over.text

            left_behind = descendants(a.process.pid)
            names = {pid: cmdline(pid) for pid in left_behind}
            # Its solver, the intake processes (one or two) and the resource tracker, at least.
            assert len(left_behind) >= 3 and any("resource_tracker" in n for n in names.values()), names
            os.kill(a.process.pid, signal.SIGKILL)
            killed = time.monotonic()
            statuses = []
            while time.monotonic() - killed < 5:
                r = cb.post("/tableaux", json=SMALL, headers=bearer(token))
                statuses.append(r.status_code)
                if r.status_code != 429:
                    break
                # What is true from b's side: when a's solve would end (its limit and grace), or a's silence + 3 s.
                assert 1 <= int(r.headers["retry-after"]) <= 30 + 2 + 1, r.headers["retry-after"]
                time.sleep(0.2)
            seconds = time.monotonic() - killed
            print(f"the token's solve place was free on b {seconds:.2f} s after a was killed "
                  f"({len(statuses) - 1} answers 429 before)")
            assert r.status_code == 201, (statuses, r.text)
            assert r.json()["map"]["summary"]["dstates"] == 8

            a.process.wait(5)
            while any(alive(pid, start) for pid, start in left_behind.items()) and time.monotonic() - killed < 5:
                time.sleep(0.05)
            left = {pid: names[pid] for pid, start in left_behind.items() if alive(pid, start)}
            print(f"{len(left_behind) - len(left)} of {len(left_behind)} processes ended within "
                  f"{time.monotonic() - killed:.2f} s of the kill")
            assert not left, f"still running 5 s after the server was killed: {left}"

            # a's spool still holds the bodies of its two hung posts; a server started again sweeps it.
            spools = lambda: {p.name: sorted(f.name for f in p.iterdir()) for p in (tmp_path / "spool").iterdir()}
            before = spools()
            assert len(before) == 2 and any(len(files) > 1 for files in before.values()), before
            a.start()
            after = spools()
            assert len(after) == 2 and len(set(after) & set(before)) == 1, (before, after)  # b's, a's new one
    finally:
        for s in flood:
            s.close()
        for s in servers:
            s.stop()
        _kill_survivors(left_behind)


def _kill_survivors(processes: dict[int, str]) -> None:
    """Should a test fail: leave none of the killed server's processes running."""
    for pid, start in processes.items():
        if alive(pid, start):
            os.kill(pid, signal.SIGKILL)
