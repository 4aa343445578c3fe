"""The resolver with real clingo: the paper's map, hand-checked tableaux, and every level load-bearing."""

import pytest

from bootmap import examples
from bootmap.errors import AxiomError, InconsistentTableau, SolveTimeout
from bootmap.mapping.resolver import Resolver
from bootmap.tableau import Step, Tableau, Travel, Turn
from support.check import LEVELS, check_map

ALL = None
NO_METRICAL = ["causal", "topological"]
NO_TOPOLOGICAL = ["causal", "metrical"]
CAUSAL = ["causal"]


def truth_accuracy(tableau, cmap):
    """Fraction of time points whose dstate matches the truth, up to renaming (one-to-one)."""
    pairs = {}
    for step, d in zip(tableau.steps, cmap.dstate_of):
        pairs.setdefault(d, set()).add(step.truth)
    one_to_one = all(len(v) == 1 for v in pairs.values()) and len(pairs) == len({s.truth for s in tableau.steps})
    return one_to_one


# --- The paper's notched rectangle ---------------------------------------------------------------------

def test_paper_tableau_gives_8_dstates_4_places_4_paths_unique(paper_tableau):
    m = Resolver().resolve(paper_tableau)
    assert len(paper_tableau) == 401
    assert (m.n_dstates, m.n_places, m.n_paths) == (8, 4, 4)
    assert m.unique and m.n_models == 1
    assert m.same(8, 0) and not m.same(4, 0)
    assert truth_accuracy(paper_tableau, m)


def test_paper_tableau_reads_like_the_papers_table(paper_tableau):
    m = Resolver().resolve(paper_tableau)
    rows = [(s["dstate"], s["place"], s["path"], s["dir"]) for s in m.steps[:9]]
    assert rows == [("S0", "P0", "Pa0", "pos"), ("S1", "P0", "Pa1", "pos"), ("S2", "P1", "Pa1", "pos"),
                    ("S3", "P1", "Pa2", "pos"), ("S4", "P2", "Pa2", "pos"), ("S5", "P2", "Pa3", "pos"),
                    ("S6", "P3", "Pa3", "pos"), ("S7", "P3", "Pa0", "pos"), ("S0", "P0", "Pa0", "pos")]
    assert {("P0", "Pa0"), ("P0", "Pa1"), ("P1", "Pa1")} <= set(m.on)
    assert ("Pa1", "P0", "P1") in m.order  # PO(Pa1, pos, P0, P1)
    assert ("P1", "Pa0") in m.right_of      # turning right off Pa0 at P0 and travelling reaches P1


def test_paper_tableau_without_metrical_level_still_8_by_the_boundary_rules(paper_tableau):
    m = Resolver(levels=NO_METRICAL).resolve(paper_tableau)
    assert (m.n_dstates, m.n_places, m.n_paths) == (8, 4, 4) and m.unique
    assert not m.same(4, 0) and m.same(8, 0)
    first = m.stats.to_dict()["bounds"][0]
    # one per view fails: the topological level rejects it (the causal level alone accepts it, below)
    assert (first["dstates"], first["result"]) == ("one dstate per class", "unsat")
    assert m.stats.classes == 4
    assert m.stats.lower_bound == 8  # and the optimiser proved fewer than 8 impossible


def test_paper_tableau_with_causal_level_only_folds_to_4_views(paper_tableau):
    m = Resolver(levels=CAUSAL).resolve(paper_tableau)
    assert m.n_dstates == 4 and m.same(4, 0)


def test_counter_clockwise_circuits_mirror_the_map():
    t = examples.notched_rectangle(circuits=5, clockwise=False)
    m = Resolver().resolve(t)
    assert (m.n_dstates, m.n_places, m.n_paths) == (8, 4, 4) and m.unique
    assert m.left_of and not m.right_of
    assert Resolver(levels=NO_METRICAL).resolve(t).n_dstates == 8


# --- Every level is load-bearing -----------------------------------------------------------------------

