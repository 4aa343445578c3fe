"""The drawing of a stored tableau's map (what the viewer draws): places in the plane, and the map itself.

The layout is computed here, on the server, from the map and its tableau (:mod:`bootmap.layout`), so the
same map is drawn the same way by every browser. The viewer polls this resource to follow appended steps:
it sends the ETag it has (``If-None-Match``) and gets ``304 Not Modified`` until the tableau's revision
changes, which costs the server two short reads (the tableau's owner, the map's revision) and no layout.
"""

from __future__ import annotations

from typing import Literal

from fastapi import APIRouter, Request, Response
from fastapi.concurrency import run_in_threadpool
from pydantic import Field

from ..auth import CallerDep, readable
from ..deps import ServicesDep, TableauId
from ..intake import draw_stored
from ..models import MapOut, Out
from ..problems import JSONRoute, openapi_responses

router = APIRouter(prefix="/tableaux/{tableau_id}", tags=["viewer"], route_class=JSONRoute)

Point = list[float]


class PlaceDrawn(Out):
    xy: Point = Field(description="Position, metres in the robot's frame (S0 faces +x), y up.")
    dstates: list[str]


class DstateDrawn(Out):
    xy: Point = Field(description="A little way from its place, towards its heading.")
    place: str | None


class PathDrawn(Out):
    places: list[str] = Field(description="Its places in pos order.")
    points: list[Point]


class Layout(Out):
    method: Literal["metrical", "odometry", "graph"] = Field(
        description="metrical: least squares of the travels along the dstates' headings; odometry: each place "
                    "at the mean of its visits' dead-reckoned poses (the travels do not close, the steps carry "
                    "odometry: a log); graph: multidimensional scaling of travel distances (no headings, or the "
                    "travels do not close).")
    closure_rms_m: float | None = Field(description="RMS residual of the metrical fit, metres (null: no headings).")
    places: dict[str, PlaceDrawn] = Field(description="Places (dstates when the map has no places).")
    dstates: dict[str, DstateDrawn]
    paths: dict[str, PathDrawn]
    trajectory: list[Point] | None = Field(description="The true [x, y] of every step with a pose, in the "
                                                       "poses' frame, to draw beside the map.")
    bounds: list[float] = Field(description="[xmin, ymin, xmax, ymax] of the places and dstates.")


class Drawing(Out):
    id: int
    revision: int
    layout: Layout
    map: MapOut


@router.get("/layout", response_model=Drawing, responses={**openapi_responses(401, 404, 422, 429), 304: {
    "description": "The revision named by If-None-Match is still the current one."}},
            summary="The map laid out for drawing (the viewer's data)")
async def read_layout(tableau_id: TableauId, services: ServicesDep, caller: CallerDep, request: Request) -> Response:
    """The map and where to draw its places, dstates and paths (and the true trajectory when the steps
    have poses). ETag: the tableau (which a new tableau never shares), its revision and the theory; with a
    matching If-None-Match, 304 and no body."""
    head = await readable(services, caller, tableau_id)  # as /map: its owner, an admin, or public
    _, theory = await run_in_threadpool(services.store.map_head, tableau_id)
    etag = f'"{head.key}-{theory}"'
    if etag in request.headers.get("if-none-match", ""):
        return Response(status_code=304, headers={"ETag": etag})
    # Laid out in an intake process, which reads the tableau and its map itself (intake.draw_stored).
    drawing = await services.intake.run(draw_stored, services.settings.database_url, tableau_id)
    return Response(drawing, media_type="application/json", headers={"ETag": etag, "Cache-Control": "no-cache"})
