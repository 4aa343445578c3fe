"""API tokens: an admin makes one for a new user (as `bootmap token create NAME` does), or revokes one."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Path, Response
from fastapi.concurrency import run_in_threadpool

from ..auth import AdminDep, digest, new_token
from ..deps import ServicesDep
from ..models import TokenCreated, TokenIn
from ..problems import JSONRoute, openapi_responses

router = APIRouter(prefix="/tokens", tags=["tokens"], route_class=JSONRoute)


@router.post("", status_code=201, response_model=TokenCreated,
             responses=openapi_responses(400, 401, 403, 409, 415, 422, 429), summary="Make an API token (admin)")
async def create_token(body: TokenIn, services: ServicesDep, admin: AdminDep) -> TokenCreated:
    """The token is in the answer, this once: only its SHA-256 is stored. 409 if the name is taken."""
    token = new_token()
    record = await run_in_threadpool(services.store.add_token, body.name, digest(token), body.admin)
    return TokenCreated(id=record.id, name=record.name, admin=record.admin, token=token)


@router.delete("/{name}", status_code=204, responses=openapi_responses(401, 403, 404, 422, 429),
               summary="Revoke an API token (admin)")
async def delete_token(name: Annotated[str, Path(pattern="^[A-Za-z0-9_.@-]{1,100}$")], services: ServicesDep,
                       admin: AdminDep) -> Response:
    """The token is refused from now on, by every server on the database. Its tableaux stay, owned by no
    one: only admins reach them."""
    await run_in_threadpool(services.store.delete_token, name)
    return Response(status_code=204)
