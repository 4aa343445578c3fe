"""Loop closing (bootmap.mapping.loops): odometry proposes which visits are one dstate, every axiom checks;
and the axioms for a robot that drove through dstates without stopping (passes_through)."""

import itertools
import math
import re
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, note, settings
from hypothesis import strategies as st

from bootmap.errors import ExplainError, SolveTimeout
from bootmap.mapping.grounding import Deadline
from bootmap.mapping.assertions import parse_assertions
from bootmap.mapping.loops import LoopCloser, dead_reckoning
from bootmap.mapping.resolver import Resolver
from bootmap.mapping.stream import MapStream
from bootmap.sim.simulation import simulate
from bootmap.sim.world import load_world
from bootmap.mapping.facts import action_symbols, typed_actions
from bootmap.tableau import Tableau, Travel, Turn
from support.check import check_map, true_partition
from support.gridworld import random_world, walk
from support.noise import ROUNDINGS, with_odometry_noise

FORMAT = "bootmap.tableau/1"


def square_laps(laps: int, side_m: float = 6.0, view=lambda corner: "corner") -> Tableau:
    """Laps of a square room, turning left at each corner; truth names corner and heading."""
    steps = []
    for lap in range(laps):
        for corner in range(4):
            heading = corner * 90
            steps.append({"view": view(corner), "truth": f"c{corner}:{heading}",
                          "action": {"type": "travel", "distance_m": side_m}})
            steps.append({"view": view((corner + 1) % 4), "truth": f"c{(corner + 1) % 4}:{heading}",
                          "action": {"type": "turn", "angle_deg": 90}})
    steps.append({"view": view(0), "truth": "c0:0"})
    return Tableau.from_dict({"format": FORMAT, "steps": steps})


def same_partition(a, b) -> bool:
    return all((a[i] == a[j]) == (b[i] == b[j]) for i, j in itertools.combinations(range(len(a)), 2))


def test_odometry_closes_the_loops_that_views_cannot():
    square = square_laps(3)
    cmap = LoopCloser().resolve(square)
    assert same_partition(cmap.dstate_of, true_partition(square))
    assert (cmap.n_dstates, cmap.n_places, cmap.n_paths) == (8, 4, 4)
    assert cmap.found_by == "loop closing" and not cmap.minimal and cmap.suspect_steps == []
    assert "loop-closed from odometry" in cmap.to_text()


def test_a_misread_view_is_outvoted_and_named():
    square = square_laps(3, view=lambda corner: f"V{corner}")
    steps = [s.to_dict() for s in square.steps]
    steps[9]["view"] = "V3"  # corner 1 seen as corner 3, once
    misread = Tableau.from_dict({"format": FORMAT, "steps": steps})
    cmap = LoopCloser().resolve(misread)
    assert same_partition(cmap.dstate_of, true_partition(square))
    assert [(s["t"], s["observed"], s["expected"]) for s in cmap.suspect_steps] == [(9, "V3", "V1")]


def test_dead_reckoning_reads_odometry_or_else_the_actions():
    square = square_laps(1, side_m=5.0)
    xy, along = dead_reckoning(square)
    assert np.allclose(xy[[0, 2, 4, 6, 8]], [[0, 0], [5, 0], [5, 5], [0, 5], [0, 0]], atol=1e-9)
    assert along[-1] == pytest.approx(20.0)
    steps = [{**s.to_dict(), "odometry": [t, 2 * t, 0]} for t, s in enumerate(square.steps)]
    xy, along = dead_reckoning(Tableau.from_dict({"format": FORMAT, "steps": steps}))
    assert xy[3].tolist() == [3, 6] and along[2] == pytest.approx(5 + math.hypot(1, 2))  # max(hop, travel)


def test_out_of_time_gives_the_last_map_the_axioms_accepted_or_none():
    with pytest.raises(SolveTimeout) as e:
        LoopCloser().resolve(square_laps(3), Deadline.after(0.0))
    assert e.value.stage == "loop closing"