def test_square_room_is_a_triangle_without_metrical_level_and_a_square_with_it():
    t = examples.square_room(circuits=3)
    triangle = Resolver(levels=NO_METRICAL).resolve(t)
    assert (triangle.n_dstates, triangle.n_places) == (6, 3)
    square = Resolver().resolve(t)
    assert (square.n_dstates, square.n_places, square.n_paths) == (8, 4, 4) and square.unique
    assert truth_accuracy(t, square)


def test_one_way_run_past_look_alike_junctions_needs_the_topological_order():
    t = examples.one_way_run(junctions=5)
    assert Resolver(levels=NO_TOPOLOGICAL).resolve(t).n_dstates == 1
    m = Resolver().resolve(t)
    assert m.n_dstates == 5 and m.unique and m.n_places == 5 and m.n_paths == 1
    assert m.paths["Pa0"] == ["P0", "P1", "P2", "P3", "P4"]


def test_corridor_with_turn_arounds_at_both_dead_ends():
    t = examples.corridor(laps=2, middle=False)
    assert Resolver(levels=CAUSAL).resolve(t).n_dstates == 2
    for levels in (ALL, NO_METRICAL):
        m = Resolver(levels=levels).resolve(t)
        assert (m.n_dstates, m.n_places, m.n_paths) == (4, 2, 1) and m.unique
        assert truth_accuracy(t, m)
    m = Resolver().resolve(t)
    dirs = {s["dstate"]: s["dir"] for s in m.steps}
    assert sorted(dirs.values()) == ["neg", "neg", "pos", "pos"]


def test_corridor_with_a_doorway_passed_both_ways():
    t = examples.corridor(laps=2, middle=True)
    m = Resolver().resolve(t)
    assert m.n_dstates == 6 and m.unique and truth_accuracy(t, m)
    # The doorway is passed in both directions but never turned at: the SSH defines places by turns,
    # so the map holds it as two places on the one path, between the two ends either way.
    assert (m.n_places, m.n_paths) == (4, 1)
    west, east = m.place_of["S0"], m.place_of[m.dstate_of[2]]
    assert m.paths["Pa0"][0] == west and m.paths["Pa0"][-1] == east


# --- Data, not program text ----------------------------------------------------------------------------

def test_view_labels_that_look_like_asp_are_ordinary_labels():
    evil = ['a). #script (python) import os #end.', 'b" :- . #show x/0.', "#const n=1.", "c).\n#program x."]
    rows = [Step(view=evil[t % 4], action=(Turn(-90.0) if t % 2 == 0 else Travel(3.0))) for t in range(16)]
    t = Tableau(tuple(rows) + (Step(view=evil[0]),))
    m = Resolver().resolve(t)
    assert set(m.views.values()) == set(evil)
    assert m.n_dstates == 8  # the four labels behave as the notched rectangle's four views


# --- Bounds, failures and extensions -------------------------------------------------------------------

def test_inconsistent_tableau_is_reported():
    # Turning around twice returns to the same dstate (one dstate per place and directed path),
    # yet the robot saw another view: no partition of the time points explains that.
    t = Tableau((Step("A", Turn(180.0)), Step("B", Turn(180.0)), Step("C")))
    with pytest.raises(InconsistentTableau, match="no map satisfies the axioms"):
        Resolver().resolve(t)
    assert Resolver(levels=CAUSAL).resolve(t).n_dstates == 3  # the causal level alone has no such rule


def test_time_limit_is_reported_with_the_bound_proved(paper_tableau):
    with pytest.raises(SolveTimeout, match="time limit") as e:
        Resolver(levels=NO_METRICAL, time_limit=0.0).resolve(paper_tableau)
    # Out of time in the first try (one dstate per view), the views, which no dstate mixes, are proved; once
    # it failed, one dstate more. Where the clock stops depends on the machine; what that proves does not.
    views = len(set(paper_tableau.views))
    assert (e.value.stage, e.value.lower_bound) in {("one dstate per class", views), ("the lower bounds", views + 1)}


