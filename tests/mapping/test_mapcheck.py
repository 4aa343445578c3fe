"""The levels that judge the map alone are asked of each map found, not searched with: the same maps.

A level whose rules read only the map's transitions and dstates (the topological one, or a user's level of
the same kind) is left out of the search and asked of every map the search finds (bootmap.mapping.mapcheck).
These tests pin which levels qualify, and that a resolver doing so gives exactly the maps of one that
searches with every level: where the level accepts every map found, where it rejects some, where it rejects
all of them, where the search is made again with it, and where it rejects every map there is.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bootmap import examples
from bootmap.errors import InconsistentTableau
from bootmap.mapping.resolver import Resolver
from bootmap.mapping.theory import load_theory
from support.gridworld import random_world, walk
from support.noise import with_misreads, with_odometry_noise



def said(cmap) -> dict:
    """What a map says, its solver figures aside."""
    d = cmap.to_dict()
    d.pop("stats")
    return d


def both(tableau, **kwargs):
    """The map of a resolver that asks the map's levels of each map found, and of one that searches with them."""
    deferred = Resolver(time_limit=120, **kwargs).resolve(tableau)
    searched = Resolver(time_limit=120, defer_map_levels=False, **kwargs).resolve(tableau)
    return deferred, searched


def results(cmap) -> list[str]:
    return [t.result for t in cmap.stats.bounds]


# --- which levels judge the map alone --------------------------------------------------------------------------

def test_the_topological_level_judges_the_map_alone_and_the_causal_and_metrical_levels_do_not():
    assert load_theory().map_levels == ("topological",)
    assert load_theory(levels=["causal", "metrical"]).map_levels == ()


def test_a_users_level_qualifies_by_what_its_rules_read(axioms_copy):
    # Reads only the map: deferred. Reads a time point's view, or an atom classically negated: searched
    # with. Derives what another file reads: searched with. Chooses: searched with. Shows a transition: searched
    # with.
    (axioms_copy / "nocycle.lp").write_text(
        "% No dstate is reached from itself by one travel.\n"
        "self_travel(D) :- next(D, travel, D).\n"
        ":- self_travel(D), dstate(D).\n"
        "#show self_travel/1.\n")
    (axioms_copy / "daylight.lp").write_text("bright(T) :- view(T, V), V != \"dark\".\n")
    (axioms_copy / "feeds.lp").write_text("hub(D) :- next(D, _, _).\n")
    (axioms_copy / "uses.lp").write_text(":- hub(D), time(D).\n")
    (axioms_copy / "chooses.lp").write_text("{ marked(D) } :- dstate(D).\n")
    (axioms_copy / "shows.lp").write_text("loop(D) :- next(D, _, D).\n#show next/3.\n")
    (axioms_copy / "negates.lp").write_text("lit(D) :- dstate(D), -lamp(D).\n")  # reads lamp/1, classically negated
    assert load_theory(axioms_copy).map_levels == ("nocycle", "topological")


def test_a_map_level_that_reads_only_itself_and_the_map_keeps_its_shown_atoms(axioms_copy, paper_tableau):
    # A user's level that only shows what it derives: its atoms are read from the check, and the map is
    # the same either way.
    (axioms_copy / "hubs.lp").write_text("% A dstate with two ways out.\n"
                                         "hub(D) :- next(D, A, _), next(D, B, _), A != B.\n#show hub/1.\n")
    theory = Resolver(axioms=axioms_copy).theory
    assert "hubs" in theory.map_levels
    deferred, searched = both(paper_tableau, axioms=axioms_copy)
    assert said(deferred) == said(searched)


# --- the same maps -------------------------------------------------------------------------------------------

def test_the_papers_tableau_is_found_without_the_topological_level_in_the_search(paper_tableau):
    deferred, searched = both(paper_tableau)
    assert said(deferred) == said(searched)
    assert (deferred.n_dstates, deferred.n_places, deferred.n_paths) == (8, 4, 4) and deferred.unique
    assert "unsettled" not in results(deferred)


def grid(seed: int):
    """A short walk of a small grid world (sizes, landmarks, loops and policy vary with the seed)."""
    rng = np.random.default_rng(seed)
    world = random_world(rng, *[(3, 3), (4, 3), (4, 4), (5, 4)][seed % 4], extra_edges=seed % 3,
                         landmarks=[0.0, 0.4][seed % 2])
    return walk(world, 40 + 5 * seed, rng, policy="explore" if seed % 2 else "random")


@pytest.mark.parametrize("seed, levels, verdicts", [
    (1, None, "some rejected"),                        # the maps the topological level accepts are the answer
    (0, ["causal", "topological"], "none accepted"),   # none accepted, all enumerated: the bound is proved
    (2, ["causal", "topological"], "searched again"),  # capped before all were enumerated: searched with it
], ids=["some-rejected", "none-accepted", "searched-again"])
def test_where_the_topological_level_rejects_maps_found_without_it_its_verdict_is_kept(seed, levels, verdicts,
                                                                                     monkeypatch):
    from bootmap.mapping.mapcheck import MapCheck

    asked = []
    real = MapCheck.__call__

    def recorded(self, model):
        out = real(self, model)
        asked.append(out is not None)
        return out

    monkeypatch.setattr(MapCheck, "__call__", recorded)
    deferred, searched = both(grid(seed), levels=levels)
    assert said(deferred) == said(searched)
    assert ("unsettled" in results(deferred)) == (verdicts == "searched again")
    if verdicts == "some rejected":
        assert any(asked) and not all(asked)
    elif verdicts == "none accepted":
        assert asked and not any(asked)
    else:  # a capped enumeration settles nothing whatever the level says: it is not asked
        assert not asked


def test_a_map_level_that_rejects_every_map_gives_the_same_inconsistency(axioms_copy, paper_tableau):
    (axioms_copy / "never.lp").write_text("% No map at all.\n:- dstate(D).\n")
    errors = []
    for defer in (True, False):
        with pytest.raises(InconsistentTableau) as e:
            Resolver(axioms=axioms_copy, defer_map_levels=defer, time_limit=60).resolve(paper_tableau.prefix(40))
        errors.append((str(e.value), e.value.levels))
    assert errors[0] == errors[1] and "never" in errors[0][1]


@settings(max_examples=10, deadline=None)
@given(seed=st.integers(0, 10_000), steps=st.integers(20, 140), size=st.sampled_from([(3, 3), (4, 3), (4, 4)]),
       noisy=st.booleans(), landmarks=st.sampled_from([0.0, 0.4]))
def test_grid_explorations_give_the_same_maps_either_way(seed, steps, size, noisy, landmarks):
    rng = np.random.default_rng(seed)
    tableau = walk(random_world(rng, *size, extra_edges=seed % 3, landmarks=landmarks), steps, rng,
                   policy="explore" if seed % 2 else "random")
    if noisy:
        tableau = with_odometry_noise(tableau, 3.0, 1.2, rng, distance_sd=0.03)
    deferred, searched = both(tableau)
    assert said(deferred) == said(searched)


@pytest.mark.parametrize("seed", [1, 4])
def test_misread_views_give_the_same_maps_either_way(seed):
    tableau, _ = with_misreads(examples.notched_rectangle(6), 0.02, np.random.default_rng(seed))
    deferred, searched = both(tableau)
    assert said(deferred) == said(searched)
