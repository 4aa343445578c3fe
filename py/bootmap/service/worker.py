"""Solves in worker processes that can be stopped for sure: a deadline, a memory cap, a bounded number.

clingo cannot interrupt grounding from inside the process, and a hostile tableau can ground for far
longer than the resolver's time limit, or grow to gigabytes. So each solve runs in a long-lived solver
process (forked from the server's forkserver, not from the server, which has threads:
:func:`helper_context`) whose address space is capped with RLIMIT_AS.
The resolver's own time limit (SolveTimeout, with the dstates proved necessary) ends most slow solves;
a process still busy ``kill_grace_s`` after it is killed and replaced. Images-only tableaux are
clustered into views in the solver process too, under the same deadline; explanations
(:class:`ExplainJob`, bootmap.mapping.explain) run there the same way.

:class:`SolverPool` is the blocking pool; :class:`SolveGate` is its front for the event loop: at most
``running`` solves at once (in threads, off the loop), at most ``waiting`` more in line, and beyond that
:class:`SolverBusy` at once (the service answers 503 with Retry-After).
"""

from __future__ import annotations

import logging
import os
import queue
import signal
import threading
import time
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Awaitable, Callable

from ..errors import (AssertionConflict, AxiomError, BootmapError, ExplainError, InconsistentTableau, SolveTimeout,
                      TableauError)
from ..proc import parent_gone, preloaded_context
from ..tableau import Tableau

log = logging.getLogger("bootmap.service")
READY_TIMEOUT_S = 60.0  # for a new solver to say it is ready: generous for a loaded machine
CANCEL_POLL_S = 0.1  # how often a waiting solve looks whether its client went away
#: What the server's solver and intake processes import, once, in the forkserver they are forked from
#: (:func:`bootmap.proc.preloaded_context`). Spawned, each imported them itself: a new solver answered its
#: first paper's tableau after 0.36 s (0.09 s forked; again for every solver replaced after a kill), an
#: intake process took 0.7 s of CPU to start.
HELPER_PRELOAD = ["bootmap.mapping.api", "bootmap.service.worker", "bootmap.service.intake", "bootmap.service.models"]
PARENT_POLL_S = 0.5  # how often a solver or intake process looks whether the server is still there


def helper_context():
    """The multiprocessing context the server starts its solver and intake processes with."""
    return preloaded_context(HELPER_PRELOAD)


class SolverBusy(BootmapError):
    """Every solver is busy and the line of waiting solves is full."""

    def __init__(self, message: str, retry_after_s: int):
        self.retry_after_s = retry_after_s
        super().__init__(message)


class SolverKilled(SolveTimeout):
    """The solver was still busy (e.g. grounding, which clingo cannot interrupt) at the hard deadline."""

    def __init__(self, message: str, time_limit_s: float):
        self.time_limit_s = time_limit_s
        super().__init__(message)


class SolverOutOfMemory(BootmapError):
    """The solve needed more memory than the solver's cap."""


class SolverCrashed(BootmapError):
    """The solver process died or failed unexpectedly (a bug: it is logged)."""


class SolveCancelled(BootmapError):
    """The client went away: its solve was stopped and the solver freed."""


@dataclass(frozen=True)
class StoredTableau:
    """A stored tableau, which the solver reads from the database itself: the server need not hold its
    text to ask a question about it."""

    url: str
    tableau_id: int


@dataclass(frozen=True)
class SolveJob:
    """What a solver needs: the tableau document and the theory snapshot to solve it with. The solver
    validates the document (bootmap.tableau, against the JSON Schema): that takes longer than many solves,
    and is better spent in a solver process than under the server's GIL."""

    document: dict | str | Path | StoredTableau  # the tableau, its JSON text, a file of it, or where it is stored
    axioms: str
    time_limit_s: float
    quantum_deg: float | None = None
    max_models: int = 10
    stream: int | None = None  # a stored tableau's id: its map is kept current as steps are appended
    # A person's assertions (bootmap.assertions/1 entries, time points): the map honours them. ``baseline``,
    # when a request changes them, is the assertions before: the reply then says what changed.
    assertions: tuple[dict, ...] = ()
    baseline: tuple[dict, ...] | None = None


