"""Schemathesis over the OpenAPI schema the server serves: no 500s, every response as the schema says.

The fuzzed server requires tokens, and the fuzzer sends an admin's (so every operation is reachable);
tests/service/test_security.py covers what happens without one.

The fuzzer posts, appends to and reloads whatever ids it draws, so it has a server of its own (the
session's settings, its own data and axioms) with the paper's tableau stored on it; the session's
server and the tableaux other test files stored there are left as they were.

Schemathesis parametrizes at import time, before any server is up, so the schema is built in-process
from the same settings; the first test checks it is exactly what the server serves.
"""

import shutil

import pytest
import schemathesis
from hypothesis import HealthCheck, settings
from schemathesis.checks import positive_data_acceptance

from bootmap.service.app import create_app
from bootmap.service.settings import Settings

from service_helpers import REPO, SESSION_SETTINGS, Server, bearer, make_token

SPEC = create_app(Settings(**SESSION_SETTINGS)).openapi()
schema = schemathesis.openapi.from_dict(SPEC)


@pytest.fixture(scope="module")
def fuzzed_server(tmp_path_factory, paper_doc):
    """A server for the fuzzer alone, with the paper's tableau stored (an id for it to find)."""
    root = tmp_path_factory.mktemp("fuzzed_server")
    shutil.copytree(REPO / "asp", root / "asp")
    s = Server(root, axioms=root / "asp", require_tokens=True, token_requests_per_minute=100_000, **SESSION_SETTINGS)
    s.token = make_token("fuzzer", admin=True, data_dir=s.data_dir)
    s.start()
    try:
        with s.client() as c:
            r = c.post("/tableaux", json=paper_doc, headers=bearer(s.token))
            assert r.status_code == 201, r.text
        yield s
    finally:
        s.stop()


def test_the_fuzzed_schema_is_the_served_one(fuzzed_server):
    with fuzzed_server.client() as c:
        assert c.get("/openapi.json").json() == SPEC


@schema.parametrize()
@settings(max_examples=30, deadline=None, suppress_health_check=list(HealthCheck))
def test_every_operation_conforms(case, fuzzed_server):
    server = fuzzed_server
    # Every other check runs. A schema-valid tableau may still be refused for what no schema can say
    # (the last step has no action, images share one length, a map exists, the solve ends in time), so
    # "schema-valid data is accepted" does not hold for this API; refusing invalid data is checked.
    case.call_and_validate(base_url=server.url, headers=bearer(server.token),
                           excluded_checks=[positive_data_acceptance])
