"""Explanations with real clingo: why two dstates differ, why two are the same, and the evidence.

Every explanation that says "different" is re-checked here twice: the solver, given the evidence
alone, finds no map in which a and b are one dstate (and finds one as soon as any other step is
dropped: the evidence is subset-minimal); and, where the evidence is one run of steps, the independent
Python checker (bootmap.testing.check) rejects every partition of it that puts a and b together.
"""

import itertools
import json
import shutil

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bootmap.cli import main
from bootmap.errors import ExplainError
from bootmap.examples import corridor, notched_rectangle, square_room
from bootmap.mapping.explain import Explainer
from bootmap.mapping.resolver import Resolver
from bootmap.tableau import Tableau
from bootmap.testing.check import check_map
from bootmap.testing.gridworld import random_world, walk

TOPO = ["causal", "topological"]


@pytest.fixture(scope="module")
def paper():
    return notched_rectangle(50)


def excerpt(tableau: Tableau, steps: list[int]) -> Tableau:
    """A run of consecutive steps as a tableau of its own (the last step loses its action)."""
    d = tableau.to_dict()
    rows = [dict(d["steps"][t]) for t in steps]
    rows[-1].pop("action", None)
    return Tableau.from_dict({"format": d["format"], "steps": rows})


def partitions(n: int):
    """Every partition of range(n), as restricted growth strings."""
    def grow(prefix, top):
        if len(prefix) == n:
            yield list(prefix)
            return
        for block in range(top + 2):
            yield from grow(prefix + [block], max(top, block))
    yield from grow([0], 0)


def recheck(explainer: Explainer, tableau: Tableau, e, levels) -> None:
    """The evidence alone forces a and b apart, and is subset-minimal."""
    assert e.verdict == "different" and e.evidence
    assert not explainer.can_be_same(tableau, e.a, e.b, e.evidence)
    for t in e.evidence:
        if t not in (e.a, e.b):
            assert explainer.can_be_same(tableau, e.a, e.b, [s for s in e.evidence if s != t]), t
    if e.evidence == list(range(e.evidence[0], e.evidence[-1] + 1)):  # one run: check independently
        sub = excerpt(tableau, e.evidence)
        a, b = e.a - e.evidence[0], e.b - e.evidence[0]
        merging = [p for p in partitions(len(sub)) if p[a] == p[b]]
        assert merging and all(check_map(sub, p, levels) for p in merging)


def test_paper_s0_s4_without_metrical_is_the_papers_boundary_argument(paper):
    ex = Explainer(levels=TOPO)
    e = ex.explain(paper, "S0", "S4")
    assert (e.a, e.b, e.verdict) == (0, 4, "different")
    assert set(e.evidence) <= set(range(5))
    cited = e.rules_cited()
    assert "on_path_no_side" in cited and "on_path" in cited          # P lies on the path ...
    assert {"right_by_turn", "left_by_turn"} & set(cited)            # ... and on one side of it
    assert "topological.lp" in e.to_text() and "right of the path" in e.sentence
    recheck(ex, paper, e, TOPO)


def test_paper_s0_s4_with_metrical_may_use_headings(paper):
    ex = Explainer()
    e = ex.explain(paper, 0, 4)
    assert e.verdict == "different" and set(e.evidence) <= set(range(5))
    assert "heading_is_feature" in e.rules_cited() and "heading 180" in e.sentence
    recheck(ex, paper, e, ["causal", "topological", "metrical"])


def test_paper_s0_s8_same_by_minimality(paper):
    e = Explainer(levels=TOPO).explain(paper, 0, 8)
    assert e.verdict == "same" and e.names == ("S0", "S0")
    assert "minimality" in e.sentence and not e.evidence
    assert e.agree_steps > 8
    # The robot only ever turned right at S0; travelling on from there is in its vocabulary.
    assert any("travel" in s for s in e.suggestion)


def test_corridor_end_facing_in_and_out_differ_by_the_turn_around():
    # With the corridor's own views the two dstates at an end differ by view alone; with every view
    # alike only the turn-around can tell them apart.
    d = corridor(2, middle=False).to_dict()
    for s in d["steps"]:
        s["view"] = "X"
    tableau = Tableau.from_dict(d)
    ex = Explainer(levels=TOPO)
    e = ex.explain(tableau, 1, 2)           # east end: arrived facing east, turned around
    assert e.verdict == "different"
    assert "turn_around_link" in e.rules_cited()
    recheck(ex, tableau, e, TOPO)


def test_square_room_is_not_a_triangle_because_of_headings():
    tableau = square_room(3)
    triangle = Resolver(levels=TOPO).resolve(tableau)
    square = Resolver().resolve(tableau)
    assert (triangle.n_dstates, square.n_dstates) == (6, 8)
    # A pair the triangle merges and the square keeps apart.
    a, b = next((a, b) for a, b in itertools.combinations(range(len(tableau)), 2)
                if triangle.same(a, b) and not square.same(a, b))
    ex = Explainer()
    e = ex.explain(tableau, a, b)
    assert e.verdict == "different"
    assert {"heading_after_turn", "heading_is_feature"} <= set(e.rules_cited())
    recheck(ex, tableau, e, ["causal", "topological", "metrical"])


