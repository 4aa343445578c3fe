"""How sure a map is: what the minimal maps found agree on, per dstate and place and for the whole map."""

import json

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from bootmap.cli import main
from bootmap.examples import notched_rectangle
from bootmap.mapping.confidence import Confidence
from bootmap.mapping.resolver import Resolver
from bootmap.tableau import Step, Tableau, Travel
from support.gridworld import random_world, walk


def undecided() -> Tableau:
    """t0 and t2 look alike but what followed differs; t4 looks alike and did nothing more: t4 may be t0's
    dstate or t2's (two minimal maps)."""
    return Tableau(tuple(Step(v, Travel(1.0) if i < 4 else None) for i, v in enumerate("ABACA")))


def test_a_unique_map_is_settled_throughout():
    cmap = Resolver().resolve(notched_rectangle(2))
    c = cmap.confidence
    assert (c.maps, c.capped, c.settled, c.unsettled) == (1, False, 1.0, [])
    assert all(d["in_maps"] == 1 and d["confusable"] == [] for d in c.dstates.values())
    assert set(c.places) == set(cmap.places) and all(p["in_maps"] == 1 for p in c.places.values())
    assert "confidence" not in cmap.to_text()  # nothing to say


def test_where_the_minimal_maps_disagree_the_map_says_which_dstates_and_with_what():
    cmap = Resolver(levels=["causal"]).resolve(undecided())
    c = cmap.confidence
    assert c.maps == 2 and c.settled == 0.4  # t1 and t3 of 5 time points
    a, b = cmap.dstate_of[0], cmap.dstate_of[2]  # t4 is with one of them in each map
    assert c.dstates[cmap.dstate_of[1]]["in_maps"] == 2 and c.dstates[cmap.dstate_of[3]]["in_maps"] == 2
    assert {c.dstates[a]["in_maps"], c.dstates[b]["in_maps"]} == {1}
    with_t4 = cmap.dstate_of[4]
    other = a if with_t4 == b else b
    assert c.dstates[other]["confusable"] == [4]
    assert "2 minimal maps; 40% of time points" in cmap.to_text()
    assert cmap.to_dict()["confidence"]["settled"] == 0.4


@settings(max_examples=40, deadline=None)
@given(maps=st.lists(st.lists(st.integers(0, 3), min_size=6, max_size=6), min_size=1, max_size=4))
def test_confidence_figures_are_consistent_with_the_maps(maps):
    dstates = [[f"S{x}" for x in m] for m in maps]
    c = Confidence.of(dstates, [[None] * 6 for _ in maps], capped=False)
    assert c.maps == len(maps) and 0.0 <= c.settled <= 1.0
    first = dstates[0]
    for d, info in c.dstates.items():
        mine = {t for t, x in enumerate(first) if x == d}
        assert 1 <= info["in_maps"] <= c.maps and not mine & set(info["confusable"])
        # the same in every map: nothing it could be confused with (a split leaves none either)
        assert (info["in_maps"] == c.maps) == (d not in c.unsettled)
        if info["in_maps"] == c.maps:
            assert info["confusable"] == []
    settled = sum(1 for t, d in enumerate(first) if d not in c.unsettled)
    assert c.settled == round(settled / len(first), 4)
    if len(maps) == 1:
        assert c.settled == 1.0


def test_on_random_walks_a_settled_dstate_is_one_in_every_minimal_map_found():
    resolver = Resolver(levels=["causal", "topological"], misreads=False)
    seen = 0
    for seed in range(9000, 9030):
        rng = np.random.default_rng(seed)
        tableau = walk(random_world(rng, 3, 4, extra_edges=2, landmarks=0.2), int(rng.integers(8, 30)), rng,
                       policy="explore")
        cmap = resolver.resolve(tableau)
        maps = [cmap.dstate_of] + cmap.alternatives
        for d, info in cmap.confidence.dstates.items():
            mine = [t for t, x in enumerate(cmap.dstate_of) if x == d]
            kept = [all(m[t] == m[mine[0]] for t in mine) and sum(x == m[mine[0]] for x in m) == len(mine)
                    for m in maps]
            assert info["in_maps"] == sum(kept)
            seen += len(maps) > 1
    assert seen > 0  # some walks were ambiguous


def test_bootmap_map_prints_and_writes_the_confidence(tmp_path, capsys):
    run = tmp_path / "run.json"
    run.write_text(json.dumps(undecided().to_dict()))
    assert main(["map", str(run), "--levels", "causal"]) == 0
    assert "confidence: 2 minimal maps; 40% of time points at a dstate every one of them agrees on" in \
        capsys.readouterr().out
    assert main(["map", str(run), "--levels", "causal", "--format", "json"]) == 0
    assert json.loads(capsys.readouterr().out)["confidence"]["minimal_maps"] == 2


@settings(max_examples=60, deadline=None)
@given(maps=st.integers(1, 4).flatmap(lambda k: st.integers(1, 12).flatmap(
    lambda n: st.lists(st.lists(st.sampled_from("ABCDE"), min_size=n, max_size=n), min_size=k, max_size=k))))
def test_a_dstates_confusable_time_points_are_those_another_map_puts_with_any_of_its_own(maps):
    c = Confidence.of(maps, [[None] * len(maps[0])] * len(maps), capped=False)
    first = maps[0]
    for d in set(first):
        mine = {t for t, x in enumerate(first) if x == d}
        others = {u for m in maps[1:] for t in mine for u, x in enumerate(m) if x == m[t]}
        assert c.dstates[d]["confusable"] == sorted(others - mine)
