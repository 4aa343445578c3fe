"""Who is calling, and may they: API tokens, owners of tableaux, and the guard against other web sites.

A token is ``bm_`` and 43 random URL-safe characters (256 bits), sent as ``Authorization: Bearer``. Only
its SHA-256 is stored: a token with that much entropy needs no slow hash, and a stolen database gives no
usable token. ``bootmap token create NAME`` (or an admin's ``POST /tokens``) makes one and shows it once.

Without tokens (the default on loopback, one user on a laptop) every request is the :data:`LOCAL` caller,
who may do everything. When tokens are required (``--require-tokens``, or listening on anything but
loopback) a request without a valid token gets 401, and each tableau belongs to the token that created it.

:class:`Guard`, the outermost middleware, refuses a Host header the server does not answer to (DNS
rebinding) and a state-changing request that a browser says comes from another site (a cross-site form
or ``fetch`` needs no preflight when it sends no custom header).
"""

from __future__ import annotations

import hashlib
import re
import secrets
from dataclasses import dataclass
from typing import Annotated

from fastapi import Depends, Request
from fastapi.concurrency import run_in_threadpool
from starlette.types import ASGIApp, Receive, Scope, Send

from ..errors import BootmapError
from .deps import Services
from .problems import Problem, from_bootmap_error, not_found, problem_response
from .store import ANY, TableauRecord

PREFIX = "bm_"


def new_token() -> str:
    return PREFIX + secrets.token_urlsafe(32)


def digest(token: str) -> str:
    return hashlib.sha256(token.encode()).hexdigest()


@dataclass(frozen=True)
class Caller:
    """Who makes a request: a token (its id and name), or the local user when tokens are off."""

    token_id: int | None
    name: str
    admin: bool

    def owns(self, record: TableauRecord) -> bool:
        return self.admin or (self.token_id is not None and record.owner_id == self.token_id)

    @property
    def owner(self) -> int | None:
        """Whose tableaux this caller's writes may touch: its token's (a token id), or ANY (an admin)."""
        return ANY if self.admin else self.token_id


LOCAL = Caller(None, "local", admin=True)


def unauthorized(detail: str) -> Problem:
    return Problem(401, "unauthorized", "Token needed", detail, headers={"WWW-Authenticate": "Bearer"})


def forbidden(detail: str) -> Problem:
    return Problem(403, "forbidden", "Not allowed", detail)


def _bearer(header: str | None) -> str | None:
    if header is None:
        return None
    scheme, _, token = header.partition(" ")
    if scheme.lower() != "bearer" or not token.strip():
        raise unauthorized("the Authorization header must be 'Bearer <token>'")
    return token.strip()


NEEDS_TOKEN = ("this server needs an API token: send 'Authorization: Bearer <token>' "
               "(an admin makes one with 'bootmap token create NAME')")


async def authenticate(services: Services, authorization: str | None) -> Caller:
    """Who sends this Authorization header (401 if nobody the server knows); a token holder's request is
    counted against its per-minute limit (429 beyond; in memory: a request writes nothing to the database
    for it, service/quotas.py). Called by :class:`Guard`, before any body is read."""
    token = _bearer(authorization)
    if token is None:
        if services.settings.tokens_required:
            raise unauthorized(NEEDS_TOKEN)
        return LOCAL
    record = await run_in_threadpool(services.store.token_by_digest, digest(token))
    if record is None:
        raise unauthorized("this token is not known to the server (mistyped, or made for another database)")
    services.quotas.count_request(record.id)
    return Caller(record.id, record.name, record.admin)


def get_caller(request: Request) -> Caller:
    """The caller :class:`Guard` authenticated for this request."""
    caller = request.scope.get("state", {}).get("caller")
    if caller is None:  # a route on an open path asked for a caller: it has none
        raise unauthorized(NEEDS_TOKEN)
    return caller


CallerDep = Annotated[Caller, Depends(get_caller)]


async def get_admin(caller: CallerDep) -> Caller:
    if not caller.admin:
        raise forbidden(f"only an admin token may do this; token {caller.name!r} is not one")
    return caller


AdminDep = Annotated[Caller, Depends(get_admin)]


async def readable(services: Services, caller: Caller, tableau_id: int) -> TableauRecord:
    """The tableau's record (no document) if the caller may read it: its owner, an admin, or anyone when
    it is public; else 404, as if it did not exist (a 403 would tell who may not read it that it does)."""
    record = await run_in_threadpool(services.store.head, tableau_id)
    check_read(caller, record)
    return record


def check_read(caller: Caller, record: TableauRecord) -> None:
    if not (record.public or caller.owns(record)):
        raise not_found(record.id)


