"""Every error as RFC 9457 problem details (``application/problem+json``), with a message a person can act on.

:class:`Problem` is the one exception the routers raise; the handlers here turn it, request validation
errors, bootmap's own exceptions and anything unexpected into a problem document. ``field`` names what
to fix in the style of the CLI's messages (``steps[3].action.angle_deg``); ``errors`` lists every invalid
field when there are several, each with a JSON Pointer into the request body.

:class:`BodyLimit` refuses bodies over the size limit before they are read, and :class:`JSONRoute` parses
request bodies so that malformed or hostile JSON gets a precise 400 instead of a generic one.
"""

from __future__ import annotations

import json
import logging
import re
from contextlib import asynccontextmanager
from typing import Any

import anyio
from fastapi import FastAPI, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from fastapi.routing import APIRoute
from starlette.exceptions import HTTPException
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from ..errors import (AssertionConflict, AxiomError, BootmapError, ExplainError, InconsistentTableau, SolveTimeout,
                      TableauError)
from .store import Conflict, NotFound, NotOwner, QuotaExceeded
from .worker import SolveCancelled, SolverBusy, SolverCrashed, SolverKilled, SolverOutOfMemory

PROBLEM_JSON = "application/problem+json"
TYPE_BASE = "https://bootmap.dev/problems/"
log = logging.getLogger("bootmap.service")


class Problem(HTTPException):
    """An error response: status, a short kind (the problem type), a title, and what to do about it."""

    def __init__(self, status: int, kind: str, title: str, detail: str, headers: dict[str, str] | None = None,
                 **extensions: Any):
        super().__init__(status_code=status, detail=detail, headers=headers)
        self.kind, self.title, self.extensions = kind, title, extensions

    def document(self, instance: str | None = None) -> dict[str, Any]:
        doc = {"type": TYPE_BASE + self.kind, "title": self.title, "status": self.status_code, "detail": self.detail}
        if instance:
            doc["instance"] = instance
        doc.update({k: v for k, v in self.extensions.items() if v is not None})
        return doc


def problem_response(p: Problem, instance: str | None = None) -> JSONResponse:
    return JSONResponse(p.document(instance), status_code=p.status_code, headers=p.headers,
                        media_type=PROBLEM_JSON)


def not_found(tableau_id: int) -> Problem:
    return Problem(404, "not-found", "No such tableau", f"no tableau has id {tableau_id}; "
                   "GET /tableaux lists the stored ones")


def invalid(field: str, reason: str, kind: str = "invalid-tableau") -> Problem:
    """A 422 naming the field to fix."""
    title = "Invalid tableau" if kind == "invalid-tableau" else "Invalid request"
    return Problem(422, kind, title, f"{field}: {reason}" if field else reason, field=field or None)


# ---------------------------------------------------------------------------------------------------
# bootmap's exceptions -> problems
# ---------------------------------------------------------------------------------------------------

# Most specific first: SolverKilled is a SolveTimeout.
_KINDS: list[tuple[type, int, str, str]] = [
    (Conflict, 409, "conflict", "Conflict"),
    (NotOwner, 403, "forbidden", "Not allowed"),
    (QuotaExceeded, 429, "quota-exceeded", "Over this token's limit"),
    (SolveCancelled, 400, "client-gone", "The client went away"),
    (SolverBusy, 503, "solvers-busy", "Every solver is busy"),
    (AssertionConflict, 409, "assertion-conflict", "The assertions clash with the experience"),
    (InconsistentTableau, 422, "inconsistent-tableau", "No map satisfies the axioms"),
    (SolveTimeout, 422, "solve-timeout", "Solve ran past its time limit"),
    (SolverOutOfMemory, 422, "solver-memory", "Solve needed more memory than allowed"),
    (AxiomError, 422, "axiom-error", "The axioms do not load"),
    (SolverCrashed, 500, "solver-crashed", "The solver failed"),
]


