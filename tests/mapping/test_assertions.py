"""A person's assertions with real clingo: same/apart, hard and soft, what they change, and the clash when
no map honours them (with the assertions, steps and axioms it needs)."""

import json

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bootmap.cli import main
from bootmap.errors import AssertionConflict, AssertionsError, InconsistentTableau
from bootmap.examples import notched_rectangle
from bootmap.mapping.api import Mapper, proved
from bootmap.mapping.assertions import load_assertions, parse_assertions
from bootmap.mapping.diff import MapDiff
from bootmap.mapping.grounding import Deadline
from bootmap.mapping.loops import LoopCloser
from bootmap.mapping.resolver import Resolver
from bootmap.tableau import Step, Tableau, Travel
from support.check import check_map
from support.gridworld import random_world, walk

TOPO = ("causal", "topological")


@pytest.fixture(scope="module")
def paper():
    return notched_rectangle(2)  # two circuits: t0, t8 and t16 are S0


def said(entries, tableau):
    return parse_assertions(entries, len(tableau))


def undecided() -> Tableau:
    """t0 and t2 look alike but what followed differs; t4 looks alike and did nothing more: t4 may be t0's
    dstate or t2's (two minimal maps)."""
    return Tableau(tuple(Step(v, Travel(1.0) if i < 4 else None) for i, v in enumerate("ABACA")))


# --- Reading assertions -------------------------------------------------------------------------------

def test_a_file_of_assertions_reads_time_points_dstates_and_soft_costs(tmp_path):
    f = tmp_path / "notes.json"
    f.write_text(json.dumps({"format": "bootmap.assertions/1", "assertions": [
        {"same": ["t3", 45]}, {"apart": ["S2", "t9"], "soft": True, "cost": 7, "note": "two doors alike"}]}))
    same, apart = load_assertions(f, n_steps=50)
    assert (same.kind, same.a, same.b, same.soft) == ("same", 3, 45, False)
    assert (apart.kind, apart.a, apart.b, apart.soft, apart.cost, apart.note) == ("apart", "S2", 9, True, 7,
                                                                                   "two doors alike")
    assert str(apart) == "apart(S2, t9) soft, cost 7"
    assert parse_assertions([{"same": [45, 3]}])[0].pair == (3, 45)  # either order


@pytest.mark.parametrize("text, where, message", [
    ('{"assertions": [{"same": ["t3", "t90"]}]}', "assertions[0].same[1]", "t90 is not in the tableau (it has t0..t49)"),
    ('{"assertions": [{"apart": ["t3", 3]}]}', "assertions[0].apart", "cannot be apart from itself"),
    ('{"assertions": [{"same": ["t3"]}]}', "assertions[0].same", "expected two time points"),
    ('{"assertions": [{"same": ["t3", "x"]}]}', "assertions[0].same[1]", "neither a time point"),
    ('{"assertions": [{"same": [1, 2], "apart": [1, 2]}]}', "assertions[0]", "exactly one of"),
    ('{"assertions": [{"same": [1, 2], "cost": 3}]}', "assertions[0].cost", "a cost is for a soft assertion"),
    ('{"assertions": [{"same": [1, 2], "soft": true, "cost": 0}]}', "assertions[0].cost", "whole number"),
    ('{"assertions": [{"same": [1, 2], "soft": "yes"}]}', "assertions[0].soft", "true or false"),
    ('{"assertions": [{"same": [1, 2], "who": "me"}]}', "assertions[0]", "unknown key 'who'"),
    ('{"format": "other/1", "assertions": []}', "format", "is not 'bootmap.assertions/1'"),
    ('{"assertions": {"same": [1, 2]}}', "assertions", "expected a list"),
    ('{"assertions": [\n{"same": [1, 2]\n]}', "", "not JSON: Expecting ',' delimiter at line 3"),
])
def test_bad_assertions_name_the_file_and_the_field(tmp_path, text, where, message):
    f = tmp_path / "notes.json"
    f.write_text(text)
    with pytest.raises(AssertionsError) as e:
        load_assertions(f, n_steps=50)
    assert str(e.value).startswith(f"{f}: {where}") and message in str(e.value)


