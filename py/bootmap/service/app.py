"""The FastAPI application: ``create_app(settings)``.

Routers, one per resource (``routers/``): tableaux, maps, recognition, axioms, health. A new resource
(e.g. explanations) is a new router module added to :data:`ROUTERS`. Everything a router needs comes
from :class:`~bootmap.service.deps.Services` through ``Depends``.
"""

from __future__ import annotations

from contextlib import asynccontextmanager

from fastapi import FastAPI
from fastapi.concurrency import run_in_threadpool
from fastapi.openapi.utils import get_openapi

from .. import __version__
from . import problems
from .deps import Services
from .models import Problem as ProblemModel
from .routers import axioms, explanations, health, maps, recognise, tableaux
from .settings import Settings

ROUTERS = (tableaux.router, maps.router, explanations.router, recognise.router, axioms.router, health.router)

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
        app.state.services = await run_in_threadpool(Services.start, settings)
        try:
            yield
        finally:
            await run_in_threadpool(app.state.services.close)

    app = FastAPI(title="bootmap", version=__version__, description=DESCRIPTION, lifespan=lifespan)
    app.state.settings = settings
    problems.install(app)
    app.add_middleware(problems.BodyLimit, max_bytes=settings.max_body_bytes)
    for router in ROUTERS:
        app.include_router(router)
    app.openapi = lambda: _openapi(app, settings)  # type: ignore[method-assign]
    return app


def _openapi(app: FastAPI, settings: Settings) -> dict:
    """FastAPI's schema, plus what only the settings know (size limits) and the problem document."""
    if app.openapi_schema:
        return app.openapi_schema
    spec = get_openapi(title=app.title, version=app.version, description=app.description, routes=app.routes)
    schemas = spec.setdefault("components", {}).setdefault("schemas", {})
    schemas["Problem"] = ProblemModel.model_json_schema(ref_template="#/components/schemas/{model}")
    for name, schema in schemas.items():
        props = schema.get("properties", {})
        if name.startswith(("TableauIn", "AppendIn")) and "steps" in props:
            props["steps"]["maxItems"] = settings.max_steps
        if name.startswith(("StepIn", "RecogniseIn")) and "image" in props:
            props["image"]["maxItems"] = settings.max_image_len
    app.openapi_schema = spec
    return spec