@dataclass(frozen=True)
class ExplainJob:
    """A question about a stored tableau: are time points (or dstates) ``a`` and ``b`` one dstate, and
    why? Solved like a map, in a solver process under the same deadline and memory cap."""

    document: dict | str | StoredTableau
    axioms: str
    time_limit_s: float
    a: str
    b: str
    levels: tuple[str, ...] | None = None
    quantum_deg: float | None = None
    assertions: tuple[dict, ...] = ()  # the stored tableau's: questions are about the map that honours them


@dataclass(frozen=True)
class RehearseJob:
    """What to do next when a stored tableau's minimal maps disagree (`bootmap rehearse`)."""

    document: dict | str | StoredTableau
    axioms: str
    time_limit_s: float
    max_length: int = 10
    quantum_deg: float | None = None


@dataclass(frozen=True)
class Rehearsed:
    plan: dict            # Plan.to_dict()
    text: str             # Plan.to_text(), as `bootmap rehearse` prints it
    seconds: float


@dataclass(frozen=True)
class Explained:
    explanation: dict     # Explanation.to_dict()
    text: str             # Explanation.to_text(), as `bootmap why` prints it
    seconds: float


@dataclass(frozen=True)
class Solved:
    map: dict             # CognitiveMap.to_dict()
    text: str             # CognitiveMap.to_text(): the annotated tableau, as `bootmap map` prints it
    views_k: int | None   # views found by clustering images, or None when the tableau had labels
    seconds: float
    diff: dict | None = None  # MapDiff.to_dict(): what changing the assertions changed (SolveJob.baseline)


# ---------------------------------------------------------------------------------------------------
# Inside the solver process
# ---------------------------------------------------------------------------------------------------

def exit_with_parent(parent_pid: int) -> None:
    """End this process as soon as the server that started it (``parent_pid``) is gone.

    A server killed outright (SIGKILL, the OOM killer) closes nothing: its solver and intake processes
    would live on, each with its memory, and keep multiprocessing's resource tracker alive too (it ends
    once no process holds its pipe). A daemon thread polls :func:`bootmap.proc.parent_gone`: the
    process's parent (the server's forkserver, which ends with the server) changes when it dies. (Not
    prctl's PR_SET_PDEATHSIG: that fires when the *thread* that started the process ends, and solvers are
    replaced from short-lived pool threads.) ``parent_pid`` is the server's pid as it started the
    process, so a server that died before this runs is noticed too.

    The process's address space is capped (RLIMIT_AS), and glibc would give the thread a malloc arena of
    its own, 64 MiB of address space it never uses: glibc is told to keep every thread of this process
    in one arena (M_ARENA_MAX), and the thread gets a small stack."""
    first_parent = os.getppid()

    def watch() -> None:
        while not parent_gone(parent_pid, first_parent):
            time.sleep(PARENT_POLL_S)
        os._exit(1)

    try:
        import ctypes

        ctypes.CDLL(None).mallopt(-8, 1)  # M_ARENA_MAX = 1 (glibc's malloc.h)
    except (OSError, AttributeError):  # not glibc: its malloc has no such arenas
        pass
    previous = threading.stack_size(256 * 1024)
    try:
        threading.Thread(target=watch, name="bootmap-parent-watch", daemon=True).start()
    finally:
        threading.stack_size(previous)


def _serve(conn, memory_mb: int, parent_pid: int) -> None:
    """The solver process: end with the server, cap memory, import the solver, then answer jobs until
    told to stop."""
    exit_with_parent(parent_pid)
    limit = memory_mb * 2**20
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = "1"  # one solve per process; BLAS thread pools would only reserve memory
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C on the server: the server stops its solvers
    from ..mapping import api  # noqa: F401  (warm: the first job should not pay for the import; forked
    # from the forkserver, it is there already)

    conn.send("ready")
    cache: dict = {}
    while True:
        try:
            job = conn.recv()
        except (EOFError, OSError):
            return
        if job is None:
            return
        try:
            conn.send(_run(job, cache))
        except OSError:  # the server is gone (an idle solver learns it from the pipe closing, above)
            return


