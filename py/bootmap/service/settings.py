"""Settings of the HTTP service: command-line options, else ``BOOTMAP_*`` environment variables, else defaults.

Every limit the service enforces is here, so an operator can size it to the machine. The table in
docs/service.md ("Settings") lists them.
"""

from __future__ import annotations

import ipaddress
import os
from pathlib import Path
from typing import Annotated

from pydantic import Field, field_validator
from pydantic_settings import BaseSettings, NoDecode, SettingsConfigDict

# Names a browser on this machine uses for a loopback server: the only hosts allowed by default.
LOOPBACK_NAMES = ("127.0.0.1", "localhost", "::1", "[::1]")
CommaList = Annotated[list[str], NoDecode]  # BOOTMAP_ALLOWED_HOSTS=a.example,b.example


def default_data_dir() -> Path:
    """``$XDG_DATA_HOME/bootmap``, else ``~/.local/share/bootmap``."""
    base = os.environ.get("XDG_DATA_HOME") or str(Path.home() / ".local" / "share")
    return Path(base) / "bootmap"


class Settings(BaseSettings):
    """Configuration of ``bootmap serve``. Each field ``x`` is read from ``BOOTMAP_X`` when not given."""

    model_config = SettingsConfigDict(env_prefix="BOOTMAP_", extra="forbid", validate_default=True)

    data_dir: Path = Field(default_factory=default_data_dir,
                           description="Directory of the SQLite database and of the axiom snapshots.")
    db: str | None = Field(None, description="Database: a file path or an SQLAlchemy URL "
                                             "(e.g. postgresql+psycopg://...); default DATA_DIR/bootmap.sqlite3.")
    sqlite_busy_timeout_s: float = Field(10.0, gt=0, le=600, description="SQLite: how long a write waits for "
                                         "another connection's write lock before it fails (reads never wait).")
    # The same variable the library reads (BOOTMAP_AXIOMS), so `bootmap map` and the service agree.
    axioms: Path | None = Field(None, description="Axiom directory; default the shipped asp/.")
    host: str = "127.0.0.1"
    port: int = Field(8000, ge=0, le=65535)
    max_body_bytes: int = Field(16 * 2**20, ge=1024, description="Largest request body, bytes.")
    max_steps: int = Field(20_000, ge=1, description="Most steps a tableau may have (after appending).")
    max_image_len: int = Field(4096, ge=1, description="Most values in one image.")
    solve_time_limit_s: float = Field(60.0, gt=0, description="The resolver's time limit per solve (as `bootmap map`'s).")
    solve_kill_grace_s: float = Field(2.0, ge=0, description="A solver still busy this long after its time "
                                                             "limit (grounding cannot be interrupted) is killed.")
    solver_memory_mb: int = Field(2048, ge=256, description="Address-space cap of each solver process, MiB.")
    max_concurrent_solves: int = Field(2, ge=1, description="Solver processes, i.e. solves at once.")
    max_queued_solves: int = Field(8, ge=0, description="Solves that may wait for a solver; beyond, 503.")
    retry_after_s: int = Field(2, ge=1, description="Retry-After of a 503 when every solver is busy.")
    max_models: int = Field(10, ge=1, le=1000, description="Minimal maps enumerated before the count is capped.")
    quantum_deg: float | None = Field(None, gt=0, le=180, description="Round angles to this many degrees; "
                                      "unset: learn the robot's action types from each tableau.")
    runs_dir: Path | None = Field(None, description="Directory of experiment runs (bootmap experiment -o DIR) "
                                  "whose figures the viewer shows, read-only; unset: none.")
    log_level: str = Field("info", pattern="^(critical|error|warning|info|debug|trace)$")

    # Who may do what (docs/service.md, "Security").
    require_tokens: bool = Field(False, description="Every request but /health, the schemas and the docs needs "
                                 "an API token; always on when the service listens on anything but loopback.")
    allowed_hosts: CommaList = Field(default_factory=list, description="Host names clients may use (the Host "
                                     "header), comma-separated; '*.example.org' matches subdomains, '*' any. "
                                     "Default: the loopback names and the --host address.")
    cors_origins: CommaList = Field(default_factory=list, description="Web origins allowed to call the API from "
                                    "a browser (CORS), comma-separated; default none.")
    # Fair share: limits per token, shared by every server on one database.
    token_max_solves: int = Field(4, ge=1, description="Solves one token may have running or waiting at once.")
    token_max_running: int | None = Field(None, ge=1, description="Solvers one token may use at once on one "
                                          "server; default half of them (at least one), so others find one free.")
    token_requests_per_minute: int = Field(600, ge=1, description="Requests one token may make per minute.")
    token_max_stored_bytes: int = Field(256 * 2**20, ge=1024, description="Bytes of tableaux and maps one token "
                                                                          "may keep stored.")
    # Bounded memory in the server process.
    body_timeout_s: float = Field(20.0, gt=0, description="A request body not received within this many "
                                                          "seconds of its headers is refused (408).")
    header_timeout_s: float = Field(10.0, gt=0, description="A request whose line and headers are not in within "
                                                             "this many seconds of its first byte: connection closed.")
    send_timeout_s: float = Field(30.0, gt=0, description="A response the client does not read for this many "
                                                           "seconds is ended and its connection closed.")
    max_meta_bytes: int = Field(64 * 2**10, ge=2, description="Largest 'meta' of a tableau, bytes of JSON.")
    max_json_values: int = Field(1_000_000, ge=100, description="Most JSON values (numbers, strings, ...) in one "
                                                                "request body.")
    max_held_body_bytes: int = Field(32 * 2**20, ge=1024, description="Bytes of request bodies the server holds "
                                     "at once (by Content-Length, else max_body_bytes); a request whose body "
                                     "does not fit waits for room before it is read.")
    spool_dir: Path | None = Field(None, description="Where request bodies are written as they arrive (each server "
                                   "a directory of its own, removed when it stops, or by the next server started "
                                   "here if it was killed); default the system's temporary directory.")
    intake_memory_mb: int = Field(1024, ge=256, description="Address-space cap of each intake process (where "
                                                            "posted tableaux are parsed and checked), MiB.")

    @field_validator("allowed_hosts", "cors_origins", mode="before")
    @classmethod
    def _split_commas(cls, value):
        return [x.strip() for x in value.split(",") if x.strip()] if isinstance(value, str) else value

    @property
    def loopback(self) -> bool:
        """Does the service listen on loopback only?"""
        if self.host == "localhost":
            return True
        try:
            return ipaddress.ip_address(self.host.strip("[]")).is_loopback
        except ValueError:
            return False

    @property
    def tokens_required(self) -> bool:
        """Tokens are optional only for one user on loopback, and only unless asked for."""
        return self.require_tokens or not self.loopback

    @property
    def hosts(self) -> list[str]:
        """The Host header values accepted: as configured, else the loopback names and the --host address."""
        if self.allowed_hosts:
            return list(self.allowed_hosts)
        wildcard = self.host in ("0.0.0.0", "::", "")
        return list(LOOPBACK_NAMES) + ([] if wildcard or self.host in LOOPBACK_NAMES else [self.host])

    @property
    def database_url(self) -> str:
        """The SQLAlchemy URL: ``db`` when it is one, else an SQLite file (``db`` or the default path)."""
        if self.db and "://" in self.db:
            return self.db
        path = Path(self.db) if self.db else self.data_dir / "bootmap.sqlite3"
        return f"sqlite:///{path.expanduser().resolve()}"
