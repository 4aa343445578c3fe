"""Every named rule of the axioms is load-bearing: deleting it changes what bootmap answers.

The cases are keyed by the rule table the theory itself reads (``%! name`` labels, :meth:`Theory.rules`), so
a rule added without a case fails ``test_every_named_rule_has_a_case``. Each case deletes the rule's lines
from a private copy of the axiom directory and asks the same question of the shipped axioms and of the copy:
the resolved map (partition, places, paths, order, sides, number of minimal maps, the bounds the search
proved), an explanation's verdict, or a loop-closed map. The answers must differ.
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Callable

import numpy as np
import pytest

from bootmap import examples
from bootmap.errors import BootmapError, InconsistentTableau, SolveTimeout
from bootmap.mapping import Explainer, Resolver, load_theory
from bootmap.mapping.assertions import parse_assertions
from bootmap.mapping.loops import LoopCloser
from bootmap.mapping.theory import default_axioms_dir, rule_lines
from bootmap.tableau import Step, Tableau, Travel, Turn
from support.gridworld import random_world, walk
from support.noise import with_misreads

SHIPPED = default_axioms_dir()
RULES = {r.name: r for r in load_theory(SHIPPED).rules()}
CT = ("causal", "topological")
CM = ("causal", "metrical")


# --- Small tableaux ---------------------------------------------------------------------------------------

def steps(rows, meta=None) -> Tableau:
    t = Tableau(tuple(Step(v, a) for v, a in rows))
    return Tableau.from_dict({**t.to_dict(), "meta": meta}) if meta else t


def grid_walk(seed: int) -> Tableau:
    """A short walk (8-17 time points) in a random 3x3 grid world; the seeds below were found by trying
    seeds until deleting the rule changed the map, so each is a case the rule decides."""
    rng = np.random.default_rng(seed)
    world = random_world(rng, 3, 3, extra_edges=int(rng.integers(0, 3)), landmarks=0.3)
    n = int(rng.integers(8, 18))
    return walk(world, n, rng, policy="random" if seed % 2 else "explore")


def place_on_both_sides() -> Tableau:
    """tests/mapping/test_resolver.py's tableau: one dstate per view puts a place on both sides of a path."""
    return steps([("a", Turn(-90.0)), ("b", Travel(2.0)), ("pd", Turn(180.0)), ("q", Travel(2.0)),
                  ("b2", Turn(-90.0)), ("a", Travel(2.0)), ("a2", Turn(90.0)),
                  ("e", Travel(2.0, heading_change_deg=90.0)), ("pe", Turn(-90.0)), ("q", None)])


def corridor_passed_through() -> Tableau:
    """A - B - C: A east to B (5 m), back, then east straight past B to C (10 m), a log that drove through."""
    return steps([("a", Travel(5.0)), ("b", Turn(180.0)), ("b'", Travel(5.0)), ("a'", Turn(180.0)),
                  ("a", Travel(10.0)), ("c", None)], meta={"passes_through": True})


def two_lengths() -> Tableau:
    """A corridor walked by a robot that stops at every dstate: from A east 4 m to B, back, and from A east
    again 6 m, to a place that looks like B. Odometry reads the lengths to a few centimetres (no two equal),
    so 4 m and 6 m are two lengths and the second visit of A is another dstate."""
    return steps([("a", Travel(4.02)), ("b", Turn(180.0)), ("b'", Travel(3.98)), ("a'", Turn(180.0)),
                  ("a", Travel(6.01)), ("b", None)])


def bent_round_a_corner() -> Tableau:
    """A log's travel that bent right on the way (a corner driven round without stopping) to a place that
    looks like where it started: the place reached lies right of the starting path, so not on it."""
    return steps([("a", Travel(5.0, heading_change_deg=-90.0)), ("a", None)], meta={"passes_through": True})


def loop_with_misreads() -> Tableau:
    """The notched rectangle, 15 circuits, two views misread (t56, t61)."""
    clean = examples.notched_rectangle(15)
    return with_misreads(clean, 1.5 / len(clean), np.random.default_rng(1))[0]


#: Actions by letter, for the walks written as strings below.
ACTIONS = {"R": Turn(-90.0), "L": Turn(90.0), "U": Turn(180.0), "F": Travel(2.0)}


def imaged(laps: dict[str, str], walk: str) -> Tableau:
    """A walk of laps, each written as its views and the action after each ("VRQFPF": V, a right turn, Q, a
    travel, P, a travel; L and U are left and about turns), ending at V. Every step has an image, its view's
    unit vector, as views clustered from images have: in a tableau of ten steps per view or more, a view with
    one or two images is then a suspect, and a cheap one (half a dstate to call a misread)."""
    text = "".join(laps[lap] for lap in walk) + "V"
    views, actions = text[::2], [ACTIONS[a] for a in text[1::2]] + [None]
    labels = sorted(set(views))
    return Tableau(tuple(Step(v, a, tuple(float(v == u) for u in labels)) for v, a in zip(views, actions)))


