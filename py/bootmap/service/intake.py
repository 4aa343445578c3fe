"""Intake: request bodies of tableaux parsed, checked and turned into stored JSON text in a separate process;
and the other work that must parse a whole stored tableau (the viewer's layout, recognition), done there too.

Parsing JSON and validating it with pydantic are C and Rust calls that hold Python's GIL from start to
end: a 16 MB body holds it for a second or more, so in a thread of the server they would still stall
every other request (``/health`` included), and the Python objects they make take many times the
body's size. In an intake process neither touches the server: it sends the body's bytes and gets back
the document as compact JSON text (what is stored and solved), or the problem to answer. The intake
processes' address space is capped like the solvers'.

Drawing a stored map (:func:`draw_stored`) and recognising an image against a stored tableau
(:func:`recognise_stored`) parse the whole tableau as well, and exporting a map as a graph file
(:func:`export_stored`) parses the whole map: they read it from the database in the intake process, and
hand the server only their answer. The fitted recognisers are kept there too. So the server's memory
does not grow with the size or the number of stored tableaux read at once.

Once solved, the prepared text is stored from the intake process too (:func:`store_prepared`): the
server never holds a tableau's text.

:func:`prepare_tableau`, :func:`prepare_append`, :func:`store_prepared`, :func:`draw_stored`,
:func:`export_stored` and :func:`recognise_stored` run in the intake process; :class:`Intake` is the
server's side.
"""

from __future__ import annotations

import asyncio
import dataclasses
import functools
import json
import os
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from ..errors import BootmapError
from .store import store_at


@dataclass(frozen=True)
class Limits:
    """The server's size limits a body is checked against (from its settings)."""

    max_steps: int
    max_image_len: int
    max_meta_bytes: int
    max_json_values: int


@dataclass(frozen=True)
class Prepared:
    # The tableau as JSON text, as stored and sent to the solver; for a body read from a file, the file
    # beside it that holds that text (PREPARED), so that the server need not hold it while it is solved.
    document: str | Path
    n_steps: int
    extends: int = 0  # for an append: the stored revision it extends


PREPARED = ".prepared"  # suffix of the prepared document's file, beside the body's


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


def prepare_tableau(body: bytes | Path, limits: Limits) -> tuple:
    """A posted tableau (its bytes, or the file the server wrote them to) -> ("ok", Prepared) or
    ("problem", ...)."""
    from .models import TableauIn

    def run():
        doc = _validated(TableauIn, _bytes(body), limits).model_dump(mode="json", exclude_unset=True)
        check_limits(doc["steps"], len(doc["steps"]), limits)
        return Prepared(_text_for(body, json.dumps(doc)), len(doc["steps"]))

    return _guarded(run)


def prepare_append(url: str, tableau_id: int, body: bytes | Path, limits: Limits) -> tuple:
    """Steps to append to a stored tableau (read from the database here) -> the whole new revision as
    ("ok", Prepared), naming the revision it extends, or ("problem", ...); Tableau.extend checks the new
    steps against the stored ones, and errors name the request's fields."""
    from ..tableau import Tableau
    from .models import AppendIn

    def run():
        new = _validated(AppendIn, _bytes(body), limits).model_dump(mode="json", exclude_unset=True)
        stored = store_at(url).get(tableau_id)
        check_limits(new["steps"], stored.n_steps + len(new["steps"]), limits)
        doc = Tableau.loads(stored.document, "stored tableau").extend(new, "request").to_dict()
        return Prepared(_text_for(body, json.dumps(doc)), len(doc["steps"]), stored.revision)

    return _guarded(run)


def store_prepared(url: str, prepared: Prepared, views_k: int | None, cmap, owner: int | None, max_bytes: int,
                   public: bool = False, tableau_id: int | None = None) -> tuple:
    """Store a solved tableau: a new one (``tableau_id`` None; ``owner`` its token id) or the next revision
    of ``tableau_id`` (``owner`` the caller's, ANY for an admin: checked by the statement that writes).
    The prepared text is read and written here: the server never holds it. -> ("ok", TableauRecord
    without its document)."""
    def run():
        store, document = store_at(url), prepared.document
        text = document.read_text() if isinstance(document, Path) else document
        if tableau_id is None:
            record = store.add(text, prepared.n_steps, views_k, cmap, owner, max_bytes, public)
        else:
            record = store.replace(tableau_id, text, prepared.n_steps, views_k, cmap, owner, max_bytes)
        return dataclasses.replace(record, document="")

    return _guarded(run)