def test_a_dstate_name_is_its_first_visit_in_the_map_without_the_assertions(paper):
    result = Mapper().honour(paper, said([{"apart": ["S0", "t8"]}], paper))
    assert result.assertions[0].pair == (0, 8)
    with pytest.raises(AssertionsError, match="no dstate S99"):
        Mapper().honour(paper, said([{"apart": ["S99", "t8"]}], paper))
    with pytest.raises(AssertionsError, match="both ends are S0"):
        Mapper().honour(paper, said([{"same": ["S0", "t0"]}], paper))


# --- Honouring them -------------------------------------------------------------------------------------

def test_apart_splits_a_dstate_and_the_diff_says_so(paper):
    result = Mapper().honour(paper, said([{"apart": ["t0", "t8"]}], paper))
    assert result.conflict is None and result.before.same(0, 8) and not result.after.same(0, 8)
    assert result.after.unique and result.after.n_dstates == result.before.n_dstates + 1
    assert result.diff.split == [{"was": "S0", "now": ["S0", "S8"]}] and not result.diff.joined
    assert "dstate S0 split: now S0, S8" in result.to_text()


def test_same_decides_what_the_experience_left_open():
    tableau = undecided()
    mapper = Mapper(levels=["causal"])
    before = mapper.map(tableau)
    assert before.n_models == 2
    for other in (0, 2):
        result = mapper.honour(tableau, said([{"same": [other, 4]}], tableau), before=before)
        assert result.after.unique and result.after.same(other, 4)
        assert result.after.n_dstates == before.n_dstates
        kept_apart = 2 - other
        assert not result.after.same(kept_apart, 4)


def test_a_soft_assertion_is_kept_only_where_it_is_worth_its_cost(paper):
    cheap = Mapper().honour(paper, said([{"apart": [0, 8], "soft": True, "cost": 3}], paper))
    assert cheap.after.same(0, 8) and cheap.broken == cheap.assertions  # a dstate costs 4: not worth it
    assert "not kept" in cheap.to_text()
    dear = Mapper().honour(paper, said([{"apart": [0, 8], "soft": True, "cost": 9}], paper))
    assert not dear.after.same(0, 8) and not dear.broken and dear.after.n_dstates == 9
    # a soft same picks among the minimal maps, as a hard one does, without ruling the others out
    tableau = undecided()
    soft = Mapper(levels=["causal"]).honour(tableau, said([{"same": [2, 4], "soft": True}], tableau))
    assert soft.after.same(2, 4) and soft.after.unique


def test_same_and_apart_that_determinism_cannot_both_honour_clash_with_their_proof(paper):
    # Both laps turn -90 at S0: t0 = t8 would make t1 = t9 (deterministic_action), which a person said are
    # apart: turn -90 from t0 reaches a time point a person told apart from where turn -90 from t8 does.
    result = Mapper().honour(paper, said([{"apart": ["t1", "t9"]}, {"same": ["t0", "t8"]}], paper))
    assert result.after is None and result.diff is None
    conflict = result.conflict
    assert [str(a) for a in conflict.assertions] == ["same(t0, t8)", "apart(t1, t9)"]
    e = conflict.explanation
    assert (e.a, e.b, e.verdict, e.evidence) == (0, 8, "different", [0, 1, 8, 9])
    cited = {r.name: f"{r.file.rsplit('/', 1)[-1]}:{r.line}" for r in e.axioms}
    assert set(cited) == {"one_value_per_feature"} and cited["one_value_per_feature"].startswith("causal.lp:")
    # the person's word, reached by the same action from both, is the premise of the proof
    assert {"told_apart_ahead", "asserted_apart"} <= set(e.rules_cited())
    text = result.to_text()
    assert "same(t0, t8); apart(t1, t9)" in text and f"one_value_per_feature ({cited['one_value_per_feature']})" in text
    assert "turn -90 from t0 reached t1, which a person told apart from t9" in text
    # the clash is minimal: each assertion alone has a map
    for one in conflict.assertions:
        assert Resolver().resolve(paper, assertions=[one]) is not None
    with pytest.raises(InconsistentTableau):
        Resolver().resolve(paper, assertions=conflict.assertions)


