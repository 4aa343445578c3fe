"""Explanations over HTTP (a real uvicorn process): the same answer `bootmap why` gives, as JSON."""

from bootmap.mapping.explain import Explainer
from bootmap.tableau import Tableau

PROBLEM = "application/problem+json"


def test_why_s0_s4_is_the_papers_boundary_argument(client, paper_id, paper_doc):
    r = client.get(f"/tableaux/{paper_id}/why", params={"a": "S0", "b": "S4", "levels": "causal,topological"})
    assert r.status_code == 200, r.text
    e = r.json()
    assert (e["a"], e["b"], e["verdict"]) == (0, 4, "different")
    assert set(e["evidence"]) <= {0, 1, 2, 3, 4}
    assert "on_path_no_side" in e["rules_cited"] and "right_by_turn" in e["rules_cited"]
    assert e["failures"][0]["rule"]["file"] == "topological.lp" and e["failures"][0]["premises"]
    assert e["levels"] == ["causal", "topological"] and "cannot be one dstate" in e["text"]
    # The service answers what the library answers.
    local = Explainer(levels=["causal", "topological"]).explain(Tableau.from_dict(paper_doc), "S0", "S4")
    assert e["evidence"] == local.evidence and e["rules_cited"] == local.rules_cited()


def test_why_same_and_all_levels(client, paper_id):
    e = client.get(f"/tableaux/{paper_id}/why", params={"a": "t0", "b": "8"}).json()
    assert e["verdict"] == "same" and e["dstates"] == ["S0", "S0"] and e["suggestion"]
    e = client.get(f"/tableaux/{paper_id}/why", params={"a": "t0", "b": "t4"}).json()
    assert e["verdict"] == "different" and "heading_is_feature" in e["rules_cited"]


def test_why_bad_questions_are_clear_problems(client, paper_id):
    cases = [({"a": "t0", "b": "t999"}, "t999"),
             ({"a": "S0", "b": "S99"}, "S99"),
             ({"a": "S0", "b": "S4", "levels": "causal,nonsense"}, "nonsense"),
             ({"a": "S0", "b": "S4", "levels": "topological"}, "causal"),
             ({"a": "a). #script (python)", "b": "S4"}, "a")]
    for params, named in cases:
        r = client.get(f"/tableaux/{paper_id}/why", params=params)
        assert r.status_code == 422, (params, r.text)
        assert r.headers["content-type"].startswith(PROBLEM) and named in r.text
    r = client.get("/tableaux/999999/why", params={"a": "S0", "b": "S4"})
    assert r.status_code == 404 and r.headers["content-type"].startswith(PROBLEM)
