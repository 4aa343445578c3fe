"""Health and the tableau format's JSON Schema."""

from __future__ import annotations

from fastapi import APIRouter
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import JSONResponse

from ... import __version__
from ...tableau import schema
from ..deps import ServicesDep
from ..models import Health
from ..problems import JSONRoute, Problem, openapi_responses

router = APIRouter(tags=["health"], route_class=JSONRoute)


@router.get("/health", response_model=Health, responses=openapi_responses(503), summary="Is the service up?")
async def health(services: ServicesDep) -> Health:
    """200 when the database answers and the solvers are up; 503 (problem details) otherwise."""
    try:
        await run_in_threadpool(services.store.ping)
    except Exception as e:  # any driver error means the same thing here: the database is not reachable
        raise Problem(503, "unhealthy", "Database unreachable", f"the database does not answer: {e}",
                      headers={"Retry-After": "5"}) from None
    alive = services.pool.alive()
    if alive == 0:
        raise Problem(503, "unhealthy", "No solver", "no solver process is running", headers={"Retry-After": "5"})
    gate = services.gate
    return Health(status="ok", version=__version__, theory=services.theories.current.id, solvers=alive,
                  solves_running=services.pool.busy, solves_waiting=gate.waiting)


@router.get("/schemas/tableau-1.schema.json", summary="JSON Schema of the tableau format",
            response_class=JSONResponse, responses={200: {"content": {"application/schema+json": {}}}})
def tableau_schema() -> JSONResponse:
    """The single source of truth for tableau documents (``bootmap.tableau/1``), as `bootmap schema` prints it."""
    return JSONResponse(schema(), media_type="application/schema+json")