def test_assertions_the_map_already_honours_need_no_search_to_be_cleared(paper, monkeypatch):
    # The map made without them is a map of the experience: where it honours a set of assertions, that set
    # cannot clash, and the explainer says so without grounding anything (a clash's deletion test asks
    # this of every subset: for the paper's same(t0, t8) alone, a search grounds fourteen windows).
    from bootmap.mapping import explain
    from bootmap.mapping.explain import Explainer

    explainer = Explainer()
    cmap = explainer.minimal_map(paper, Deadline.after(60))
    grounded = []
    real = explain.Grounding.ground
    monkeypatch.setattr(explain.Grounding, "ground", lambda self, *parts: grounded.append(1) or real(self, *parts))
    honoured = said([{"same": ["t0", "t8"]}, {"apart": ["t0", "t1"]}], paper)
    assert explainer.conflict(paper, honoured, cmap=cmap, local=True) is None
    assert explainer.conflict(paper, honoured, cmap=cmap) is None and not grounded
    clash = said([{"same": ["t0", "t8"]}, {"apart": ["t1", "t9"]}], paper)
    assert [str(x) for x in explainer.conflict(paper, clash, cmap=cmap, local=True).assertions] == [
        "same(t0, t8)", "apart(t1, t9)"]
    assert grounded  # a clash is still searched for and proved


def test_an_apart_the_axioms_refute_is_a_clash_with_its_proof():
    """There and back again: a robot that turns around twice on the spot faces the way it faced before, at
    the same place on the same path; the topological level makes those two one dstate (two dstates of one
    place facing one way along one path are one), so a person's apart of them clashes, and the proof names
    the assertion, the axiom (file:line) and the three steps."""
    from bootmap.tableau import Turn
    tableau = Tableau(tuple(Step(v, a) for v, a in
                            [("A", Turn(180.0)), ("B", Turn(180.0)), ("A", Travel(1.0)), ("C", None)]))
    result = Mapper(time_limit=60).honour(tableau, said([{"apart": [0, 2]}], tableau))
    c = result.conflict
    assert result.after is None and c is not None and [str(x) for x in c.assertions] == ["apart(t0, t2)"]
    e = c.explanation
    assert e.verdict == "same" and e.supposed == "apart" and e.evidence == [0, 1, 2]
    cited = {r.name: r.cite() for r in e.axioms}
    assert cited["one_dstate_per_place_and_direction"].startswith("one_dstate_per_place_and_direction (topological.lp:")
    text = c.to_text()
    assert "cannot be different dstates" in text and "Suppose t0 and t2 are different dstates" in text
    assert "t1 view 'B'" in text or "t1 view B" in text
    # without the topological level the two may differ: no clash
    assert Mapper(time_limit=60, levels=["causal", "metrical"]).honour(
        tableau, said([{"apart": [0, 2]}], tableau)).conflict is None
    # loop closing: the apart refuses the join, and the axioms reject the partition without it
    looped = Mapper(time_limit=60, how="loops").honour(tableau, said([{"apart": [0, 2]}], tableau)).conflict
    assert looped is not None and looped.explanation.verdict == "same"
    assert [r.name for r in looped.explanation.axioms] == ["one_dstate_per_place_and_direction"]
    assert "cannot be different dstates of a loop-closed map" in looped.to_text()


def test_an_assertion_the_experience_alone_refutes_is_the_whole_clash(paper):
    result = Mapper().honour(paper, said([{"same": ["t0", "t4"]}, {"apart": ["t2", "t10"]}], paper))
    assert [str(a) for a in result.conflict.assertions] == ["same(t0, t4)"]  # the other is not part of it
    assert "heading 0" in result.conflict.sentence and "heading 180" in result.conflict.sentence


