"""Explanations: why two dstates of a stored tableau differ, or why they are the same (`bootmap why`)."""

from __future__ import annotations

import dataclasses
from typing import Annotated

from fastapi import APIRouter, Query, Request
from fastapi.concurrency import run_in_threadpool

from ...errors import AxiomError
from ...mapping.theory import select_levels
from ..auth import CallerDep, readable
from ..deps import ServicesDep, TableauId
from ..models import ExplanationOut
from ..problems import JSONRoute, invalid, openapi_responses
from ..worker import StoredTableau

router = APIRouter(prefix="/tableaux/{tableau_id}", tags=["explanations"], route_class=JSONRoute)

# A time point (t4 or 4) or a dstate name of the map (S4).
POINT = r"^(t?[0-9]{1,9}|S[0-9]{1,9})$"
Point = Annotated[str, Query(pattern=POINT, description="A time point (t4 or 4) or a dstate (S4).")]


@router.get("/why", response_model=ExplanationOut, responses=openapi_responses(401, 403, 404, 422, 429, 500, 503),
            summary="Why two dstates differ, or why they are the same")
async def why(tableau_id: TableauId, a: Point, b: Point, services: ServicesDep, caller: CallerDep, request: Request,
              levels: Annotated[str | None, Query(pattern=r"^[a-z][a-z0-9_]*(,[a-z][a-z0-9_]*)*$",
                                                  description="Levels to use, e.g. causal,topological "
                                                              "(default: all); a pair may have a proof at "
                                                              "each.")] = None) -> ExplanationOut:
    """If every minimal map keeps a and b apart: a subset-minimal set of steps that alone forces them
    apart, the axioms the contradiction needs, and the chain of rule instances (each citing its
    '%! name', file and line) from those steps to the failing axiom. If they are the same: why
    (minimality) and what experience would test it. If minimal maps disagree: which of them keep a and b
    apart. Dstate names (S4) are those of the minimal map with the chosen levels."""
    chosen = _levels(levels, services)
    await readable(services, caller, tableau_id)
    stored = StoredTableau(services.settings.database_url, tableau_id)  # the solver reads it
    # about the map as stored: the one that honours the owner's assertions
    said = tuple(r.entry for r in await run_in_threadpool(services.store.assertions, tableau_id))
    job = dataclasses.replace(services.explain_job(stored, a, b, chosen), assertions=said)
    explained = await services.solve(job, caller.token_id, request)
    return ExplanationOut.model_validate({**explained.explanation, "text": explained.text})


def _levels(levels: str | None, services) -> tuple[str, ...] | None:
    if levels is None:
        return None
    try:
        return tuple(select_levels(levels.split(","), list(services.theories.current.theory.levels)))
    except AxiomError as e:
        raise invalid("levels", str(e), kind="invalid-request") from None