def two_odd_views_at_one_place() -> Tableau:
    """Laps of the causal level: at V the robot turns right, left or around to Q, travels to P and on to V.
    Twice it turned from Q back to P instead (around, then left), travelled on and saw a view seen nowhere
    else (X, then Y), and turned (right, then left) to a Q that travels on to V. X and Y are suspects, each
    expected to be V (V, or the other odd view, follows that travel from P; only V precedes that turn to
    Q); but neither can be the laps' V, whose turns reach a Q that travels on to P. Read as seen they are a
    dstate each, and the P before them two (one travelled to X, the other to Y): eight dstates. Taken as
    misreads, together at one V dstate the laps never reach, they would save two dstates for the cost of
    one: but that dstate no time point holds as V, the view its misreads expected."""
    laps = {"R": "VRQFPF", "L": "VLQFPF", "U": "VUQFPF", "X": "VRQUPFXRQF", "Y": "VRQLPFYLQF"}
    return imaged(laps, "RLURLUXRLURLUYR")


def first_view_either_way() -> Tableau:
    """Laps of the causal level: at V the robot turns right or left to Q, travels to P and on to V. Once
    it saw that Q as Y (a view seen once, a misread: read as seen, it sets the laps before it apart). It
    started at a place seen as X, and left it by a right turn to Q, as V's right turn does; later, turning
    left at Q, it travelled from another P to X again and turned left to P. That second X can join no dstate
    of the laps (it is expected to be V or Q, but V's left turn reaches Q, and Q's the P before it), and the
    first X may be at its dstate, read as seen, or at V, a misread; or both may be misreads, where a dstate
    of V or Q is split for the second. Five dstates each way: only what the misreads cost tells these maps
    apart."""
    laps = {"S": "XRQFPF", "R": "VRQFPF", "L": "VLQFPF", "Y": "VRYFPF", "X": "VRQLPFXLPF"}
    return imaged(laps, "SRLRLYRLRLXRLRLR")


def loop_with_one_odd_view() -> Tableau:
    """Four views in a loop of right turns, lap after lap, one of them seen as W (test_misreads.py)."""
    views = ["XYZV"[t % 4] for t in range(16)]
    views[9] = "W"
    return steps([(v, Turn(-90.0)) for v in views[:-1]] + [(views[-1], None)])


# --- What is observed --------------------------------------------------------------------------------------

def observe_map(m) -> tuple:
    return ("map", m.n_dstates, tuple(m.dstate_of), sorted(m.places.items()), sorted(m.paths.items()),
            sorted(m.on), sorted(m.order), sorted(m.right_of), sorted(m.left_of), sorted(m.views.items()),
            sorted(m.headings.items()), m.n_models, m.models_capped, [s["t"] for s in m.suspect_steps],
            m.stats.lower_bound, [(b.dstates, b.result) for b in m.stats.bounds])


def resolved(tableau: Callable[[], Tableau], levels=None, mutant_limit: float = 60.0):
    """The map the resolver gives. A deleted rule's resolution may get a shorter limit where the shipped
    axioms' map cannot be its answer anyway (it shows misreads the copy cannot derive)."""
    def run(axioms: Path, shipped: bool):
        try:
            return observe_map(Resolver(axioms=axioms, levels=levels,
                                        time_limit=60.0 if shipped else mutant_limit).resolve(tableau()))
        except InconsistentTableau:
            return ("inconsistent",)
        except SolveTimeout:
            return ("timeout",)
        except (BootmapError, AttributeError, KeyError) as e:  # a theory without the rule can break the reader
            return ("failed", type(e).__name__)
    return run


def undecided() -> Tableau:
    """t0 and t2 look alike but what followed differs; t4 looks alike and did nothing more: two minimal maps
    (t4 with t0, or with t2; test_explain.py)."""
    travel = Travel(1.0)
    return steps([("A", travel), ("B", travel), ("A", travel), ("C", travel), ("A", None)])


def asserted(tableau: Callable[[], Tableau], assertions: list, levels=None):
    """The map the resolver gives with a person's assertions (core/assert.lp)."""
    def run(axioms: Path, shipped: bool):
        said = parse_assertions(assertions, len(tableau()))
        try:
            return observe_map(Resolver(axioms=axioms, levels=levels, time_limit=60).resolve(tableau(), assertions=said))
        except InconsistentTableau:
            return ("inconsistent",)
    return run