def test_unknown_level_and_missing_causal_level_are_refused():
    with pytest.raises(AxiomError, match="unknown level"):
        Resolver(levels=["causal", "nope"])
    with pytest.raises(AxiomError, match="cannot be switched off"):
        Resolver(levels=["topological"])


def test_axiom_file_that_does_not_parse_is_refused_with_clingos_message(axioms_copy):
    (axioms_copy / "broken.lp").write_text("this is not ( asp.\n")
    with pytest.raises(AxiomError) as e:
        Resolver(axioms=axioms_copy)
    assert "broken.lp" in str(e.value) and "syntax error" in str(e.value)


def test_a_new_lp_file_extends_the_theory_without_python_changes(axioms_copy):
    # Two visits that look the same, but one by day and one by night: a user's new level tells them apart.
    (axioms_copy / "daylight.lp").write_text(
        "% daylight.lp: the light at a time point is a feature of its dstate\n"
        "%! light_is_feature\n"
        "feature(T, light, night) :- time(T), T >= 4.\n"
        "feature(T, light, day) :- time(T), T < 4.\n")
    t = examples.notched_rectangle(circuits=2)
    plain = Resolver(axioms=axioms_copy, levels=["causal"]).resolve(t)
    extended = Resolver(axioms=axioms_copy, levels=["causal", "daylight"]).resolve(t)
    assert plain.n_dstates == 4 and plain.same(0, 4) and plain.same(0, 8)
    night = range(4, len(t))
    assert not any(extended.same(a, b) for a in range(4) for b in night)
    assert extended.n_dstates > plain.n_dstates


def test_shipped_paper_tableau_file_is_the_one_the_examples_build():
    from pathlib import Path

    from bootmap.tableau import load

    assert load(Path(__file__).parents[1] / "data" / "paper_notched_rectangle.json").steps == \
        examples.notched_rectangle(circuits=50).steps


def test_a_feature_only_some_time_points_show_does_not_split_the_others(axioms_copy):
    # Only night visits are marked: an unmarked visit may still be the same dstate as a marked one.
    (axioms_copy / "night.lp").write_text("feature(T, light, night) :- time(T), T >= 16.\n")
    t = examples.notched_rectangle(circuits=3)
    m = Resolver(axioms=axioms_copy).resolve(t)
    assert m.n_dstates == 8 and m.same(0, 16) and m.same(0, 8)


def test_time_out_hands_back_a_valid_map_found_on_the_way(paper_tableau, monkeypatch):
    from bootmap.mapping.search.exact import ExactSearch

    real_solve = ExactSearch.solve

    def run_out_of_time_when_optimising(self, layout, what, models=None, optimise=False, keep=False, defer=True):
        if optimise:  # pretend the optimiser's proof runs out of time before its first model
            raise self.budget.timed_out(what, [])
        return real_solve(self, layout, what, models, optimise, keep, defer)

    monkeypatch.setattr(ExactSearch, "solve", run_out_of_time_when_optimising)
    with pytest.raises(SolveTimeout) as e:
        Resolver(levels=NO_METRICAL).resolve(paper_tableau)
    best = e.value.best_map
    assert e.value.lower_bound == 5 and "not proved minimal" in str(e.value)  # 4 was proved impossible
    assert best is not None and not best.minimal and not best.unique
    assert best.n_dstates >= 8 and "NOT PROVED MINIMAL" in best.to_text()
    assert not best.same(0, 4)  # a valid map must keep S4 apart from S0


def test_several_minimal_maps_are_counted_and_listed():
    # t0 and t2 both see A and travel, then see different views: they differ. The final A (t4) has no
    # future, so it may be either of them: two minimal maps of 4 dstates.
    rows = (Step("A", Travel(1.0)), Step("B", Travel(1.0)), Step("A", Travel(1.0)), Step("C", Travel(1.0)), Step("A"))
    m = Resolver(levels=CAUSAL).resolve(Tableau(rows))
    assert m.n_dstates == 4 and m.n_models == 2 and not m.unique and not m.models_capped
    assert len(m.alternatives) == 1
    assert {m.dstate_of[4], m.alternatives[0][4]} == {m.dstate_of[0], m.dstate_of[2]}


