"""What the routers depend on, injected with FastAPI's ``Depends``: one :class:`Services` per application."""

from __future__ import annotations

import pathlib
import re
from dataclasses import dataclass
from typing import Annotated

from annotated_types import Ge, Le
from fastapi import Depends, Path, Request
from fastapi.concurrency import run_in_threadpool
from pydantic import BeforeValidator

from ..tableau import FORMAT
from .intake import Intake, Limits, intake_workers
from .quotas import Quotas
from .settings import Settings
from .spool import Spool
from .store import Store
from .theory import LoadedTheory, Theories
from .worker import (Explained, ExplainJob, Job, Rehearsed, RehearseJob, Solved, SolveGate, SolveJob, SolverPool,
                     StoredTableau)


@dataclass
class Services:
    settings: Settings
    store: Store
    theories: Theories
    pool: SolverPool
    gate: SolveGate
    intake: Intake
    quotas: Quotas
    spool: Spool

    @property
    def limits(self) -> Limits:
        s = self.settings
        return Limits(s.max_steps, s.max_image_len, s.max_meta_bytes, s.max_json_values)

    @classmethod
    def start(cls, settings: Settings) -> "Services":
        """Open the store, start this server's heartbeat (:class:`Quotas`), snapshot the theory, start and
        warm the solvers (blocking: a second or two)."""
        settings.data_dir.mkdir(parents=True, exist_ok=True)
        store = Store(settings.database_url, settings.sqlite_busy_timeout_s)
        quotas = Quotas(store, settings.token_requests_per_minute, settings.token_max_solves,
                        settings.solve_time_limit_s + settings.solve_kill_grace_s)
        quotas.start()
        theories = Theories(settings.axioms, settings.data_dir)
        pool = SolverPool(settings.max_concurrent_solves, settings.solver_memory_mb, settings.solve_kill_grace_s)
        gate = SolveGate(pool, settings.max_concurrent_solves, settings.max_queued_solves, settings.retry_after_s,
                         settings.token_max_running)
        intake = Intake(intake_workers(), settings.intake_memory_mb)
        services = cls(settings, store, theories, pool, gate, intake, quotas, Spool.open(settings.spool_dir))
        intake.warm()
        pool.warm(services.job({"format": FORMAT, "steps": [
            {"view": "a", "action": {"type": "travel", "distance_m": 1.0}}, {"view": "b"}]})[0])
        return services

    def close(self) -> None:
        self.quotas.close()  # first: this server's solve places free at once for the other servers
        self.intake.close()
        self.pool.close()
        self.store.close()
        self.spool.close()

    def job(self, document: dict | str | pathlib.Path, stream: int | None = None) -> tuple[SolveJob, LoadedTheory]:
        """A solve of a tableau document with the current theory, and that theory (its id goes with the map).
        ``stream``: the stored tableau's id, when the document extends it (its map is then kept current)."""
        theory, s = self.theories.current, self.settings
        return SolveJob(document, str(theory.snapshot), s.solve_time_limit_s, s.quantum_deg, s.max_models,
                        stream), theory


    async def solve(self, job: Job, token_id: int | None, request: Request) -> Solved | Explained | Rehearsed:
        """Solve in the pool, holding one of the token's solve places (shared by every server on the
        database) meanwhile; stopped if the client goes away."""
        lease = None
        if token_id is not None:
            lease = await run_in_threadpool(self.quotas.lease_solve, token_id)
        try:
            return await self.gate.solve(job, lambda: client_gone(request), token_id)
        finally:
            if lease is not None:
                await run_in_threadpool(self.quotas.release_solve, lease)

    def explain_job(self, document: dict | str | StoredTableau, a: str, b: str, levels: tuple[str, ...] | None) -> ExplainJob:
        """A question about a tableau document, with the current theory."""
        theory, s = self.theories.current, self.settings
        return ExplainJob(document, str(theory.snapshot), s.solve_time_limit_s, a, b, levels, s.quantum_deg)

    def rehearse_job(self, document: dict | str | StoredTableau, max_length: int) -> RehearseJob:
        """What to do next for a tableau document, with the current theory."""
        theory, s = self.theories.current, self.settings
        return RehearseJob(document, str(theory.snapshot), s.solve_time_limit_s, max_length, s.quantum_deg)


async def client_gone(request: Request) -> None:
    """Return when the client has closed the connection (its body is read by then: what the server
    receives next is the disconnect)."""
    while (await request.receive())["type"] != "http.disconnect":
        pass


def get_services(request: Request) -> Services:
    return request.app.state.services


def _canonical_id(value: object) -> object:
    # "01" and "+1" would parse as 1: one tableau, one path.
    if isinstance(value, str) and not re.fullmatch(r"[1-9][0-9]{0,18}", value):
        raise ValueError("should be a positive integer written without sign or leading zeros")
    return value


ServicesDep = Annotated[Services, Depends(get_services)]
# The bounds as annotated_types (not Path(ge=, le=)): beside a BeforeValidator, FastAPI would publish
# Path's as "ge"/"le", which no OpenAPI tool reads, instead of "minimum"/"maximum".
TableauId = Annotated[int, Ge(1), Le(2**63 - 1), BeforeValidator(_canonical_id),
                      Path(description="The id the tableau was created with.")]
