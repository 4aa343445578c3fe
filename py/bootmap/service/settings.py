"""Settings of the HTTP service: command-line options, else ``BOOTMAP_*`` environment variables, else defaults.

Every limit the service enforces is here, so an operator can size it to the machine. The table in
README.md ("Service") and docs/service.md lists them.
"""

from __future__ import annotations

import os
from pathlib import Path

from pydantic import Field
from pydantic_settings import BaseSettings, SettingsConfigDict


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
    # The same variable the library reads (BOOTMAP_AXIOMS), so `bootmap map` and the service agree.
    axioms: Path | None = Field(None, description="Axiom directory; default the shipped asp/.")
    host: str = "127.0.0.1"
    port: int = Field(8000, ge=0, le=65535)
    max_body_bytes: int = Field(16 * 2**20, ge=1024, description="Largest request body, bytes.")
    max_steps: int = Field(20_000, ge=1, description="Most steps a tableau may have (after appending).")
    max_image_len: int = Field(4096, ge=1, description="Most values in one image.")
    solve_time_limit_s: float = Field(30.0, gt=0, description="The resolver's time limit per solve.")
    solve_kill_grace_s: float = Field(2.0, ge=0, description="A solver still busy this long after its time "
                                                             "limit (grounding cannot be interrupted) is killed.")
    solver_memory_mb: int = Field(2048, ge=256, description="Address-space cap of each solver process, MiB.")
    max_concurrent_solves: int = Field(2, ge=1, description="Solver processes, i.e. solves at once.")
    max_queued_solves: int = Field(8, ge=0, description="Solves that may wait for a solver; beyond, 503.")
    retry_after_s: int = Field(2, ge=1, description="Retry-After of a 503 when every solver is busy.")
    max_models: int = Field(10, ge=1, le=1000, description="Minimal maps enumerated before the count is capped.")
    quantum_deg: float | None = Field(None, gt=0, le=180, description="Round angles to this many degrees; "
                                      "unset: learn the robot's action types from each tableau.")
    log_level: str = Field("info", pattern="^(critical|error|warning|info|debug|trace)$")

    @property
    def database_url(self) -> str:
        """The SQLAlchemy URL: ``db`` when it is one, else an SQLite file (``db`` or the default path)."""
        if self.db and "://" in self.db:
            return self.db
        path = Path(self.db) if self.db else self.data_dir / "bootmap.sqlite3"
        return f"sqlite:///{path.expanduser().resolve()}"