# --- Hand-made grid worlds (views from local geometry; truth = node and heading) -----------------------

def _script(ascii_world, start, actions, frames=None):
    from support.gridworld import GridWorld, scripted

    return scripted(GridWorld.from_ascii(ascii_world).with_frames(frames or {}), start, actions)


T_JUNCTION = """
+-+-+
  |
  +
"""


def test_t_junction_explored_from_the_stem_gives_the_true_map():
    # From the south end up the stem; at the junction turn to each arm in turn, out to its dead end and back.
    t = _script(T_JUNCTION, ((1, 0), 90), [
        "travel", "right", "travel", "around", "travel", "left", "travel", "around", "travel", "left",
        "travel", "around", "travel", "right", "travel", "around", "travel"])
    for levels in (ALL, NO_METRICAL, NO_TOPOLOGICAL):
        m = Resolver(levels=levels).resolve(t)
        assert m.n_dstates == 10 and m.unique and truth_accuracy(t, m)
    m = Resolver().resolve(t)
    assert (m.n_places, m.n_paths) == (4, 2)
    junction = m.place_of[m.dstate_of[1]]
    assert len(m.places[junction]) == 4  # facing each of the four ways at the junction
    stem, bar = m.path_of[m.dstate_of[0]][0], m.path_of[m.dstate_of[2]][0]
    assert len(m.paths[stem]) == 2 and len(m.paths[bar]) == 3


SQUARE_LOOP = """
+-+
| |
+-+
"""


def test_loop_taken_in_both_directions():
    # Twice round counter-clockwise, turn around in a corner, twice round clockwise. The four corners
    # look alike, so without headings the loop folds; with them every dstate is found.
    t = _script(SQUARE_LOOP, ((0, 0), 0), (["travel", "left"] * 8)[:-1] + ["around"] + (["travel", "right"] * 8)[:-1])
    m = Resolver().resolve(t)
    assert m.n_dstates == 16 and m.unique and truth_accuracy(t, m)
    assert Resolver(levels=NO_METRICAL).resolve(t).n_dstates < 16
    # Places are dstates linked by turns: the robot turned left at each corner one way round and right the
    # other, so the two turns at a corner are linked only where it turned around: 4 + 3 places, and each
    # side is a path per direction except the side it turned around on.
    assert (m.n_places, m.n_paths) == (7, 7)


# --- Travels that bend: the heading a travel adds (heading_after_travel) -----------------------------------
# Every tableau above travels straight, so nothing there depends on a travel's heading change.

def test_l_shaped_corridor_walked_both_ways_faces_where_the_bend_leads():
    # West end W, a corridor that leaves it eastwards and bends left by 90 into the other end E (E's
    # frame is turned by 90: the corridor enters E from the south). Out to E, turn around, back to W,
    # turn around, twice. Headings by hand: leaving W 0; arriving at E 0 + 90 = 90; turned around 270;
    # back at W 270 - 90 = 180; turned around 0 again. Four dstates, as in a straight corridor (views
    # and turn-arounds tell them apart), on one path between two places; only their headings show the bend.
    t = _script("+-+", ((0, 0), 0), ["travel", "around"] * 4, frames={(1, 0): 90})
    m = Resolver().resolve(t)
    assert (m.n_dstates, m.n_places, m.n_paths) == (4, 2, 1) and m.unique and truth_accuracy(t, m)
    assert [m.headings[m.dstate_of[i]] for i in range(5)] == [0, 90, 270, 180, 0]


