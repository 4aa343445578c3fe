"""Maps of stored tableaux: the minimal map, its text table, the map as a graph file (GraphML, node-link JSON,
DOT), and every minimal map when there are several."""

from __future__ import annotations

import json
from typing import Annotated, Literal

from fastapi import APIRouter, Query, Response
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import PlainTextResponse

from ..auth import CallerDep, readable
from ..deps import ServicesDep, TableauId
from ..intake import export_stored
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


#: Graph format -> its media type (GraphML has no registered type of its own: it is XML).
GRAPH_MEDIA_TYPES = {"graphml": "application/xml", "json-graph": "application/json", "dot": "text/vnd.graphviz"}
GraphFormat = Annotated[Literal["graphml", "json-graph", "dot"], Query(
    alias="format", description="graphml: GraphML (Gephi, yEd, Cytoscape, networkx.read_graphml); json-graph: "
                                "networkx's node-link JSON (networkx.node_link_graph, d3); dot: Graphviz DOT.")]
GRAPH_RESPONSES = {200: {"description": "The map as a graph file in the format asked for.", "content": {
    "application/xml": {"schema": {"type": "string"}}, "application/json": {"schema": {"type": "object"}},
    "text/vnd.graphviz": {"schema": {"type": "string"}}}}, **READ_ERRORS}


@router.get("/map/graph", response_class=Response, responses=GRAPH_RESPONSES,
            summary="The map as a graph file: GraphML, node-link JSON or DOT")
async def read_map_graph(tableau_id: TableauId, services: ServicesDep, caller: CallerDep,
                         fmt: GraphFormat = "graphml") -> Response:
    """The map as a graph for graph tools (bootmap.mapping.export): dstates, places and paths are nodes
    (``kind`` tells them apart); the actions between dstates (``turn``/``travel``, the action's word and how
    many times it was taken), a dstate's place (``at``), a place on a path with its position along it
    (``on``, ``pos``) and the side of a path a place is on (``right_of``/``left_of``) are edges. The same
    file as `bootmap map --format FORMAT`."""
    await readable(services, caller, tableau_id)  # as /map: its owner, an admin, or public
    text = await services.intake.run(export_stored, services.settings.database_url, tableau_id, fmt)
    return Response(text, media_type=GRAPH_MEDIA_TYPES[fmt])


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
