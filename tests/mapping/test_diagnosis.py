"""When no map satisfies the axioms, the resolver says which level fails (bootmap.mapping.diagnosis)."""

import json
import shutil

import pytest

from bootmap.cli import main
from bootmap.errors import EXIT_FAILURE, InconsistentTableau
from bootmap.mapping import Resolver
from bootmap.mapping.theory import default_axioms_dir
from bootmap.tableau import Step, Tableau, Turn

# Turning around twice returns to the same dstate, yet the robot saw another view: the topological level
# (one dstate per place and direction) forbids it; the causal and metrical levels alone do not.
AROUND_TWICE = Tableau((Step("A", Turn(180.0)), Step("B", Turn(180.0)), Step("C")))


def test_the_failing_level_is_named_in_fields_and_message():
    with pytest.raises(InconsistentTableau) as e:
        Resolver().resolve(AROUND_TWICE)
    assert e.value.failing_levels == ["topological"] and e.value.diagnosed
    assert set(e.value.levels) == {"causal", "metrical", "topological"}
    assert "the topological level fails even with the causal level alone beside it" in str(e.value)


def test_the_causal_level_alone_failing_is_said_so(tmp_path):
    # A user's level that contradicts every tableau with a view B, added beside the shipped ones.
    axioms = tmp_path / "asp"
    shutil.copytree(default_axioms_dir(), axioms)
    (axioms / "causal.lp").write_text((axioms / "causal.lp").read_text() + '\n:- view(_, "B").\n')
    with pytest.raises(InconsistentTableau) as e:
        Resolver(axioms=axioms).resolve(AROUND_TWICE)
    assert e.value.failing_levels == ["causal"] and "the causal axioms alone already fail" in str(e.value)


def test_only_the_levels_together_failing_is_said_so(tmp_path):
    # Two user levels, each satisfiable beside the causal level, contradictory together.
    axioms = tmp_path / "asp"
    shutil.copytree(default_axioms_dir(), axioms)
    (axioms / "red.lp").write_text("% red: a dstate seen red\nred(D) :- is(T, D), view(T, \"A\").\n")
    (axioms / "not_red.lp").write_text("% not_red: ...but nothing may be red\n:- red(_).\n")
    with pytest.raises(InconsistentTableau) as e:
        Resolver(axioms=axioms, levels=["causal", "red", "not_red"]).resolve(AROUND_TWICE)
    assert e.value.failing_levels == [] and e.value.diagnosed
    assert "only the levels together fail" in str(e.value)


def test_bootmap_map_shows_the_failing_level(tmp_path, capsys):
    path = tmp_path / "t.json"
    path.write_text(json.dumps(AROUND_TWICE.to_dict()))
    assert main(["map", str(path)]) == EXIT_FAILURE
    err = capsys.readouterr().err
    assert "no map satisfies the axioms" in err and "the topological level fails" in err


def test_without_diagnosis_the_resolver_stops_at_the_first_failure():
    with pytest.raises(InconsistentTableau) as e:
        Resolver(diagnose=False).resolve(AROUND_TWICE)
    assert e.value.failing_levels == [] and not e.value.diagnosed and "fails" not in str(e.value)
