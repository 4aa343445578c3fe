"""Proofs read as sentences: every atom of the shipped axioms a proof shows has a phrase."""

import re

import pytest

from bootmap import examples
from bootmap.mapping import Explainer
from bootmap.tableau import Step, Tableau, Travel, Turn

RAW_ATOM = re.compile(r"\b[a-z_]+\(")  # e.g. heading(0, 0, 0): an atom a person would have to decode


def all_nodes(nodes):
    for n in nodes:
        yield n
        yield from all_nodes(n.premises)


def assert_reads_as_sentences(e):
    texts = [e.sentence] + [n.text for f in e.failures for n in all_nodes(f.premises)]
    assert e.failures and all(texts)
    raw = [t for t in texts if RAW_ATOM.search(t)]
    assert not raw, raw
    assert not RAW_ATOM.search(e.to_text())


@pytest.mark.parametrize("levels", [["causal", "metrical"], ["causal", "topological"], None])
def test_an_explanation_of_the_paper_reads_as_sentences(levels):
    e = Explainer(levels=levels).explain(examples.notched_rectangle(2), "S0", "S4")
    assert e.verdict == "different"
    assert_reads_as_sentences(e)


def test_headings_after_bent_travels_read_as_sentences():
    # An L-shaped corridor walked out and back: the travel bends 90 degrees, so the end of the walk faces
    # the other way from its start although both ends look alike (view A). Only the metrical level, by
    # heading_after_travel, tells t0 from t2.
    rows = (Step("A", Travel(3.0, 90.0)), Step("B", Turn(180.0)), Step("A"))
    e = Explainer(levels=["causal", "metrical"]).explain(Tableau(rows), 0, 2)
    assert e.verdict == "different"
    assert_reads_as_sentences(e)
    assert "heading_after_travel" in e.rules_cited()
    assert "net heading change 90 degrees" in e.to_text()
