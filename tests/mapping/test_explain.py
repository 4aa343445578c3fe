"""Explanations with real clingo: why two dstates differ, why two are the same, and the evidence.

Every explanation that says "different" is re-checked here twice: the solver, given the evidence
alone, finds no map in which a and b are one dstate (and finds one as soon as any other step is
dropped: the evidence is subset-minimal); and, where the evidence is one run of steps, the independent
Python checker (support.check) rejects every partition of it that puts a and b together.
"""

import itertools
import json
import shutil
from dataclasses import replace

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
from support.check import check_map
from support.gridworld import random_world, walk

TOPO = ["causal", "topological"]


@pytest.fixture(scope="module")
def paper():
    return notched_rectangle(50)


def view_partitions(views: list[str]):
    """Every partition of range(len(views)) whose blocks hold one view each (no other partition can be a
    map), as lists of block numbers."""
    def grow(i, blocks, block_views):
        if i == len(views):
            yield list(blocks)
            return
        for k, v in enumerate(block_views):
            if v == views[i]:
                yield from grow(i + 1, blocks + [k], block_views)
        yield from grow(i + 1, blocks + [len(block_views)], block_views + [views[i]])
    yield from grow(0, [], [])


def recheck(explainer: Explainer, tableau: Tableau, e, levels) -> None:
    """The evidence alone forces a and b apart, and is subset-minimal (by the solver); and, by brute force
    with the independent Python checker (support.check), every partition of the evidence's time
    points that puts a and b together breaks an axiom - contiguous evidence or not."""
    assert e.verdict == "different" and e.evidence
    assert not explainer.can_be_same(tableau, e.a, e.b, e.evidence)
    for t in e.evidence:
        if t not in (e.a, e.b):
            assert explainer.can_be_same(tableau, e.a, e.b, [s for s in e.evidence if s != t]), t
    keep = sorted(e.evidence)
    a, b = keep.index(e.a), keep.index(e.b)
    views = [tableau.steps[t].view for t in keep]
    merging = [p for p in view_partitions(views) if p[a] == p[b]]
    if tableau.steps[e.a].view != tableau.steps[e.b].view:
        assert not merging  # told apart by their views alone
        return
    assert merging and all(check_map(tableau, p, levels, keep=keep) for p in merging), keep
    # ... while the evidence without any one step has a partition putting them together that passes.
    for t in keep:
        if t not in (e.a, e.b):
            rest = [s for s in keep if s != t]
            ra, rb = rest.index(e.a), rest.index(e.b)
            rviews = [tableau.steps[s].view for s in rest]
            assert any(not check_map(tableau, p, levels, keep=rest)
                       for p in view_partitions(rviews) if p[ra] == p[rb]), (keep, t)


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


def test_an_axiom_file_edited_between_two_explanations_is_read_again(tmp_path):
    # The instrumented theory is parsed once for as long as its files are unchanged (every explainer of
    # the process shares it); an edit reaches the next explainer made, as it reaches the next resolver.
    axioms = tmp_path / "asp"
    shutil.copytree(Resolver().theory.directory, axioms)
    daylight = axioms / "daylight.lp"
    daylight.write_text(DAYLIGHT)
    tableau = notched_rectangle(3)

    def explained():
        return Explainer(axioms=axioms, levels=["causal", "topological", "daylight"]).explain(tableau, 0, 16)

    assert [r.name for r in explained().axioms] == ["day_differs_from_night"]
    assert [r.name for r in explained().axioms] == ["day_differs_from_night"]  # unchanged: the same rules
    daylight.write_text(DAYLIGHT.replace("day_differs_from_night", "day_apart_from_night"))  # renamed
    assert [r.name for r in explained().axioms] == ["day_apart_from_night"]
    daylight.write_text(DAYLIGHT.split("% A dstate seen at daytime")[0])  # the constraint taken out
    assert explained().verdict == "same"