@st.composite
def noisy_walks(draw):
    seed = draw(st.integers(0, 2**32 - 1), label="seed")
    rng = np.random.default_rng(seed)
    world = random_world(rng, draw(st.integers(3, 4)), draw(st.integers(3, 4)), extra_edges=draw(st.integers(0, 3)),
                         landmarks=draw(st.sampled_from([0.0, 0.3])), cell_m=8.0)
    clean = walk(world, draw(st.integers(10, 60)), rng, policy=draw(st.sampled_from(["random", "explore"])))
    noise = draw(st.sampled_from([0.0, 2.0, 5.0]), label="turn_sd")
    return world, with_odometry_noise(clean, noise, noise / 2, rng, rounding=draw(st.sampled_from(ROUNDINGS)))


def _typed(action, angle):
    if action is None:
        return None
    return Turn(angle) if isinstance(action, Turn) else Travel(action.distance_m, angle)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(noisy_walks())
def test_a_loop_closed_map_satisfies_every_axiom_and_keeps_within_odometry(walked):
    world, tableau = walked
    note(f"tableau: {tableau.dumps()}")
    closer = LoopCloser()
    cmap = closer.resolve(tableau)
    # Every axiom holds (the independent re-check, on the angles of the learned action types), each
    # dstate showing the view the map gives it (the others are misreads) ...
    angles, _, _ = typed_actions(tableau)
    typed = Tableau(tuple(replace(s, view=cmap.views[d], action=_typed(s.action, a))
                          for s, d, a in zip(tableau.steps, cmap.dstate_of, angles + [None])))
    assert check_map(typed, cmap.dstate_of, quantum_deg=1) == []
    assert {s["t"] for s in cmap.suspect_steps} == {t for t, s in enumerate(tableau.steps)
                                                   if s.view != cmap.views[cmap.dstate_of[t]]}
    # ... and no two visits of one dstate face two ways or lie beyond what odometry may drift between them.
    heading = np.concatenate([[0], np.cumsum(angles)]) % 360
    xy, along = dead_reckoning(tableau, angles)
    for i, j in itertools.combinations(range(len(tableau)), 2):
        if cmap.dstate_of[i] == cmap.dstate_of[j]:
            assert heading[i] == heading[j]
            assert math.dist(xy[i], xy[j]) <= closer.radius_m + closer.drift_share * (along[j] - along[i]) + 1e-9
    assert LoopCloser().resolve(tableau).dstate_of == cmap.dstate_of  # deterministic


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 2**32 - 1))
def test_exact_odometry_on_a_walk_with_landmarks_everywhere_gives_the_true_map(seed):
    # Every node looks different: the true partition is what views and odometry both say.
    rng = np.random.default_rng(seed)
    world = random_world(rng, 4, 4, extra_edges=2, landmarks=1.0, letters="ABCDEFGHIJKLMNOP", cell_m=8.0)
    tableau = walk(world, 40, rng, policy="explore")
    note(f"tableau: {tableau.dumps()}")
    cmap = LoopCloser().resolve(tableau)
    assert same_partition(cmap.dstate_of, true_partition(tableau)) and cmap.suspect_steps == []


# -- the axioms for a robot that drove through dstates ------------------------------------------------

def corridor_passed_through(passes_through: bool) -> Tableau:
    """A corridor A - B - C: from A east to B (5 m), back to A, then east again straight past B to C (10 m).
    Where the robot stopped at every dstate, the second travel from A east would have ended at B."""
    go = lambda m: {"type": "travel", "distance_m": m}  # noqa: E731
    back = {"type": "turn", "angle_deg": 180}
    steps = [{"view": "a", "action": go(5)}, {"view": "b", "action": back}, {"view": "b'", "action": go(5)},
             {"view": "a'", "action": back}, {"view": "a", "action": go(10)}, {"view": "c"}]
    return Tableau.from_dict({"format": FORMAT, "steps": steps,
                              "meta": {"passes_through": True} if passes_through else {}})


