"""Schemathesis over the OpenAPI schema the server serves: no 500s, every response as the schema says.

Schemathesis parametrizes at import time, before the session's server is up, so the schema is built
in-process from the same settings; the first test checks it is exactly what the server serves.
"""

import schemathesis
from hypothesis import HealthCheck, settings
from schemathesis.checks import positive_data_acceptance

from bootmap.service.app import create_app
from bootmap.service.settings import Settings

from service_helpers import SESSION_SETTINGS

SPEC = create_app(Settings(**SESSION_SETTINGS)).openapi()
schema = schemathesis.openapi.from_dict(SPEC)


def test_the_fuzzed_schema_is_the_served_one(client):
    assert client.get("/openapi.json").json() == SPEC


@schema.parametrize()
@settings(max_examples=30, deadline=None, suppress_health_check=list(HealthCheck))
def test_every_operation_conforms(case, server, paper_id):
    # Every other check runs. A schema-valid tableau may still be refused for what no schema can say
    # (the last step has no action, images share one length, a map exists, the solve ends in time), so
    # "schema-valid data is accepted" does not hold for this API; refusing invalid data is checked.
    case.call_and_validate(base_url=server.url, excluded_checks=[positive_data_acceptance])
