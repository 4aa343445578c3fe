"""Rehearsal: the actions that tell a stored tableau's minimal maps apart (`bootmap rehearse`)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Query, Request

from ..auth import CallerDep, readable
from ..deps import ServicesDep, TableauId
from ..models import RehearsalOut
from ..problems import JSONRoute, openapi_responses
from ..worker import StoredTableau

router = APIRouter(prefix="/tableaux/{tableau_id}", tags=["rehearsals"], route_class=JSONRoute)


@router.get("/rehearsal", response_model=RehearsalOut, responses=openapi_responses(401, 403, 404, 422, 429, 500, 503),
            summary="What to do next when the minimal maps disagree")
async def rehearsal(tableau_id: TableauId, services: ServicesDep, caller: CallerDep, request: Request,
                    max_length: Annotated[int, Query(ge=1, le=20, description="Longest plan searched for.")] = 10
                    ) -> RehearsalOut:
    """The paper's rehearsal procedure: the shortest actions from where the robot is whose outcome the
    minimal maps predict differently, with what each map predicts along them; kind "nothing" when the
    map is unique."""
    await readable(services, caller, tableau_id)
    stored = StoredTableau(services.settings.database_url, tableau_id)  # the solver reads it
    rehearsed = await services.solve(services.rehearse_job(stored, max_length), caller.token_id, request)
    return RehearsalOut.model_validate({**rehearsed.plan, "text": rehearsed.text})