def test_a_travel_may_pass_a_dstate_only_where_the_tableau_says_so():
    passing = Resolver().resolve(corridor_passed_through(True))
    assert passing.dstate_of[0] == passing.dstate_of[4]  # A east both times: travels of 5 and 10 m differ
    stopping = Resolver().resolve(corridor_passed_through(False))
    assert stopping.dstate_of[0] != stopping.dstate_of[4]  # from one dstate a travel always goes as far
    # The independent re-check of the axioms agrees on both readings.
    assert check_map(corridor_passed_through(True), passing.dstate_of) == []
    assert check_map(corridor_passed_through(False), passing.dstate_of) != []
    # On the topological level both travels from A east run along one path, B before C.
    assert passing.n_paths == 1 and len(passing.paths["Pa0"]) == 3



def bent(change_deg: float) -> Tableau:
    """A log's travel of 5 m from a place to one that looks the same, bending by ``change_deg`` on the way
    (a corner driven round without stopping, which the turn detector did not cut out as a turn)."""
    steps = [{"view": "a", "action": {"type": "travel", "distance_m": 5, "heading_change_deg": change_deg}},
             {"view": "a"}]
    return Tableau.from_dict({"format": FORMAT, "steps": steps, "meta": {"passes_through": True}})


@pytest.mark.parametrize("change, side", [(-90.0, "right"), (90.0, "left")])
def test_a_travel_that_bent_round_a_corner_leaves_its_path_and_its_place_lies_on_that_side(change, side):
    topological = ("causal", "topological")
    straight = Resolver(levels=topological).resolve(bent(0.0))
    assert straight.n_dstates == 2 and straight.n_paths == 1  # a travel along one path, to a place ahead
    turned = Resolver(levels=topological).resolve(bent(change))
    # Two paths: the bend left the first; and the place reached lies on the bend's side of it, so it is
    # not the place the travel started from (which is on that path), though both look alike.
    assert turned.n_dstates == 2 and turned.n_paths == 2
    assert check_map(bent(change), turned.dstate_of) == []
    assert any(side in v for v in check_map(bent(change), ["S0", "S0"]))
    # It is an action of its own: a straight travel of the same length is another.
    def action(t: Tableau):
        return action_symbols(t, typed_actions(t)[0])[0]
    assert str(action(bent(change))) == f"travel(50,{int(change)})" and str(action(bent(0.0))) == "travel(50)"


def test_odometry_alone_maps_a_simulated_taylor_hall():
    # The simulated robot (pymunk, its real-robot odometry) explores the paper's building; with every
    # view the same, the map is still the true one: dead reckoning on the learned action types.
    world = load_world("taylor_hall")
    tableau = simulate(world, policy=world.policy, steps=100, seed=7)
    blind = tableau.with_views(["corridor"] * len(tableau))
    cmap = LoopCloser().resolve(blind)
    assert cmap.n_dstates == 20 and same_partition(cmap.dstate_of, true_partition(tableau))


def test_a_stream_resolves_a_passing_tableau_anew_at_every_step():
    # Determinism alone places nothing where a travel may end at any dstate further on.
    full = corridor_passed_through(True)
    stream = MapStream()
    for n in range(1, len(full) + 1):
        assert stream.update(full.prefix(n)).dstate_of == Resolver().resolve(full.prefix(n)).dstate_of
    assert stream.extended_ == 0


def test_why_two_visits_are_one_dstate_names_each_join_and_its_evidence():
    square = square_laps(3)
    e = LoopCloser().explain(square, "t1", "t17")
    assert e.verdict == "same" and e.names[0] == e.names[1]
    # Every join on the way from t1 to t17 is cited, each proposed by odometry or forced by determinism.
    assert e.joins and all(" = " in j and (": proposed (" in j or ": forced: " in j) for j in e.joins)
    assert any("dead reckoning puts them 0.0 m apart" in j for j in e.joins)
    assert e.to_dict()["found_by"] == "loop closing" and "t1 (S1) vs t17 (S1): same" in e.to_text()