def can_be_same(tableau: Callable[[], Tableau], a: int, b: int, keep, levels=None):
    """The explainer's question: can a and b be one dstate in some map of the kept steps?"""
    def run(axioms: Path, shipped: bool):
        return Explainer(axioms=axioms, levels=levels, time_limit=60).can_be_same(tableau(), a, b, list(keep))
    return run


def loop_closed(tableau: Callable[[], Tableau]):
    """The loop closer's map (odometry proposes, clingo checks with the partition fixed)."""
    def run(axioms: Path, shipped: bool):
        try:
            return observe_map(LoopCloser(Resolver(axioms=axioms, time_limit=60)).resolve(tableau()))
        except BootmapError as e:
            return ("failed", type(e).__name__)
    return run


PAPER1 = lambda: examples.notched_rectangle(1)  # noqa: E731
PAPER2 = lambda: examples.notched_rectangle(2)  # noqa: E731
CORRIDOR = lambda: examples.corridor(laps=1)  # noqa: E731

SCENARIOS = {
    "paper": resolved(PAPER1),
    "paper_without_headings": resolved(PAPER2, CT),
    "corridor": resolved(CORRIDOR),
    "both_sides": resolved(place_on_both_sides, CT),
    "passing": resolved(corridor_passed_through),
    "two_lengths": resolved(two_lengths),
    "odd_view": resolved(loop_with_one_odd_view),
    "misreads": resolved(loop_with_misreads, mutant_limit=1.0),
    "odd_views_at_one_place": resolved(two_odd_views_at_one_place, ("causal",)),
    "first_view_either_way": resolved(first_view_either_way, ("causal",)),
    "turned_around_in_place": resolved(lambda: steps([("a", Turn(180.0)), ("a", None)]), CT),
    "travelled_to_itself": resolved(lambda: steps([("a", Travel(2.0)), ("a", None)]), CT),
    "bent_to_itself": resolved(bent_round_a_corner, CT),
    "walk2": resolved(lambda: grid_walk(2), CT),
    "walk22": resolved(lambda: grid_walk(22), CT),
    "walk82": resolved(lambda: grid_walk(82), CT),
    "walk148": resolved(lambda: grid_walk(148), CT),
    "walk473": resolved(lambda: grid_walk(473), CT),
    "S0_S4_apart": can_be_same(PAPER2, 0, 4, range(9), CT),
    "headings_after_a_gap": can_be_same(PAPER2, 4, 8, [0, *range(2, 10)], CM),
    "loop_closing": loop_closed(lambda: grid_walk(0)),
    "asserted_same": asserted(PAPER2, [{"same": [0, 4]}], CT),
    "asserted_apart": asserted(PAPER1, [{"apart": [0, 8]}]),
    "preferred_same": asserted(undecided, [{"same": [2, 4], "soft": True}], ("causal",)),
    "preferred_apart": asserted(PAPER1, [{"apart": [0, 8], "soft": True, "cost": 9}]),
    "told_apart_ahead": asserted(PAPER2, [{"apart": [8, 16]}]),
}

