"""The FastAPI application: ``create_app(settings)``.

Routers, one per resource (``routers/``): tableaux, maps, recognition, axioms, health. A new resource
(e.g. explanations) is a new router module added to :data:`ROUTERS`. Everything a router needs comes
from :class:`~bootmap.service.deps.Services` through ``Depends``.
"""

from __future__ import annotations

from contextlib import asynccontextmanager

import logging

from fastapi import FastAPI
from fastapi.concurrency import run_in_threadpool
from fastapi.middleware.cors import CORSMiddleware
from fastapi.openapi.utils import get_openapi

from .. import __version__
from . import headers, problems
from .auth import Guard
from .connections import SendTimeout
from .deps import Services
from .models import AppendIn, TableauIn
from .models import Problem as ProblemModel
from .routers import assertions, axioms, explanations, health, maps, recognise, rehearsals, tableaux, tokens
from .routers import layout, viewer
from .settings import Settings

ROUTERS = (tableaux.router, maps.router, assertions.router, explanations.router, rehearsals.router, recognise.router,
           axioms.router, tokens.router, health.router)
# The map viewer: the page at /, its files, the layout it draws, experiment runs' figures.
ROUTERS += (layout.router, viewer.router)

DESCRIPTION = """\
Post a robot's experience (a tableau: views or images at distinctive states, and the actions between
them) and get its cognitive map: dstates, places and paths, resolved by clingo from the axioms of the
Spatial Semantic Hierarchy. Tableaux and maps are stored; steps can be appended as exploration goes on;
new images are recognised by nearest neighbour. Every error is RFC 9457 problem details. See
docs/service.md."""


def create_app(settings: Settings | None = None) -> FastAPI:
    """The service. Its store, theory and solver processes start with the application (lifespan)."""
    settings = settings or Settings()

    @asynccontextmanager
    async def lifespan(app: FastAPI):
        _log_through_uvicorn()
        app.state.services = await run_in_threadpool(Services.start, settings)
        try:
            yield
        finally:
            await run_in_threadpool(app.state.services.close)

    app = FastAPI(title="bootmap", version=__version__, description=DESCRIPTION, lifespan=lifespan)
    app.state.settings = settings
    problems.install(app)
    # Added last = outermost: the guard sees a request first, then the send time-out, CORS, the body limit.
    # Around all of them (and Starlette's own error handling), the security headers: on every response.
    app.add_middleware(problems.BodyLimit, max_bytes=settings.max_body_bytes, timeout_s=settings.body_timeout_s,
                       held_bytes=settings.max_held_body_bytes)
    if settings.cors_origins:
        app.add_middleware(CORSMiddleware, allow_origins=settings.cors_origins, allow_methods=["*"],
                           allow_headers=["Authorization", "Content-Type"], expose_headers=["Location", "Retry-After"])
    app.add_middleware(SendTimeout, timeout_s=settings.send_timeout_s)
    app.add_middleware(Guard, hosts=settings.hosts, origins=settings.cors_origins)
    for router in ROUTERS:
        app.include_router(router)
    headers.wrap(app)
    app.openapi = lambda: _openapi(app, settings)  # type: ignore[method-assign]
    return app


def _log_through_uvicorn() -> None:
    """The service's own log lines (a solver that died, an unexpected error) go where uvicorn's go."""
    ours, theirs = logging.getLogger("bootmap.service"), logging.getLogger("uvicorn.error")
    if not ours.handlers and theirs.handlers:
        for handler in theirs.handlers:
            ours.addHandler(handler)
        ours.setLevel(logging.INFO)
        ours.propagate = False


def _openapi(app: FastAPI, settings: Settings) -> dict:
    """FastAPI's schema, plus what only the settings know (size limits) and the problem document."""
    if app.openapi_schema:
        return app.openapi_schema
    spec = get_openapi(title=app.title, version=app.version, description=app.description, routes=app.routes)
    spec.setdefault("components", {}).setdefault("securitySchemes", {})["token"] = {
        "type": "http", "scheme": "bearer", "description": "An API token (bootmap token create NAME); needed "
        "when the server requires tokens (docs/service.md, Security)."}
    spec["security"] = [{"token": []}, {}]  # optional on a loopback server without tokens
    schemas = spec.setdefault("components", {}).setdefault("schemas", {})
    schemas["Problem"] = ProblemModel.model_json_schema(ref_template="#/components/schemas/{model}")
    for model in (TableauIn, AppendIn):  # bodies their routes read themselves (intake): not in FastAPI's list
        schema = model.model_json_schema(ref_template="#/components/schemas/{model}")
        schemas.update(schema.pop("$defs", {}))
        schemas[model.__name__] = schema
    for name, schema in schemas.items():
        props = schema.get("properties", {})
        if name.startswith(("TableauIn", "AppendIn")) and "steps" in props:
            props["steps"]["maxItems"] = settings.max_steps
        if name.startswith(("StepIn", "RecogniseIn")) and "image" in props:
            props["image"]["maxItems"] = settings.max_image_len
    app.openapi_schema = spec
    return spec
