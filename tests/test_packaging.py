"""The axioms are found from an editable install and from a built wheel installed elsewhere."""

import os
import subprocess
import sys
import sysconfig
import venv
import zipfile
from pathlib import Path

import pytest

from bootmap.mapping.theory import default_axioms_dir

REPO = Path(__file__).resolve().parent.parent


def test_the_release_files_say_the_licence_and_how_to_cite():
    import tomllib

    import yaml

    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    assert project["license"]["text"] == "MIT" and "MIT License" in (REPO / "LICENSE").read_text()
    cff = yaml.safe_load((REPO / "CITATION.cff").read_text())
    assert cff["cff-version"] == "1.2.0" and cff["version"] == project["version"] and cff["license"] == "MIT"
    assert any(r["title"] == "Bootstrap Learning for Place Recognition" and r["year"] == 2002
               for r in cff["references"])
    assert f"## {project['version']}" in (REPO / "CHANGELOG.md").read_text()
    assert (REPO / "py" / "bootmap" / "py.typed").exists()


def test_editable_install_reads_the_repository_axioms():
    assert default_axioms_dir() == REPO / "asp"


@pytest.mark.slow
def test_built_wheel_carries_the_axioms_and_maps_a_tableau(tmp_path):
    dist = tmp_path / "dist"
    subprocess.run([sys.executable, "-m", "build", "--wheel", "--no-isolation", "--outdir", str(dist), str(REPO)],
                   check=True, capture_output=True, timeout=300)
    wheel = next(dist.glob("bootmap-*.whl"))
    # The viewer's page and modules ship in the package: nothing for a user to build.
    shipped = set(zipfile.ZipFile(wheel).namelist())
    assert {f"bootmap/service/static/{f}" for f in ("index.html", "app.js", "api.js", "draw.js", "table.js",
                                                     "why.js", "zoom.js", "viewer.css")} <= shipped
    assert "bootmap/py.typed" in shipped  # type checkers read the package's annotations
    env_dir = tmp_path / "clean"
    venv.create(env_dir, with_pip=False)
    py = env_dir / "bin" / "python"
    purelib = Path(subprocess.check_output([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                                           text=True).strip())
    # Reuse the dependencies already installed here (no network), but not the editable bootmap:
    # a plain path entry in a .pth file does not process the editable install's own .pth hook.
    (purelib / "deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--quiet", "--target", str(purelib),
                    str(wheel)], check=True, timeout=300)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "BOOTMAP_AXIOMS")}
    where = subprocess.check_output([str(py), "-c", "import bootmap.mapping.theory as a; print(a.default_axioms_dir())"],
                                    text=True, cwd=tmp_path, env=env).strip()
    assert where.startswith(str(purelib)) and where.endswith("bootmap/asp")
    tableau = tmp_path / "paper.json"
    tableau.write_text(subprocess.check_output(
        [sys.executable, "-c", "from bootmap import examples; print(examples.notched_rectangle(3).dumps())"], text=True))
    out = subprocess.run([str(py), "-m", "bootmap.cli", "map", str(tableau)], capture_output=True, text=True,
                         cwd=tmp_path, env=env, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("8 dstates, 4 places, 4 paths")
    names = subprocess.check_output([str(py), "-c", "import bootmap.sim.world as w; print(w.worlds_dir(), w.world_names())"],
                                    text=True, cwd=tmp_path, env=env)
    assert names.startswith(str(purelib)) and "notched_rectangle" in names and "taylor_hall" in names