def test_why_two_visits_are_different_dstates_names_what_keeps_them_apart():
    square = square_laps(3)
    closer = LoopCloser()
    heading = closer.explain(square, 0, 2)  # corner 0 facing east, corner 1 facing north
    assert heading.verdict == "different" and "they face different ways (headings 0 and 90" in heading.sentence
    far = closer.explain(square, 0, 1)  # two corners, one side apart, both facing east
    assert "dead reckoning puts them 6.0 m apart after 6 m driven, more than odometry may drift" in far.sentence
    # Joining t1 to a later visit of corner 0 would join corner 0 and corner 1 through their dstates.
    folded = closer.explain(square, 1, 24)
    assert folded.verdict == "different" and "making them one makes t" in folded.sentence
    with pytest.raises(ExplainError, match="time point 99 is not in the tableau"):
        closer.explain(square, 0, 99)


def test_why_names_the_axiom_that_rejects_joining_two_visits():
    # Odometry that hardly moved over a 5 m travel proposes its two ends as one dstate; a travel always
    # leaves its place, so the axioms refuse, and the explanation cites the rule, file and line.
    steps = [{"view": "a", "odometry": [0, 0, 0], "action": {"type": "travel", "distance_m": 5}},
             {"view": "a", "odometry": [0.5, 0, 0]}]
    glitch = Tableau.from_dict({"format": FORMAT, "steps": steps})
    closer = LoopCloser()
    assert closer.resolve(glitch).n_dstates == 2
    e = closer.explain(glitch, 0, 1)
    assert e.verdict == "different"
    assert re.search(r"it breaks order_(irreflexive|asymmetric) \(topological\.lp:\d+\)\.$", e.sentence)
    assert e.to_dict()["rules_cited"] == [r.name for r in e.axioms] and e.axioms[0].level == "topological"


def _turns_while_driving(second_turn_at: float) -> Tableau:
    """A loop of four left turns taken while driving (each turn's ends 4 m apart), then the first corner's
    turn again, begun at ``second_turn_at`` m along the first leg (the first began at 0)."""
    x0 = second_turn_at
    at = [(0, 0, 0), (4, 0, 90), (4, 20, 90), (4, 20, 180), (-16, 20, 180), (-16, 20, 270), (-16, 0, 270),
          (-16, 0, 0), (x0, 0, 0), (x0 + 4, 0, 90)]
    actions = [{"type": "turn", "angle_deg": 90}, {"type": "travel", "distance_m": 20.0}] * 4
    actions[-1] = {"type": "travel", "distance_m": 16.0 + x0}
    actions.append({"type": "turn", "angle_deg": 90})
    steps = [{"view": "corner", "odometry": list(p), "action": a} for p, a in zip(at, actions)]
    steps.append({"view": "corner", "odometry": list(at[-1])})
    return Tableau.from_dict({"format": FORMAT, "steps": steps, "meta": {"passes_through": True}})


def test_a_visit_is_where_the_middle_of_its_turn_is_not_its_nearest_end():
    """Turns taken while driving end metres from where they began. The first corner turned again 4.5 m
    further on has its nearest end 0.5 m from the first turn's, but its middle 4.5 m away, beyond the
    place radius: not one place. Begun 1 m further on, its middle is 1 m away: one dstate."""
    far = LoopCloser().resolve(_turns_while_driving(4.5))
    assert far.dstate_of[8] != far.dstate_of[0] and far.dstate_of[9] != far.dstate_of[1]
    near = LoopCloser().resolve(_turns_while_driving(1.0))
    assert near.dstate_of[8] == near.dstate_of[0] and near.dstate_of[9] == near.dstate_of[1]


def _chained_near_visits(last_x: float = 4.0) -> Tableau:
    """Three visits at one corridor's west end facing east: t0 at 0 m, t8 at 12 m (after 428 m driven
    round a block: beyond the 7.3 m a near pair may be apart), t12 at ``last_x`` m (after 888 m more: at 4 m
    odometry puts it near each of the others, though t0 and t8 are not near each other)."""
    x = last_x
    at = [(0, 0, 0), (120, 0, 0), (120, 0, 90), (120, 100, 90), (120, 100, 180), (12, 100, 180), (12, 100, 270),
          (12, 0, 270), (12, 0, 0), (452, 0, 0), (452, 0, 180), (x, 0, 180), (x, 0, 0), (x + 50, 0, 0)]
    legs = [120, 90, 100, 90, 108, 90, 100, 90, 440, 180, 448, 180, 50]
    steps = [{"view": "corner", "odometry": list(p)} for p in at]
    for step, (k, leg) in zip(steps, enumerate(legs)):
        step["action"] = ({"type": "travel", "distance_m": float(leg)} if k % 2 == 0 else
                          {"type": "turn", "angle_deg": float(leg)})
    return Tableau.from_dict({"format": FORMAT, "steps": steps, "meta": {"passes_through": True}})