def _bytes(body: bytes | Path) -> bytes:
    return body.read_bytes() if isinstance(body, Path) else body


def _text_for(body: bytes | Path, document: str) -> str | Path:
    """The prepared document, in a file beside the body's when the body came in a file."""
    if not isinstance(body, Path):
        return document
    out = body.with_name(body.name + PREPARED)
    out.write_text(document)
    return out


def draw_stored(url: str, tableau_id: int) -> tuple:
    """The viewer's drawing of a stored tableau's map (GET /tableaux/{id}/layout) -> ("ok", JSON text).
    Read from the database here: the tableau and its map are parsed in this process, never the server's."""
    from ..layout import layout

    def run():
        store = store_at(url)
        record, cmap = store.get(tableau_id), store.get_map(tableau_id)
        # If an append landed between the two reads, the tableau has more steps than the map: the layout
        # reads only the map's (their first steps are the same).
        m = json.loads(cmap.document)
        head = json.dumps({"id": tableau_id, "revision": m["revision"],
                           "layout": layout(m, json.loads(record.document))})
        del record, m
        # The map as stored (validated when it was solved): served as it is, not serialised again.
        return head[:-1] + ', "map": ' + cmap.document + "}"

    return _guarded(run, STORED_TOO_LARGE)


def export_stored(url: str, tableau_id: int, fmt: str) -> tuple:
    """A stored tableau's map as a graph file (GET /tableaux/{id}/map/graph) -> ("ok", its text), in one of
    :data:`bootmap.mapping.export.FORMATS`. The map is parsed and the graph built in this process, never
    the server's."""
    from ..mapping.export import write

    def run():
        return write(json.loads(store_at(url).get_map(tableau_id).document), fmt)

    return _guarded(run, STORED_TOO_LARGE)


def recognise_stored(url: str, tableau_id: int, image: list[float]) -> tuple:
    """The dstate of an image by nearest neighbour over a stored tableau's images labelled by its map
    (POST /tableaux/{id}/recognise) -> ("ok", dict). The recogniser is fitted here, once per revision of
    the tableau (:func:`_fitted`), and kept in this process, never the server's."""
    from .problems import Problem, invalid

    def run():
        store = store_at(url)
        for _ in range(5):  # an append may land between the reads: then read again
            try:
                fitted = _fitted(url, tableau_id, store.head(tableau_id).key)
                break
            except _Moved:
                continue
        else:
            raise Problem(409, "conflict", "Tableau changing", f"tableau {tableau_id} is being appended to; retry")
        model, dstates = fitted
        if len(image) != model.n_features_in_:
            raise invalid("image", f"has {len(image)} values; the images of tableau {tableau_id} have "
                                   f"{model.n_features_in_}", kind="invalid-request")
        labels, distances = model.predict_with_distance([image])
        dstate = str(labels[0])
        return {"dstate": dstate, "distance": float(distances[0]), "view": dstates[dstate]["view"],
                "place": dstates[dstate]["place"]}

    return _guarded(run, STORED_TOO_LARGE)


class _Moved(Exception):
    """The tableau changed between two reads."""


@functools.lru_cache(maxsize=2)
def _fitted(url: str, tableau_id: int, key: str):
    """The recogniser of the tableau revision ``key`` (TableauRecord.key: a new tableau never has the same)
    and the map's dstates; :class:`_Moved` (not cached) if the tableau is no longer at that revision."""
    from ..recognise import NoImages, recogniser_for_map
    from ..tableau import Tableau
    from .problems import Problem

    store = store_at(url)
    record, cmap = store.get(tableau_id), store.get_map(tableau_id)
    if record.key != key or cmap.revision != record.revision:
        raise _Moved()
    m = json.loads(cmap.document)
    try:
        model = recogniser_for_map(Tableau.loads(record.document, "stored tableau"), [row["dstate"] for row in m["steps"]])
    except NoImages as e:
        raise Problem(409, "no-images", "The tableau has no images", str(e)) from None
    return model, m["dstates"]


