"""A person's assertions about a stored tableau's map (bootmap.mapping.assertions): list them, say that two
time points (or dstates) are one dstate or not, take one back. Each change re-solves the map with the
assertions in force and stores it as the tableau's next revision; the answer says what changed. Where no
map honours them, 409 with the clash (the assertions, steps and axioms it needs) and nothing is stored.
Only the tableau's owner (or an admin) reads or changes them.
"""

from __future__ import annotations

import dataclasses
import json
import re
from typing import Annotated

from annotated_types import Ge, Le
from fastapi import Path

from fastapi import APIRouter, Request, Response
from fastapi.concurrency import run_in_threadpool

from ...errors import AssertionsError
from ...mapping.assertions import SOFT_COST, parse_assertions
from ..auth import CallerDep, writable
from ..deps import ServicesDep, TableauId
from ..models import AssertedOut, AssertionIn, AssertionList, AssertionOut
from ..problems import JSONRoute, Problem, invalid, openapi_responses
from ..store import AssertionRecord
from ..worker import StoredTableau
from .tableaux import _map_record

router = APIRouter(prefix="/tableaux/{tableau_id}/assertions", tags=["assertions"], route_class=JSONRoute)
CHANGE_ERRORS = openapi_responses(400, 401, 403, 404, 409, 415, 422, 429, 500, 503)
_DSTATE = re.compile(r"S[0-9]+")
AssertionId = Annotated[int, Ge(1), Le(2**63 - 1), Path(description="The assertion's id (GET lists them).")]


@router.get("", response_model=AssertionList, responses=openapi_responses(401, 403, 404, 422, 429),
            summary="A tableau's assertions")
async def list_assertions(tableau_id: TableauId, services: ServicesDep, caller: CallerDep) -> AssertionList:
    """What was said about the tableau's map, by whom and when, oldest first; ``held`` says whether the
    stored map does what each says (a soft one may have been broken). Only its owner or an admin may read
    them."""
    await writable(services, caller, tableau_id)
    records, dstate_of = await run_in_threadpool(_stored, services, tableau_id)
    return AssertionList(assertions=[_out(r, dstate_of) for r in records])


@router.post("", status_code=201, response_model=AssertedOut, responses=CHANGE_ERRORS,
             summary="Say two time points are one dstate, or not")
async def add_assertion(tableau_id: TableauId, body: AssertionIn, services: ServicesDep, caller: CallerDep,
                        request: Request) -> Response:
    """Add a person's assertion (``same``: a manual loop closure; ``apart``: a closure refused) and re-solve
    the map with every assertion in force. Time points are t3 or 3; a dstate (S4) stands for its first
    visit in the map as it stands. The answer is the new map and what changed (dstates, places and paths
    joined or split), stored as the tableau's next revision. 409 with ``conflict`` (the clashing
    assertions, the steps and the axioms, file and line) when no map honours them: nothing is stored."""
    record = await writable(services, caller, tableau_id)
    records, dstate_of = await run_in_threadpool(_stored, services, tableau_id)
    entry = _checked(body, record.n_steps, dstate_of)
    baseline = tuple(r.entry for r in records)
    solved, theory = await _solve(services, caller, request, tableau_id, baseline + (entry,), baseline)
    cmap = await run_in_threadpool(_map_record, solved, record.revision + 1, theory)
    kind = "same" if "same" in entry else "apart"
    made = await run_in_threadpool(services.store.add_assertion, tableau_id, kind, *entry[kind], entry["soft"],
                                   entry.get("cost", SOFT_COST), body.note, caller.name, cmap, caller.owner)
    return _answer(cmap, solved.diff, records + [made], made, status=201,
                   headers={"Location": f"/tableaux/{tableau_id}/assertions/{made.id}"})


@router.delete("/{assertion_id}", response_model=AssertedOut, responses=CHANGE_ERRORS,
               summary="Take an assertion back")