#: rule -> the scenario whose answer changes without it (what changes, in a word).
CASES = {
    "asked_same": "S0_S4_apart",                # the supposition is ignored: S0 and S4 "can" be one
    "candidate_dstates": "paper",               # no candidates: no map
    "fixed_dstate": "loop_closing",             # a fixed partition has no candidates: nothing checks
    "misread_candidates": "misreads",           # a misread cannot join another view's dstate
    "misread": "misreads",                      # no view is taken as a misread
    "misread_joins_held": "odd_views_at_one_place",  # X and Y open a dstate with no view: no map to read
    "fewest_misreads": "first_view_either_way",  # a misread that saves nothing is free: five maps, not one
    "dstate_bound": "odd_views_at_one_place",   # a bound the misread search sets is not kept: another map
    "fewest_dstates": "paper_without_headings",  # nothing is minimised
    "time_point": "paper",
    "view_is_feature": "corridor",
    "turn_action": "paper",
    "travel_action": "paper",
    "travel_action_passing": "passing",         # travels of a log that drove through link nothing
    "future_view_is_feature": "odd_view",      # the search proves less before it starts
    "one_dstate_per_time": "paper",
    "dstate_exists": "paper",
    "dstate_shows_feature": "paper",
    "dstate_shows_view": "paper",
    "one_value_per_feature": "two_lengths",     # views and headings split classes anyway; lengths do not
    "experience": "paper",
    "deterministic_action": "odd_view",
    "view_of": "paper",
    "heading_origin": "paper",
    "heading_resumed": "headings_after_a_gap",
    "heading_after_turn": "paper",
    "heading_after_travel": "corridor",
    "heading_is_feature": "paper",
    "length_is_feature": "two_lengths",
    "turn_link": "paper",
    "turn_around_link": "corridor",
    "travel_link": "paper",
    "turn_linked": "paper",
    "same_place": "paper",
    "place_of": "paper",
    "same_path": "paper",
    "one_direction": "turned_around_in_place",
    "turn_leaves_path": "walk473",
    "path_rep": "paper",
    "path_of": "paper",
    "one_dstate_per_place_and_direction": "walk82",
    "order_by_travel": "paper",
    "order_transitive": "corridor",
    "order_turn_around": "walk22",
    "on_path": "paper_without_headings",
    "right_by_turn": "paper",
    "left_by_turn": "both_sides",
    "sides_along_path": "both_sides",
    "sides_turn_around": "walk148",
    "on_path_no_side": "paper_without_headings",
    "one_side": "both_sides",
    "sides_by_bend": "bent_to_itself",          # the place a bend reached may be the one it left: 1 dstate
    "asserted_same": "asserted_same",           # the person's join is not made: a map instead of the clash
    "asserted_apart": "asserted_apart",         # S0's visits stay one dstate
    "preferred_same": "preferred_same",         # both minimal maps instead of the one that keeps it
    "preferred_apart": "preferred_apart",       # not worth a dstate to anybody: 8 dstates, not 9
    "told_apart_ahead": "told_apart_ahead",     # the search proves less before it starts: bounds climbed
}

#: Rules whose deletion alone changes nothing found; each with why (and, for a pair, the case that deletes
#: both and shows the pair load-bearing).
EXCEPTIONS = {
    "order_irreflexive": "with one_dstate_per_place_and_direction, a place ahead of (behind) a dstate's own "
                         "place closes a cycle along the path, which puts a place both ahead and behind: "
                         "order_asymmetric refutes it too (deleting both: test_the_strict_order_rules_...)",
    "order_asymmetric": "a place both ahead of and behind a dstate closes a cycle along the path through it, "
                        "which puts some dstate's own place ahead of it: order_irreflexive refutes it too",
}


def without(names: list[str], dest: Path) -> Path:
    """A copy of the shipped axioms with the named rules' lines blanked (line numbers kept)."""
    shutil.copytree(SHIPPED, dest)
    for name in names:
        rule = RULES[name]
        source = Path(rule.file)
        target = dest / source.relative_to(SHIPPED)
        lines = target.read_text().splitlines(keepends=True)
        doomed = [n for n, label in rule_lines(source).items() if label == name]
        assert doomed, f"rule {name} has no lines under its label"
        for n in doomed:
            lines[n - 1] = "\n"
        target.write_text("".join(lines))
    return dest


_shipped: dict[str, object] = {}


def shipped_answer(scenario: str):
    if scenario not in _shipped:
        _shipped[scenario] = SCENARIOS[scenario](SHIPPED, True)
    return _shipped[scenario]


def test_every_named_rule_has_a_case_or_a_stated_exception():
    assert sorted(CASES.keys() | EXCEPTIONS.keys()) == sorted(RULES), "a rule without a case, or a case for no rule"
    assert not CASES.keys() & EXCEPTIONS.keys()
    assert set(CASES.values()) <= set(SCENARIOS)


def test_every_rule_label_names_the_lines_below_it():
    # The explainer cites rules by line: a label followed by a comment names nothing.
    assert [name for name, rule in RULES.items() if not rule.text] == []


@pytest.mark.parametrize("rule", sorted(CASES))
def test_deleting_a_named_rule_changes_the_answer(rule, tmp_path):
    scenario = CASES[rule]
    before = shipped_answer(scenario)
    assert not isinstance(before, tuple) or before[0] not in ("timeout", "failed"), before
    after = SCENARIOS[scenario](without([rule], tmp_path / "asp"), False)
    assert after != before, f"{rule} deleted, {scenario} answers as before"


def test_the_strict_order_rules_together_keep_a_travel_from_returning_to_its_start(tmp_path):
    scenario = SCENARIOS["travelled_to_itself"]
    before = shipped_answer("travelled_to_itself")
    assert before[1] == 2  # a travel reaches another place: two dstates, though both look alike
    for name in ("order_irreflexive", "order_asymmetric"):
        assert scenario(without([name], tmp_path / name), False) == before
    both = scenario(without(["order_irreflexive", "order_asymmetric"], tmp_path / "both"), False)
    assert both[1] == 1