def test_a_loop_closers_map_makes_a_persons_join_with_all_that_determinism_then_joins(paper):
    # A loop closer that proposes nothing keeps every visit its own dstate; asserting that t0 is t8 joins
    # the second lap to the first step by step, as far as the actions agree.
    doc, rng = paper.to_dict(), np.random.default_rng(0)
    for step in doc["steps"]:  # travels read a few per cent off: no two visits dead-reckoned to one spot
        if step.get("action", {}).get("type") == "travel":
            step["action"]["distance_m"] *= rng.uniform(0.95, 1.05)
    drifted = Tableau.from_dict(doc)
    shy = LoopCloser(Resolver(), radius_m=1e-6, near_share=0.0, drift_share=0.0, context=10 ** 6)
    before = shy.resolve(drifted)
    assert before.n_dstates == len(drifted)
    after = shy.resolve(drifted, assertions=said([{"same": ["t0", "t8"]}], drifted))
    assert [after.same(t, t + 8) for t in range(9)] == [True] * 9
    assert len(MapDiff.between(before, after).joined) == 8 and after.n_dstates == 8  # the true map: t16 is t8 too
    clash = said([{"same": ["t0", "t8"]}, {"apart": ["t3", "t11"]}], drifted)
    with pytest.raises(InconsistentTableau):
        shy.resolve(drifted, assertions=clash)
    refused = shy.conflict(drifted, clash, before, Deadline.after(30))
    assert [str(a) for a in refused.assertions] == ["same(t0, t8)", "apart(t3, t11)"]
    assert "a person said they are different dstates" in refused.sentence


def test_an_apart_that_lifts_a_clean_exploration_over_its_bound_is_answered_by_reading_views_as_seen():
    """A person's apart splits a dstate, and determinism carries the split back: the map needs more
    dstates than the classes' lower bound says. On clean experience (aliasing makes some views look
    surprising, but no misread is evident) the exact maps just above the bound are looked for before any
    misread is weighed; weighing misreads at every bound up to the answer timed out (20 s) on 20 of 36
    such aparts on 240-step explorations."""
    rng = np.random.default_rng(0)
    tableau = walk(random_world(rng, 4, 4, extra_edges=3, landmarks=0.4), 240, rng, policy="explore")
    before = Resolver().resolve(tableau)
    assert before.same(123, 212)
    apart = said([{"apart": [123, 212]}], tableau)
    cmap = Resolver(time_limit=60).resolve(tableau, assertions=apart)
    assert not cmap.same(123, 212) and cmap.minimal and not cmap.suspect_steps
    assert not [t for t in cmap.stats.bounds if "misreads" in t.dstates], cmap.stats.bounds
    # The fewest dstates reading every view as seen, as a search that never weighs misreads finds them.
    as_seen = Resolver(time_limit=60, misreads=False).resolve(tableau, assertions=apart)
    assert cmap.n_dstates == as_seen.n_dstates > before.n_dstates
    assert check_map(tableau, cmap.dstate_of) == []


# --- Invariants over random walks ---------------------------------------------------------------------

@settings(max_examples=12, deadline=None, suppress_health_check=list(HealthCheck))
@given(seed=st.integers(0, 10 ** 6), kind=st.sampled_from(["same", "apart"]), pick=st.integers(0, 10 ** 6))
def test_every_answer_honours_the_assertions_or_is_a_minimal_clash(seed, kind, pick):
    rng = np.random.default_rng(seed)
    world = random_world(rng, 3, 3, extra_edges=int(rng.integers(0, 3)), landmarks=0.3)
    tableau = walk(world, int(rng.integers(10, 24)), rng, policy="explore")
    views = tableau.views
    pairs = [(a, b) for a in range(len(tableau)) for b in range(a + 1, len(tableau)) if views[a] == views[b]]
    if not pairs:
        return
    a, b = pairs[pick % len(pairs)]
    mapper = Mapper(levels=TOPO, misreads=False)
    result = mapper.honour(tableau, said([{kind: [a, b]}], tableau))
    if result.conflict is None:
        after = result.after
        assert after.same(a, b) == (kind == "same")
        assert check_map(tableau, after.dstate_of, levels=TOPO) == []  # the independent checker agrees
        assert after.n_dstates >= result.before.n_dstates  # minimal without them: never fewer with them
    else:
        e = result.conflict.explanation
        assert {a, b} <= set(e.evidence) and e.supposed == kind
        assert check_map(tableau, result.before.dstate_of, levels=TOPO) == []
        if kind == "same":  # no map of the evidence alone joins them
            assert e.verdict == "different" and not mapper.explainer.can_be_same(tableau, a, b, e.evidence)
        else:  # an apart clashes where the topological level makes them one dstate: no map keeps them apart
            assert e.verdict == "same" and not mapper.explainer.can_be_apart(tableau, a, b, e.evidence)
            assert "one_dstate_per_place_and_direction" in [r.name for r in e.axioms]


