"""The vocabulary (bootmap.mapping.vocabulary) agrees with the axiom files, and notices when it does not."""

import re
import shutil

import pytest
from clingo import Function, Number, String

from bootmap.mapping import vocabulary as vocab
from bootmap.mapping.theory import default_axioms_dir, load_theory


def axiom_files(directory):
    return sorted(directory.glob("*.lp")) + sorted((directory / "core").glob("*.lp"))


def test_the_shipped_axioms_use_every_predicate_of_the_vocabulary():
    assert vocab.mismatches(axiom_files(default_axioms_dir())) == []


def test_every_shown_atom_is_in_the_vocabulary():
    # Python reads what the theory shows; a #show of a predicate it does not know would be lost.
    theory = load_theory()
    shown = set()
    for f in theory.files:
        for line in f.read_text().splitlines():
            if line.startswith("#show ") and "/" in line:
                name, arity = line[len("#show "):].rstrip(".").split("/")
                shown.add((name, int(arity)))
    known = {p.signature for p in vocab.PREDICATES}
    assert shown and shown <= known, shown - known


@pytest.mark.parametrize("file, old, new, problem", [
    ("metrical.lp", "heading", "facing", "heading/3"),            # a derived predicate Python reads
    ("causal.lp", "view", "seen", "view/2"),                      # a tableau fact no rule reads any more
    ("core/partition.lp", "slots", "room", "slots/2"),            # a layout fact no rule reads any more
    ("topological.lp", "right", "right_of", "right/2"),           # a shown predicate
])
def test_renaming_a_predicate_in_an_lp_file_is_caught(tmp_path, file, old, new, problem):
    copy = tmp_path / "asp"
    shutil.copytree(default_axioms_dir(), copy)
    path = copy / file
    text = path.read_text()
    renamed = re.sub(rf"\b{old}\(", f"{new}(", text)
    assert renamed != text
    path.write_text(renamed)
    assert load_theory(copy).files  # still a theory clingo parses: only the name changed
    found = vocab.mismatches(axiom_files(copy))
    assert any(problem in p for p in found), found


def test_a_changed_future_depth_default_is_caught(tmp_path):
    copy = tmp_path / "asp"
    shutil.copytree(default_axioms_dir(), copy)
    causal = copy / "causal.lp"
    causal.write_text(causal.read_text().replace("#const future_depth = 8.", "#const future_depth = 6."))
    assert any("future_depth = 6" in p for p in vocab.mismatches(axiom_files(copy)))


def test_labels_become_strings_never_constants():
    # A view label that looks like program text is data: a clingo string, quoted when printed.
    atom = vocab.VIEW(3, "a). #script (python)")
    assert atom == Function("view", [Number(3), String("a). #script (python)")])
    assert str(atom) == 'view(3,"a). #script (python)")'
    with pytest.raises(TypeError, match="view/2 takes 2"):
        vocab.VIEW(3)


def test_every_phrase_names_only_arguments_the_predicate_has():
    for p in vocab.PREDICATES:
        if p.phrase:
            used = {int(m) for m in re.findall(r"\{P?(\d)\}", p.phrase)}
            assert used <= set(range(p.arity)), p


def test_the_predicate_dictionary_in_docs_asp_md_names_every_predicate_of_the_vocabulary():
    from pathlib import Path

    doc = (Path(__file__).resolve().parents[2] / "docs" / "asp.md").read_text()
    predicates = [x for x in vars(vocab).values() if isinstance(x, vocab.Predicate)]
    assert len(predicates) > 30
    missing = [f"{p.name}/{p.arity}" for p in predicates if not re.search(r"`" + re.escape(p.name) + r"(\(|`)", doc)]
    assert not missing, f"docs/asp.md has no entry for {missing}"


def test_the_vocabulary_names_every_function_term_of_the_shipped_axioms_and_no_other():
    assert vocab.term_mismatches(axiom_files(default_axioms_dir())) == []
    assert {(t.name, t.arity) for t in vocab.TERMS} >= {("d", 2), ("k", 3), ("c", 2), ("after", 1), ("s", 1)}


def test_a_renamed_function_term_in_an_lp_file_is_caught(tmp_path):
    shutil.copytree(default_axioms_dir(), tmp_path / "asp")
    causal = tmp_path / "asp" / "causal.lp"
    causal.write_text(causal.read_text().replace("after(S)", "seen_after(S)"))
    problems = vocab.term_mismatches(axiom_files(tmp_path / "asp"))
    assert "no rule uses the term after/1" in problems
    assert "the rules use the term seen_after/1, which the vocabulary does not name" in problems


def test_terms_are_built_as_the_axioms_build_them():
    assert str(vocab.CLASS_KEY_TERM(vocab.VIEW_FEATURE(), "V0", vocab.NIL())) == 'k(view,"V0",nil)'
    assert str(vocab.action_term("travel", 0, 40)) == "travel(40)" and str(vocab.action_term("turn", -90)) == "turn(-90)"
    assert vocab.SEQUENCE.matches(vocab.SEQUENCE(vocab.TURN_ACTION(90), vocab.NIL()))
    with pytest.raises(TypeError):
        vocab.FIXED_DSTATE(1, 2)
