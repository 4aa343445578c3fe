"""The tableau format: valid documents load, every malformed one is refused with its place named."""

import json
import math

import pytest
from hypothesis import given, strategies as st

from bootmap.errors import TableauError
from bootmap.tableau import Tableau, Travel, Turn, load, schema

OK_STEPS = [{"view": "V0", "action": {"type": "turn", "angle_deg": -90}},
            {"view": "V1", "action": {"type": "travel", "distance_m": 4.0, "heading_change_deg": 0}},
            {"view": "V2"}]


def doc(steps):
    return {"format": "bootmap.tableau/1", "steps": steps}


def test_valid_tableau_loads_with_its_actions():
    t = Tableau.from_dict(doc(OK_STEPS))
    assert t.views == ["V0", "V1", "V2"]
    assert t.actions == [Turn(-90.0), Travel(4.0, 0.0)]


def test_round_trip_through_json_keeps_everything():
    steps = [dict(OK_STEPS[0], image=[1.0, 2.5], truth="S0", pose=[0.0, 1.0, 3.1]),
             dict(OK_STEPS[1], truth=3), {"view": "V2", "truth": "S2"}]
    t = Tableau.from_dict(doc(steps))
    assert Tableau.loads(t.dumps()) == t


BAD = [
    ("unknown action type", [{"view": "a", "action": {"type": "jump"}}, {"view": "b"}],
     "steps[0].action.type", "unknown action type 'jump'"),
    ("missing action", [{"view": "a"}, {"view": "b"}], "steps[0].action", "needs an action"),
    ("action on last step", [{"view": "a", "action": {"type": "turn", "angle_deg": 90}}], "steps[0].action",
     "no step follows"),
    ("empty", [], "steps", "at least one step"),
    ("string distance", [{"view": "a", "action": {"type": "travel", "distance_m": "4"}}, {"view": "b"}],
     "steps[0].action.distance_m", "not of type 'number'"),
    ("boolean angle", [{"view": "a", "action": {"type": "turn", "angle_deg": True}}, {"view": "b"}],
     "steps[0].action.angle_deg", "not of type 'number'"),
    ("integer view", [{"view": "a", "action": {"type": "turn", "angle_deg": 90}}, {"view": 7}],
     "steps[1].view", "not of type 'string'"),
    ("negative distance", [{"view": "a", "action": {"type": "travel", "distance_m": -1}}, {"view": "b"}],
     "steps[0].action.distance_m", "less than or equal to the minimum"),
    ("absurd angle", [{"view": "a", "action": {"type": "turn", "angle_deg": 1e9}}, {"view": "b"}],
     "steps[0].action.angle_deg", "greater than the maximum"),
    ("unknown field", [{"view": "a", "action": {"type": "turn", "angle_deg": 9, "speed": 1}}, {"view": "b"}],
     "steps[0].action", "unknown field"),
    ("no view nor image", [{"action": {"type": "turn", "angle_deg": 9}}, {"view": "b"}], "steps[0]",
     "needs a view or an image"),
    ("ragged images", [{"view": "a", "image": [1, 2], "action": {"type": "turn", "angle_deg": 9}},
                       {"view": "b", "image": [1]}], "steps[1].image", "has 1 values"),
]


@pytest.mark.parametrize("name,steps,where,what", BAD, ids=[b[0] for b in BAD])
def test_malformed_tableau_names_step_and_field(name, steps, where, what):
    with pytest.raises(TableauError) as e:
        Tableau.from_dict(doc(steps), source="t.json")
    assert f"t.json: {where}" in str(e.value)
    assert what in str(e.value)


@pytest.mark.parametrize("constant", ["NaN", "Infinity", "-Infinity"])
def test_non_finite_numbers_are_refused(constant):
    text = '{"format": "bootmap.tableau/1", "steps": [{"view": "a", "action": {"type": "turn", "angle_deg": %s}}, ' \
           '{"view": "b"}]}' % constant
    with pytest.raises(TableauError, match="not a finite number"):
        Tableau.loads(text)


def test_non_finite_number_built_in_python_is_refused():
    steps = [{"view": "a", "action": {"type": "turn", "angle_deg": math.nan}}, {"view": "b"}]
    with pytest.raises(TableauError, match=r"steps\[0\].action.angle_deg"):
        Tableau.from_dict(doc(steps))


