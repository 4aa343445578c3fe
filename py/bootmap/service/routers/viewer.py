"""The map viewer: the page at ``/``, its files under ``/viewer/``, and the figures of experiment runs.

The page (``service/static/``) is plain HTML, CSS and ES modules shipped in the package: nothing to
build. It reads the service's own resources (``/tableaux``, ``/tableaux/{id}/layout``, ``/why``,
``/axioms``) with the user's token when one is given. Experiment runs (``bootmap experiment -o DIR``)
are found under the ``runs_dir`` setting, read-only: a run is a directory with a ``results.json``, at
most two levels down (``--seeds`` writes ``DIR/seed_N``); only the PNG files listed are ever served. Any
valid token may see them (runs belong to the server, not to a token); the page and its files need none.
"""

from __future__ import annotations

import json
import re
from pathlib import Path, PurePosixPath
from typing import Annotated

from fastapi import APIRouter, Query
from fastapi.responses import FileResponse
from pydantic import Field

from ..auth import CallerDep
from ..deps import ServicesDep
from ..models import Out
from ..problems import JSONRoute, Problem, openapi_responses

router = APIRouter(route_class=JSONRoute)

STATIC = Path(__file__).resolve().parent.parent / "static"
MEDIA_TYPES = {".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8",
               ".css": "text/css; charset=utf-8", ".svg": "image/svg+xml", ".png": "image/png"}
STATIC_NAME = re.compile(r"[a-z0-9][a-z0-9_-]{0,60}\.(html|js|css|svg|png)")
MAX_RUNS = 500


@router.get("/", include_in_schema=False)
def page() -> FileResponse:
    """The viewer."""
    return _static("index.html")


@router.get("/viewer/{name}", include_in_schema=False)
def static_file(name: str) -> FileResponse:
    """One of the viewer's files (a flat directory; names are checked, never joined as given)."""
    if not STATIC_NAME.fullmatch(name) or not (STATIC / name).is_file():
        raise Problem(404, "not-found", "Not found", f"the viewer has no file {name[:80]!r}")
    return _static(name)


def _static(name: str) -> FileResponse:
    # no-cache: the browser revalidates (ETag), so an upgraded server's page is never stale.
    return FileResponse(STATIC / name, media_type=MEDIA_TYPES[Path(name).suffix],
                        headers={"Cache-Control": "no-cache"})


# ---------------------------------------------------------------------------------------------------
# Experiment runs and their figures
# ---------------------------------------------------------------------------------------------------

class Run(Out):
    name: str = Field(description="The run's directory under runs_dir, e.g. 'nr' or 'th5/seed_1'.")
    world: str | None
    seed: int | None
    figures: list[str] = Field(description="PNG files of the run (GET /runs/figure?run=...&name=...).")


class Runs(Out):
    configured: bool = Field(description="Whether the server has a runs directory (bootmap serve --runs-dir).")
    runs: list[Run]


@router.get("/runs", response_model=Runs, tags=["viewer"], summary="Experiment runs with figures",
            responses=openapi_responses(401, 429))
def list_runs(services: ServicesDep, caller: CallerDep) -> Runs:
    """Runs written by `bootmap experiment -o DIR` under the server's runs directory, with their figures
    (M and U against k, learning curves, the world and the run)."""
    root = services.settings.runs_dir
    return Runs(configured=root is not None, runs=_runs(root) if root is not None else [])


@router.get("/runs/figure", response_class=FileResponse, tags=["viewer"], summary="A figure of a run",
            responses={200: {"content": {"image/png": {}}}, **openapi_responses(401, 404, 422, 429)})
def read_figure(services: ServicesDep, caller: CallerDep,
                run: Annotated[str, Query(max_length=200, description="A run's name, as /runs lists it.")],
                name: Annotated[str, Query(max_length=100, description="A PNG file of that run.")]) -> FileResponse:
    """The PNG itself. Only files /runs lists are served."""
    root = services.settings.runs_dir
    found = {r.name: r for r in _runs(root)} if root is not None else {}
    if run not in found or name not in found[run].figures:
        raise Problem(404, "not-found", "No such figure",
                      f"no figure {name[:100]!r} in run {run[:200]!r}" if found else "this server has no runs "
                      "directory (bootmap serve --runs-dir DIR)")
    return FileResponse(root / run / name, media_type="image/png")


def _runs(root: Path) -> list[Run]:
    results = sorted([*root.glob("results.json"), *root.glob("*/results.json"), *root.glob("*/*/results.json")])
    out = []
    for path in results[:MAX_RUNS]:
        folder = path.parent
        name = PurePosixPath(*folder.relative_to(root).parts).as_posix() if folder != root else "."
        world, seed = _about(path)
        figures = sorted(p.name for p in folder.glob("*.png") if p.is_file())
        out.append(Run(name=name, world=world, seed=seed, figures=figures))
    return out


def _about(results: Path) -> tuple[str | None, int | None]:
    """The run's world and seed from its results.json (None where it says nothing readable)."""
    try:
        data = json.loads(results.read_text())
    except (OSError, ValueError):
        return None, None
    world, seed = data.get("world"), data.get("seed")
    return (world if isinstance(world, str) else None), (seed if isinstance(seed, int) else None)