def bent_room(circuits=3):
    """Clockwise circuits of a room with four look-alike corners, like examples.square_room, but at each
    corner the robot turns right by only 45 and the wall to the next corner bends right by another 45
    (a rounded room): a lap still turns -360 in all, half of it in travels."""
    rows = []
    for t in range(8 * circuits):
        corner = t // 2 % 4
        action = Turn(-45.0) if t % 2 == 0 else Travel(3.0, heading_change_deg=-45.0)
        rows.append(Step("corner" if t % 2 == 0 else "wall", action, truth=f"C{corner}{'in' if t % 2 == 0 else 'out'}"))
    return Tableau(tuple(rows) + (Step("corner", truth="C0in"),))


def test_loop_of_bent_walls_is_a_square_room_only_when_the_bends_count():
    # As in the square room, the topological rules alone accept three corners (6 dstates). With the bends
    # each corner turns the robot by -45 - 45 = -90, so three corners make -270, not a whole turn: four
    # corners, 8 dstates, 4 places (a corner's two dstates share it), 4 paths (one wall each). Were the
    # bends left out, a corner would turn only -45 and the robot would face back the way it started
    # only after 8 corners: the room's truth (4 corners) would then not be a map at all.
    t = bent_room(circuits=3)
    assert Resolver(levels=NO_METRICAL).resolve(t).n_dstates == 6
    m = Resolver().resolve(t)
    assert (m.n_dstates, m.n_places, m.n_paths) == (8, 4, 4) and m.unique and truth_accuracy(t, m)


BENT_COMB = """
+-+-+-+-+-+
  | | | |
  + + + +
"""


def test_curved_hallway_with_look_alike_side_corridors_is_told_apart_by_its_bends():
    # A hallway with four side corridors to the south, the nodes between (1, 1) and (4, 1) turned by
    # 0, 30, 60 and 90, so the hallway bends left by 30 at each junction. East from (1, 1) to (4, 1),
    # turn around, west back to (1, 1). Every junction looks alike going east (".FRB": front, right and
    # back open) and going west ("LF.B"). The headings by hand: east 0, 30, 60, 90; turned around 270;
    # west 270 - 30 = 240, 210, 180. All eight differ, so the causal and metrical levels alone keep the
    # eight true dstates apart; in a straight hallway (every heading 0 or 180) they fold to two.
    actions = ["travel"] * 3 + ["around"] + ["travel"] * 3
    start = ((1, 1), 0)
    frames = {(2, 1): 30, (3, 1): 60, (4, 1): 90}
    straight = _script(BENT_COMB, start, actions)
    assert Resolver(levels=NO_TOPOLOGICAL).resolve(straight).n_dstates == 2
    t = _script(BENT_COMB, start, actions, frames=frames)
    assert [s.view for s in t.steps] == [".FRB"] * 4 + ["LF.B"] * 4
    m = Resolver(levels=NO_TOPOLOGICAL).resolve(t)
    assert m.n_dstates == 8 and m.unique and truth_accuracy(t, m)
    assert [m.headings[d] for d in m.dstate_of] == [0, 30, 60, 90, 270, 240, 210, 180]
    # With the topological level the order along the hallway separates them anyway, bends or not.
    assert Resolver().resolve(t).n_dstates == 8


# --- one_side: the only rule that keeps a place off both sides of a path ------------------------------------

def place_on_both_sides():
    """Facing along a path at X (dstate a), the robot turns right, travels to P, turns around, travels
    back to X, turns right onto the first path again (a), travels on to Y (a2), turns left and travels,
    by a corridor that bends left by 90, to P again (pe), where it turns right and faces the way it
    faced after the turn-around (q). Every view is distinct except the two a's and the two q's."""
    rows = [("a", Turn(-90.0)), ("b", Travel(2.0)), ("pd", Turn(180.0)), ("q", Travel(2.0)), ("b2", Turn(-90.0)),
            ("a", Travel(2.0)), ("a2", Turn(90.0)), ("e", Travel(2.0, heading_change_deg=90.0)), ("pe", Turn(-90.0)),
            ("q", None)]
    return Tableau(tuple(Step(v, a) for v, a in rows))


