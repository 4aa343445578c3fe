"""The committed Killian excerpt, read once."""


import pytest

from bootmap.ingest.g2o import read_g2o

from log_data import EXCERPT


@pytest.fixture(scope="session")
def excerpt_scans():
    return read_g2o(EXCERPT)


@pytest.fixture(scope="session")
def excerpt_lines():
    return EXCERPT.read_text().splitlines()
