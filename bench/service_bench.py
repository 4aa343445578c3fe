"""Load on the HTTP service over loopback: throughput and latency percentiles (a benchmark, not a test).

Starts ``bootmap serve`` on a free port with a fresh data directory (or uses --url), then, with
``--clients`` concurrent clients (threads, one keep-alive connection each):

1. posts the paper's 401-step tableau ``--posts`` times (each post is validated, solved and stored), and
2. reads its stored map ``--reads`` times.

Targets on the project's 2-core machine: p50 under 0.5 s for post-and-solve, over 300 map reads per second,
and no failed request. Each is printed beside the measured figure; the exit status is 1 if any is missed.

    .venv/bin/python bench/service_bench.py [--clients 4] [--posts 200] [--reads 2000] [--url URL]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import httpx
import numpy as np

from bootmap import examples
from targets import Targets

POST_P50_MAX_S = 0.5
READS_PER_S_MIN = 300.0


def start_server(data_dir: Path) -> tuple[subprocess.Popen, str]:
    log = data_dir / "server.log"
    env = {k: v for k, v in os.environ.items() if not k.startswith("BOOTMAP_")} | {"BOOTMAP_LOG_LEVEL": "warning"}
    # Warning level keeps uvicorn's access log (one line per request) out of the measurement; the start-up
    # line is then not logged, so the port is chosen here.
    port = _free_port()
    with open(log, "w") as f:
        proc = subprocess.Popen([sys.executable, "-m", "bootmap.cli", "serve", "--port", str(port),
                                 "--data-dir", str(data_dir)], stdout=f, stderr=subprocess.STDOUT, env=env)
    url = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        try:
            if httpx.get(url + "/health").status_code == 200:
                return proc, url
        except httpx.TransportError:
            time.sleep(0.1)
    proc.kill()
    raise SystemExit(f"the server did not start:\n{log.read_text()}")


def _free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def run(url: str, clients: int, n: int, request) -> tuple[np.ndarray, float, int]:
    """``n`` requests over ``clients`` threads; returns latencies (s), wall time (s), failures."""
    latencies: list[float] = []
    failures = [0]
    lock = threading.Lock()
    counter = iter(range(n))

    def work():
        with httpx.Client(base_url=url, timeout=120) as c:
            while True:
                with lock:
                    if next(counter, None) is None:
                        return
                t0 = time.perf_counter()
                ok = request(c)
                dt = time.perf_counter() - t0
                with lock:
                    latencies.append(dt)
                    failures[0] += not ok

    threads = [threading.Thread(target=work) for _ in range(clients)]
    t0 = time.perf_counter()
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    return np.array(latencies), time.perf_counter() - t0, failures[0]


def report(name: str, lat: np.ndarray, wall: float, failures: int) -> dict:
    p50, p90, p99 = np.percentile(lat, [50, 90, 99]) * 1000
    print(f"{name:34} {len(lat):5d} req  {len(lat) / wall:7.1f} req/s  p50 {p50:6.1f} ms  p90 {p90:6.1f} ms  "
          f"p99 {p99:6.1f} ms  max {lat.max() * 1000:6.1f} ms  failures {failures}")
    return {"p50_s": p50 / 1000, "per_s": len(lat) / wall, "failures": failures}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--url", help="a running server (default: start one)")
    ap.add_argument("--clients", type=int, default=4)
    ap.add_argument("--posts", type=int, default=200)
    ap.add_argument("--reads", type=int, default=2000)
    args = ap.parse_args()
    paper = examples.notched_rectangle(circuits=50).to_dict()
    proc = None
    with tempfile.TemporaryDirectory() as tmp:
        url = args.url
        if url is None:
            proc, url = start_server(Path(tmp))
        try:
            ids: list[int] = []

            def post(c: httpx.Client) -> bool:
                r = c.post("/tableaux", json=paper)
                if r.status_code == 201:
                    ids.append(r.json()["id"])
                return r.status_code == 201 and r.json()["map"]["summary"]["dstates"] == 8

            with httpx.Client(base_url=url) as c:  # warm: first solves, first imports
                for _ in range(4):
                    post(c)
            print(f"bootmap service at {url}, {args.clients} concurrent clients, loopback, "
                  f"{os.cpu_count()} CPUs")
            posts = report("POST /tableaux (401 steps, solve)", *run(url, args.clients, args.posts, post))
            target = ids[0]
            reads = report("GET /tableaux/{id}/map", *run(url, args.clients, args.reads,
                                                          lambda c: c.get(f"/tableaux/{target}/map").status_code == 200))
        finally:
            if proc is not None:
                proc.terminate()
                proc.wait(20)
    print()
    targets = Targets()
    targets.check("POST /tableaux p50", posts["p50_s"], "<", POST_P50_MAX_S, fmt="{:.3f}", unit=" s")
    targets.check("GET /tableaux/{id}/map throughput", reads["per_s"], ">", READS_PER_S_MIN, fmt="{:.0f}",
                  unit=" req/s")
    targets.check("failed requests", posts["failures"] + reads["failures"], "==", 0, fmt="{}")
    return targets.exit_status()


if __name__ == "__main__":
    sys.exit(main())