@pytest.mark.parametrize("text,what", [("{", "not valid JSON"), ("[" * 100000, "nested too deeply"),
                                        ('{"format": "bootmap.tableau/2", "steps": [{"view": "a"}]}',
                                         "unsupported format"),
                                        ('{"steps": [{"view": "a"}]}', "'format' is a required property")])
def test_broken_documents_are_refused(text, what):
    with pytest.raises(TableauError, match=what):
        Tableau.loads(text)


@pytest.mark.parametrize("data, where", [
    ('{"format": "bootmap.tableau/1",\n "steps": [{"view": "caf\xe9"}]}'.encode("latin-1"), "line 2 column 25"),
    (b"\x89PNG\r\n\x1a\n" + bytes(range(256)), "line 1 column 1"),
])
def test_bytes_that_are_not_utf8_are_refused_saying_where(tmp_path, data, where):
    path = tmp_path / "run.json"
    path.write_bytes(data)
    with pytest.raises(TableauError, match=rf"run\.json: not UTF-8 text \(JSON is\): byte 0x[0-9a-f]{{2}} at {where}"):
        load(path)


@pytest.mark.parametrize("name, data", [("run.bag", bytes(range(256))), ("run.g2o", b"VERTEX_SE2 0 0 0 0\n"),
                                        ("run.log.gz", b"\x1f\x8b\x08\x00")])
def test_a_robots_log_given_as_a_tableau_says_which_command_reads_it(tmp_path, name, data):
    path = tmp_path / name
    path.write_bytes(data)
    with pytest.raises(TableauError, match=rf"a robot's log is read into a tableau by `bootmap ingest {name}"):
        load(path)


def test_the_command_line_exits_2_on_a_log_or_a_binary_file(tmp_path, capsys):
    from bootmap.cli import main

    for name in ("run.mcap", "picture.png"):
        (tmp_path / name).write_bytes(bytes(range(200, 256)) * 4)
        assert main(["map", str(tmp_path / name)]) == 2
        err = capsys.readouterr().err
        assert f"{name}: not UTF-8 text" in err and "Traceback" not in err
        assert ("bootmap ingest" in err) == name.endswith(".mcap")


@pytest.mark.parametrize("match, where, said", [
    ({"a": 0, "b": 3, "score": 0.9}, "meta.place_matches[0].b",
     "names no time point of the tableau (3; it has 0 to 2)"),
    ({"a": 1, "b": 1, "score": 0.9}, "meta.place_matches[0]", "matches time point 1 with itself"),
    ({"a": 0, "b": 2, "score": 1.2}, "meta.place_matches[0].score", "1.2 is greater than the maximum of 1"),
])
def test_a_place_match_the_tableau_cannot_hold_is_refused_when_read_naming_file_and_field(tmp_path, capsys, match,
                                                                                         where, said):
    from bootmap.cli import main

    turn = {"type": "turn", "angle_deg": 90}
    steps = [{"view": "a", "action": turn}, {"view": "b", "action": turn}, {"view": "a"}]
    run = tmp_path / "run.json"
    run.write_text(json.dumps({"format": "bootmap.tableau/1", "steps": steps, "meta": {"place_matches": [match]}}))
    with pytest.raises(TableauError) as e:
        load(run)
    assert e.value.where == f"{run}: {where}" and said in str(e.value)
    assert main(["map", str(run)]) == 2
    err = capsys.readouterr().err
    assert f"{run}: {where}" in err and "Traceback" not in err


def test_missing_file_is_named(tmp_path):
    with pytest.raises(TableauError, match="nope.json: cannot read"):
        load(tmp_path / "nope.json")


def test_schema_is_valid_json_schema_and_describes_the_format():
    import jsonschema

    jsonschema.Draft202012Validator.check_schema(schema())
    assert schema()["properties"]["format"]["const"] == "bootmap.tableau/1"


labels = st.text(min_size=1, max_size=30)


@given(st.lists(st.tuples(labels, st.sampled_from(["turn", "travel"]),
                          st.floats(-359, 359, allow_nan=False)), min_size=1, max_size=12), labels)
def test_any_well_formed_tableau_round_trips(rows, last):
    steps = [{"view": v, "action": ({"type": "turn", "angle_deg": x} if k == "turn"
                                    else {"type": "travel", "distance_m": abs(x) + 0.1})} for v, k, x in rows]
    steps.append({"view": last})
    t = Tableau.from_dict(doc(steps))
    assert len(t) == len(steps)
    assert Tableau.loads(json.dumps(t.to_dict())) == t