Job = SolveJob | ExplainJob | RehearseJob


def _run(job: Job, cache: dict) -> tuple:
    """One job -> ("ok", Solved | Explained) or a tagged error tuple (exceptions with custom fields do not
    pickle)."""
    try:
        if isinstance(job, ExplainJob):
            return _explain(job, cache)
        return _rehearse(job, cache) if isinstance(job, RehearseJob) else _solve(job, cache)
    except TableauError as e:
        return "tableau", e.reason, e.where
    except AxiomError as e:
        return "axioms", str(e)
    except MemoryError:  # clingo's bad_alloc under RLIMIT_AS, in the solve or in naming the failing levels
        return ("memory",)
    except Exception:  # a bug: report it, keep serving
        return "crash", traceback.format_exc()


def _solve(job: SolveJob, cache: dict) -> tuple:
    from ..mapping import Deadline

    start = time.perf_counter()
    deadline = Deadline.after(job.time_limit_s)  # validation and clustering count against it too
    try:
        tableau, k = _views(_tableau(job.document))
        mapper = _mapper(cache, job.axioms, None, job.quantum_deg, job.max_models)
        if job.assertions or job.baseline is not None:
            return _asserted(job, mapper, tableau, k, deadline, start)
        # A stored tableau's stream: the same map as a fresh one, sooner when the steps repeat what this
        # solver saw last time (bootmap.mapping.stream).
        stream = None if job.stream is None else _cached(
            cache, ("stream", job.axioms, job.quantum_deg, job.max_models, job.stream), mapper.stream)
        cmap = mapper.map(tableau, deadline, stream)
        # Questions about this tableau (the viewer's first click) need not resolve it again in this solver.
        mapper.remember(tableau, cmap)
        return "ok", Solved(cmap.to_dict(), cmap.to_text(), k, time.perf_counter() - start)
    except InconsistentTableau as e:  # the resolver names the failing levels within the same deadline
        return "inconsistent", str(e), e.failing_levels, e.diagnosed
    except SolveTimeout as e:
        return "timeout", str(e), e.lower_bound, e.best_map


def _asserted(job: SolveJob, mapper, tableau: Tableau, k: int | None, deadline, start: float) -> tuple:
    """The map that honours the job's assertions (and, when they changed, what changed), or the clash."""
    from ..mapping.assertions import parse_assertions

    said = parse_assertions(list(job.assertions), len(tableau))
    try:
        if job.baseline is None:
            cmap, diff = mapper.map(tableau, deadline, assertions=said), None
        else:
            baseline = parse_assertions(list(job.baseline), len(tableau))
            before = mapper.map(tableau, deadline, assertions=baseline)
            result = mapper.honour(tableau, said, deadline, before=before, baseline=baseline)
            if result.conflict is not None:
                raise AssertionConflict(result.conflict.sentence, result.conflict)
            cmap, diff = result.after, result.diff.to_dict()
    except AssertionConflict as e:
        return "conflict", str(e), e.conflict.to_dict(), e.conflict.to_text()
    return "ok", Solved(cmap.to_dict(), cmap.to_text(), k, time.perf_counter() - start, diff)


def _explain(job: ExplainJob, cache: dict) -> tuple:
    from ..mapping import Deadline

    start = time.perf_counter()
    deadline = Deadline.after(job.time_limit_s)
    try:
        tableau, _ = _views(_tableau(job.document))
        said = _said(job.assertions, tableau)
        e = _mapper(cache, job.axioms, job.levels, job.quantum_deg).explain(tableau, job.a, job.b, deadline, said)
        return "ok", Explained(e.to_dict(), e.to_text(), time.perf_counter() - start)
    except ExplainError as e:
        return "question", str(e)
    except InconsistentTableau as e:
        return "inconsistent", str(e), e.failing_levels, e.diagnosed
    except SolveTimeout as e:
        return "timeout", str(e), e.lower_bound, None