def test_near_proposals_make_one_dstate_only_of_visits_all_near_each_other():
    """A dstate is one place: a near proposal joins t12 to t0 (4 m apart), and then not t8 to them,
    although t8 is near t12 (8 m after 888 m driven), because t8 is not near t0 (12 m after 428 m).
    Joined by chains of near pairs, a dstate could stretch along a corridor (Killian: one visit 12 m from
    the other two of its dstate)."""
    tableau = _chained_near_visits()
    cmap = LoopCloser().resolve(tableau)
    assert cmap.dstate_of[0] == cmap.dstate_of[12] and cmap.dstate_of[8] != cmap.dstate_of[12]
    why = LoopCloser().explain(tableau, 8, 12)
    assert why.verdict == "different"
    assert "makes t8 and t0 one" in why.sentence and "12.0 m apart after 428 m driven" in why.sentence
    assert "more than a near proposal allows (7.3 m)" in why.sentence


def test_a_dstate_a_person_made_is_one_place_whatever_odometry_says_of_its_visits():
    """t12 at 20 m is near t8 (8 m after 888 m driven) but not t0 (20 m after 1,316 m: beyond 16.2 m). Alone,
    t12 joins t8 and t0 stays apart. A person saying t0 and t8 are one dstate makes them one place: t12,
    near t8, then joins it too (held to the drift bound, not to the near bound towards t0)."""
    tableau = _chained_near_visits(last_x=20.0)
    alone = LoopCloser().resolve(tableau).dstate_of
    assert alone[8] == alone[12] and alone[0] != alone[8]
    said = LoopCloser().resolve(tableau, assertions=parse_assertions([{"same": [0, 8]}], len(tableau))).dstate_of
    assert said[0] == said[8] == said[12]


def test_of_two_near_visits_that_are_not_near_each_other_the_nearer_in_metres_is_joined():
    """t12 at 6.5 m: 6.5 m from t0 (after 1,316 m driven: a sixth of the 16.2 m allowed) and 5.5 m from t8
    (after 888 m: nearly half of 11.9 m). t0 and t8 cannot both join it (12 m apart after 428 m). The
    nearer in metres is joined, as the truth's places are drawn, not the one nearer as a share of the
    drift odometry is allowed."""
    cmap = LoopCloser().resolve(_chained_near_visits(last_x=6.5))
    assert cmap.dstate_of[8] == cmap.dstate_of[12] != cmap.dstate_of[0]


def _square_drive(at, matches: list[dict] | None = None) -> Tableau:
    """A log's tableau of sides of 20 m driven and turns of 90 degrees on the spot, in turn, with odometry
    ``at`` each time point, and the laser's ``matches`` (``meta.place_matches``) where given."""
    steps = [{"view": "corner", "odometry": list(p),
              "action": {"type": "travel", "distance_m": 20.0} if k % 2 == 0 else {"type": "turn", "angle_deg": 90}}
             for k, p in enumerate(at)]
    del steps[-1]["action"]
    meta = {"passes_through": True} | ({} if matches is None else {"place_matches": matches})
    return Tableau.from_dict({"format": FORMAT, "steps": steps, "meta": meta})


def _drifted_loop(matches: list[dict] | None = None) -> Tableau:
    """A loop of four corners, 20 m a side, turned on the spot, then the first side again: dead reckoning
    puts the second visit of the first corner (t8) 5 m from the first (t0) after 80 m driven, beyond what a
    near proposal allows (3.8 m), and only one action around them agrees: odometry proposes nothing. The
    laser's ``matches`` (``meta.place_matches``) may."""
    at = [(0, 0, 0), (20, 0, 0), (20, 0, 90), (20, 20, 90), (20, 20, 180), (0, 20, 180), (0, 20, 270),
          (5, 0, 270), (5, 0, 0), (25, 0, 0)]
    return _square_drive(at, matches)