def from_bootmap_error(e: BootmapError) -> Problem:
    """The problem for one of bootmap's own exceptions (solver outcomes included)."""
    if isinstance(e, TableauError):
        return invalid(e.where.split(": ", 1)[-1] if e.where else "", e.reason)
    if isinstance(e, NotFound):
        return not_found(e.tableau_id) if e.tableau_id else Problem(404, "not-found", "Not found", str(e))
    if isinstance(e, ExplainError):
        return Problem(422, "invalid-question", "Invalid question", str(e))
    for cls, status, kind, title in _KINDS:
        if isinstance(e, cls):
            retry = getattr(e, "retry_after_s", None)
            headers = {"Retry-After": str(retry)} if retry is not None else None
            return Problem(status, kind, title, str(e), headers=headers, **_extensions(e))
    return Problem(500, "internal", "Internal error", f"{type(e).__name__}: {e}")


def _extensions(e: BootmapError) -> dict[str, Any]:
    """What a client can use beyond the message: the failing levels, the bound proved, the best map."""
    if isinstance(e, AssertionConflict):
        conflict = e.conflict if isinstance(e.conflict, dict) or e.conflict is None else e.conflict.to_dict()
        return {"conflict": conflict, "text": e.text}
    if isinstance(e, InconsistentTableau):
        return {"failing_levels": e.failing_levels}
    if isinstance(e, SolverKilled):
        return {"time_limit_s": e.time_limit_s}
    if isinstance(e, SolveTimeout):
        best = e.best_map
        return {"lower_bound": e.lower_bound, "best_map": None if best is None else {
            "dstates": best.n_dstates, "places": best.n_places, "paths": best.n_paths, "proved_minimal": False}}
    return {}


# ---------------------------------------------------------------------------------------------------
# Request validation errors (pydantic) -> one problem naming the fields
# ---------------------------------------------------------------------------------------------------

# Pydantic puts the branch of a union in an error's location ("truth", "str"); a person wants the field.
_BRANCHES = {"str", "constrained-str", "int", "float", "bool", "list", "dict", "none", "nullable", "turn", "travel"}


def _is_branch(part: Any) -> bool:
    return isinstance(part, str) and (part in _BRANCHES or "[" in part or "(" in part)


def field_path(loc: tuple | list) -> str:
    """("body", "steps", 3, "action", "turn", "angle_deg") -> "steps[3].action.angle_deg"."""
    parts = [p for p in loc[1:] if not _is_branch(p)] if loc and loc[0] in ("body", "query", "path") else list(loc)
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    if loc and loc[0] in ("query", "path") and out:
        out = f"{loc[0]} parameter {out}"
    return out[:200] + ("..." if len(out) > 200 else "")


def _pointer(loc: tuple | list) -> str:
    parts = [p for p in loc[1:] if not _is_branch(p)]
    return "#/" + "/".join(str(p).replace("~", "~0").replace("/", "~1") for p in parts)


def _message(err: dict) -> str:
    kind, ctx = err.get("type"), err.get("ctx") or {}
    if kind == "extra_forbidden":
        return "unknown field"
    if kind == "missing":
        return "missing"
    if kind == "union_tag_invalid":
        return f"unknown action type {ctx.get('tag')!r} (expected 'turn' or 'travel')"
    if kind == "finite_number":
        return "not a finite number (JSON has no NaN or Infinity)"
    if kind == "recursion_loop" or kind == "recursion_depth_exceeded":
        return "nested too deeply"
    if kind == "string_pattern_mismatch" and "x00" in str(ctx.get("pattern")):
        return "contains a NUL character (\\u0000), which the solver cannot hold in a label"
    if kind == "literal_error" and ctx.get("expected") == repr("bootmap.tableau/1"):
        return f"unsupported format {err.get('input')!r} (expected 'bootmap.tableau/1')"
    return str(err.get("msg", "invalid")).removeprefix("Value error, ")


