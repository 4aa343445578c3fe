"""The walls as a compass (bootmap.mapping.compass): a turn's angle read from the laser images at its ends,
with odometry only choosing among the rotations the walls allow; and what that does to the typing and the
map where odometry is poor."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bootmap.mapping.compass import WallCompass, overlap_agrees, rotation_candidates, wall_directions
from bootmap.mapping.facts import typing_of
from bootmap.mapping.motion import MotionPrimitives
from bootmap.sim.laser import Scene, SweepCaster
from bootmap.sim.world import load_world
from bootmap.tableau import Step, Tableau, Travel, Turn

BEAMS = np.linspace(-math.pi / 2, math.pi / 2, 180)
LASER = {"angle_min": -math.pi / 2, "angle_max": math.pi / 2, "range_max": 8.0}
# Where the Taylor Hall robot stops: corridor ends, junctions, and the middle of a corridor (x, y metres).
SPOTS = [(1.2, 1.2), (25.0, 1.2), (55.0, 1.2), (78.8, 1.2), (25.0, -10.8), (55.0, 13.2), (66.8, 13.2), (40.0, 1.2)]


@pytest.fixture(scope="module")
def hall():
    world = load_world("taylor_hall")
    return Scene.of_world(world), SweepCaster(BEAMS, 8.0)


def scan(hall, x, y, heading_deg, rng=None, noise_m=0.01):
    scene, caster = hall
    r = caster.cast(scene, x, y, math.radians(heading_deg))
    if rng is not None:
        r = np.where(r < 8.0, r + rng.normal(0.0, noise_m, r.shape), r)
    return tuple(np.round(r, 4).tolist())


def turns_tableau(hall, turns, rng, odometry_sd):
    """A robot turning on the spot at Taylor Hall's dstates: ``turns`` as (spot, heading, true angle), each
    read by odometry with Gaussian error; returns the tableau and the true angles."""
    steps, truth = [], []
    for (x, y), heading, angle in turns:
        read = angle + rng.normal(0.0, odometry_sd)
        steps.append(Step(action=Turn(round(read, 1)), image=scan(hall, x, y, heading, rng)))
        steps.append(Step(action=Travel(0.0, 0.0), image=scan(hall, x, y, heading + angle, rng)))
        truth.append(angle)
    steps[-1] = Step(image=steps[-1].image)
    return Tableau(tuple(steps), "taylor_hall", {"laser": LASER}), truth


def wrap(a):
    return (a + 180.0) % 360.0 - 180.0


def test_a_corridor_seen_before_and_after_a_turn_around_gives_its_rotation(hall):
    before, after = scan(hall, 40.0, 1.2, 0.0), scan(hall, 40.0, 1.2, 180.0)
    h = [wall_directions(s, BEAMS, 8.0) for s in (before, after)]
    angles = [a for a, _ in rotation_candidates(*h)]
    # the images share no beam, yet both show the corridor's walls: 0 or 180 (a wall has no sense)
    assert min(abs(wrap(a - 180.0)) for a in angles) < 1.0
    assert overlap_agrees(before, after, BEAMS, 8.0, 180.0) is None  # nothing to compare
    # turned by 90 instead, the beams both images share would disagree
    assert overlap_agrees(before, after, BEAMS, 8.0, -90.0) is False


def right_or_ambiguous(compass, t, angle):
    """The compass read action ``t`` as ``angle``, or as another candidate with ``angle`` beside it."""
    r = compass.results_[t]
    return abs(wrap(r.reading - angle)) < 1.5 or (r.alternative is not None and abs(wrap(r.alternative - angle)) < 1.5)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_turns_read_from_the_walls_are_right_where_odometry_is_off_by_tens_of_degrees(hall, seed):
    rng = np.random.default_rng(seed)
    turns = [(SPOTS[rng.integers(len(SPOTS))], float(rng.choice([0, 90, 180, -90])), float(rng.choice([90, -90, 180])))
             for _ in range(40)]
    tableau, truth = turns_tableau(hall, turns, rng, odometry_sd=15.0)  # three times a good robot's
    compass = WallCompass().fit(tableau)
    odometry = [tableau.steps[t].action.angle_deg for t in range(0, len(tableau.actions), 2)]
    assert max(abs(wrap(o - a)) for o, a in zip(odometry, truth)) > 20  # odometry alone would mistype some
    wrong = [(o, compass.results_[2 * k], a) for k, (o, a) in enumerate(zip(odometry, truth))
             if not right_or_ambiguous(compass, 2 * k, a)]
    assert not wrong
    # and nearly every turn is read right outright (ambiguous only where odometry strayed tens of degrees)
    ambiguous = sum(compass.results_[2 * k].alternative is not None for k in range(len(truth)))
    assert ambiguous <= sum(abs(wrap(o - a)) > 25 for o, a in zip(odometry, truth))


def test_a_turn_around_read_as_minus_124_is_read_as_180(hall):
    # a robot whose odometry strays by 15 degrees (s.d.) on its turns; this turn-around it reads 56 off
    rng = np.random.default_rng(5)
    turns = [((40.0, 1.2), 0.0, 180.0)] + [(SPOTS[i % len(SPOTS)], 0.0, 90.0 * (1 - 2 * (i % 2))) for i in range(12)]
    tableau, _ = turns_tableau(hall, turns, rng, odometry_sd=15.0)
    steps = list(tableau.steps)
    steps[0] = Step(action=Turn(236.0), image=steps[0].image)  # odometry 56 degrees off: nearer -90 than 180
    compass = WallCompass().fit(Tableau(tuple(steps), "taylor_hall", {"laser": LASER}))
    assert abs(wrap(compass.readings_[0] - 180.0)) < 1.0
    # odometry alone types it -90
    assert MotionPrimitives().fit([s.action for s in steps[:-1]]).angles_[0] == -90


@settings(max_examples=25, deadline=None)
@given(spot=st.sampled_from(SPOTS), heading=st.sampled_from([0.0, 90.0, 180.0, -90.0]),
       angle=st.sampled_from([90.0, -90.0, 180.0]), error=st.floats(-30.0, 30.0))
def test_one_turn_on_the_spot_is_read_within_a_degree(hall, spot, heading, angle, error):
    # A tableau of a few turns, odometry's spread learned from them; the turn under test read `error` off.
    rng = np.random.default_rng(0)
    others = [(SPOTS[i], 0.0, 90.0 * (1 - 2 * (i % 2))) for i in range(6)]
    tableau, _ = turns_tableau(hall, [(spot, heading, angle)] + others, rng, odometry_sd=10.0)
    steps = list(tableau.steps)
    steps[0] = Step(action=Turn(angle + error), image=steps[0].image)
    compass = WallCompass().fit(Tableau(tuple(steps), "taylor_hall", {"laser": LASER}))
    assert right_or_ambiguous(compass, 0, angle)
    if abs(error) < 20:
        assert abs(wrap(compass.readings_[0] - angle)) < 1.0


def test_without_the_lasers_geometry_or_images_odometry_is_read():
    steps = (Step(view="a", action=Turn(-87.0)), Step(view="b", action=Travel(2.0, 3.0)), Step(view="c"))
    compass = WallCompass().fit(Tableau(steps, "w", {}))
    assert not compass.used_ and compass.readings_ == [-87.0, 3.0] and compass.confirmed_ == [False, False]


def test_untrusted_readings_take_the_nearest_grid_angle_and_make_no_type():
    # Laser readings near 90, 180 and 0; one odometry reading the laser could not confirm, at -124.
    actions = [Turn(a) for a in (90.2, -89.8, 179.9, 90.1, -90.3, 180.2, 89.9, -124.0)] + [Travel(3.0, 0.1)] * 5
    trusted = [True] * 7 + [False] + [True] * 5
    m = MotionPrimitives(resolution_deg=0.0, exact_deg=0.0).fit(actions, trusted=trusted)
    assert m.grid_deg_ == 90 and m.angles_[7] == -90
    assert sorted(t.angle for t in m.types_ if t.kind == "turn") == [-90, 90, 180]
    # with every reading trusted, the stray would make a grid of its own
    assert MotionPrimitives(resolution_deg=0.0).fit(actions).grid_deg_ < 90


def test_typing_reads_the_walls_and_names_the_misled_turn_a_suspect(hall):
    rng = np.random.default_rng(7)
    turns = [((40.0, 1.2), 0.0, 180.0)] + [(SPOTS[i % len(SPOTS)], 0.0, 90.0 * (1 - 2 * (i % 2))) for i in range(10)]
    tableau, truth = turns_tableau(hall, turns, rng, odometry_sd=12.0)
    steps = list(tableau.steps)
    steps[0] = Step(action=Turn(236.0), image=steps[0].image)  # a turn-around odometry reads nearer -90
    tableau = Tableau(tuple(steps), "taylor_hall", {"laser": LASER}).with_views([f"v{t}" for t in range(len(steps))])
    typing = typing_of(tableau)
    assert typing.grid == 90
    typed = [typing.angles[t] for t in range(0, len(tableau.actions), 2)]
    suspects = {s.t: s.alternative for s in typing.suspects()}
    assert all(a == int(b) or suspects.get(2 * k) == int(b) for k, (a, b) in enumerate(zip(typed, truth)))
    assert typed[0] == 180
    # odometry alone types the turn-around -90 and does not suspect it
    plain = typing_of(tableau, compass=False)
    assert plain.angles[0] == -90 and 0 not in {s.t for s in plain.suspects()}


def test_two_turns_misled_by_90_degrees_are_retyped_together():
    """Righting one of two mistyped turns leaves as many headings wrong; weighed together (views and
    headings) both are found, and no decoy."""
    from bootmap.mapping.motion import TypeSuspect
    from bootmap.mapping.search.retyping import jointly_retyped, view_headings
    from support.gridworld import random_world, walk

    rng = np.random.default_rng(4)
    clean = walk(random_world(rng, 5, 4, extra_edges=4, landmarks=0.4), 300, rng, policy="explore")
    views = clean.views
    true = [int(round(a.angle_deg if isinstance(a, Turn) else a.heading_change_deg)) for a in clean.actions]
    turns = [t for t, a in enumerate(clean.actions) if isinstance(a, Turn) and abs(a.angle_deg) == 90]
    first, second = turns[len(turns) // 3], turns[2 * len(turns) // 3]
    typed = list(true)
    suspects = []
    for t in (first, second):
        typed[t] = int(wrap(true[t] + 90)) if true[t] != 90 else 180
        suspects.append(TypeSuspect(t, "turn", float(typed[t]), typed[t], true[t]))
    for t in turns[1:6]:  # right turns suspected of being another
        if t not in (first, second):
            suspects.append(TypeSuspect(t, "turn", float(true[t]), true[t], int(wrap(true[t] + 90))))
    suspects.sort(key=lambda s: s.t)
    assert view_headings(views, typed) > view_headings(views, true)
    chosen = jointly_retyped(suspects, typed, views)
    assert sorted(s.t for s in chosen) == [first, second]


def test_a_log_that_drove_through_its_dstates_is_read_by_odometry(hall):
    rng = np.random.default_rng(2)
    tableau, _ = turns_tableau(hall, [(SPOTS[i], 0.0, 90.0) for i in range(4)], rng, odometry_sd=10.0)
    assert WallCompass().fit(tableau).used_
    log = Tableau(tableau.steps, "log", {"laser": LASER, "passes_through": True})
    compass = WallCompass().fit(log)
    assert not compass.used_ and compass.readings_ == [a.angle_deg if isinstance(a, Turn) else 0.0 for a in log.actions]


def test_the_map_says_which_angles_the_walls_read(hall):
    from bootmap.mapping.cogmap import readings_text

    rng = np.random.default_rng(3)
    tableau, _ = turns_tableau(hall, [(SPOTS[i], 0.0, 90.0 * (1 - 2 * (i % 2))) for i in range(8)], rng, 8.0)
    typing = typing_of(tableau.with_views([f"v{t}" for t in range(len(tableau.steps))]))
    turns = [a for a in typing.types if a.kind == "turn"]
    assert sum(a.from_walls for a in turns) == sum(a.count for a in turns) == 8
    assert all(a.to_dict()["read_from_walls"] == a.from_walls for a in typing.types)
    assert "angles read from the walls: 8 of 8 turns" in readings_text(typing.types, [])
    plain = typing_of(tableau.with_views([f"v{t}" for t in range(len(tableau.steps))]), compass=False)
    assert "walls" not in readings_text(plain.types, [])


def test_a_good_odometry_is_not_overruled_by_a_candidate_far_from_it(hall):
    """A robot whose odometry strays by 4 degrees reads a right turn at a crossing as -87; the beams both
    images share disagree (a third of the after image spoilt), refuting -90. The turn-around the walls also
    allow is 90 degrees from odometry's reading: odometry's own reading stands (typed -90), not 180."""
    rng = np.random.default_rng(0)
    turns = [((25.0, 1.2), 0.0, -90.0)] + [(SPOTS[i % len(SPOTS)], 0.0, 90.0 * (1 - 2 * (i % 2))) for i in range(12)]
    tableau, _ = turns_tableau(hall, turns, rng, odometry_sd=4.0)
    steps = list(tableau.steps)
    after = np.array(steps[1].image)
    spoilt = rng.choice(len(after), size=60, replace=False)
    after[spoilt] = rng.uniform(0.3, 7.0, size=60)
    steps[0] = Step(action=Turn(-87.0), image=steps[0].image)
    steps[1] = Step(action=steps[1].action, image=tuple(after.tolist()))
    spoilt_tableau = Tableau(tuple(steps), "taylor_hall", {"laser": LASER})
    compass = WallCompass().fit(spoilt_tableau)
    assert abs(wrap(compass.readings_[0] + 90.0)) < 5.0
    assert typing_of(spoilt_tableau.with_views([f"v{t}" for t in range(len(steps))])).angles[0] == -90
