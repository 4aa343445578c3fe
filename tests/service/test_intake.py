"""The intake's checks before parsing: the count of JSON values from separators never undercounts, so a
body is never parsed when it holds more values than the server allows."""

import json

from hypothesis import given
from hypothesis import strategies as st

from bootmap.service.intake import Limits, prepare_tableau
from bootmap.service.problems import count_values

json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False, allow_infinity=False) | st.text(),
    lambda inner: st.lists(inner, max_size=5) | st.dictionaries(st.text(max_size=5), inner, max_size=5),
    max_leaves=40)


def values_in(x) -> int:
    """Every value, containers and object keys included (each costs the parser an object)."""
    if isinstance(x, list):
        return 1 + sum(values_in(v) for v in x)
    if isinstance(x, dict):
        return 1 + sum(1 + values_in(v) for v in x.values())
    return 1


@given(json_values, st.booleans())
def test_the_count_of_values_is_never_below_the_true_count(x, pretty):
    text = json.dumps(x, indent=2 if pretty else None).encode()
    assert count_values(text) >= values_in(x)


def test_a_body_over_the_value_limit_is_refused_before_it_is_parsed():
    body = json.dumps({"format": "bootmap.tableau/1", "steps": [{"view": "a"}], "meta": {"x": [1] * 500}}).encode()
    kind, status, problem_kind, *_ = prepare_tableau(body, Limits(10, 10, 10**6, 100))
    assert (kind, status, problem_kind) == ("problem", 413, "too-many-values")
    kind, prepared = prepare_tableau(body, Limits(10, 10, 10**6, 1000))
    assert kind == "ok" and prepared.n_steps == 1 and json.loads(prepared.document)["meta"]["x"] == [1] * 500