def validation_problem(errors: list[dict]) -> Problem:
    """One 422 for every invalid field; a union's branches that all failed are one field."""
    seen: dict[str, dict] = {}
    by_type: dict[str, bool] = {}  # was the field's message a union branch's "wrong type"?
    for err in errors:
        field = field_path(err.get("loc", ()))
        item = {"field": field, "detail": _message(err)}
        if err.get("loc", ("",))[0] == "body":
            item["pointer"] = _pointer(err["loc"])  # RFC 9457's suggestion: a JSON Pointer into the body
        wrong_type = str(err.get("type", "")).endswith("_type")
        # Of a union's branches, the one whose type matched says what is wrong with the value.
        if field not in seen or (by_type[field] and not wrong_type):
            seen[field], by_type[field] = item, wrong_type
    items = list(seen.values())
    first = items[0] if items else {"field": "", "detail": "invalid request"}
    if first["field"] == "" and errors and errors[0].get("type") == "missing":
        return Problem(422, "invalid-request", "Invalid request", "the request needs a JSON body")
    if first["field"] == "" and errors and errors[0].get("type") in ("model_attributes_type", "dict_type"):
        return Problem(415, "unsupported-media-type", "Send JSON",
                       "the body must be a JSON object sent with Content-Type: application/json")
    more = f" (and {len(items) - 1} more invalid field(s), see errors)" if len(items) > 1 else ""
    detail = f"{first['field']}: {first['detail']}" if first["field"] else first["detail"]
    return Problem(422, "invalid-request", "Invalid request", detail + more, field=first["field"] or None,
                   errors=items[:50])


# ---------------------------------------------------------------------------------------------------
# Parsing the body
# ---------------------------------------------------------------------------------------------------

_SURROGATE_ESCAPE = re.compile(rb"\\u[dD][89a-fA-F]", re.ASCII)


def count_values(body: bytes) -> int:
    """An upper bound of the JSON values in ``body``, from its separators (C speed, before parsing): a
    value after the first in an array follows a comma, an object's value a colon."""
    return sum(body.count(c) for c in (b",", b":", b"[", b"{")) + 1


def parse_json(body: bytes, max_values: int | None = None) -> Any:
    """JSON text -> data, or a 400 saying what is wrong and where. Numbers too long for Python, nesting
    too deep for its parser and lone UTF-16 surrogates (which no UTF-8 text can carry) are refused here;
    a body of more than ``max_values`` values is refused (413) before it is parsed, since each value
    costs the server far more memory than its text."""
    if max_values is not None and count_values(body) > max_values:
        raise Problem(413, "too-many-values", "Too many values",
                      f"the body holds about {count_values(body)} JSON values, more than this server's limit of "
                      f"{max_values} per request (BOOTMAP_MAX_JSON_VALUES)", limit_values=max_values)
    try:
        # Decoded here, strictly: json.loads would also take UTF-16 and UTF-32, which the API does not.
        data = json.loads(body.decode("utf-8") if isinstance(body, (bytes, bytearray)) else body,
                          object_pairs_hook=_unique_keys)
    except json.JSONDecodeError as e:
        raise Problem(400, "malformed-json", "Malformed JSON",
                      f"not valid JSON: {e.msg} at line {e.lineno} column {e.colno}") from None
    except UnicodeDecodeError as e:
        raise Problem(400, "malformed-json", "Malformed JSON", f"not UTF-8 text: {e.reason} at byte {e.start}") \
            from None
    except RecursionError:
        raise Problem(400, "malformed-json", "Malformed JSON", "JSON nested too deeply") from None
    except ValueError as e:  # e.g. an integer of more than 4300 digits
        raise Problem(400, "malformed-json", "Malformed JSON", f"not acceptable JSON: {e}") from None
    if _SURROGATE_ESCAPE.search(body):
        _check_surrogates(data, [])
    return data


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """An object, refusing a key given twice (JSON parsers disagree on which one wins)."""
    data = dict(pairs)
    if len(data) != len(pairs):
        seen: set[str] = set()
        twice = next(k for k, _ in pairs if k in seen or seen.add(k))
        raise Problem(400, "malformed-json", "Malformed JSON", f"the key {twice[:100]!r} appears twice in one object")
    return data


def _check_surrogates(x: Any, path: list) -> None:
    if isinstance(x, str):
        try:
            x.encode("utf-8")
        except UnicodeEncodeError:
            raise Problem(400, "malformed-json", "Malformed JSON",
                          f"{field_path(['body', *path]) or 'body'}: a lone UTF-16 surrogate (\\ud800-\\udfff) "
                          "is not a character") from None
    elif isinstance(x, dict):
        for k, v in x.items():
            _check_surrogates(k, path)
            _check_surrogates(v, path + [k])
    elif isinstance(x, list):
        for i, v in enumerate(x):
            _check_surrogates(v, path + [i])


