"""Intake: request bodies of tableaux parsed, checked and turned into stored JSON text in a separate process.

Parsing JSON and validating it with pydantic are C and Rust calls that hold Python's GIL from start to
end: a 16 MB body holds it for a second or more, so in a thread of the server they would still stall
every other request (``/health`` included), and the Python objects they make take many times the
body's size. In an intake process neither touches the server: it sends the body's bytes and gets back
the document as compact JSON text (what is stored and solved), or the problem to answer. The intake
processes' address space is capped like the solvers'.

:func:`prepare_tableau` and :func:`prepare_append` run in the intake process; :class:`Intake` is the
server's side.
"""

from __future__ import annotations

import asyncio
import json
import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Any

from pydantic import ValidationError

from ..errors import BootmapError


@dataclass(frozen=True)
class Limits:
    """The server's size limits a body is checked against (from its settings)."""

    max_steps: int
    max_image_len: int
    max_meta_bytes: int
    max_json_values: int


@dataclass(frozen=True)
class Prepared:
    document: str  # the tableau as JSON text, as stored and sent to the solver
    n_steps: int


# ---------------------------------------------------------------------------------------------------
# In the intake process
# ---------------------------------------------------------------------------------------------------

def _start(memory_mb: int, parent_pid: int) -> None:
    """An intake process starts: it ends with the server (``parent_pid``), its address space is capped."""
    import resource

    from .worker import exit_with_parent

    exit_with_parent(parent_pid)
    limit = memory_mb * 2**20
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def prepare_tableau(body: bytes, limits: Limits) -> tuple:
    """A posted tableau -> ("ok", Prepared) or ("problem", ...)."""
    from .models import TableauIn

    def run():
        doc = _validated(TableauIn, body, limits).model_dump(mode="json", exclude_unset=True)
        check_limits(doc["steps"], len(doc["steps"]), limits)
        return Prepared(json.dumps(doc), len(doc["steps"]))

    return _guarded(run)


def prepare_append(stored: str, stored_steps: int, body: bytes, limits: Limits) -> tuple:
    """Steps to append -> the whole new revision as ("ok", Prepared), or ("problem", ...); Tableau.extend
    checks the new steps against the stored ones, and errors name the request's fields."""
    from ..tableau import Tableau
    from .models import AppendIn

    def run():
        new = _validated(AppendIn, body, limits).model_dump(mode="json", exclude_unset=True)
        check_limits(new["steps"], stored_steps + len(new["steps"]), limits)
        doc = Tableau.loads(stored, "stored tableau").extend(new, "request").to_dict()
        return Prepared(json.dumps(doc), len(doc["steps"]))

    return _guarded(run)


def _validated(model: Any, body: bytes, limits: Limits) -> Any:
    from .problems import parse_json, validation_problem

    data = parse_json(body, limits.max_json_values)
    if isinstance(data, dict) and "meta" in data:  # before pydantic copies it
        size = len(json.dumps(data["meta"]))
        if size > limits.max_meta_bytes:
            from .problems import invalid

            raise invalid("meta", f"{size} bytes of JSON, more than this server's limit of {limits.max_meta_bytes} "
                                  "(BOOTMAP_MAX_META_BYTES): keep run information short", kind="too-large")
    try:
        # As FastAPI validates a body (from_attributes), so that errors are the same as for other routes.
        return model.model_validate(data, from_attributes=True)
    except ValidationError as e:
        raise validation_problem([{**err, "loc": ("body", *err["loc"])} for err in e.errors(include_url=False)]) \
            from None


def check_limits(steps: list[dict], total: int, limits: Any) -> None:
    """Steps and image lengths within the server's limits (``limits``: Limits or Settings)."""
    from .problems import invalid

    if total > limits.max_steps:
        raise invalid("steps", f"{total} steps, more than this server's limit of {limits.max_steps} "
                               "(BOOTMAP_MAX_STEPS)", kind="too-many-steps")
    for i, step in enumerate(steps):
        if len(step.get("image", ())) > limits.max_image_len:
            raise invalid(f"steps[{i}].image", f"{len(step['image'])} values, more than this server's limit of "
                                               f"{limits.max_image_len} (BOOTMAP_MAX_IMAGE_LEN)", kind="too-large")


def _guarded(run) -> tuple:
    from .problems import Problem, from_bootmap_error

    try:
        return "ok", run()
    except Problem as p:
        return _problem(p)
    except BootmapError as e:
        return _problem(from_bootmap_error(e))
    except MemoryError:
        return "problem", 413, "body-too-large", "Request body too large", \
            "the body needs more memory to parse than this server allows (BOOTMAP_INTAKE_MEMORY_MB)", None, {}


def _problem(p) -> tuple:
    # A Problem does not pickle (an HTTPException with its own constructor): send its parts.
    return "problem", p.status_code, p.kind, p.title, p.detail, p.headers, p.extensions


# ---------------------------------------------------------------------------------------------------
# In the server
# ---------------------------------------------------------------------------------------------------

class Intake:
    """``workers`` intake processes (spawned, address space capped at ``memory_mb`` MiB)."""

    def __init__(self, workers: int, memory_mb: int):
        self.workers, self.memory_mb = workers, memory_mb
        self._pool = self._new_pool()

    def _new_pool(self) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(self.workers, mp_context=multiprocessing.get_context("spawn"),
                                   initializer=_start, initargs=(self.memory_mb, os.getpid()))

    def warm(self) -> None:
        """Start every intake process and import the models, so the first request pays no start-up."""
        futures = [self._pool.submit(prepare_tableau, b"{}", Limits(1, 1, 2, 100)) for _ in range(self.workers)]
        for f in futures:
            f.result(timeout=120)

    def close(self) -> None:
        self._pool.shutdown(wait=False, cancel_futures=True)

    async def run(self, fn, *args) -> Prepared:
        """Run ``fn`` in an intake process; its problem is raised here."""
        from .problems import Problem

        try:
            reply = await asyncio.get_running_loop().run_in_executor(self._pool, fn, *args)
        except BrokenProcessPool:  # an intake process died (e.g. killed at its memory cap): start afresh
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = self._new_pool()
            raise Problem(413, "body-too-large", "Request body too large",
                          "the body could not be parsed within this server's intake memory "
                          "(BOOTMAP_INTAKE_MEMORY_MB)") from None
        if reply[0] == "ok":
            return reply[1]
        _, status, kind, title, detail, headers, extensions = reply
        raise Problem(status, kind, title, detail, headers=headers, **extensions)


def intake_workers() -> int:
    """One intake process per core, at most two: parsing is brief, and the solvers need the cores."""
    return max(1, min(2, os.cpu_count() or 1))
