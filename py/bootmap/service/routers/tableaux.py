"""Tableaux: create one (it is solved at once), list them, read one, append steps to one, publish or
delete one. Each belongs to the token that created it (docs/service.md, "Security").

A tableau is stored only with its map: when no map can be found (the tableau is inconsistent, the solve
runs past its limits, every solver is busy) the request fails and nothing is stored, so a stored tableau
always has a map. Appending is the same: the new revision is stored only once it is solved.
"""

from __future__ import annotations

import dataclasses
import json
from contextlib import asynccontextmanager
from typing import Annotated

from fastapi import APIRouter, Query, Request, Response
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import StreamingResponse
from starlette.background import BackgroundTask

from ..auth import Caller, CallerDep, check_read, writable
from ..deps import Services, ServicesDep, TableauId
from ..intake import PREPARED, prepare_append, prepare_tableau, store_prepared
from ..models import MapOut, TableauCreated, TableauList, TableauListItem, TableauOut, TableauSharing
from ..problems import JSONRoute, Problem, openapi_responses
from ..store import MapRecord, Stream, TableauRecord
from ..theory import LoadedTheory
from ..worker import Solved

router = APIRouter(prefix="/tableaux", tags=["tableaux"], route_class=JSONRoute)
SOLVE_ERRORS = openapi_responses(400, 401, 403, 413, 415, 422, 429, 500, 503)
READ_ERRORS = openapi_responses(401, 404, 422, 429)


def read_stream(services: Services, caller: Caller, tableau_id: int, what: str) -> Stream:
    """A stored text (``tableau``, ``map``, ``text``) the caller may read (else 404 before any of it is
    copied: a token that may not read a tableau costs the server no copy of it)."""
    return services.store.stream(tableau_id, what, lambda head: check_read(caller, head))


def streamed(stream: Stream, before: str = "", after: str = "", media_type: str = "application/json") -> Response:
    """A stored text as the response: at once when small, else streamed from its copy."""
    if stream.whole is not None:  # small: one response, no streaming
        return Response(before.encode() + stream.whole + after.encode(), media_type=media_type)

    def chunks():
        yield before.encode()
        yield from stream
        yield after.encode()

    return StreamingResponse(chunks(), media_type=media_type, background=BackgroundTask(stream.close))


def json_body(model: str) -> dict:
    """The OpenAPI request body of a route that reads its body itself (app._openapi adds the model)."""
    return {"requestBody": {"required": True, "content": {"application/json": {
        "schema": {"$ref": f"#/components/schemas/{model}"}}}}}


@asynccontextmanager
async def body_file(request: Request, services: Services):
    """The request's body, which must be JSON (415 otherwise; 422 if there is none), written to a file
    in this server's spool as it arrives, for an intake process to read: the server never holds it whole.
    The file, and the prepared document the intake writes beside it (intake.PREPARED), are removed after."""
    mime = request.headers.get("content-type", "").split(";")[0].strip().lower()
    fd, path = services.spool.new_file()
    try:
        with open(fd, "wb") as file:
            async for chunk in request.stream():
                file.write(chunk)
            empty = not file.tell()
        if empty:
            raise Problem(422, "invalid-request", "Invalid request", "the request needs a JSON body")
        if not (mime == "application/json" or (mime.startswith("application/") and mime.endswith("+json"))):
            raise Problem(415, "unsupported-media-type", "Send JSON",
                          "the body must be a JSON object sent with Content-Type: application/json")
        yield path
    finally:
        path.unlink(missing_ok=True)
        path.with_name(path.name + PREPARED).unlink(missing_ok=True)


@router.post("", status_code=201, response_model=TableauCreated, responses=SOLVE_ERRORS,
             openapi_extra=json_body("TableauIn"), summary="Create a tableau and solve it")
async def create_tableau(services: ServicesDep, caller: CallerDep, request: Request,
                         public: Annotated[bool, Query(description="Anyone may read it (not change it).")] = False
                         ) -> Response:
    """Store a tableau (TableauIn) and return its id and its minimal map. Steps may carry view labels, or
    images only: then the images are clustered into views first (k-means, k chosen by the measure M), as
    `bootmap map` does. Fails with 422 when no map satisfies the axioms or the solve runs past its limits
    (nothing is stored then), with 503 and Retry-After when every solver is busy, and with 429 when the
    token is over its limits. The tableau belongs to the caller's token."""
    # Parsed, checked and stored by an intake process (bootmap.service.intake): the server never holds the text.
    async with body_file(request, services) as body:
        prepared = await services.intake.run(prepare_tableau, body, services.limits)
        solved, theory = await _solve(services, prepared.document, caller, request)
        cmap = await run_in_threadpool(_map_record, solved, 1, theory)
        record = await services.intake.run(store_prepared, services.settings.database_url, prepared, solved.views_k,
                                           cmap, caller.token_id, services.settings.token_max_stored_bytes, public)
    return _with_map(record, cmap, status=201, headers={"Location": f"/tableaux/{record.id}"})


@router.get("", response_model=TableauList, responses=openapi_responses(401, 422, 429),
            summary="List stored tableaux")
