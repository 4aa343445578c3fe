"""The release: its files, the axioms found from an editable install, and a wheel built from a release tag that
installs in a clean environment and runs the demo."""

import os
import re
import subprocess
import sys
import sysconfig
import venv
import zipfile
from pathlib import Path

import pytest

from bootmap.mapping.theory import default_axioms_dir
from support.readme import missing, shown_commands

REPO = Path(__file__).resolve().parent.parent


def test_the_release_files_say_the_licence_and_how_to_cite():
    import tomllib

    import yaml

    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    assert project["license"]["text"] == "MIT" and "MIT License" in (REPO / "LICENSE").read_text()
    # The version is the release tag's (hatch-vcs); the citation and the changelog name the release.
    assert "version" in project["dynamic"] and "version" not in project
    cff = yaml.safe_load((REPO / "CITATION.cff").read_text())
    assert cff["cff-version"] == "1.2.0" and cff["license"] == "MIT"
    newest = re.search(r"^## (\S+)", (REPO / "CHANGELOG.md").read_text(), re.M).group(1)
    assert cff["version"] == newest
    assert any(r["title"] == "Bootstrap Learning for Place Recognition" and r["year"] == 2002
               for r in cff["references"])
    assert (REPO / "py" / "bootmap" / "py.typed").exists()


def test_editable_install_reads_the_repository_axioms():
    assert default_axioms_dir() == REPO / "asp"


@pytest.mark.slow
def test_built_wheel_carries_the_axioms_and_runs_the_demo(tmp_path):
    # A release: the repository's committed tree, tagged with the version the citation names.
    import yaml

    release = yaml.safe_load((REPO / "CITATION.cff").read_text())["version"]
    repo = tmp_path / "repo"
    subprocess.run(["git", "clone", "--quiet", str(REPO), str(repo)], check=True, timeout=120)
    subprocess.run(["git", "-C", str(repo), "tag", f"v{release}"], check=True)
    dist = tmp_path / "dist"
    subprocess.run([sys.executable, "-m", "build", "--wheel", "--no-isolation", "--outdir", str(dist), str(repo)],
                   check=True, capture_output=True, timeout=300)
    wheel = next(dist.glob("bootmap-*.whl"))
    assert wheel.name.startswith(f"bootmap-{release}-")  # the tag sets the version
    # The viewer's page and modules ship in the package: nothing for a user to build.
    shipped = set(zipfile.ZipFile(wheel).namelist())
    assert {f"bootmap/service/static/{f}" for f in ("index.html", "app.js", "api.js", "assert.js", "draw.js",
                                                     "table.js", "why.js", "zoom.js", "viewer.css")} <= shipped
    assert "bootmap/asp/core/assert.lp" in shipped  # every axiom file, the core's too
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
    version = subprocess.run([str(py), "-m", "bootmap.cli", "--version"], capture_output=True, text=True, cwd=tmp_path,
                             env=env, timeout=60)
    assert version.stdout.strip() == f"bootmap {release}"
    # What `make demo` runs, from the installed wheel: the paper's experiment on both worlds, its tableau.
    demo = subprocess.run([str(py), "-m", "bootmap.cli", "demo"], capture_output=True, text=True, cwd=tmp_path,
                          env=env, timeout=300)
    assert demo.returncode == 0, demo.stdout[-2000:] + demo.stderr  # every check of the paper holds on its seed
    assert "reports: out/notched_rectangle/report.md, out/taylor_hall/report.md" in demo.stdout
    assert (tmp_path / "out" / "taylor_hall" / "report.md").is_file()
    assert "8 dstates, 4 places, 4 paths" in demo.stdout and "NOT" not in demo.stdout
    assert "t0 (S0) and t4 (S4) cannot be one dstate" in demo.stdout and "on_path_no_side" in demo.stdout
    # The demo runs the README's Taylor Hall experiment: what the README shows it print, it prints (all but
    # the report's folder, which the demo names after the world).
    (shown,) = [text for args, text in shown_commands() if args[:2] == ["experiment", "taylor_hall"]]
    assert missing(shown.replace("report: out/th/report.md", ""), demo.stdout) == []
    names = subprocess.check_output([str(py), "-c", "import bootmap.sim.world as w; print(w.worlds_dir(), w.world_names())"],
                                    text=True, cwd=tmp_path, env=env)
    assert names.startswith(str(purelib)) and "notched_rectangle" in names and "taylor_hall" in names