def _validated(model: Any, body: bytes, limits: Limits) -> Any:
    from .problems import parse_json, validation_problem

    data = parse_json(body, limits.max_json_values)
    if isinstance(data, dict) and "meta" in data:  # before pydantic copies it
        from .problems import invalid

        size = len(json.dumps(data["meta"]))
        if size > limits.max_meta_bytes:
            raise invalid("meta", f"{size} bytes of JSON, more than this server's limit of {limits.max_meta_bytes} "
                                  "(BOOTMAP_MAX_META_BYTES): keep run information short", kind="too-large")
        where = _huge_integer(data["meta"], "meta")
        if where is not None:
            raise invalid(where, "an integer beyond 64 bits, which other JSON readers cannot hold; send it as a "
                                 "string", kind="invalid-request")
    try:
        # As FastAPI validates a body (from_attributes), so that errors are the same as for other routes.
        return model.model_validate(data, from_attributes=True)
    except ValidationError as e:
        raise validation_problem([{**err, "loc": ("body", *err["loc"])} for err in e.errors(include_url=False)]) \
            from None


def _huge_integer(x: Any, where: str) -> str | None:
    """Where in ``x`` an integer lies outside 64 bits (None: nowhere)."""
    if isinstance(x, int) and not isinstance(x, bool):
        return where if not -2**63 <= x < 2**63 else None
    items = x.items() if isinstance(x, dict) else enumerate(x) if isinstance(x, list) else ()
    for k, v in items:
        found = _huge_integer(v, f"{where}[{k}]" if isinstance(k, int) else f"{where}.{k}")
        if found is not None:
            return found
    return None


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


BODY_TOO_LARGE = ("problem", 413, "body-too-large", "Request body too large",
                  "the body needs more memory to parse than this server allows (BOOTMAP_INTAKE_MEMORY_MB)", None, {})
STORED_TOO_LARGE = ("problem", 422, "too-large", "Tableau too large",
                    "the stored tableau needs more memory for this than this server allows "
                    "(BOOTMAP_INTAKE_MEMORY_MB)", None, {})


def _guarded(run, too_large: tuple = BODY_TOO_LARGE) -> tuple:
    from .problems import Problem, from_bootmap_error

    try:
        return "ok", run()
    except Problem as p:
        return _problem(p)
    except BootmapError as e:
        return _problem(from_bootmap_error(e))
    except MemoryError:
        _fitted.cache_clear()  # what this process keeps goes first: the next request may fit
        return too_large


def _problem(p) -> tuple:
    # A Problem does not pickle (an HTTPException with its own constructor): send its parts.
    return "problem", p.status_code, p.kind, p.title, p.detail, p.headers, p.extensions


# ---------------------------------------------------------------------------------------------------
# In the server
# ---------------------------------------------------------------------------------------------------

class Intake:
    """``workers`` intake processes (forked from the server's forkserver, address space capped at
    ``memory_mb`` MiB)."""

    def __init__(self, workers: int, memory_mb: int):
        self.workers, self.memory_mb = workers, memory_mb
        self._pool = self._new_pool()

    def _new_pool(self) -> ProcessPoolExecutor:
        from .worker import helper_context

        return ProcessPoolExecutor(self.workers, mp_context=helper_context(),
                                   initializer=_start, initargs=(self.memory_mb, os.getpid()))

    def warm(self) -> None:
        """Start every intake process and import the models, so the first request pays no start-up."""
        futures = [self._pool.submit(prepare_tableau, b"{}", Limits(1, 1, 2, 100)) for _ in range(self.workers)]
        for f in futures:
            f.result(timeout=120)

    def close(self) -> None:
        self._pool.shutdown(wait=False, cancel_futures=True)

    async def run(self, fn, *args, **kwargs) -> Any:
        """Run ``fn`` in an intake process; its problem is raised here."""
        from .problems import Problem

        try:
            reply = await asyncio.get_running_loop().run_in_executor(self._pool, functools.partial(fn, *args, **kwargs))
        except BrokenProcessPool:  # an intake process died (e.g. killed at its memory cap): start afresh
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = self._new_pool()
            reply = BODY_TOO_LARGE if fn in (prepare_tableau, prepare_append) else STORED_TOO_LARGE
        if reply[0] == "ok":
            return reply[1]
        _, status, kind, title, detail, headers, extensions = reply
        raise Problem(status, kind, title, detail, headers=headers, **extensions)


def intake_workers() -> int:
    """One intake process per core, at most two: parsing is brief, and the solvers need the cores."""
    return max(1, min(2, os.cpu_count() or 1))
