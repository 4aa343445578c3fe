"""Recognition: the dstate of a new image, by nearest neighbour over a stored tableau's labelled images."""

from __future__ import annotations

import json

from fastapi import APIRouter
from fastapi.concurrency import run_in_threadpool

from ...tableau import Tableau
from ..auth import CallerDep, readable
from ..deps import Services, ServicesDep, TableauId
from ..models import RecogniseIn, Recognition
from ..problems import JSONRoute, Problem, invalid, openapi_responses

router = APIRouter(prefix="/tableaux/{tableau_id}", tags=["recognition"], route_class=JSONRoute)


@router.post("/recognise", response_model=Recognition, responses=openapi_responses(400, 401, 403, 404, 409, 413, 415, 422, 429),
             summary="Recognise the dstate of an image")
async def recognise(tableau_id: TableauId, body: RecogniseIn, services: ServicesDep,
                    caller: CallerDep) -> Recognition:
    """The map labels every stored image with its dstate; a new image gets the dstate of the nearest
    stored one (the paper's section 7), with the Euclidean distance to it: a large distance means an
    unfamiliar image. 409 if the tableau has no images."""
    await readable(services, caller, tableau_id)
    return await run_in_threadpool(_recognise, services, tableau_id, body.image)


def _recognise(services: Services, tableau_id: int, image: list[float]) -> Recognition:
    model, dstates = _model(services, tableau_id)
    if len(image) != model.n_features_in_:
        raise invalid("image", f"has {len(image)} values; the images of tableau {tableau_id} have "
                               f"{model.n_features_in_}", kind="invalid-request")
    labels, distances = model.predict_with_distance([image])
    dstate = str(labels[0])
    return Recognition(dstate=dstate, distance=float(distances[0]), view=dstates[dstate]["view"],
                       place=dstates[dstate]["place"])


def _model(services: Services, tableau_id: int):
    """The recogniser of the tableau's current revision (fitted once, then cached) and its dstates."""
    store = services.store
    for _ in range(5):  # an append may land between the two reads: then read again
        record, stored_map = store.get(tableau_id), store.get_map(tableau_id)
        if stored_map.revision == record.revision:
            return services.recognisers.get((tableau_id, record.revision),
                                            lambda: _fit(record.document, stored_map.document))
    raise Problem(409, "conflict", "Tableau changing", f"tableau {tableau_id} is being appended to; retry")


def _fit(tableau_json: str, map_json: str):
    from ...recognise import NoImages, recogniser_for_map  # scikit-learn: imported on the first recognition only

    m = json.loads(map_json)
    try:
        model = recogniser_for_map(Tableau.loads(tableau_json, "stored tableau"), [row["dstate"] for row in m["steps"]])
    except NoImages as e:
        raise Problem(409, "no-images", "The tableau has no images", str(e)) from None
    return model, m["dstates"]
