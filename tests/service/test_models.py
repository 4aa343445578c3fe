"""The service's request model, its OpenAPI schema and the tableau's JSON Schema accept the same documents.

The JSON Schema is the source of truth (bootmap.tableau validates with it); the pydantic model is what
FastAPI checks first and what OpenAPI publishes. Hypothesis draws documents near the valid ones (wrong
types, bools for numbers, nulls, unknown fields, bad action types, out-of-range numbers) and the three
must agree on every one. Known, deliberate differences are outside what is drawn: integers too large for
a float, ``meta`` nested deeper than pydantic's limit, and NUL in a view label (clingo would cut the label
there) are refused by the service only.
"""

import jsonschema
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import ValidationError

from bootmap.service.app import create_app
from bootmap.service.models import TableauIn
from bootmap.service.settings import Settings
from bootmap.tableau import FORMAT, Tableau, _fast_validator, schema

SOURCE_OF_TRUTH = jsonschema.Draft202012Validator(schema())
SPEC = create_app(Settings()).openapi()
OPENAPI = jsonschema.Draft202012Validator({"$ref": "#/components/schemas/TableauIn",
                                           "components": SPEC["components"]})


def verdicts(doc) -> tuple[bool, bool, bool]:
    try:
        TableauIn.model_validate(doc)
        model = True
    except ValidationError:
        model = False
    truth = SOURCE_OF_TRUTH.is_valid(doc)
    # bootmap.tableau's fast path (jsonschema-rs) must give the same verdict as jsonschema itself.
    assert _fast_validator().is_valid(doc) == truth, "jsonschema-rs and jsonschema disagree"
    return truth, model, OPENAPI.is_valid(doc)


text = st.text(st.characters(exclude_characters="\x00"), max_size=3)
junk = st.one_of(st.none(), st.booleans(), text, st.lists(st.integers(), max_size=2),
                 st.dictionaries(st.text(max_size=2), st.integers(), max_size=1),
                 st.sampled_from([0, -1, 0.5, 360, 360.5, -360.5, 100000, 100000.5, 1e300, "", "fly", 3.0]))
finite = st.one_of(st.integers(-10**6, 10**6), st.floats(allow_nan=False, allow_infinity=False))
angle = st.one_of(st.integers(-360, 360), st.floats(-360, 360))
action = st.one_of(
    st.fixed_dictionaries({"type": st.just("turn"), "angle_deg": angle}),
    st.fixed_dictionaries({"type": st.just("travel"), "distance_m": st.floats(0, 1e5, exclude_min=True)},
                          optional={"heading_change_deg": angle}))
step = st.fixed_dictionaries({}, optional={
    "view": text.filter(bool), "action": action, "image": st.lists(finite, min_size=1, max_size=3),
    "truth": st.one_of(text, st.integers()), "pose": st.lists(finite, min_size=3, max_size=3)}
).filter(lambda d: "view" in d or "image" in d)
resolution = st.fixed_dictionaries({}, optional={"distance_m": st.floats(0, 1, exclude_min=True),
                                                 "angle_deg": st.floats(0, 10, exclude_min=True)})
meta = st.one_of(st.dictionaries(text, finite, max_size=2),
                 st.fixed_dictionaries({"resolution": resolution}, optional={"seed": st.integers(0, 99)}))
valid = st.fixed_dictionaries({"format": st.just(FORMAT), "steps": st.lists(step, min_size=1, max_size=3)},
                              optional={"world": text, "meta": meta})


def _places(x, path=()):
    """Every (path to a container, key) in a document."""
    if isinstance(x, dict):
        for k, v in x.items():
            yield path, k
            yield from _places(v, path + (k,))
    elif isinstance(x, list):
        for i, v in enumerate(x):
            yield path, i
            yield from _places(v, path + (i,))


@st.composite
def document(draw):
    """A valid tableau, or one with a single change: a value replaced, a field removed or one added."""
    doc = draw(valid)
    change = draw(st.sampled_from(["none", "replace", "remove", "add"]))
    if change == "none":
        return doc
    path, key = draw(st.sampled_from(list(_places(doc))))
    parent = doc
    for k in path:
        parent = parent[k]
    if change == "replace":
        parent[key] = draw(junk)
    elif change == "remove" and isinstance(parent, dict):
        del parent[key]
    elif isinstance(parent, dict):
        parent[draw(st.sampled_from(["colour", "speed", "view", "image", "type"]))] = draw(junk)
    return doc


@settings(max_examples=400, deadline=None)
@given(document())
def test_model_openapi_and_json_schema_agree(doc):
    truth, model, openapi = verdicts(doc)
    assert model == truth, f"pydantic {'accepts' if model else 'refuses'} what the JSON Schema does not"
    assert openapi == truth, f"the OpenAPI schema {'accepts' if openapi else 'refuses'} what the JSON Schema does not"


def test_the_papers_tableau_is_accepted_by_all_three(paper_doc):
    assert verdicts(paper_doc) == (True, True, True)


@pytest.mark.parametrize("bad", [
    {"angle_deg": False}, {"angle_deg": "90"}, {"angle_deg": None}, {"angle_deg": 361}, {"angle_deg": [90]},
])
def test_no_coercion_and_no_out_of_range_numbers(bad):
    doc = {"format": FORMAT, "steps": [{"view": "a", "action": {"type": "turn", **bad}}, {"view": "b"}]}
    assert verdicts(doc) == (False, False, False)


@pytest.mark.parametrize("step", [{"view": None}, {"truth": "S0"}, {"view": "a", "image": []},
                                  {"view": "a", "secret": 1}, {"view": ""}, {"view": "a", "pose": [0, 0]}])
def test_nulls_unknown_fields_and_empty_values_are_refused(step):
    assert verdicts({"format": FORMAT, "steps": [step]}) == (False, False, False)


def test_integral_floats_are_integers_as_in_json_schema():
    doc = {"format": FORMAT, "steps": [{"view": "a", "truth": 3.0}]}
    assert verdicts(doc) == (True, True, True)
    assert Tableau.from_dict(doc).steps[0].truth == 3


@pytest.mark.parametrize("given, ok", [({"distance_m": 0.01, "angle_deg": 0.1}, True), ({"angle_deg": 1}, True),
                                       ({"distance_m": 0}, False), ({"angle_deg": 11}, False),
                                       ({"distance_m": "0.01"}, False), ({"ticks": 0.01}, False), (0.01, False)])
def test_the_resolution_a_tableau_states_is_checked_by_all_three(given, ok):
    doc = {"format": FORMAT, "meta": {"resolution": given, "seed": 3}, "steps": [{"view": "a"}]}
    assert verdicts(doc) == (ok, ok, ok)


def test_nul_in_a_label_is_refused_by_all_three():
    assert verdicts({"format": FORMAT, "steps": [{"view": "a\x00b"}]}) == (False, False, False)