class ByteBudget:
    """At most ``capacity`` bytes of request bodies parsed at once (a larger body counts as the whole
    budget): parsing makes Python objects many times the size of the text, so this bounds the memory
    parsing takes. Others wait their turn; nothing is refused."""

    def __init__(self, capacity: int):
        self.capacity, self.used = capacity, 0
        self._changed: anyio.Condition | None = None

    @asynccontextmanager
    async def hold(self, n: int):
        n = min(n, self.capacity)
        if self._changed is None:  # made in the event loop that uses it
            self._changed = anyio.Condition()
        async with self._changed:
            while self.used + n > self.capacity:
                await self._changed.wait()
            self.used += n
        try:
            yield
        finally:
            with anyio.CancelScope(shield=True):
                async with self._changed:
                    self.used -= n
                    self._changed.notify_all()


# The bodies FastAPI parses (an image to recognise, sharing, a token's name) are small; tableaux and
# appends are read by their routes and parsed in an intake process (bootmap.service.intake).
SMALL_BODY_BYTES = 2**20


class _JSONRequest(Request):
    """A request whose (small) JSON body is parsed and validated against the route's body model in a
    worker thread, off the event loop: FastAPI then gets the model instance, which it passes without
    validating again."""

    body_field: Any = None

    async def json(self) -> Any:
        if not hasattr(self, "_json"):
            body = await self.body()
            if len(body) > SMALL_BODY_BYTES:
                raise Problem(413, "body-too-large", "Request body too large",
                              f"this request's body may have at most {SMALL_BODY_BYTES} bytes",
                              limit_bytes=SMALL_BODY_BYTES)
            self._json = await run_in_threadpool(_parse_and_validate, body, self.body_field,
                                                 self.app.state.settings.max_json_values)
        return self._json


def _parse_and_validate(body: bytes, body_field: Any, max_values: int) -> Any:
    data = parse_json(body, max_values)
    if body_field is None:
        return data
    model, errors = body_field.validate(data, loc=("body",))
    if errors:
        raise validation_problem(list(errors))
    return model


class JSONRoute(APIRoute):
    """A route whose request body is parsed by :func:`parse_json` and validated off the event loop."""

    def get_route_handler(self):
        handler = super().get_route_handler()
        body_field = self.body_field

        async def route(request: Request):
            r = _JSONRequest(request.scope, request.receive)
            r.body_field = body_field
            return await handler(r)

        return route


class BodyLimit:
    """Refuse a request body over ``max_bytes``: at once when Content-Length says so, else as soon as the
    bytes read pass the limit. Nothing over the limit is ever held in memory. A body not received in
    full within ``timeout_s`` once reading starts is refused (408) and the connection closed. Bodies held
    at once are bounded by ``held_bytes`` (by Content-Length, else ``max_bytes``): a request whose body
    does not fit waits for room before it is read."""

    def __init__(self, app: ASGIApp, max_bytes: int, timeout_s: float = 20.0, held_bytes: int | None = None):
        self.app, self.max_bytes, self.timeout_s = app, max_bytes, timeout_s
        self.budget = ByteBudget(held_bytes or 4 * max_bytes)

    def _too_large(self) -> Problem:
        return Problem(413, "body-too-large", "Request body too large",
                       f"the request body is larger than this server's limit of {self.max_bytes} bytes "
                       "(BOOTMAP_MAX_BODY_BYTES)", limit_bytes=self.max_bytes)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        length = dict(scope["headers"]).get(b"content-length")
        if length is not None and (not length.isdigit() or int(length) > self.max_bytes):
            response = problem_response(self._too_large() if length.isdigit() else
                                        Problem(400, "bad-request", "Bad request", "invalid Content-Length"))
            return await response(scope, receive, send)
        chunked = b"chunked" in dict(scope["headers"]).get(b"transfer-encoding", b"").lower()
        size = int(length) if length is not None else (self.max_bytes if chunked else 0)
        if size == 0:
            return await self._run(scope, receive, send)
        async with self.budget.hold(size):  # held until the response is sent: the body lives that long
            await self._run(scope, receive, send)

    async def _run(self, scope: Scope, receive: Receive, send: Send) -> None:
        seen, complete = 0, False
        deadline = anyio.current_time() + self.timeout_s

        async def limited() -> Message:
            nonlocal seen, complete
            if complete:  # the body is in; what comes next is the disconnect, whenever it comes
                return await receive()
            with anyio.move_on_after(max(0.0, deadline - anyio.current_time())) as timer:
                message = await receive()
            if timer.cancelled_caught:
                raise Problem(408, "body-timeout", "Request body too slow",
                              f"the request body did not arrive within {self.timeout_s:g} s "
                              "(BOOTMAP_BODY_TIMEOUT_S)", headers={"Connection": "close"})
            complete = message["type"] != "http.request" or not message.get("more_body", False)
            seen += len(message.get("body", b""))
            if seen > self.max_bytes:
                raise self._too_large()  # an HTTPException: FastAPI passes it to the handlers below
            return message

        await self.app(scope, limited, send)