def _rehearse(job: RehearseJob, cache: dict) -> tuple:
    from ..mapping import Deadline

    start = time.perf_counter()
    deadline = Deadline.after(job.time_limit_s)
    try:
        tableau, _ = _views(_tableau(job.document))
        plan = _mapper(cache, job.axioms, None, job.quantum_deg).rehearse(tableau, job.max_length, deadline=deadline)
        return "ok", Rehearsed(plan.to_dict(), plan.to_text(), time.perf_counter() - start)
    except InconsistentTableau as e:
        return "inconsistent", str(e), e.failing_levels, e.diagnosed
    except SolveTimeout as e:
        return "timeout", str(e), e.lower_bound, None


def _said(assertions: tuple[dict, ...], tableau: Tableau) -> list:
    if not assertions:
        return []
    from ..mapping.assertions import parse_assertions

    return parse_assertions(list(assertions), len(tableau))


def _mapper(cache: dict, axioms: str, levels: tuple[str, ...] | None, quantum_deg: float | None,
            max_models: int = 10):
    """This solver's :class:`~bootmap.mapping.api.Mapper` for a theory and settings, kept: loading a theory
    parses every file, and its explainer keeps the maps it was told of. Each job passes its own deadline."""
    from ..mapping.api import Mapper

    return _cached(cache, ("mapper", axioms, levels, quantum_deg, max_models),
                   lambda: Mapper(axioms=axioms, levels=levels, quantum_deg=quantum_deg, max_models=max_models))


def _tableau(document: dict | str | Path | StoredTableau) -> Tableau:
    if isinstance(document, Path):  # a prepared document the server did not read (intake.PREPARED)
        document = document.read_text()
    elif isinstance(document, StoredTableau):
        from .store import store_at

        document = store_at(document.url).get(document.tableau_id).document
    return Tableau.loads(document, "tableau") if isinstance(document, str) else Tableau.from_dict(document, "tableau")


def _views(tableau: Tableau) -> tuple[Tableau, int | None]:
    if tableau.labelled:
        return tableau, None
    from ..views import tableau_with_views  # scikit-learn: only for images-only tableaux

    return tableau_with_views(tableau)


def _cached(cache: dict, key: tuple, make):
    """A mapper (or a stored tableau's stream) for the job's theory, kept."""
    if key not in cache:
        if len(cache) > 16:
            cache.clear()
        cache[key] = make()
    return cache[key]


# ---------------------------------------------------------------------------------------------------
# In the server
# ---------------------------------------------------------------------------------------------------

class _Worker:
    """One solver process and the pipe to it."""

    def __init__(self, ctx, memory_mb: int):
        self.conn, child = ctx.Pipe()
        self.process = ctx.Process(target=_serve, args=(child, memory_mb, os.getpid()), name="bootmap-solver",
                                   daemon=True)
        self.process.start()
        child.close()
        self.ready = False

    def alive(self) -> bool:
        return self.process.is_alive()

    def run(self, job: SolveJob, hard_deadline_s: float, cancel: threading.Event | None = None) -> tuple:
        """Send the job and wait for the reply, at most ``hard_deadline_s``; ``cancel`` set meanwhile
        (the client went away) kills the solver at once: clingo cannot be interrupted any other way."""
        if not self.ready:
            self._await_ready()
        self.conn.send(job)
        deadline = time.monotonic() + hard_deadline_s
        while not self.conn.poll(min(CANCEL_POLL_S, max(0.0, deadline - time.monotonic()))):
            if cancel is not None and cancel.is_set():
                self.kill()
                raise SolveCancelled("the client went away; its solve was stopped")
            if time.monotonic() >= deadline:
                self.kill()
                raise SolverKilled(f"the solver was stopped at the deadline of {hard_deadline_s:g} s (this server's "
                                   f"time limit of {job.time_limit_s:g} s plus grace), still busy: clingo cannot "
                                   "interrupt grounding, and this tableau grounds for longer than that",
                                   job.time_limit_s)
        try:
            return self.conn.recv()
        except (EOFError, OSError):
            self.process.join(timeout=2)  # its exit code
            code = self.process.exitcode
            self.kill()
            if code in (-signal.SIGABRT, 127):
                # Under the address-space cap an allocation that fails outside Python ends the process:
                # glibc exits 127 when a solve thread's thread-local data cannot be allocated; Rust's
                # allocator and an uncaught std::bad_alloc abort. The solve ran out of memory, as when
                # clingo raises it.
                log.warning("solver process %s aborted during a solve: out of memory", self.process.pid)
                return ("memory",)
            log.error("solver process %s died during a solve (exit code %s)", self.process.pid, code)
            raise SolverCrashed("the solver process died during the solve (the server log says how)") from None

    def _await_ready(self) -> None:
        if not self.conn.poll(READY_TIMEOUT_S) or self.conn.recv() != "ready":
            self.kill()
            raise SolverCrashed("a solver process did not start")
        self.ready = True

    def kill(self) -> None:
        self.process.kill()
        self.process.join(5)
        self.conn.close()

    def stop(self) -> None:
        try:
            self.conn.send(None)
        except OSError:
            pass
        self.process.join(2)
        if self.process.is_alive():
            self.kill()