def list_tableaux(services: ServicesDep, caller: CallerDep, limit: Annotated[int, Query(ge=1, le=1000)] = 100,
                  offset: Annotated[int, Query(ge=0, le=2**62)] = 0) -> TableauList:
    """The caller's tableaux and the public ones (an admin's: every one)."""
    total, rows = services.store.list(limit, offset, caller.token_id, everyone=caller.admin)
    return TableauList(total=total, items=[
        TableauListItem(id=r.id, revision=r.revision, steps=r.n_steps, dstates=r.dstates, places=r.places,
                        paths=r.paths, updated=r.updated_at) for r in rows])


@router.get("/{tableau_id}", response_model=TableauOut, responses=READ_ERRORS, summary="Read a stored tableau")
def read_tableau(tableau_id: TableauId, services: ServicesDep, caller: CallerDep) -> Response:
    """The tableau as stored (images-only tableaux as posted; the views found are in its map)."""
    stream = read_stream(services, caller, tableau_id, "tableau")
    head = json.dumps(_info(stream.head))
    # Validated when it was stored: its text is streamed as it is, in chunks, never parsed or held whole.
    return streamed(stream, head[:-1] + ', "tableau": ', "}")


@router.delete("/{tableau_id}", status_code=204, responses=READ_ERRORS, summary="Delete a tableau and its map")
async def delete_tableau(tableau_id: TableauId, services: ServicesDep, caller: CallerDep) -> Response:
    """Only its owner or an admin may; the bytes it took count no more against the owner's quota."""
    await writable(services, caller, tableau_id)
    await run_in_threadpool(services.store.delete, tableau_id, caller.owner)
    return Response(status_code=204)


@router.put("/{tableau_id}/sharing", response_model=TableauSharing, responses=openapi_responses(
    400, 401, 403, 404, 415, 422, 429), summary="Make a tableau public or private")
async def share_tableau(tableau_id: TableauId, body: TableauSharing, services: ServicesDep,
                        caller: CallerDep) -> TableauSharing:
    """A public tableau (and its maps) may be read by anyone; only its owner or an admin changes it."""
    await writable(services, caller, tableau_id)
    await run_in_threadpool(services.store.set_public, tableau_id, body.public, caller.owner)
    return body


@router.post("/{tableau_id}/steps", response_model=TableauCreated, responses=openapi_responses(
    400, 401, 403, 404, 409, 413, 415, 422, 429, 500, 503), openapi_extra=json_body("AppendIn"),
    summary="Append steps and solve again")
async def append_steps(tableau_id: TableauId, services: ServicesDep, caller: CallerDep, request: Request) -> Response:
    """Exploration went on: add steps (AppendIn) after the stored ones (``action`` leads from the stored
    last step to the first new one), bring the map up to date and store it as the next revision: the map
    a fresh solve would give, found by extending the last one where the new steps repeat known ones
    (bootmap.mapping.stream), else by solving the whole tableau again. New
    steps are like the stored ones: view labels, or images only. 409 if another append got there first;
    403 unless the caller owns the tableau."""
    await writable(services, caller, tableau_id)
    async with body_file(request, services) as body:  # the intake process reads the stored tableau itself
        prepared = await services.intake.run(prepare_append, services.settings.database_url, tableau_id, body,
                                             services.limits)
        # the assertions in force: the new revision's map honours them (read at the revision the store
        # checks: a change to them makes a revision of its own)
        said = tuple(r.entry for r in await run_in_threadpool(services.store.assertions, tableau_id))
        solved, theory = await _solve(services, prepared.document, caller, request, stream=tableau_id,
                                      assertions=said)
        cmap = await run_in_threadpool(_map_record, solved, prepared.extends + 1, theory)
        # The owner and the revision read above are checked again by the statement that stores the new
        # revision: if the tableau was deleted meanwhile, 404; if another append got there first, 409.
        stored = await services.intake.run(store_prepared, services.settings.database_url, prepared, solved.views_k,
                                           cmap, caller.owner, services.settings.token_max_stored_bytes,
                                           tableau_id=tableau_id)
    return _with_map(stored, cmap)


# ---------------------------------------------------------------------------------------------------

async def _solve(services: Services, document: str, caller: Caller, request: Request, stream: int | None = None,
                 assertions: tuple[dict, ...] = ()):
    job, theory = services.job(document, stream)
    if assertions:
        job = dataclasses.replace(job, assertions=assertions)
    return await services.solve(job, caller.token_id, request), theory


def _map_record(solved: Solved, revision: int, theory: LoadedTheory) -> MapRecord:
    """The map as the API serves it, validated against its response model once, here: every response
    that carries it (create, append, read) serves this text."""
    m = MapOut.model_validate({**solved.map, "revision": revision, "theory": theory.id,
                               "views_from_images": solved.views_k})
    return MapRecord(revision, theory.id, m.summary.dstates, m.summary.places, m.summary.paths,
                     m.model_dump_json(), solved.text)


def _info(record: TableauRecord) -> dict:
    return {"id": record.id, "revision": record.revision, "steps": record.n_steps,
            "created": _iso(record.created_at), "updated": _iso(record.updated_at), "views_from_images": record.views_k,
            "public": record.public}


def _iso(t) -> str:
    return t.isoformat().replace("+00:00", "Z")  # as pydantic writes UTC times


def _with_map(record: TableauRecord, cmap: MapRecord, status: int = 200, headers: dict | None = None) -> Response:
    """The tableau's information and its map (a TableauCreated), from the map's stored text."""
    head = json.dumps(_info(record))
    return Response(head[:-1] + ', "map": ' + cmap.document + "}", status_code=status, headers=headers,
                    media_type="application/json")