DAYLIGHT = """\
% The robot explored by day up to time 11 and by night from time 12 on.
%! seen_by_day
daytime(T) :- time(T), T < 12.
%! seen_by_night
night(T) :- time(T), T >= 12.

% A dstate seen at daytime differs from one seen at night.
%! day_differs_from_night
:- is(T1, D), is(T2, D), daytime(T1), night(T2).
"""


def test_a_users_new_rule_is_cited_by_name(tmp_path):
    axioms = tmp_path / "asp"
    shutil.copytree(Resolver().theory.directory, axioms)
    (axioms / "daylight.lp").write_text(DAYLIGHT)
    tableau = notched_rectangle(3)
    ex = Explainer(axioms=axioms, levels=["causal", "topological", "daylight"])
    e = ex.explain(tableau, 0, 16)         # S0 by day and S0 by night
    assert e.verdict == "different"
    assert [r.name for r in e.axioms] == ["day_differs_from_night"]
    assert {"seen_by_day", "seen_by_night"} <= set(e.rules_cited())
    assert "daylight.lp" in e.to_text()
    assert not ex.can_be_same(tableau, 0, 16, e.evidence)
    # Without the new level nothing separates them.
    assert Explainer(axioms=axioms, levels=TOPO).explain(tableau, 0, 16).verdict == "same"


def test_different_views_are_a_one_line_proof(paper):
    e = Explainer().explain(paper, 0, 1)
    assert e.verdict == "different" and e.evidence == [0, 1]
    assert e.rules_cited()[:2] == ["one_value_per_feature", "view_is_feature"]


def test_undecided_when_minimal_maps_disagree():
    # t0 and t2 look alike but travelling on showed different views, so they differ; the last look-alike,
    # t4, did nothing more: it may be either of them - two minimal maps.
    views, travel = ["A", "B", "A", "C", "A"], {"type": "travel", "distance_m": 1.0}
    steps = [{"view": v, "action": travel} for v in views[:-1]] + [{"view": views[-1]}]
    tableau = Tableau.from_dict({"format": "bootmap.tableau/1", "steps": steps})
    e = Explainer(levels=["causal"]).explain(tableau, 0, 4)
    assert e.verdict == "undecided"
    assert sorted(alt["apart"] for alt in e.alternatives) == [False, True]
    assert "disagree" in e.sentence and "minimal map 2" in e.to_text()
    assert Explainer(levels=["causal"]).explain(tableau, 0, 2).verdict == "different"


def test_bad_questions_are_clear(paper):
    ex = Explainer(levels=TOPO)
    with pytest.raises(ExplainError, match="t0..t400"):
        ex.explain(paper, 0, 999)
    with pytest.raises(ExplainError, match="S99"):
        ex.explain(paper, "S99", "S0")


def test_cli_why_text_json_and_bad_input(tmp_path, capsys):
    path = tmp_path / "paper.json"
    path.write_text(notched_rectangle(3).dumps())
    assert main(["why", str(path), "S0", "S4", "--levels", "causal,topological"]) == 0
    text = capsys.readouterr().out
    assert "different" in text and "on_path_no_side (topological.lp:" in text
    assert main(["why", str(path), "t0", "t8", "--format", "json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["verdict"] == "same" and data["dstates"] == ["S0", "S0"]
    assert main(["why", str(path), "t0", "nowhere"]) == 2
    assert "nowhere" in capsys.readouterr().err


@st.composite
def walks_and_pairs(draw):
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    world = random_world(rng, 3, 3, extra_edges=1, landmarks=0.3)
    tableau = walk(world, draw(st.integers(8, 24)), rng)
    a, b = sorted(draw(st.lists(st.integers(0, len(tableau) - 1), min_size=2, max_size=2, unique=True)))
    return tableau, a, b


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(walks_and_pairs())
def test_every_verdict_agrees_with_the_map_and_every_proof_rechecks(case):
    tableau, a, b = case
    ex = Explainer(levels=TOPO, time_limit=20)
    cmap = ex.resolver.resolve(tableau)
    e = ex.explain(tableau, a, b)
    maps = [cmap.dstate_of] + cmap.alternatives
    if e.verdict == "same":
        assert all(m[a] == m[b] for m in maps)
    elif e.verdict == "undecided":
        assert len({m[a] == m[b] for m in maps}) == 2
    else:
        assert all(m[a] != m[b] for m in maps)
        if e.evidence:
            recheck(ex, tableau, e, TOPO)


def test_cli_why_out_of_time_exits_1(tmp_path, capsys):
    path = tmp_path / "paper.json"
    path.write_text(notched_rectangle(50).dumps())
    assert main(["why", str(path), "S0", "S4", "--levels", "causal,topological", "--time-limit", "1e-6"]) == 1
    assert "time limit" in capsys.readouterr().err
