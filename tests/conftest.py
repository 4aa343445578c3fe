"""Shared fixtures: the real axioms, the paper's tableau."""

from pathlib import Path

import pytest

from bootmap import examples

REPO = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="session")
def paper_tableau():
    return examples.notched_rectangle(circuits=50)


@pytest.fixture
def axioms_copy(tmp_path):
    """A private copy of the axiom directory a test may extend or break."""
    import shutil

    dest = tmp_path / "asp"
    shutil.copytree(REPO / "asp", dest)
    return dest


# Property tests draw the same examples on every run (CI included): a failure is reproducible, and a
# green run is not luck. Set HYPOTHESIS_PROFILE=explore locally to search new examples.
import os

from hypothesis import settings

settings.register_profile("ci", derandomize=True, print_blob=True)
settings.register_profile("explore", derandomize=False, print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


def pytest_collection_modifyitems(config, items):
    """Modules with a slow test run first. pytest-xdist hands whole modules to the workers in this order,
    and a long module drawn last keeps every other worker idle until it ends."""
    slow = {item.nodeid.split("::")[0] for item in items if item.get_closest_marker("slow")}
    items.sort(key=lambda item: item.nodeid.split("::")[0] not in slow)  # stable: the order within stays