def test_a_place_match_the_laser_verified_proposes_a_join_odometry_cannot():
    alone = LoopCloser().resolve(_drifted_loop())
    assert alone.dstate_of[8] != alone.dstate_of[0] and alone.n_dstates == 10
    matched = _drifted_loop([{"a": 0, "b": 8, "score": 0.9}])
    cmap = LoopCloser().resolve(matched)
    # t0 = t8, and determinism then joins where both travelled to: t1 = t9
    assert cmap.dstate_of[8] == cmap.dstate_of[0] and cmap.dstate_of[9] == cmap.dstate_of[1]
    assert cmap.n_dstates == 8
    why = LoopCloser().explain(matched, 0, 8)
    assert why.verdict == "same"
    said = ("t0 = t8: proposed (recognised): the laser matches their places, verified by the places around them, "
            "with score 0.90 (loop closing proposes 0.7 or more)")
    assert any(j.startswith(said) for j in why.joins)
    forced = LoopCloser().explain(matched, 1, 9)
    assert any(j.startswith("t1 = t9: forced: t0 and t8 are one dstate") for j in forced.joins)


def test_a_weak_place_match_or_one_facing_another_way_proposes_nothing():
    weak = _drifted_loop([{"a": 0, "b": 8, "score": 0.6}])
    assert LoopCloser().resolve(weak).n_dstates == 10
    assert LoopCloser(match_score=0.5).resolve(weak).n_dstates == 8  # the bound is the closer's to set
    why = LoopCloser().explain(weak, 0, 8)
    assert why.verdict == "different" and "only for want of evidence" in why.sentence
    assert "with score 0.60 (loop closing proposes 0.7 or more)" in why.sentence
    turned = _drifted_loop([{"a": 0, "b": 6, "score": 1.0}])  # facing east and facing south
    assert LoopCloser().resolve(turned).n_dstates == 10
    # Beyond the drift bound no match joins: t8 20 m further on than the laser says (80 m driven: 7 m).
    far = [s.to_dict() for s in _drifted_loop().steps]
    far[8]["odometry"], far[9]["odometry"] = [20, 0, 0], [40, 0, 0]
    far = Tableau.from_dict({"format": FORMAT, "steps": far,
                             "meta": {"passes_through": True, "place_matches": [{"a": 0, "b": 8, "score": 1.0}]}})
    assert LoopCloser().resolve(far).dstate_of[8] != LoopCloser().resolve(far).dstate_of[0]


def _closed_loop(matches: list[dict] | None = None) -> Tableau:
    """The loop of :func:`_drifted_loop` with exact odometry: t8 where t0 was, facing east again, so odometry
    proposes t0 = t8 (and t1 = t9) as near."""
    steps = [s.to_dict() for s in _drifted_loop().steps]
    steps[7]["odometry"], steps[8]["odometry"], steps[9]["odometry"] = [0, 0, 270], [0, 0, 0], [20, 0, 0]
    meta = {"passes_through": True} | ({} if matches is None else {"place_matches": matches})
    return Tableau.from_dict({"format": FORMAT, "steps": steps, "meta": meta})