@pytest.mark.parametrize("levels", [NO_METRICAL, ALL], ids=["causal+topological", "all"])
def test_one_side_is_the_only_rule_that_keeps_a_place_off_both_sides_of_a_path(axioms_copy, levels):
    # One dstate per view (8) puts P = {pd, q, pe} right of the path of a (turn right at t0, travel to
    # P) and left of it (a travels to a2, which turns left and travels to P; sides are shared along a
    # path). By hand, nothing else is wrong with it: places {a, b, b2}, {pd, q, pe}, {a2, e}; paths
    # {b, pd, q, b2} (q, b2 facing back), {a, a2}, {e, pe}; no turn stays on its path, no place is
    # ahead of or behind itself, and the only other sides (Y right of b2's path and so left of b's,
    # X right of pe's path and e's) hold no place on those paths. Headings agree too: 0, 270, 270, 90,
    # 90, 0, 0, 90, 180 (the bend), 90. So one_side alone refutes it, and the minimal maps split one
    # repeated view instead: the second a (a's path then holds only the right turn) or the second q
    # (pe's turn then reaches a place of its own, not P).
    t = place_on_both_sides()
    one_view_one_dstate = list(t.views)
    broken = check_map(t, one_view_one_dstate, levels or LEVELS)
    assert broken and all(v.startswith("one_side:") for v in broken)

    with_rule = Resolver(axioms=axioms_copy, levels=levels).resolve(t)
    assert with_rule.n_dstates == 9 and with_rule.n_models == 2
    maps = [with_rule.dstate_of] + with_rule.alternatives
    assert sorted((m[0] == m[5], m[3] == m[9]) for m in maps) == [(False, True), (True, False)]
    assert all(check_map(t, m, levels or LEVELS) == [] for m in maps)

    rules = axioms_copy / "topological.lp"
    text = rules.read_text()
    assert text.count(":- right(D, P), left(D, P).\n") == 1
    rules.write_text(text.replace(":- right(D, P), left(D, P).\n", ""))
    without_rule = Resolver(axioms=axioms_copy, levels=levels).resolve(t)
    assert without_rule.n_dstates == 8 and without_rule.unique
    assert without_rule.same(0, 5) and without_rule.same(3, 9)          # one dstate per view
    assert (without_rule.n_places, without_rule.n_paths) == (3, 3)


@pytest.mark.parametrize("left, ground_s, solves", [
    (None, 100.0, True),   # no time limit: always
    (60.0, 4.0, True),     # the preparation (about 1.5 times the grounding) ends well inside the limit
    (0.5, 6.3, False),     # half a second left after a grounding of 6.3 s: the solve would start 9 s late
    (0.0, 0.2, True),      # a small grounding's preparation fits in the grace
])
def test_a_search_grounded_near_the_deadline_is_solved_only_if_its_preparation_ends_in_time(left, ground_s, solves):
    from bootmap.mapping.grounding import Deadline
    from bootmap.mapping.search.budget import Budget

    class Fixed(Deadline):  # a clock that does not move: the verdict depends on nothing but the figures
        def remaining(self):
            return left

    budget = Budget(Fixed(None, None), lambda what, improving, limit: SolveTimeout(what))
    assert budget.prepares_in_time(ground_s) is solves


def test_a_search_whose_solve_would_not_start_in_time_is_not_solved(paper_tableau, monkeypatch):
    # Every search grounding ends with no time to prepare its solve: the resolver stops at the first one,
    # with the best map known, and never asks clingo to solve it.
    from bootmap.mapping.grounding import Grounding
    from bootmap.mapping.search.budget import Budget

    solved: list[str] = []
    real_solve = Grounding.solve
    monkeypatch.setattr(Budget, "prepares_in_time", lambda self, ground_s: False)
    monkeypatch.setattr(Grounding, "solve", lambda self, *a, **k: solved.append("solve") or real_solve(self, *a, **k))
    with pytest.raises(SolveTimeout) as e:
        Resolver(levels=NO_METRICAL).resolve(paper_tableau)
    assert "grounded, not solved" in str(e.value)
    # No search was solved; nor was the first try grounded: without headings the room's corners alias, and
    # determinism over the classes refutes one dstate per class from the steps.
    assert solved == []


