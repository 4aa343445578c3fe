"""How many minimal maps, and which: counted against brute force; travel lengths as odometry reads them."""


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
