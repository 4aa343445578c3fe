"""Recognition: the dstate of a new image, by nearest neighbour over a stored tableau's labelled images."""

from __future__ import annotations

from fastapi import APIRouter

from ..auth import CallerDep, readable
from ..deps import ServicesDep, TableauId
from ..intake import recognise_stored
from ..models import RecogniseIn, Recognition
from ..problems import JSONRoute, openapi_responses

router = APIRouter(prefix="/tableaux/{tableau_id}", tags=["recognition"], route_class=JSONRoute)


@router.post("/recognise", response_model=Recognition, responses=openapi_responses(400, 401, 403, 404, 409, 413, 415, 422, 429),
             summary="Recognise the dstate of an image")
async def recognise(tableau_id: TableauId, body: RecogniseIn, services: ServicesDep,
                    caller: CallerDep) -> Recognition:
    """The map labels every stored image with its dstate; a new image gets the dstate of the nearest
    stored one (the paper's section 7), with the Euclidean distance to it: a large distance means an
    unfamiliar image. 409 if the tableau has no images."""
    await readable(services, caller, tableau_id)
    # Fitted (once per revision) and asked in an intake process, which reads the tableau itself.
    found = await services.intake.run(recognise_stored, services.settings.database_url, tableau_id, body.image)
    return Recognition(**found)