def test_odometry_near_alone_proposes_no_visits_the_laser_places_elsewhere():
    """Where the laser matched a visit's place with earlier visits and none of them is the place odometry
    puts it at, nearness alone proposes nothing; a match with that place, however weak, or with the other end
    of its turn, or no match of the visit at all, leaves odometry's proposal standing."""
    assert LoopCloser().resolve(_closed_loop()).dstate_of[8] == LoopCloser().resolve(_closed_loop()).dstate_of[0]
    elsewhere = _closed_loop([{"a": 4, "b": 8, "score": 0.9}])  # t8's place is t4's, says the laser
    cmap = LoopCloser().resolve(elsewhere)
    assert cmap.dstate_of[8] != cmap.dstate_of[0] and cmap.dstate_of[9] == cmap.dstate_of[1]  # t9: no match
    why = LoopCloser().explain(elsewhere, 0, 8)
    assert why.verdict == "different" and "only for want of evidence" in why.sentence
    assert ("0.0 m apart after 80 m driven (within 3.8 m, near), but the laser matches t8's place, verified by "
            "the places around it, with t4, not with t0's: odometry alone proposes no visits the laser "
            "places elsewhere") in why.sentence
    for confirmed in ([{"a": 4, "b": 8, "score": 0.9}, {"a": 0, "b": 8, "score": 0.3}],  # among its matches
                      [{"a": 4, "b": 8, "score": 0.9}, {"a": 0, "b": 7, "score": 0.8}],  # the other end of t8's turn
                      [{"a": 2, "b": 5, "score": 0.9}]):  # a match of another visit: nothing said of t8
        cmap = LoopCloser().resolve(_closed_loop(confirmed))
        assert cmap.dstate_of[8] == cmap.dstate_of[0], confirmed


@pytest.mark.parametrize("match, where", [
    ({"a": 0, "b": 10, "score": 0.9}, "tableau: meta.place_matches[0].b"),
    ({"a": 3, "b": 3, "score": 0.9}, "tableau: meta.place_matches[0]"),
])
def test_a_place_match_naming_no_time_point_or_one_twice_is_refused_by_place(match, where):
    from bootmap.errors import TableauError
    with pytest.raises(TableauError) as e:
        LoopCloser().resolve(_drifted_loop([match]))
    assert e.value.where == where


@pytest.mark.parametrize("matches, where", [
    ({"a": 0, "b": 8}, "tableau: meta.place_matches"),
    ([[0, 8, 0.9]], "tableau: meta.place_matches[0]"),
    ([{"a": 0, "b": 12, "score": 0.9}], "tableau: meta.place_matches[0].b"),
    ([{"a": 0, "b": 8, "score": "high"}], "tableau: meta.place_matches[0].score"),
])
def test_place_matches_set_in_code_are_checked_by_loop_closing_as_a_read_tableau_is(matches, where):
    """A tableau whose meta is set in code is not read through the schema: its matches are checked where they
    are read, with the same messages."""
    from bootmap.errors import TableauError
    loop = _drifted_loop()
    made = Tableau(loop.steps, loop.world, dict(loop.meta, place_matches=matches))
    with pytest.raises(TableauError) as e:
        LoopCloser().resolve(made)
    assert e.value.where == where


def test_a_place_match_out_of_shape_is_refused_when_read_and_a_prefix_keeps_the_matches_within_it():
    from bootmap.errors import TableauError
    with pytest.raises(TableauError, match=r"place_matches"):
        _drifted_loop([{"a": 0, "b": 8, "score": 1.5}])
    with pytest.raises(TableauError, match=r"place_matches"):
        _drifted_loop([{"a": 0, "b": 8}])
    matched = _drifted_loop([{"a": 0, "b": 8, "score": 0.9}, {"a": 1, "b": 5, "score": 0.8}])
    assert matched.prefix(8).meta["place_matches"] == [{"a": 1, "b": 5, "score": 0.8}]
    assert LoopCloser().resolve(matched.prefix(8)).n_dstates == 8