@settings(max_examples=40, deadline=None)
@given(keep=st.sets(st.integers(0, 40), max_size=30))
def test_an_excerpt_holds_the_kept_views_the_actions_between_kept_steps_and_a_resume_after_each_gap(keep):
    from bootmap.mapping.facts import Excerpts, tableau_facts

    facts = tableau_facts(notched_rectangle(5))
    got = {str(f) for f in Excerpts(facts)(keep)}
    # From the definition, on the facts' text: view(T, V) of a kept T; turn/travel/length(T, _) where T
    # and T + 1 are kept; resume(T) where T is kept and T - 1 is not (T > 0).
    expected = set()
    for f in map(str, facts):
        name, t = f.split("(")[0], int(f.split("(")[1].split(",")[0].rstrip(")"))
        if t in keep and (name == "view" or t + 1 in keep):
            expected.add(f)
    expected |= {f"resume({t})" for t in keep if t > 0 and t - 1 not in keep}
    assert got == expected


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
    """A random walk and two of its time points, mostly with the same view: pairs of different views are
    told apart by the view alone, so only same-view pairs reach "same", "undecided" and the real proofs."""
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    world = random_world(rng, 3, 3, extra_edges=1, landmarks=0.3)
    tableau = walk(world, draw(st.integers(8, 20)), rng)
    by_view: dict = {}
    for t, v in enumerate(tableau.views):
        by_view.setdefault(v, []).append(t)
    alike = [ts for ts in by_view.values() if len(ts) >= 2]
    if alike and draw(st.integers(0, 9)) > 0:
        ts = draw(st.sampled_from(sorted(alike)))
        a, b = sorted(draw(st.lists(st.sampled_from(ts), min_size=2, max_size=2, unique=True)))
    else:
        a, b = sorted(draw(st.lists(st.integers(0, len(tableau) - 1), min_size=2, max_size=2, unique=True)))
    return tableau, a, b


def check_verdict(ex: Explainer, tableau: Tableau, a: int, b: int) -> str:
    """The explanation agrees with the minimal maps, and every "different" has evidence that rechecks,
    unless no contradiction exists at all (minimality alone keeps them apart: then they can be one dstate
    in some valid map of the whole tableau). Returns the verdict, and for "different" what evidence."""
    cmap = ex.resolver.resolve(tableau)
    e = ex.explain(tableau, a, b)
    maps = [cmap.dstate_of] + cmap.alternatives
    if e.verdict == "same":
        assert all(m[a] == m[b] for m in maps) and not e.evidence
    elif e.verdict == "undecided":
        assert len({m[a] == m[b] for m in maps}) == 2
    elif e.evidence:
        assert all(m[a] != m[b] for m in maps)
        recheck(ex, tableau, e, TOPO)
        one_run = e.evidence == list(range(e.evidence[0], e.evidence[-1] + 1))
        return "different, one run of evidence" if one_run else "different, evidence with gaps"
    else:
        assert all(m[a] != m[b] for m in maps)
        assert ex.can_be_same(tableau, a, b), "different without evidence, yet no map can merge them"
    return e.verdict


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(walks_and_pairs())
def test_every_verdict_agrees_with_the_map_and_every_proof_rechecks(case):
    check_verdict(Explainer(levels=TOPO, time_limit=20), *case)


def test_the_property_reaches_every_kind_of_verdict():
    # The property above draws at random; here a fixed sample of look-alike pairs, near and far apart,
    # must reach "same" and "different" with evidence in one run and with gaps (which only the brute
    # force over partitions of an excerpt can recheck), so no branch goes untried.
    ex = Explainer(levels=TOPO, time_limit=20)
    seen = set()
    for seed in range(8):
        rng = np.random.default_rng(seed)
        tableau = walk(random_world(rng, 3, 3, extra_edges=1, landmarks=0.3), 20, rng)
        ts = [t for t, v in enumerate(tableau.views) if v == tableau.views[0]]
        for b in {ts[1], ts[-1]} if len(ts) > 1 else ():
            seen.add(check_verdict(ex, tableau, 0, b))
    assert {"same", "different, one run of evidence", "different, evidence with gaps"} <= seen, seen


def test_cli_why_out_of_time_exits_1(tmp_path, capsys):
    path = tmp_path / "paper.json"
    path.write_text(notched_rectangle(50).dumps())
    assert main(["why", str(path), "S0", "S4", "--levels", "causal,topological", "--time-limit", "1e-6"]) == 1
    assert "time limit" in capsys.readouterr().err


def test_questions_about_one_experience_resolve_it_once_and_new_experience_again(monkeypatch):
    # The viewer asks about pair after pair of one tableau: the minimal map is resolved the first time
    # only. Appended steps are new experience, and images or truth that the axioms never see are not.
    calls = []
    resolve = Resolver.resolve
    monkeypatch.setattr(Resolver, "resolve", lambda self, tableau, deadline: calls.append(len(tableau))
                        or resolve(self, tableau, deadline))
    explainer = Explainer(levels=["causal", "topological"])
    tableau = notched_rectangle(2)
    first = explainer.explain(tableau, "S0", "S4")
    again = explainer.explain(tableau, "t1", "t5")
    assert (first.verdict, again.verdict) == ("different", "different") and calls == [17]
    relabelled = Tableau(tuple(replace(s, truth=f"x{i}") for i, s in enumerate(tableau.steps)), tableau.world)
    assert explainer.explain(relabelled, "t0", "t8").verdict == "same" and calls == [17]
    longer = tableau.extend({"action": {"type": "turn", "angle_deg": -90}, "steps": [{"view": "V1"}]}, "test")
    assert explainer.explain(longer, "t0", "t4").evidence == first.evidence and calls == [17, 18]
