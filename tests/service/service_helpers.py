"""The service under test: ``bootmap serve`` (uvicorn) in a subprocess on 127.0.0.1, with its own data."""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import httpx

REPO = Path(__file__).resolve().parents[2]
# Debian's chromium, which the viewer's browser tests drive through Playwright by path (never `playwright
# install`); the tests that need it skip without it.
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
SESSION_SETTINGS = {"solve_time_limit_s": 3, "solve_kill_grace_s": 1, "max_concurrent_solves": 1,
                    "max_queued_solves": 1, "max_body_bytes": 4 * 2**20, "max_steps": 10_000,
                    "max_image_len": 512, "retry_after_s": 3}
#: The shared server's settings: a solve limit far beyond any solve the tests post to it, a margin and not
#: a subject, so that no verdict depends on how busy the machine is; the tests whose subject is the time
#: limit start a server with the 3 s of SESSION_SETTINGS of their own (test_limits.py).
PATIENT_SETTINGS = {**SESSION_SETTINGS, "solve_time_limit_s": 60}


class Server:
    """``bootmap serve --port 0`` in a subprocess; the port is read from uvicorn's start-up line."""

    def __init__(self, root: Path, **settings):
        self.root, self.settings = root, settings
        self.data_dir, self.log = root / "data", root / "server.log"
        self.process: subprocess.Popen | None = None
        self.url = ""

    def start(self, timeout: float = 60) -> "Server":
        env = {k: v for k, v in os.environ.items() if not k.startswith("BOOTMAP_")}
        env.update({f"BOOTMAP_{k.upper()}": str(v) for k, v in self.settings.items()})
        seen = self.log.stat().st_size if self.log.exists() else 0  # a restart appends to the same log
        with open(self.log, "a") as log:
            self.process = subprocess.Popen(
                [sys.executable, "-m", "bootmap.cli", "serve", "--port", "0", "--data-dir", str(self.data_dir)],
                stdout=log, stderr=subprocess.STDOUT, env=env, cwd=self.root)
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            found = re.search(r"Uvicorn running on (http://127\.0\.0\.1:\d+)", self.log.read_text()[seen:])
            if found:
                self.url = found.group(1)
                return self
            if self.process.poll() is not None:
                break
            time.sleep(0.05)
        self.stop()
        raise RuntimeError(f"the server did not start:\n{self.log.read_text()}")

    def stop(self) -> None:
        if self.process and self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(20)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()

    def client(self, timeout: float = 60) -> httpx.Client:
        return httpx.Client(base_url=self.url, timeout=timeout)


def serving(root: Path, **settings):
    """A server started for a fixture: yields it, and stops it when the fixture ends."""
    s = Server(root, **settings).start()
    yield s
    s.stop()


def make_token(name: str, *, admin: bool = False, data_dir: Path | None = None, db: str | None = None) -> str:
    """``bootmap token create NAME``: the token is the last line it prints."""
    where = ["--db", db] if db else ["--data-dir", str(data_dir)]
    env = {k: v for k, v in os.environ.items() if not k.startswith("BOOTMAP_")}
    out = subprocess.run([sys.executable, "-m", "bootmap.cli", "token", "create", name, *where,
                          *(["--admin"] if admin else [])], capture_output=True, text=True, env=env, timeout=60)
    assert out.returncode == 0, out.stderr
    return out.stdout.strip().splitlines()[-1]


def bearer(token: str) -> dict[str, str]:
    return {"Authorization": f"Bearer {token}"}