@settings(max_examples=20, deadline=None, suppress_health_check=list(HealthCheck))
@given(seed=st.integers(0, 10 ** 6), kind=st.sampled_from(["same", "apart"]), pick=st.integers(0, 10 ** 6),
       keep=st.booleans())
def test_a_search_from_what_the_map_before_proves_gives_the_fresh_resolves_maps(seed, kind, pick, keep):
    """The map before an assertion proves how many dstates every map with it needs (a map that honours
    more assertions honours fewer), and the search may start there; its maps are a fresh resolve's. With an
    assertion of the map before dropped (``keep`` false), it proves nothing."""
    rng = np.random.default_rng(seed)
    world = random_world(rng, 4, 3, extra_edges=int(rng.integers(0, 3)), landmarks=0.3)
    tableau = walk(world, int(rng.integers(30, 80)), rng, policy="explore")
    views = tableau.views
    pairs = [(a, b) for a in range(len(tableau)) for b in range(a + 1, len(tableau)) if views[a] == views[b]]
    if len(pairs) < 2:
        return
    first, second = pairs[pick % len(pairs)], pairs[(pick // len(pairs) + 1) % len(pairs)]
    resolver = Resolver(time_limit=60)
    baseline = said([{"apart": list(first)}], tableau)
    try:
        before = resolver.resolve(tableau, assertions=baseline)
    except InconsistentTableau:  # the axioms make them one dstate (test_an_apart_the_axioms_refute_...)
        return
    now = said(([{"apart": list(first)}] if keep else []) + [{kind: list(second)}], tableau)
    bound = proved(before, baseline, now)
    if keep and before.minimal and not before.suspect_steps:
        broken = before.unique and not all(x.holds_in(before) for x in now)
        assert bound == before.n_dstates + broken
    else:
        assert bound == 0
    try:
        fresh = resolver.resolve(tableau, assertions=now)
    except InconsistentTableau:
        with pytest.raises(InconsistentTableau):
            resolver.resolve(tableau, assertions=now, at_least=bound)
        return
    told = resolver.resolve(tableau, assertions=now, at_least=bound)
    if fresh.models_capped:  # which of more minimal maps than are listed depends on the search's path
        assert told.n_dstates == fresh.n_dstates
        return
    a, b = told.to_dict(), fresh.to_dict()
    a.pop("stats"), b.pop("stats")
    assert a == b


def test_an_apart_starts_from_the_dstates_the_map_before_it_proves(paper_tableau):
    """A person's apart on the paper's room, the map before it given (as the service keeps it): that map,
    the only minimal one, has 8 dstates (one per class) and breaks the apart, so every map with it needs 9;
    the search starts there, without the one-dstate-per-class try, and finds the fresh resolve's map."""
    mapper = Mapper(time_limit=60)
    before = mapper.map(paper_tableau)
    apart = said([{"apart": [200, 208]}], paper_tableau)
    result = mapper.honour(paper_tableau, apart, before=before)
    fresh = Resolver(time_limit=60).resolve(paper_tableau, assertions=apart)
    assert proved(before, [], apart) == 9 == before.n_dstates + 1
    assert result.after.n_dstates == fresh.n_dstates == 16 and result.after.dstate_of == fresh.dstate_of
    assert "one dstate per class" not in [t.dstates for t in result.after.stats.bounds]
    assert "one dstate per class" in [t.dstates for t in fresh.stats.bounds]
    # a map before that honoured an assertion the new ones drop proves nothing
    assert proved(before, said([{"apart": [1, 9]}], paper_tableau), apart) == 0


@pytest.mark.slow
@settings(max_examples=12, deadline=None, suppress_health_check=list(HealthCheck))
@given(seed=st.integers(0, 10 ** 6), kinds=st.lists(st.sampled_from(["same", "apart"]), min_size=1, max_size=3))
def test_every_loop_closed_answer_honours_the_assertions_or_is_a_minimal_clash(seed, kinds):
    """Loop closing with a person's assertions, any mix of them: the map honours every one, or the clash is
    one loop closing cannot honour and every smaller set can (an apart alone may clash too)."""
    rng = np.random.default_rng(seed)
    world = random_world(rng, 3 + seed % 2, 3, extra_edges=int(rng.integers(0, 3)), landmarks=0.3)
    tableau = walk(world, int(rng.integers(12, 30)), rng, policy="explore" if seed % 3 else "random")
    views = tableau.views
    pairs = [(a, b) for a in range(len(tableau)) for b in range(a + 1, len(tableau)) if views[a] == views[b]]
    if len(pairs) < len(kinds):
        return
    picks = rng.choice(len(pairs), size=len(kinds), replace=False)
    assertions = said([{kind: list(pairs[i])} for kind, i in zip(kinds, picks)], tableau)
    mapper = Mapper(time_limit=60, how="loops")
    result = mapper.honour(tableau, assertions)
    if result.conflict is None:
        assert all(x.holds_in(result.after) for x in assertions)
        return
    clash, deadline = result.conflict.assertions, Deadline.after(60)
    assert {str(x) for x in clash} <= {str(x) for x in assertions}
    assert not mapper.closer._holds(tableau, clash, deadline)
    for x in clash:
        rest = [y for y in clash if y is not x]
        assert not rest or mapper.closer._holds(tableau, rest, deadline)


# --- The command line -----------------------------------------------------------------------------------

def test_bootmap_map_assert_prints_the_map_and_what_changed_or_the_clash(tmp_path, capsys, paper):
    run = tmp_path / "run.json"
    run.write_text(json.dumps(paper.to_dict()))
    notes = tmp_path / "notes.json"
    notes.write_text(json.dumps({"assertions": [{"apart": ["S0", "t8"]}]}))
    assert main(["map", str(run), "--assert", str(notes)]) == 0
    out = capsys.readouterr().out
    assert "9 dstates" in out and "assertions: apart(t0, t8) (all kept)" in out and "S0 split" in out
    assert main(["map", str(run), "--assert", str(notes), "--format", "json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["summary"]["dstates"] == 9 and doc["assertions"][0]["held"] and doc["conflict"] is None
    assert doc["diff"]["split"] == [{"was": "S0", "now": ["S0", "S8"]}]
    notes.write_text(json.dumps({"assertions": [{"same": ["t0", "t8"]}, {"apart": ["t1", "t9"]}]}))
    assert main(["map", str(run), "--assert", str(notes)]) == 1
    out = capsys.readouterr().out
    assert "no map honours the assertions" in out and "one_value_per_feature (causal.lp:" in out
    notes.write_text('{"assertions": [{"apart": ["t1", "t1"]}]}')
    assert main(["map", str(run), "--assert", str(notes)]) == 2
    assert f"{notes}: assertions[0].apart: t1 is always its own dstate" in capsys.readouterr().err


def test_why_explains_the_map_that_honours_the_assertions_citing_the_persons_word(paper):
    apart = said([{"apart": ["t0", "t8"]}], paper)
    e = Mapper().explain(paper, "t0", "t8", assertions=apart)
    assert (e.verdict, e.evidence) == ("different", [0, 8])
    assert e.rules_cited() == ["one_value_per_feature", "asserted_apart"]
    assert "a person says t0 and t8 are different dstates" in e.to_text()
    assert Mapper().explain(paper, "t0", "t8").verdict == "same"  # without it, one dstate
    # a pair the assertion does not touch is explained as before, the assertion no part of its evidence
    e = Mapper().explain(paper, "t0", "t4", assertions=apart)
    assert e.verdict == "different" and "asserted_apart" not in e.rules_cited()