def _figure_eight() -> Tableau:
    """Two loops of 400 m from one corner, c0 (100 m sides, turned on the spot), each closing there facing east:
    t0, t8 and t17. Dead reckoning drifts 6.5 m round the first loop and 5 m round the second, so t8 is near
    t0 (within 3 m + 1% of 400 m) and t17 near t8, but t17 lies 11.5 m from t0 after 800 m driven, beyond the
    11 m a near pair may drift: joined along the drive alone, the three cannot be one place."""
    at = [(0, 0, 0), (100, 0, 0), (100, 0, 90), (100, 100, 90), (100, 100, 180), (0, 100, 180), (0, 100, 270),
          (6.5, 0, 270), (6.5, 0, 0), (6.5, 0, 180), (-93.5, 0, 180), (-93.5, 0, 270), (-93.5, -100, 270),
          (-93.5, -100, 0), (6.5, -100, 0), (6.5, -100, 90), (11.5, 0, 90), (11.5, 0, 0)]
    turns = {1: 90, 3: 90, 5: 90, 7: 90, 8: 180, 10: 90, 12: 90, 14: 90, 16: -90}
    steps = [{"view": "corner", "odometry": list(p),
              "action": {"type": "turn", "angle_deg": turns[k]} if k in turns else
              {"type": "travel", "distance_m": 100.0}} for k, p in enumerate(at)]
    del steps[-1]["action"]
    return Tableau.from_dict({"format": FORMAT, "steps": steps, "meta": {"passes_through": True}})


def test_a_closed_loop_re_anchors_dead_reckoning_for_the_visits_around_it():
    """The second loop closed (t8 = t17, nearest first) refuses t0 = t8 by complete linkage (t0 and t17 11.5 m
    apart after 800 m); re-anchored at that closure, t17 is t0's drift round the first loop away (6.5 m through
    400 m of drive and a join counted as 300 m), near enough, and all three are one dstate."""
    eight = _figure_eight()
    cmap = LoopCloser().resolve(eight)
    assert cmap.dstate_of[0] == cmap.dstate_of[8] == cmap.dstate_of[17]
    assert cmap.n_dstates == 16
    assert check_map(eight, cmap.dstate_of) == []
    why = LoopCloser().explain(eight, 0, 17)
    assert ("t0 = t17: proposed (near): dead reckoning re-anchored at the loops closed puts them 6.5 m apart, "
            "700 m of drive between them that way, not the 800 m driven (within 10.0 m)") in why.joins


def _two_drifted_laps(matches: list[dict] | None = None) -> Tableau:
    """Two laps of a square of 20 m sides, turned on the spot: dead reckoning puts the second lap 5 m east of
    the first (t8 5 m from t0 after 81 m), beyond a near pair's bound (3.8 m) but within the drift bound (7 m),
    and eight actions agree around each pair of laps' visits: odometry proposes them as retraced."""
    square = [(0, 0, 0), (20, 0, 0), (20, 0, 90), (20, 20, 90), (20, 20, 180), (0, 20, 180), (0, 20, 270)]
    at = square + [(5, 0, 270)] + [(x + 5, y, h) for x, y, h in square] + [(10, 0, 270), (10, 0, 0)]
    return _square_drive(at, matches)


def test_retraced_visits_the_laser_places_elsewhere_are_not_proposed_either():
    """The laser's withholding holds for both of odometry's kinds of proposal: a pair retraced (the same
    actions around it, one view) is not proposed where the laser matched the later visit's place with earlier
    visits, none of them the earlier visit's place; its neighbours, retraced too, still are."""
    laps = _two_drifted_laps()
    alone = LoopCloser().resolve(laps)
    assert alone.dstate_of[0] == alone.dstate_of[8] and alone.n_dstates == 8  # the second lap is the first
    assert any(j.startswith("t0 = t8: proposed (retraced): the same 8 actions around them")
               for j in LoopCloser().explain(laps, 0, 8).joins)
    elsewhere = _two_drifted_laps([{"a": 4, "b": 8, "score": 0.9}])  # t8's place is t4's, says the laser
    cmap = LoopCloser().resolve(elsewhere)
    assert cmap.dstate_of[0] != cmap.dstate_of[8]
    assert all(cmap.dstate_of[t] == cmap.dstate_of[t + 8] for t in range(1, 9))  # t1 = t9 on, and all it forces
    why = LoopCloser().explain(elsewhere, 0, 8)
    assert why.verdict == "different" and "only for want of evidence" in why.sentence
    assert ("the same 8 actions around them, one view, and dead reckoning puts them 5.0 m apart after 81 m driven "
            "(within 7.0 m, retraced), but the laser matches t8's place, verified by the places around it, with t4, "
            "not with t0's: odometry alone proposes no visits the laser places elsewhere") in why.sentence