async def writable(services: Services, caller: Caller, tableau_id: int) -> TableauRecord:
    """The tableau's record if the caller may change it (append, delete, publish): its owner or an admin;
    404 if the caller may not even read it, 403 if it may read it (public) but not change it. The write
    itself checks the owner again, in the statement that writes (``Caller.owner``)."""
    record = await readable(services, caller, tableau_id)
    if not caller.owns(record):
        raise forbidden(f"tableau {tableau_id} belongs to another token; only its owner or an admin may change it")
    return record


# ---------------------------------------------------------------------------------------------------
# Host and cross-site guard (ASGI middleware, outermost)
# ---------------------------------------------------------------------------------------------------

SAFE_METHODS = {"GET", "HEAD", "OPTIONS"}
# What anyone may read without a token, even when tokens are required.
OPEN_PATHS = {"/health", "/docs", "/docs/oauth2-redirect", "/redoc", "/openapi.json", "/axioms",
              "/schemas/tableau-1.schema.json", "/"}
# The map viewer's page and files: no data in them, and the page asks for the token itself.
OPEN_PREFIXES = ("/viewer/",)


def host_allowed(host: str, allowed: list[str]) -> bool:
    """As Starlette's TrustedHostMiddleware matches: exact names, '*.domain' for subdomains, '*' for any;
    the port is ignored. IPv6 literals keep their brackets."""
    form = re.fullmatch(r"(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9._-]+)(:[0-9]{1,5})?", host)
    if form is None:  # e.g. "127.0.0.1:80@evil.example", which a URL built from it would send elsewhere
        return False
    name = form.group(1).lower()
    for pattern in allowed:
        if pattern == "*" or name == pattern.lower():
            return True
        if pattern.startswith("*.") and name.endswith(pattern[1:].lower()):
            return True
    return False


# GETs that start a solve: a page elsewhere must not make a laptop's loopback service spend its solvers.
SOLVING_GETS = re.compile(r"/tableaux/[^/]+/(why|rehearsal)")


class Guard:
    """The outermost middleware. Refuse (problem details) a Host the server does not answer to (400); a
    request that changes something or starts a solve which a browser marks as coming from another site
    (403): ``Sec-Fetch-Site: cross-site``, or an ``Origin`` that is neither this server (scheme, host and
    port) nor a configured CORS origin; and, outside the open paths, a request without a valid token
    (401) or over its token's request rate (429). All of that happens before the body is read: a caller
    without a valid token costs the server no body, no buffer and no parsing. The caller found is
    handed to the routes in the request's state (:func:`get_caller`). HEAD is answered as GET (uvicorn
    sends no body for it)."""

    def __init__(self, app: ASGIApp, hosts: list[str], origins: list[str]):
        self.app, self.hosts, self.origins = app, hosts, set(origins)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        headers = {k.decode("latin-1"): v.decode("latin-1") for k, v in scope["headers"]}
        host, method, path = headers.get("host", ""), scope["method"], scope["path"]
        try:
            if not host_allowed(host, self.hosts):
                raise Problem(400, "invalid-host", "Host not allowed",
                              f"this server does not answer to the host {host[:100]!r} (BOOTMAP_ALLOWED_HOSTS)")
            if ((method not in SAFE_METHODS or SOLVING_GETS.fullmatch(path))
                    and self._cross_site(headers, scope.get("scheme", "http"), host)):
                raise forbidden("a request from another web site may not change anything here or start a solve "
                                "(its Origin is not allowed; see BOOTMAP_CORS_ORIGINS)")
            caller = None
            if method != "OPTIONS" and path not in OPEN_PATHS and not path.startswith(OPEN_PREFIXES):
                caller = await authenticate(scope["app"].state.services, headers.get("authorization"))
        except Problem as p:
            return await problem_response(p, path)(scope, receive, send)
        except BootmapError as e:  # over the token's request rate
            return await problem_response(from_bootmap_error(e), path)(scope, receive, send)
        scope = {**scope, "state": {**scope.get("state", {}), "caller": caller}}
        if method == "HEAD":  # answered as GET; the server sends no body for HEAD
            scope["method"] = "GET"
        await self.app(scope, receive, send)

    def _cross_site(self, headers: dict[str, str], scheme: str, host: str) -> bool:
        origin = headers.get("origin")
        if origin is not None and origin in self.origins:
            return False
        if headers.get("sec-fetch-site") == "cross-site":
            return True
        if origin is None:
            return False  # not a browser's cross-origin request (browsers send Origin on every such POST)
        return origin.lower() != f"{scheme}://{host}".lower()