def test_an_integer_beyond_any_float_is_refused_by_name():
    text = '{"format": "bootmap.tableau/1", "steps": [{"view": "a", "pose": [1' + "0" * 400 + ", 0, 0]}]}"
    with pytest.raises(TableauError, match=r"steps\[0\]\.pose\[0\]: a number of 401 digits is too large"):
        Tableau.loads(text)


def test_image_values_are_bounded_so_that_distances_stay_finite():
    for value in (1e10, -1.7e308, 10**400):
        with pytest.raises(TableauError, match=r"steps\[0\]\.image\[0\]"):
            Tableau.from_dict({"format": "bootmap.tableau/1", "steps": [{"image": [value]}]})
    assert Tableau.from_dict({"format": "bootmap.tableau/1", "steps": [{"image": [1e9, -1e9]}]}).steps[0].image == \
        (1e9, -1e9)


def test_a_nul_in_a_view_label_is_refused():
    # clingo holds strings as C strings: "a\0b" and "a\0c" would be one view.
    doc = {"format": "bootmap.tableau/1", "steps": [{"view": "a\u0000b"}]}
    with pytest.raises(TableauError, match=r"steps\[0\]\.view: .*NUL"):
        Tableau.from_dict(doc)
    assert Tableau.from_dict({"format": "bootmap.tableau/1", "steps": [{"view": "a). #script (python)"}]})


BAD_STEPS = [{"view": "V9", "action": {"type": "jump"}}, {"view": 3, "action": {"type": "turn", "angle_deg": 0}},
             {"action": {"type": "turn", "angle_deg": 0}}, {"view": "V9", "action": {"type": "turn", "angle_deg": 999}},
             {"view": "V9", "action": {"type": "turn", "angle_deg": 90}, "colour": "red"}]


@given(st.integers(2, 60), st.integers(0, 59), st.sampled_from(BAD_STEPS))
def test_a_bad_step_among_repeated_good_ones_is_named_by_its_own_index(laps, where, bad):
    # Repeated steps are schema-checked once each; the error must still name the bad step where it is,
    # with the message the plain check gives.
    good = [OK_STEPS[0], OK_STEPS[1]] * laps + [OK_STEPS[2]]
    where = where % (len(good) - 1)
    steps = good[:where] + [bad] + good[where + 1:]
    with pytest.raises(TableauError) as repeated:
        Tableau.from_dict(doc(steps))
    with pytest.raises(TableauError) as alone:
        Tableau.from_dict(doc([bad, OK_STEPS[2]]))
    assert repeated.value.where.startswith(f"tableau: steps[{where}]")
    assert repeated.value.reason == alone.value.reason
    assert Tableau.from_dict(doc(good)).steps[:2] == Tableau.from_dict(doc(OK_STEPS)).steps[:2]


def test_odometry_round_trips_and_a_bad_one_is_named():
    steps = [{"view": "a", "odometry": [1.5, -2.0, 0.25], "action": {"type": "travel", "distance_m": 3}},
             {"view": "b", "odometry": [4.5, -2.0, 0.25]}]
    t = Tableau.from_dict(doc(steps))
    assert t.steps[1].odometry == (4.5, -2.0, 0.25) and Tableau.loads(t.dumps()) == t
    assert t.with_views(["x", "y"]).steps[0].odometry == (1.5, -2.0, 0.25)  # kept through copies
    assert t.prefix(1).steps[0].odometry == (1.5, -2.0, 0.25)
    with pytest.raises(TableauError, match=r"steps\[1\]\.odometry"):
        Tableau.from_dict(doc([steps[0], {"view": "b", "odometry": [1, 2]}]))
    with pytest.raises(TableauError, match=r"steps\[1\]\.odometry\[2\]"):
        Tableau.from_dict(doc([steps[0], {"view": "b", "odometry": [1, 2, math.nan]}]))


def test_a_tableau_built_in_code_is_held_to_what_a_document_is():
    from bootmap.tableau import Step, Tableau, Turn

    with pytest.raises(TableauError, match=r"last step has an action") as e:
        Tableau((Step("A", Turn(90.0)), Step("B", Turn(90.0))))
    assert e.value.where == "tableau: steps[1].action"
    with pytest.raises(TableauError, match=r"every step but the last needs an action") as e:
        Tableau((Step("A"), Step("B")))
    assert e.value.where == "tableau: steps[0].action"
    assert len(Tableau((Step("A", Turn(90.0)), Step("B")))) == 2