def test_a_first_try_slowed_by_a_busy_host_does_not_refuse_the_search(monkeypatch, tmp_path):
    # The paper's room with misclustered views read as seen, 43 steps, resolved as a stream resolves it,
    # told the dstates the last map proved: the first try grounds in a few milliseconds, and the search at
    # that bound (first of all) is predicted from it, a thousandfold. While the process waited for the
    # processor (a busy host), its first grounding took 0.2 s by the wall clock: predicted from that, the
    # search "would take about 50 s" and was refused. The process's CPU time is what predicts it. (A
    # theory a user changed, here by a comment: the stock axioms' prepass is worked out without grounding.)
    import shutil

    import numpy as np
    from support.noise import with_misreads

    from bootmap.mapping.grounding import Grounding
    from bootmap.mapping.theory import default_axioms_dir

    axioms = tmp_path / "asp"
    shutil.copytree(default_axioms_dir(), axioms)
    (axioms / "causal.lp").write_text((axioms / "causal.lp").read_text() + "\n% a user's note\n")
    tableau = with_misreads(examples.notched_rectangle(6), 0.02, np.random.default_rng(3))[0].prefix(43)
    quiet = Resolver(axioms=axioms, time_limit=30, misreads=False).resolve(tableau)
    real, grounded = Grounding.ground, []

    def first_waited(self, *args, **kwargs):
        out = real(self, *args, **kwargs)
        if not grounded:
            self.ground_s += 0.2  # the wall clock ran on; the process's CPU time did not
        grounded.append(self)
        return out

    monkeypatch.setattr(Grounding, "ground", first_waited)
    busy = Resolver(axioms=axioms, time_limit=30, misreads=False).resolve(tableau, at_least=quiet.n_dstates)
    assert len(grounded) > 1 and busy.dstate_of == quiet.dstate_of and busy.n_models == quiet.n_models


class _WakesEarly:
    """A real clingo solve handle whose first wait ends at once, reporting "not done", as clasp's wait
    does when its condition variable wakes before the time-out."""

    def __init__(self, handle):
        self.handle, self.waits = handle, 0

    def wait(self, timeout=None):
        self.waits += 1
        return False if self.waits == 1 else self.handle.wait(timeout)


def test_a_wait_that_wakes_early_is_not_taken_for_the_deadline():
    # A resolve of a small random walk ended "time limit of 60 s reached while looking for one dstate per
    # class" a few seconds after it began: clasp's wait came back early, and one early "not done" was
    # taken for the time-out.
    import clingo

    from bootmap.mapping.grounding import Deadline, wait_until

    control = clingo.Control(["0"])
    control.add("base", [], "{ a(1..14) }.")
    control.ground([("base", [])])
    models = []
    with control.solve(on_model=lambda m: models.append(1), async_=True) as handle:
        woken = _WakesEarly(handle)
        assert wait_until(woken, Deadline.after(60))
        assert woken.waits >= 2
        assert handle.get().satisfiable
    assert len(models) == 2 ** 14


def test_a_search_that_outlasts_its_deadline_is_waited_for_until_the_deadline_only():
    import time

    import clingo

    from bootmap.mapping.grounding import Deadline, wait_until

    control = clingo.Control()  # twelve pigeons in eleven holes: far longer than the deadline
    control.add("base", [], "p(1..12). h(1..11). { in(P, H) : h(H) } = 1 :- p(P). "
                            ":- in(P1, H), in(P2, H), P1 < P2.")
    control.ground([("base", [])])
    start = time.perf_counter()
    with control.solve(async_=True) as handle:
        woken = _WakesEarly(handle)
        assert not wait_until(woken, Deadline.after(0.3))
        handle.cancel()
    assert time.perf_counter() - start >= 0.3  # not at the early wake-up