# ---------------------------------------------------------------------------------------------------
# Handlers
# ---------------------------------------------------------------------------------------------------

_TITLES = {400: "Bad request", 401: "Token needed", 403: "Not allowed", 404: "Not found", 405: "Method not allowed",
           406: "Not acceptable", 408: "Request body too slow", 413: "Request body too large", 415: "Unsupported media type",
           422: "Invalid request", 429: "Too many requests",
           500: "Internal error", 503: "Service unavailable"}


def _allowed_methods(request: Request, fallback: str) -> str:
    """Every method the API documents at this path. (Starlette's 405 names only the methods of the first
    route that matched the path, not of every route there.)"""
    methods: set[str] = set()
    for template, operations in request.app.openapi().get("paths", {}).items():
        pattern = re.sub(r"\\\{[^}]+\\\}", "[^/]+", re.escape(template))
        if re.fullmatch(pattern, request.url.path):
            methods |= {m.upper() for m in operations}
    if "GET" in methods:
        methods.add("HEAD")
    return ", ".join(sorted(methods)) or fallback


def install(app: FastAPI) -> None:
    """Register the problem handlers on ``app``."""

    async def on_problem(request: Request, exc: Problem):
        return problem_response(exc, request.url.path)

    async def on_http(request: Request, exc: HTTPException):
        detail = exc.detail
        if exc.status_code == 404 and detail == "Not Found":
            detail = f"nothing at {request.url.path}; the API is listed at /docs"
        elif exc.status_code == 405:
            detail = f"{request.method} is not allowed on {request.url.path}"
            exc.headers = {"Allow": _allowed_methods(request, (exc.headers or {}).get("Allow", ""))}
        elif exc.status_code == 400 and exc.__cause__ is not None:
            detail = f"the body could not be read: {type(exc.__cause__).__name__}"
        p = Problem(exc.status_code, "http-" + str(exc.status_code), _TITLES.get(exc.status_code, "Error"),
                    str(detail), headers=getattr(exc, "headers", None))
        return problem_response(p, request.url.path)

    async def on_validation(request: Request, exc: RequestValidationError):
        return problem_response(validation_problem(list(exc.errors())), request.url.path)

    async def on_bootmap(request: Request, exc: BootmapError):
        return problem_response(from_bootmap_error(exc), request.url.path)

    async def on_other(request: Request, exc: Exception):
        log.exception("unexpected error on %s %s", request.method, request.url.path)
        return problem_response(Problem(500, "internal", "Internal error",
                                        "the server failed on this request; it is logged"), request.url.path)

    app.add_exception_handler(Problem, on_problem)
    app.add_exception_handler(HTTPException, on_http)
    app.add_exception_handler(RequestValidationError, on_validation)
    app.add_exception_handler(BootmapError, on_bootmap)
    app.add_exception_handler(Exception, on_other)


def openapi_responses(*statuses: int) -> dict[int | str, dict]:
    """OpenAPI entries for error statuses, all with the problem schema."""
    from .models import Problem as ProblemModel

    return {s: {"model": ProblemModel, "description": _TITLES.get(s, "Error"),
                "content": {PROBLEM_JSON: {"schema": {"$ref": "#/components/schemas/Problem"}}}}
            for s in statuses}


__all__ = ["BodyLimit", "JSONRoute", "Problem", "install", "openapi_responses", "parse_json",
           "validation_problem"]