class SolverPool:
    """``size`` solver processes, each capped at ``memory_mb`` MiB. :meth:`solve` blocks until one is free."""

    def __init__(self, size: int, memory_mb: int, kill_grace_s: float = 2.0):
        self._ctx = helper_context()
        self.size, self.memory_mb, self.kill_grace_s = size, memory_mb, kill_grace_s
        self._idle: queue.Queue[_Worker] = queue.Queue()
        self._workers: list[_Worker] = []
        self._lock = threading.Lock()
        self.busy = 0
        self.closed = False
        for _ in range(size):
            self._idle.put(self._spawn())

    def _spawn(self) -> _Worker:
        w = _Worker(self._ctx, self.memory_mb)
        with self._lock:
            self._workers = [x for x in self._workers if x.alive()] + [w]
        return w

    def alive(self) -> int:
        with self._lock:
            return sum(w.alive() for w in self._workers)

    def solve(self, job: Job, cancel: threading.Event | None = None) -> Solved | Explained | Rehearsed:
        """Solve (or explain) in a free solver; raises bootmap's exceptions (see :func:`_outcome`), and
        SolveCancelled if ``cancel`` is set before the reply."""
        worker = self._idle.get()
        with self._lock:
            self.busy += 1
        try:
            if cancel is not None and cancel.is_set():
                raise SolveCancelled("the client went away before its solve started")
            reply = worker.run(job, job.time_limit_s + self.kill_grace_s, cancel)
            if reply[0] == "memory":
                # After clingo's bad_alloc the process's heap is full and fragmented: whether it can start
                # its next solve's thread depends on where the allocation failed. A fresh solver can.
                worker.stop()
        finally:
            with self._lock:
                self.busy -= 1
            if not self.closed:  # no new solver after shutdown
                self._idle.put(worker if worker.alive() else self._spawn())
        return _outcome(reply, self.memory_mb)

    def warm(self, job: SolveJob) -> None:
        """Run ``job`` once in every solver, so that the first real solve pays no start-up."""
        workers = [self._idle.get() for _ in range(self.size)]
        try:
            for w in workers:
                _outcome(w.run(job, READY_TIMEOUT_S + job.time_limit_s), self.memory_mb)
        finally:
            for w in workers:
                self._idle.put(w if w.alive() else self._spawn())

    def close(self) -> None:
        with self._lock:
            self.closed = True
            workers, self._workers = self._workers, []
        for w in workers:
            w.stop()


def _outcome(reply: tuple, memory_mb: int) -> Solved | Explained | Rehearsed:
    kind, *rest = reply
    if kind == "ok":
        return rest[0]
    if kind == "inconsistent":
        raise InconsistentTableau(rest[0], failing_levels=tuple(rest[1]), diagnosed=rest[2])
    if kind == "timeout":
        raise SolveTimeout(rest[0], lower_bound=rest[1], best_map=rest[2])
    if kind == "tableau":
        raise TableauError(rest[0], rest[1])
    if kind == "axioms":
        raise AxiomError(rest[0])
    if kind == "question":
        raise ExplainError(rest[0])
    if kind == "conflict":
        raise AssertionConflict(rest[0], conflict=rest[1], text=rest[2])
    if kind == "memory":
        raise SolverOutOfMemory(f"the solve needed more than this server's solver memory of {memory_mb} MiB "
                                "(BOOTMAP_SOLVER_MEMORY_MB)")
    log.error("solver failed:\n%s", rest[0])
    raise SolverCrashed("the solver failed on this tableau (the server log has the details)")


