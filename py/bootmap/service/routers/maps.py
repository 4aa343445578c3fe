"""Maps of stored tableaux: the minimal map, its text table, and every minimal map when there are several."""

from __future__ import annotations

import json

from fastapi import APIRouter, Response
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import PlainTextResponse

from ..auth import CallerDep, readable
from ..deps import ServicesDep, TableauId
from ..models import MapOut, MinimalMap, MinimalMaps
from ..problems import JSONRoute, openapi_responses
from .tableaux import read_stream, streamed

router = APIRouter(prefix="/tableaux/{tableau_id}", tags=["maps"], route_class=JSONRoute)
READ_ERRORS = openapi_responses(401, 404, 422, 429)


@router.get("/map", response_model=MapOut, responses=READ_ERRORS, summary="The tableau's minimal map")
def read_map(tableau_id: TableauId, services: ServicesDep, caller: CallerDep) -> Response:
    """Dstates, places and paths; which places are on which path, their order along it, and which side of
    a path a place is on; and every step annotated with its dstate, place, path and direction, like the
    paper's table (6)."""
    # Stored as the API serves it (validated when solved), so a read is a lookup, streamed in chunks.
    return streamed(read_stream(services, caller, tableau_id, "map"))


@router.get("/map/text", response_class=PlainTextResponse, responses=READ_ERRORS,
            summary="The annotated tableau as text")
def read_map_text(tableau_id: TableauId, services: ServicesDep, caller: CallerDep) -> Response:
    """The map as `bootmap map` prints it: a summary line, then t, view, dstate, place, path, dir and action
    for every step, then the paths and sides."""
    return streamed(read_stream(services, caller, tableau_id, "text"), media_type="text/plain; charset=utf-8")


@router.get("/maps", response_model=MinimalMaps, responses=READ_ERRORS, summary="Every minimal map")
async def read_minimal_maps(tableau_id: TableauId, services: ServicesDep, caller: CallerDep) -> MinimalMaps:
    """When the experience does not tell some dstates apart, several maps with the fewest dstates explain
    it: each is given as the dstate of every time point (the first is the one /map describes)."""
    await readable(services, caller, tableau_id)
    return await run_in_threadpool(_minimal_maps, services.store.get_map(tableau_id).document)


def _minimal_maps(document: str) -> MinimalMaps:
    m = json.loads(document)
    sequences = [[row["dstate"] for row in m["steps"]]] + m["alternatives"]
    summary = m["summary"]
    return MinimalMaps(unique=summary["unique"], capped=summary["minimal_maps_capped"],
                       maps=[MinimalMap(dstates=len(set(seq)), dstate_of=seq) for seq in sequences])
