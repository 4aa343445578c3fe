"""The axioms: the files and named rules the service solves with, and reloading them after an edit."""

from __future__ import annotations

from fastapi import APIRouter
from fastapi.concurrency import run_in_threadpool

from ..auth import AdminDep
from ..deps import ServicesDep
from ..models import AxiomsOut
from ..problems import JSONRoute, openapi_responses

router = APIRouter(prefix="/axioms", tags=["axioms"], route_class=JSONRoute)


@router.get("", response_model=AxiomsOut, summary="The loaded axiom files and their rules")
def read_axioms(services: ServicesDep) -> AxiomsOut:
    """Every level (a top-level .lp file) and the core search files, with each rule named by a
    '%! name' comment: its name, line and text."""
    return AxiomsOut.model_validate(services.theories.current.listing())


@router.post("/reload", response_model=AxiomsOut, responses=openapi_responses(401, 403, 422, 429, 500),
             summary="Reload the axiom directory (admin)")
async def reload_axioms(services: ServicesDep, admin: AdminDep) -> AxiomsOut:
    """Read the axiom directory again after a user edited or added .lp files. A file that does not parse is
    refused with clingo's message (422) and the theory in use stays as it was. Only an admin may. Maps already stored keep
    the theory they were solved with (their ``theory`` field); new solves use the reloaded one."""
    loaded = await run_in_threadpool(services.theories.reload)
    return AxiomsOut.model_validate(loaded.listing())