async def remove_assertion(tableau_id: TableauId, assertion_id: AssertionId, services: ServicesDep,
                           caller: CallerDep, request: Request) -> Response:
    """Remove an assertion and re-solve the map with the others; the answer is the new map and what
    changed, stored as the tableau's next revision."""
    record = await writable(services, caller, tableau_id)
    records, _ = await run_in_threadpool(_stored, services, tableau_id)
    if not any(r.id == assertion_id for r in records):
        raise Problem(404, "not-found", "No such assertion", f"tableau {tableau_id} has no assertion "
                      f"{assertion_id}; GET /tableaux/{tableau_id}/assertions lists them")
    rest = [r for r in records if r.id != assertion_id]
    solved, theory = await _solve(services, caller, request, tableau_id, tuple(r.entry for r in rest),
                                  tuple(r.entry for r in records))
    cmap = await run_in_threadpool(_map_record, solved, record.revision + 1, theory)
    await run_in_threadpool(services.store.delete_assertion, tableau_id, assertion_id, cmap, caller.owner)
    return _answer(cmap, solved.diff, rest, None)


# ---------------------------------------------------------------------------------------------------

def _stored(services, tableau_id: int) -> tuple[list[AssertionRecord], list[str]]:
    """The tableau's assertions and the dstate of each time point in its stored map."""
    records = services.store.assertions(tableau_id)
    document = json.loads(services.store.get_map(tableau_id).document)
    return records, [row["dstate"] for row in document["steps"]]


def _checked(body: AssertionIn, n_steps: int, dstate_of: list[str]) -> dict:
    """The assertion as a bootmap.assertions/1 entry of time points, or a 422 naming the field."""
    kind = "same" if body.same is not None else "apart"
    if (body.same is None) == (body.apart is None):
        raise invalid("", "say exactly one of 'same' or 'apart', with two time points", kind="invalid-request")
    points = []
    for i, point in enumerate(body.same if kind == "same" else body.apart):
        if isinstance(point, str) and _DSTATE.fullmatch(point):
            if point not in dstate_of:
                raise invalid(f"{kind}[{i}]", f"the map has no dstate {point} (it has S0..S{_last(dstate_of)})",
                              kind="invalid-request")
            point = dstate_of.index(point)
        points.append(point)
    entry = {kind: points, "soft": body.soft}
    if body.cost is not None:
        entry["cost"] = body.cost
    try:
        (said,) = parse_assertions([entry], n_steps)
    except AssertionsError as e:
        raise invalid(e.where.removeprefix("assertions: assertions[0].").removeprefix("assertions[0]."), e.reason,
                      kind="invalid-request") from None
    return {kind: [said.a, said.b], "soft": said.soft, **({"cost": said.cost} if said.soft else {})}


def _last(dstate_of: list[str]) -> int:
    return max(int(d[1:]) for d in dstate_of)


async def _solve(services, caller, request: Request, tableau_id: int, assertions: tuple, baseline: tuple):
    job, theory = services.job(StoredTableau(services.settings.database_url, tableau_id))
    job = dataclasses.replace(job, assertions=assertions, baseline=baseline)
    return await services.solve(job, caller.token_id, request), theory


def _out(record: AssertionRecord, dstate_of: list[str]) -> AssertionOut:
    pair = [f"t{record.a}", f"t{record.b}"]
    same = dstate_of[record.a] == dstate_of[record.b]
    return AssertionOut(id=record.id, same=pair if record.kind == "same" else None,
                        apart=pair if record.kind == "apart" else None, soft=record.soft,
                        cost=record.cost if record.soft else None, note=record.note, by=record.made_by,
                        at=record.created_at, held=same == (record.kind == "same"))


def _answer(cmap, diff: dict, records: list[AssertionRecord], made: AssertionRecord | None, status: int = 200,
            headers: dict | None = None) -> Response:
    """The new map (its stored text, as every read serves it), what changed and the assertions now."""
    dstate_of = [row["dstate"] for row in json.loads(cmap.document)["steps"]]
    head = {"assertion": None if made is None else _out(made, dstate_of).model_dump(mode="json"),
            "assertions": [_out(r, dstate_of).model_dump(mode="json") for r in records], "diff": diff}
    text = json.dumps(head)
    return Response(text[:-1] + ', "map": ' + cmap.document + "}", status_code=status, headers=headers,
                    media_type="application/json")