class SolveGate:
    """The event loop's door to the pool: at most ``running`` solves at once (in threads, off the loop),
    at most ``waiting`` more in line, and beyond that :class:`SolverBusy` at once.

    Fair share between callers: one caller (a token) runs at most ``per_caller`` solves at once however
    many it sends, so a solver stays free for the others; when a solver frees, the longest-waiting solve
    whose caller is under that bound starts. Callers are keys (a token id, or None for the local user,
    who is alone and not bounded)."""

    def __init__(self, pool: SolverPool, running: int, waiting: int, retry_after_s: int,
                 per_caller: int | None = None):
        self.pool, self.running, self.capacity, self.retry_after_s = pool, running, running + waiting, retry_after_s
        self.per_caller = per_caller or max(1, running // 2)
        self.admitted = 0  # touched only from the event loop thread: no lock needed
        self._line: list[tuple[int, Any]] = []  # (ticket, caller) of solves waiting, in arrival order
        self._started: dict[Any, int] = {}  # caller -> solves running
        self._tickets = 0
        self._changed: Any = None

    @property
    def waiting(self) -> int:
        return len(self._line)

    def _next(self) -> int | None:
        """The ticket that may start now: the first in line whose caller is under its bound."""
        if sum(self._started.values()) >= self.running:
            return None
        for ticket, caller in self._line:
            if caller is None or self._started.get(caller, 0) < self.per_caller:
                return ticket
        return None

    async def _start(self, caller: Any) -> None:
        import anyio

        if self._changed is None:  # made in the loop that uses it
            self._changed = anyio.Condition()
        self._tickets += 1
        ticket = self._tickets
        async with self._changed:
            self._line.append((ticket, caller))
            try:
                while self._next() != ticket:
                    await self._changed.wait()
            except BaseException:  # cancelled (the client went away): the line moves on without it
                self._line.remove((ticket, caller))
                self._changed.notify_all()
                raise
            self._line.remove((ticket, caller))
            self._started[caller] = self._started.get(caller, 0) + 1

    async def _end(self, caller: Any) -> None:
        import anyio

        self._started[caller] -= 1
        if not self._started[caller]:
            del self._started[caller]
        with anyio.CancelScope(shield=True):
            async with self._changed:
                self._changed.notify_all()

    async def solve(self, job: Job, gone: Callable[[], Awaitable[None]] | None = None,
                    caller: Any = None) -> Solved | Explained:
        """Solve in the pool. ``gone`` returns when the client has gone away: then a waiting solve leaves
        the line at once and a running one is stopped (its solver killed and replaced), and
        SolveCancelled is raised."""
        import anyio

        if self.admitted >= self.capacity:
            raise SolverBusy(f"all {self.running} solvers are busy and {self.capacity - self.running} solves are "
                             f"waiting; retry in {self.retry_after_s} s", self.retry_after_s)
        self.admitted += 1
        cancel = threading.Event()
        outcome: list = []  # the result, or the exception (raised outside the task group, unwrapped)
        try:
            async with anyio.create_task_group() as tg:
                async def watch() -> None:
                    await gone()
                    cancel.set()  # a running solve: its thread kills the solver and returns at once
                    tg.cancel_scope.cancel()  # a waiting one: it leaves the line

                if gone is not None:
                    tg.start_soon(watch)
                await self._start(caller)
                try:
                    outcome.append(await anyio.to_thread.run_sync(self.pool.solve, job, cancel))
                except Exception as e:
                    outcome.append(e)
                finally:
                    await self._end(caller)
                tg.cancel_scope.cancel()
        finally:
            self.admitted -= 1
        if not outcome:
            raise SolveCancelled("the client went away; its solve was stopped")
        if isinstance(outcome[0], Exception):
            raise outcome[0]
        return outcome[0]
