"""Data flows one way: no module of the package imports from a later stage of the pipeline.

The stages, in order (docs/architecture.md): the foundation every stage shares (the tableau, errors,
images), the sources of experience (the simulator, real robots' logs read into tableaux), views, the map,
recognition, the agent that explores with its own map, the experiments that measure all of it, the
service, and the command line on top (``cli.py`` and each package's ``commands.py``, which register the
sub-commands). A module may import from its own stage or an earlier one. Every import counts, those
inside functions too (they are how a heavy dependency is put off, not how a layer is skipped).
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "py" / "bootmap"

# (stage, the modules and packages in it): a module belongs to the stage of its longest listed prefix.
STAGES: list[tuple[str, tuple[str, ...]]] = [
    ("foundation", ("bootmap", "bootmap.errors", "bootmap.arguments", "bootmap.proc", "bootmap.images",
                    "bootmap.tableau", "bootmap.metrics", "bootmap.examples", "bootmap.paths",
                    "bootmap.lazy", "bootmap.walls")),
    ("sources", ("bootmap.sim", "bootmap.ingest", "bootmap.ingest.scans", "bootmap.ingest.carmen", "bootmap.ingest.g2o",
                 "bootmap.ingest.rosbag", "bootmap.ingest.dstates", "bootmap.ingest.places", "bootmap.ingest.truth",
                 "bootmap.ingest.ingest")),
    ("views", ("bootmap.views", "bootmap.scan_match", "bootmap.surroundings")),
    ("map", ("bootmap.mapping", "bootmap.layout")),
    ("recognition", ("bootmap.recognise", "bootmap.learners", "bootmap.alignment")),
    ("agent", ("bootmap.agent",)),
    ("experiments", ("bootmap.experiments",)),
    ("service", ("bootmap.service",)),
    ("command line", ("bootmap.cli", "*.commands")),
]
ORDER = {name: i for i, (name, _) in enumerate(STAGES)}


def stage_of(module: str) -> str:
    """The stage of a module (dotted name): its package's ``commands`` module is the command line's."""
    if module.rsplit(".", 1)[-1] == "commands":
        return "command line"
    best, length = None, -1
    for stage, prefixes in STAGES:
        for prefix in prefixes:
            if (module == prefix or module.startswith(prefix + ".")) and len(prefix) > length:
                best, length = stage, len(prefix)
    if best is None:
        raise KeyError(f"{module} belongs to no stage: add it to STAGES")
    return best


def modules() -> dict[str, Path]:
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        out[name] = path
    return out


def imports_of(module: str, source: str, is_package: bool = False) -> set[str]:
    """The bootmap modules ``source`` imports (relative imports resolved), anywhere in it."""
    package = module if is_package else module.rsplit(".", 1)[0]
    found = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.split(".")[0] == "bootmap"}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != "bootmap":
                continue
            # "from . import x" and "from .pkg import mod" may name modules: count the deepest that exists.
            found |= {f"{target}.{a.name}" for a in node.names} | {target}
    return found


def upward(module: str, imported: set[str], known: set[str]) -> list[str]:
    """The imports of ``module`` from a later stage than its own."""
    own = ORDER[stage_of(module)]
    return sorted(name for name in imported if name in known and ORDER[stage_of(name)] > own)


def test_every_module_belongs_to_a_stage():
    for name in modules():
        stage_of(name)


def test_no_module_imports_from_a_later_stage():
    found = modules()
    known = set(found)
    offences = {}
    for name, path in found.items():
        bad = upward(name, imports_of(name, path.read_text(), path.name == "__init__.py"), known)
        if bad:
            offences[f"{name} ({stage_of(name)})"] = [f"{b} ({stage_of(b)})" for b in bad]
    assert not offences, f"imports from a later stage: {offences}"


@pytest.mark.parametrize("module, source, expected", [
    ("bootmap.sim.simulation", "def f():\n    from ..mapping.resolver import Resolver\n", ["bootmap.mapping.resolver"]),
    ("bootmap.views", "import bootmap.service.app\n", ["bootmap.service.app"]),
    ("bootmap.mapping.resolver", "from ..views import cluster\n", []),
    ("bootmap.sim.commands", "from ..agent import make_policy\n", []),
])
def test_the_check_sees_an_upward_import_wherever_it_is(module, source, expected):
    known = set(modules())
    assert upward(module, imports_of(module, source), known) == expected


def test_the_command_line_builds_its_parser_without_the_heavy_libraries():
    """`bootmap --help` answers at once: building the parser loads none of the libraries the commands
    use when they run (bench/startup_bench.py times it)."""
    heavy = ("scipy", "sklearn", "pymunk", "clingo", "matplotlib", "fastapi", "sqlalchemy", "small_gicp")
    code = ("import sys; from bootmap.cli import build_parser; build_parser(); "
            f"print(sorted(m for m in {heavy!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_loop_closing_loads_scipy_only_once_a_loop_is_closed():
    """Every mapper loads loop closing (the service's solvers too, whose memory is capped); re-anchoring
    dead reckoning needs scipy's shortest paths, some 25 MB, only once a join is made."""
    code = ("import sys; from bootmap.mapping.loops import LoopCloser; print('scipy' in sys.modules); "
            "from bootmap.tableau import Tableau; "
            "lap = [{'view': 'c', 'action': {'type': 'travel', 'distance_m': 5}}, "
            "{'view': 'c', 'action': {'type': 'turn', 'angle_deg': 90}}] * 4; "
            "t = Tableau.from_dict({'format': 'bootmap.tableau/1', 'steps': lap * 2 + [{'view': 'c'}]}); "
            "print(LoopCloser().resolve(t).n_dstates, 'scipy' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "8", "True"]
