"""The drawing of a stored tableau's map (what the viewer draws): places in the plane, and the map itself.

The layout is computed here, on the server, from the map and its tableau (:mod:`bootmap.layout`), so the
same map is drawn the same way by every browser. The viewer polls this resource to follow appended steps:
it sends the ETag it has (``If-None-Match``) and gets ``304 Not Modified`` until the tableau's revision
changes, which costs the server one read of the stored map and no layout.
"""

from __future__ import annotations

import json
from typing import Literal

from fastapi import APIRouter, Request, Response
from pydantic import Field

from ...layout import layout
from ..auth import CallerDep, check_read
from ..deps import Services, ServicesDep, TableauId
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


@router.get("/layout", response_model=Drawing, responses={**openapi_responses(401, 403, 404, 422, 429), 304: {
    "description": "The revision named by If-None-Match is still the current one."}},
            summary="The map laid out for drawing (the viewer's data)")
def read_layout(tableau_id: TableauId, services: ServicesDep, caller: CallerDep, request: Request) -> Response:
    """The map and where to draw its places, dstates and paths (and the true trajectory when the steps
    have poses). ETag: the revision and the theory; with a matching If-None-Match, 304 and no body."""
    check_read(caller, services.store.head(tableau_id))  # as /map: its owner, an admin, or public
    cmap = services.store.get_map(tableau_id)
    etag = f'"r{cmap.revision}-{cmap.theory}"'
    if etag in request.headers.get("if-none-match", ""):
        return Response(status_code=304, headers={"ETag": etag})
    drawing = _drawing(services, tableau_id, cmap.document)
    return Response(drawing, media_type="application/json", headers={"ETag": etag, "Cache-Control": "no-cache"})


def _drawing(services: Services, tableau_id: int, map_document: str) -> str:
    # Read after the map: if an append lands between the two reads, the tableau has more steps than the
    # map, and the layout reads only the map's (their first steps are the same).
    record = services.store.get(tableau_id)
    m = json.loads(map_document)
    head = json.dumps({"id": tableau_id, "revision": m["revision"],
                       "layout": layout(m, json.loads(record.document))})
    # The map as stored (validated when it was solved): served as it is, not serialised again.
    return head[:-1] + ', "map": ' + map_document + "}"

