"""Tableaux: create one (it is solved at once), list them, read one, append steps to one.

A tableau is stored only with its map: when no map can be found (the tableau is inconsistent, the solve
runs past its limits, every solver is busy) the request fails and nothing is stored, so a stored tableau
always has a map. Appending is the same: the new revision is stored only once it is solved.
"""

from __future__ import annotations

import json
from typing import Annotated

from fastapi import APIRouter, Query, Response
from fastapi.concurrency import run_in_threadpool

from ...tableau import Tableau
from ..deps import Services, ServicesDep, TableauId
from ..models import AppendIn, MapOut, TableauCreated, TableauIn, TableauList, TableauListItem, TableauOut
from ..problems import JSONRoute, invalid, openapi_responses
from ..settings import Settings
from ..store import MapRecord, TableauRecord
from ..theory import LoadedTheory
from ..worker import Solved

router = APIRouter(prefix="/tableaux", tags=["tableaux"], route_class=JSONRoute)
SOLVE_ERRORS = openapi_responses(400, 413, 415, 422, 500, 503)


@router.post("", status_code=201, response_model=TableauCreated, responses=SOLVE_ERRORS,
             summary="Create a tableau and solve it")
async def create_tableau(body: TableauIn, services: ServicesDep) -> Response:
    """Store a tableau and return its id and its minimal map. Steps may carry view labels, or images only:
    then the images are clustered into views first (k-means, k chosen by the measure M), as `bootmap map`
    does. Fails with 422 when no map satisfies the axioms or the solve runs past its limits (nothing is
    stored then), and with 503 and Retry-After when every solver is busy."""
    doc = body.model_dump(mode="json", exclude_unset=True)
    _check_limits(doc["steps"], len(doc["steps"]), services.settings)
    solved, theory = await _solve(services, doc)  # the solver validates it with bootmap.tableau first
    cmap = await run_in_threadpool(_map_record, solved, 1, theory)
    record = await run_in_threadpool(services.store.add, json.dumps(doc), len(doc["steps"]), solved.views_k, cmap)
    return _with_map(record, cmap, status=201, headers={"Location": f"/tableaux/{record.id}"})


@router.get("", response_model=TableauList, responses=openapi_responses(422), summary="List stored tableaux")
def list_tableaux(services: ServicesDep, limit: Annotated[int, Query(ge=1, le=1000)] = 100,
                  offset: Annotated[int, Query(ge=0, le=2**62)] = 0) -> TableauList:
    total, rows = services.store.list(limit, offset)
    return TableauList(total=total, items=[
        TableauListItem(id=r.id, revision=r.revision, steps=r.n_steps, dstates=r.dstates, places=r.places,
                        paths=r.paths, updated=r.updated_at) for r in rows])


@router.get("/{tableau_id}", response_model=TableauOut, responses=openapi_responses(404, 422),
            summary="Read a stored tableau")
def read_tableau(tableau_id: TableauId, services: ServicesDep) -> Response:
    """The tableau as stored (images-only tableaux as posted; the views found are in its map)."""
    record = services.store.get(tableau_id)
    head = json.dumps(_info(record))
    # Validated when it was stored: its text is served as it is, not parsed and serialised again.
    return Response(head[:-1] + ', "tableau": ' + record.document + "}", media_type="application/json")


@router.post("/{tableau_id}/steps", response_model=TableauCreated, responses=openapi_responses(
    400, 404, 409, 413, 415, 422, 500, 503), summary="Append steps and solve again")
async def append_steps(tableau_id: TableauId, body: AppendIn, services: ServicesDep) -> Response:
    """Exploration went on: add steps after the stored ones (``action`` leads from the stored last step to
    the first new one), solve the whole tableau again and store it as the next revision. New steps are
    like the stored ones: view labels, or images only. 409 if another append got there first."""
    record = await run_in_threadpool(services.store.get, tableau_id)
    new = body.model_dump(mode="json", exclude_unset=True)
    _check_limits(new["steps"], record.n_steps + len(new["steps"]), services.settings)
    doc = await run_in_threadpool(_extended, record, new)
    solved, theory = await _solve(services, doc)
    cmap = await run_in_threadpool(_map_record, solved, record.revision + 1, theory)
    stored = await run_in_threadpool(services.store.replace, tableau_id, json.dumps(doc), len(doc["steps"]),
                                     solved.views_k, cmap)
    return _with_map(stored, cmap)


# ---------------------------------------------------------------------------------------------------

def _check_limits(steps: list[dict], total: int, settings: Settings) -> None:
    if total > settings.max_steps:
        raise invalid("steps", f"{total} steps, more than this server's limit of {settings.max_steps} "
                               "(BOOTMAP_MAX_STEPS)", kind="too-many-steps")
    for i, step in enumerate(steps):
        if len(step.get("image", ())) > settings.max_image_len:
            raise invalid(f"steps[{i}].image", f"{len(step['image'])} values, more than this server's limit of "
                                               f"{settings.max_image_len} (BOOTMAP_MAX_IMAGE_LEN)", kind="too-large")


async def _solve(services: Services, document: dict):
    job, theory = services.job(document)
    return await services.gate.solve(job), theory


def _map_record(solved: Solved, revision: int, theory: LoadedTheory) -> MapRecord:
    """The map as the API serves it, validated against its response model once, here: every response
    that carries it (create, append, read) serves this text."""
    m = MapOut.model_validate({**solved.map, "revision": revision, "theory": theory.id,
                               "views_from_images": solved.views_k})
    return MapRecord(revision, theory.id, m.summary.dstates, m.summary.places, m.summary.paths,
                     m.model_dump_json(), solved.text)


def _info(record: TableauRecord) -> dict:
    return {"id": record.id, "revision": record.revision, "steps": record.n_steps,
            "created": _iso(record.created_at), "updated": _iso(record.updated_at), "views_from_images": record.views_k}


def _iso(t) -> str:
    return t.isoformat().replace("+00:00", "Z")  # as pydantic writes UTC times


def _with_map(record: TableauRecord, cmap: MapRecord, status: int = 200, headers: dict | None = None) -> Response:
    """The tableau's information and its map (a TableauCreated), from the map's stored text."""
    head = json.dumps(_info(record))
    return Response(head[:-1] + ', "map": ' + cmap.document + "}", status_code=status, headers=headers,
                    media_type="application/json")


def _extended(record: TableauRecord, new: dict) -> dict:
    """The stored tableau with the new steps after it (Tableau.extend checks them; errors name the
    request's fields)."""
    return Tableau.loads(record.document, "stored tableau").extend(new, "request").to_dict()
