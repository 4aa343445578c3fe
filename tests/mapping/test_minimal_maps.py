"""How many minimal maps, and which: counted against brute force; travel lengths as odometry reads them."""


from hypothesis import given, strategies as st

from bootmap.mapping import Resolver
from bootmap.mapping.motion import length_types
from support.check import check_map

from test_axiom_rules import CT, place_on_both_sides, two_lengths
from test_lower_bound import brute_force_minimal_maps


def test_minimal_maps_beyond_max_models_are_reported_capped_not_unique():
    t = place_on_both_sides()
    fewest, n_minimal = brute_force_minimal_maps(t, CT)
    assert n_minimal >= 2  # the case this test is about
    every = Resolver(levels=CT, max_models=n_minimal).resolve(t)
    assert (every.n_dstates, every.n_models, every.models_capped, every.unique) == (fewest, n_minimal, False, False)
    capped = Resolver(levels=CT, max_models=n_minimal - 1).resolve(t)
    assert capped.n_dstates == fewest and capped.models_capped and not capped.unique
    assert "+ minimal maps" in capped.to_text() and capped.to_dict()["summary"]["minimal_maps_capped"] is True


def test_travels_of_4_and_6_metres_are_two_lengths_so_a_robot_that_stops_has_two_dstates_there():
    t = two_lengths()
    distances = [s.action.distance_m for s in t.steps if s.action is not None and hasattr(s.action, "distance_m")]
    assert len(set(length_types(distances))) == 2  # 4.02 and 3.98 m one length, 6.01 m another
    m = Resolver().resolve(t)
    assert not m.same(0, 4)  # from one dstate a travel always goes as far
    merged = list(m.dstate_of)
    merged[4] = merged[0]
    assert any(v.startswith("one_value_per_feature") for v in check_map(t, merged))
    fewest, n_minimal = brute_force_minimal_maps(t, ("causal", "topological", "metrical"))
    assert (m.n_dstates, m.n_models) == (fewest, n_minimal)


def test_the_map_shown_and_its_alternatives_do_not_depend_on_the_search_that_found_them():
    # The paper's room, six circuits, two views misclustered in 41 steps and read as seen: four minimal maps
    # of 36 dstates.
    # A fresh resolve climbs from the classes' bound and finds them by optimising; told the answer's size
    # (as a stream is), the search finds them at that bound, and clingo enumerates them in another order.
    import numpy as np
    from bootmap.examples import notched_rectangle
    from support.noise import with_misreads

    tableau = with_misreads(notched_rectangle(6), 0.02, np.random.default_rng(4))[0].prefix(41)
    resolver = Resolver(time_limit=30, misreads=False)
    fresh = resolver.resolve(tableau)
    told = resolver.resolve(tableau, at_least=fresh.n_dstates)
    assert fresh.n_models == 4 and not fresh.models_capped  # every minimal map listed: the case at hand
    assert [t.dstates for t in told.stats.bounds] != [t.dstates for t in fresh.stats.bounds]
    a, b = fresh.to_dict(), told.to_dict()
    a.pop("stats"), b.pop("stats")
    assert a == b


@given(st.lists(st.lists(st.integers(0, 3), min_size=4, max_size=4), min_size=1, max_size=6, unique_by=tuple),
       st.randoms(use_true_random=False))
def test_minimal_maps_are_ordered_by_what_they_say_not_by_when_they_were_found(partitions, rnd):
    from clingo import Function, Number
    from bootmap.mapping.cogmap import canonical_order

    def model(dstates):
        return [Function("is", [Number(t), Function("d", [Number(d)])]) for t, d in enumerate(dstates)]

    def said(models):
        return [[str(atom) for atom in m] for m in models]

    models = [model(p) for p in partitions]
    shuffled = models[:]
    rnd.shuffle(shuffled)
    ordered = canonical_order(models, 4)
    assert said(canonical_order(shuffled, 4)) == said(ordered)
    assert sorted(said(ordered)) == sorted(said(models))  # the same maps, none lost

    def first_appearance(m):
        seen = {}
        return [seen.setdefault(str(a.arguments[1]), len(seen)) for a in m]
    assert [first_appearance(m) for m in ordered] == sorted(first_appearance(m) for m in ordered)
