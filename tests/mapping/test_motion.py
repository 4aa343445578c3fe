"""Motion primitives (bootmap.mapping.motion): action types learned from measured angles, so that odometry
noise no longer changes the map; clean experience keeps its own angles."""

import json

import numpy as np
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

from bootmap.cli import main
from bootmap.mapping import Resolver
from bootmap.mapping.motion import (GRID_EVIDENCE, LENGTH_RATIO, LENGTH_TAIL, NEAR_SHARE, LengthTypes,
                                   MotionPrimitives, exact_readings, length_types, reading_step)
from bootmap.mapping.facts import travel_length_types
from bootmap.metrics import dstate_accuracy
from bootmap.tableau import Step, Tableau, Travel, Turn
from support.check import true_partition
from support.gridworld import random_world, walk
from support.noise import LOGGED, ROUNDINGS, Rounding, rounded, with_odometry_noise

READINGS = pytest.mark.parametrize("rounding", ROUNDINGS, ids=["logged", "unrounded"])


@settings(max_examples=60, deadline=None)
@given(st.lists(st.sampled_from([-135, -90, -45, -30, 0, 7, 15, 30, 45, 60, 90, 120, 180]), min_size=2, max_size=40),
       st.lists(st.sampled_from([-90, -15, 0, 0, 0, 15, 90]), min_size=2, max_size=40))
def test_exact_angles_that_repeat_are_kept_as_they_are(turns, bends):
    # Clean experience (hand-written, or a simulator without odometry noise) reads the same angle the same
    # way every time: each value is its own type, and the axioms see exactly the angles given.
    turns, bends = turns + turns, bends + bends  # every value at least twice
    actions = [Turn(float(a)) for a in turns] + [Travel(2.0, float(b)) for b in bends]
    m = MotionPrimitives().fit(actions)
    assert m.angles_ == turns + bends
    assert sum(t.count for t in m.types_) == len(actions) and all(t.sd_deg == 0 for t in m.types_)


@READINGS
@pytest.mark.parametrize("turn_sd, drift_sd", [(0, 0), (3, 1.5), (6, 3), (10, 4)])
@pytest.mark.parametrize("seed", [101, 202, 303])
def test_turn_noise_up_to_10_degrees_does_not_change_the_map(seed, turn_sd, drift_sd, rounding):
    # Long explorations of random grid worlds, read with turn noise, travel drift and 3% error on
    # distances (none on the clean ones), recorded as a log records them or unrounded: the learned action
    # types give the true map, exactly as the clean tableau does.
    rng = np.random.default_rng(seed)
    world = random_world(rng, 4, 3, extra_edges=2, landmarks=0.4)
    clean = walk(world, 300, rng, policy="explore")
    tableau = with_odometry_noise(clean, turn_sd, drift_sd, rng, distance_sd=0.03 if turn_sd else 0.0,
                                  rounding=rounding)
    truth = true_partition(tableau)
    cmap = Resolver(time_limit=60).resolve(tableau)
    assert cmap.n_dstates == len(set(truth)) and dstate_accuracy(truth, cmap.dstate_of) == 1.0
    assert cmap.minimal and cmap.unique
    assert {t.angle for t in cmap.action_types if t.kind == "turn"} <= {-90, 90, 180}


def test_a_fixed_quantum_breaks_where_learned_types_do_not():
    # An example: one turn read at -98 degrees. Rounded to 15 degrees it is -105, every later
    # heading is off, and the map splits dstates; learned, it is one of the robot's right turns.
    rng = np.random.default_rng(7)
    world = random_world(rng, 3, 3, extra_edges=1, landmarks=0.4)
    clean = walk(world, 120, rng, policy="explore")
    t = next(i for i, a in enumerate(clean.actions) if isinstance(a, Turn) and a.angle_deg == -90)
    steps = list(clean.steps)
    steps[t] = Step(steps[t].view, Turn(-98.0), None, steps[t].truth, steps[t].pose)
    tableau = Tableau(tuple(steps), clean.world)
    truth = true_partition(tableau)
    assert dstate_accuracy(truth, Resolver().resolve(tableau).dstate_of) == 1.0
    assert Resolver(quantum_deg=15).resolve(tableau).n_dstates > len(set(truth))


def test_bootmap_map_names_the_action_types_and_refuses_a_bad_quantum(tmp_path, capsys):
    rng = np.random.default_rng(5)
    tableau = with_odometry_noise(walk(random_world(rng, 3, 3, landmarks=0.4), 60, rng), 5, 2, rng)
    path = tmp_path / "t.json"
    path.write_text(tableau.dumps())
    assert main(["map", str(path)]) == 0
    assert "action types: turn " in capsys.readouterr().out
    assert main(["map", str(path), "--format", "json"]) == 0
    types = json.loads(capsys.readouterr().out)["action_types"]
    assert sum(t["count"] for t in types) == len(tableau) - 1
    assert {t["kind"] for t in types} == {"turn", "travel"}
    with pytest.raises(SystemExit) as e:
        main(["map", str(path), "--quantum", "0"])
    assert e.value.code == 2 and "expected degrees in (0, 180]" in capsys.readouterr().err


def test_travel_lengths_tell_look_alike_dstates_apart_and_odometry_error_does_not():
    # t0 and t3 look alike (view A, heading 0) and both travel on to a look-alike B (heading 0): three
    # dstates (A, B, C), unless the travel from t0 is 15 m and from t3 4 m, which the same travel from one
    # dstate cannot be: then A is two dstates.
    def tableau(first, second):
        return Tableau((Step("A", Travel(first)), Step("B", Turn(-90.0)), Step("C", Turn(90.0)),
                        Step("A", Travel(second)), Step("B")))

    causal_metrical = Resolver(levels=["causal", "metrical"])
    assert causal_metrical.resolve(tableau(15.0, 4.0)).n_dstates == 4
    assert causal_metrical.resolve(tableau(4.1, 3.9)).n_dstates == 3  # within odometry error: one length
    assert Resolver(levels=["causal"]).resolve(tableau(15.0, 4.0)).n_dstates == 3  # lengths are metrical
    from bootmap.mapping import Explainer

    e = Explainer(levels=["causal", "metrical"]).explain(tableau(15.0, 4.0), 0, 3)
    assert e.verdict == "different" and "length_is_feature" in e.rules_cited()
    assert "the travel from t0 was 150 dm long" in e.to_text()


@settings(max_examples=12, deadline=None)
@given(seed=st.integers(0, 2**31), width=st.integers(3, 5), turn_sd=st.floats(0, 10), drift_sd=st.floats(0, 4),
       distance_sd=st.floats(0, 0.04), rounding=st.sampled_from(ROUNDINGS + (Rounding(0.001, 0.01),)))
def test_property_noisy_walks_of_random_worlds_resolve_to_the_truth(seed, width, turn_sd, drift_sd, distance_sd,
                                                                     rounding):
    # A random world, explored for 240 steps, read with random odometry noise within the bounds the typing promises
    # (turns up to sd 10 degrees, travel drift up to sd 4, distances up to 4% off), recorded at a log's
    # resolution, a finer one or unrounded: the map is the truth.
    rng = np.random.default_rng(seed)
    world = random_world(rng, width, 3, extra_edges=2, landmarks=0.4)
    tableau = with_odometry_noise(walk(world, 240, rng, policy="explore"), turn_sd, drift_sd, rng,
                                  distance_sd=distance_sd, rounding=rounding)
    truth = true_partition(tableau)
    cmap = Resolver(time_limit=60).resolve(tableau)
    assert cmap.n_dstates == len(set(truth)) and dstate_accuracy(truth, cmap.dstate_of) == 1.0, \
        [str(t) for t in cmap.action_types]


@pytest.mark.parametrize("centre, sd, strays", [(-174, 5, [163.0, 163.4]), (175, 8, [-151.0, -153.0, -156.0])])
def test_a_few_stray_turn_arounds_do_not_set_the_grid(centre, sd, strays):
    # A real robot's turn-arounds (Taylor Hall seeds 94 and 52 in the simulator) read -174 +- 5 or +175 +- 8,
    # and a few far off: two alike by chance (to 0.4 degrees), or three together 27 degrees off. They are a
    # tail of the turn-around, not a primitive: were they one, no grid would hold every type, and each
    # travel's +1 degree would make every heading its own (a map of 100 dstates for 20).
    rng = np.random.default_rng(0)
    actions = ([Turn(float(a)) for a in centre + sd * rng.standard_normal(18)] + [Turn(float(a)) for a in strays]
               + [Turn(float(a)) for a in -90 + 5 * rng.standard_normal(12)]
               + [Travel(20.0, float(b)) for b in 1 + 3 * rng.standard_normal(50)])
    m = MotionPrimitives().fit(actions)
    assert m.grid_deg_ == 90
    assert sorted({t.angle for t in m.types_ if t.kind == "turn"}) == [-90, 180]
    assert {t.angle for t in m.types_ if t.kind == "travel"} == {0}


def test_a_bend_read_three_times_far_from_the_grid_is_a_primitive():
    # Three readings of a 45-degree bend beside many right turns: no grid angle of 90 is near 45, so the
    # bend is a primitive of its own and the grid is 45.
    rng = np.random.default_rng(1)
    actions = ([Turn(float(a)) for a in -90 + 4 * rng.standard_normal(20)]
               + [Travel(10.0, float(b)) for b in [44.0, 46.5, 45.2]]
               + [Travel(10.0, float(b)) for b in 2 * rng.standard_normal(30)])
    m = MotionPrimitives().fit(actions)
    assert m.grid_deg_ == 45
    assert sorted({t.angle for t in m.types_ if t.kind == "travel"}) == [0, 45]


# Taylor Hall seed 12 at twice the laser noise: the travels' heading changes as odometry read them.
SEED_12_TRAVELS = [-23.0, -12.7, -10.7, -9.6, -9.1, -5.3, -4.9, -4.4, -4.3, -3.8, -3.6, -3.5, -3.0, -2.9, -2.7,
                   -1.8, -1.7, -1.5, -1.3, -0.9, -0.9, -0.9, -0.7, -0.7, -0.6, -0.5, -0.3, -0.3, -0.2, -0.2, 0.0,
                   0.1, 0.1, 0.1, 0.2, 0.3, 0.3, 0.3, 0.4, 0.9, 0.9, 1.1, 1.5, 2.1, 2.6, 2.7, 2.8, 2.8, 3.5, 3.7,
                   6.2, 7.8, 9.8, 12.5]


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 10_000), st.floats(1.5, 4.0), st.floats(-30.0, -18.0))
def test_a_stray_bend_does_not_gather_the_tail_of_straight_travels_into_a_type(seed, sd, stray):
    # Seed 12's travels (above) are 0 +- 3.5 with a heavy tail, and one read -23. The k-means steps grew
    # the stray into a type of five at -13 +- 5.5, which set a 15-degree grid and gave a map of 55
    # dstates for 20. A stray with the tail it gathers is still one type: here fifty straight travels,
    # four of them read 8-14 degrees off, and a stray beyond.
    rng = np.random.default_rng(seed)
    bends = np.concatenate([sd * rng.standard_normal(45), rng.uniform(-14.0, -8.0, 4), [stray]])
    turns = np.concatenate([-90 + 5 * rng.standard_normal(12), 180 + 8 * rng.standard_normal(20)])
    for travels in (bends, SEED_12_TRAVELS):
        m = MotionPrimitives().fit([Turn(float(a)) for a in turns] + [Travel(20.0, float(b)) for b in travels])
        assert m.grid_deg_ == 90, [str(t) for t in m.types_]
        assert {t.angle for t in m.types_ if t.kind == "travel"} == {0}


def test_neighbouring_exact_types_fifteen_degrees_apart_stay_two():
    # The rejoining of neighbours is for noise: travels read exactly 0 and exactly -15, each many times,
    # are two primitives (a hand-written tableau), as are two noisy types 30 degrees apart.
    exact = MotionPrimitives().fit([Travel(3.0, 0.0)] * 20 + [Travel(3.0, -15.0)] * 4 + [Turn(90.0)] * 3)
    assert sorted({t.angle for t in exact.types_ if t.kind == "travel"}) == [-15, 0]
    rng = np.random.default_rng(3)
    noisy = MotionPrimitives().fit([Travel(3.0, float(b)) for b in 2 * rng.standard_normal(30)]
                                   + [Travel(3.0, float(b)) for b in 30 + 2 * rng.standard_normal(10)])
    assert sorted({t.angle for t in noisy.types_ if t.kind == "travel"}) == [0, 30]


@pytest.mark.parametrize("seed", [16, 101, 117])
def test_45_degree_geometry_with_4_degrees_of_noise_does_not_change_the_map(seed):
    # Worlds whose corridors bend by multiples of 45 degrees, read with 4 degrees of turn noise and travel
    # drift. A bend seen five times among 168 travels (seed 16) once counted as strays of travel 0, the
    # grid came out at 90 and no map was found in 30 s: it is 11 spreads from any other type, a primitive.
    rng = np.random.default_rng(seed)
    world = random_world(rng, 4, 3, extra_edges=2, landmarks=0.4, bends=0.5, bend_deg=45)
    tableau = with_odometry_noise(walk(world, 300, rng, policy="explore"), 4.0, 4.0, rng)
    truth = true_partition(tableau)
    cmap = Resolver(time_limit=60).resolve(tableau)
    assert cmap.n_dstates == len(set(truth)) and dstate_accuracy(truth, cmap.dstate_of) == 1.0, \
        [str(t) for t in cmap.action_types]
    assert {t.angle % 45 for t in cmap.action_types} == {0}


def test_bends_are_drawn_from_multiples_of_the_bend_angle():
    world = random_world(np.random.default_rng(3), 5, 4, bends=1.0, bend_deg=45)
    assert world.frames and all(a % 45 == 0 for a in world.frames.values())
    with pytest.raises(ValueError, match="bend_deg"):
        random_world(np.random.default_rng(3), 5, 4, bends=1.0, bend_deg=20)


# -------------------------------------------------------------------------------------------------
# Readings at their resolution: clean or noisy never hinges on whether numbers repeat
# -------------------------------------------------------------------------------------------------

CORRIDORS_M = (1.5, 2.5, 4.0, 6.5, 10.5, 17.0)  # neighbours more than 1.6 times apart


@settings(max_examples=80, deadline=None)
@given(corridors=st.lists(st.sampled_from(CORRIDORS_M), min_size=1, max_size=4, unique=True),
       reads=st.one_of(st.integers(5, 40), st.integers(300, 1000)), error=st.floats(0.005, 0.04),
       step=st.sampled_from([0.01, 0.001, 0.0]), seed=st.integers(0, 2**31))
@example(corridors=[2.5], reads=1000, error=0.04, step=0.01, seed=1)
def test_rounded_lengths_of_one_corridor_are_one_type(corridors, reads, error, step, seed):
    # Each corridor driven many times, its length read a share ``error`` off (sd) and recorded to the
    # centimetre, the millimetre or unrounded: rounded readings repeat (3.95 m, 3.96 m, each several
    # times), and are still one corridor. Typing each repeated value as its own length made a 20-place
    # floor need 214 dstates. Driven hundreds of times, a corridor's readings spread wider than
    # LENGTH_RATIO at their extremes (318 readings of 2 m at 3%: 1.77-2.23 m) and are still one corridor.
    rng = np.random.default_rng(seed)
    truth = [c for c in corridors for _ in range(reads)]
    read = [c * (1 + error * rng.standard_normal()) for c in truth]
    read = [round(round(d / step) * step, 3) if step else d for d in read]
    labels = length_types(read)
    assert len(set(labels)) == len(corridors)
    assert all(len({lab for lab, c in zip(labels, truth) if c == corridor}) == 1 for corridor in corridors)
    # The resolution the readings show is the one they were recorded at, or coarser where every reading
    # happens to lie on a coarser step; exact only where each corridor was read as one value.
    learned = LengthTypes().fit(read)
    assert learned.resolution_m_ >= step and (not learned.exact_ or len(set(read)) == len(corridors))


@settings(max_examples=80, deadline=None)
@given(lengths=st.lists(st.floats(0.3, 40.0), min_size=2, max_size=120), step=st.sampled_from([0.01, 0.0]))
def test_no_length_type_spans_lengths_odometry_tells_apart(lengths, step):
    # A log's travels come in every length, each a small step from the next, so that splitting only where
    # one length is 25% longer than the one before chained 1.4 m and 22.9 m into one type (a log's whole
    # drive one action, and determinism then joined every place to every other). Whatever the lengths,
    # no type of readings that are not exact spans more than LENGTH_RATIO (but for LENGTH_TAIL of its
    # readings at either end), and each type is a run of the sorted lengths.
    read = [round(round(d / step) * step, 3) if step else d for d in lengths]
    learned = LengthTypes().fit(read)
    if learned.exact_:
        return
    groups: dict[int, list[float]] = {}
    for d, label in zip(read, learned.labels_):
        groups.setdefault(label, []).append(d)
    for g in groups.values():
        g, tail = sorted(g), int(len(g) * LENGTH_TAIL)
        assert g[-1 - tail] <= LENGTH_RATIO * g[tail] + 1e-9
    spans = sorted((min(g), max(g)) for g in groups.values())
    assert all(a[1] < b[0] for a, b in zip(spans, spans[1:]))


@settings(max_examples=80, deadline=None)
@given(units=st.lists(st.integers(10, 2000), min_size=1, max_size=6, unique=True), repeat=st.integers(2, 5),
       step=st.sampled_from([0.1, 0.01, 0.001]))
def test_exact_lengths_are_each_their_own_type_at_any_resolution(units, repeat, step):
    # Clean experience (hand-written, or a simulator without odometry error): every length read the same
    # way every time. Lengths at least two steps of the resolution apart are as many types as values,
    # however fine or coarse the resolution.
    # Stated with the tableau, the resolution keeps every exact length its own type. Read from the readings
    # alone, lengths that lie evenly on a coarser grid (2.0, 2.2 and 2.4 m) look like one travel read with
    # noise at that grid, and are typed so (a tableau states its resolution where they are not).
    units = sorted(units)
    spaced = [u * 2 for u in units]  # no two neighbouring steps
    lengths = [round(u * step, 3) for u in spaced] * repeat
    # (lengths a hundredth of a typical one apart, again and again, are noise, not primitives)
    gaps = np.diff(sorted(set(lengths)))
    assume(int((gaps <= NEAR_SHARE * np.median(lengths)).sum()) < GRID_EVIDENCE)
    for learned in (LengthTypes(resolution_m=step).fit(lengths), LengthTypes().fit(lengths)):
        if learned.resolution_m_ > step * 2 * np.gcd.reduce(units) + 1e-9:
            continue  # a coarser grid than any the lengths were written on: they read as noise on it
        assert learned.exact_ and len(learned.types_) == len(units)
        assert [t.count for t in learned.types_] == [repeat] * len(units)


GRIDS_SEEN = [(0.05, 0.5), (0.2, 2.0), (0.25, 2.5), (0.02, 0.25), (0.0123, 0.7)]


@settings(max_examples=60, deadline=None)
@given(corridors=st.lists(st.sampled_from(CORRIDORS_M[1:]), min_size=1, max_size=4, unique=True),
       reads=st.integers(20, 200), grid=st.sampled_from(GRIDS_SEEN), seed=st.integers(0, 2**31))
def test_noisy_readings_recorded_on_any_grid_are_the_robots_few_actions(corridors, reads, grid, seed):
    # An encoder or a log may record on a step that is no power of ten (5 cm, half a degree, 2.5 degrees,
    # an encoder's tick): each corridor's readings, noisy by as much as a grid step, then fall on a few
    # neighbouring grid values, which repeat. They are still one corridor each, and the robot's few turns;
    # where the grid shows (readings on neighbouring grid steps, again and again), it is the resolution.
    step_m, step_deg = grid
    corridors = [c for c in corridors if step_m <= 0.06 * c]  # noise of 3% spans a step or more
    assume(corridors)
    rng = np.random.default_rng(seed)
    truth = [c for c in corridors for _ in range(reads)]
    turns = rng.choice([-90.0, 90.0, 180.0], size=len(truth))
    steps = []
    for c, a in zip(truth, turns):
        steps += [Step("A", Travel(c * (1 + 0.03 * rng.standard_normal()), 1.0 * rng.standard_normal())),
                  Step("A", Turn(a + max(3.0, step_deg) * rng.standard_normal()))]
    tableau = rounded(Tableau(tuple(steps) + (Step("A"),)), Rounding(step_m, step_deg))
    distances = [a.distance_m for a in tableau.actions if isinstance(a, Travel)]
    learned = LengthTypes().fit(distances)
    assert not learned.exact_
    assert all(len({lab for lab, c in zip(learned.labels_, truth) if c == corridor}) == 1 for corridor in corridors)
    assert len(set(learned.labels_)) == len(corridors)
    m = MotionPrimitives().fit(tableau.actions)
    assert not m.exact_["turn"] and m.angles_[1::2] == [int(a) for a in turns]
    # (the resolution shown: the grid, or the decimal step it lies on where too few readings show it)
    assert step_deg / m.resolution_["turn"] == pytest.approx(round(step_deg / m.resolution_["turn"]))


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**31), turn_sd=st.floats(0.2, 8.0), n=st.integers(40, 600),
       rounding=st.sampled_from([LOGGED, Rounding(0.01, 1.0), Rounding(0.001, 0.01)]))
def test_rounded_noisy_turns_are_typed_as_the_unrounded_ones(seed, turn_sd, n, rounding):
    # Turns read with noise and recorded to a tenth of a degree (or a whole degree, or a hundredth)
    # repeat, the more so the longer the run; they are still the robot's few turns.
    rng = np.random.default_rng(seed)
    true_turns = rng.choice([-90.0, 90.0, 180.0], size=n)
    actions = [Turn(float(a + turn_sd * rng.standard_normal())) for a in true_turns]
    actions += [Travel(2.0, float(turn_sd / 3 * rng.standard_normal())) for _ in range(n)]
    steps = [Step("A", a) for a in actions] + [Step("A")]
    tableau = rounded(Tableau(tuple(steps)), rounding)
    m = MotionPrimitives().fit(tableau.actions)
    assert m.angles_[:n] == [int(a) for a in true_turns] and set(m.angles_[n:]) == {0}
    assert m.resolution_["turn"] == rounding.angle_deg or turn_sd * 3 < rounding.angle_deg
    assert not m.exact_["turn"]


@settings(max_examples=40, deadline=None)
@given(corridors=st.lists(st.sampled_from(CORRIDORS_M[1:]), min_size=1, max_size=4, unique=True),
       reads=st.integers(20, 200), printed=st.sampled_from([(0.0123, 3), (0.0328084, 2), (0.000123, 6)]),
       seed=st.integers(0, 2**31))
def test_noisy_readings_on_a_grid_the_printed_step_does_not_divide_are_noisy(corridors, reads, printed, seed):
    # An encoder's tick printed finer than it is (12.3 mm to the millimetre), or centimetres converted to
    # feet and printed to the hundredth: a corridor's readings lie 3 or 4 printed steps apart, never on
    # neighbouring ones, and repeat. They are noisy readings of few lengths, not as many exact ones.
    tick, decimals = printed
    rng = np.random.default_rng(seed)
    truth = [c for c in corridors for _ in range(reads)]
    read = [round(round(c * (1 + 0.03 * rng.standard_normal()) / tick) * tick, decimals) for c in truth]
    learned = LengthTypes().fit(read)
    assert not learned.exact_ and len(set(learned.labels_)) == len(corridors)
    assert all(len({lab for lab, c in zip(learned.labels_, truth) if c == corridor}) == 1 for corridor in corridors)
    turns = rng.choice([-90.0, 90.0, 180.0], size=reads)
    step_deg = 360 / 4096  # a gyro's tick, printed to the hundredth of a degree
    m = MotionPrimitives().fit([Turn(round(round((a + 3.0 * rng.standard_normal()) / step_deg) * step_deg, 2))
                                for a in turns])
    assert not m.exact_["turn"] and m.angles_ == [int(a) for a in turns]


def test_distances_read_by_odometry_that_reads_its_turns_with_noise_are_noisy():
    # Recorded to 25 cm, a 4 m corridor read 3% off falls on 4.0 m eleven times and on 4.25 m five: it looks
    # exact, two lengths. The same odometry read the turns with noise, so it read the distances with noise:
    # one corridor. With exact turns (a clean tableau), exact distances stay what they are.
    distances = [2.0] * 16 + [4.0] * 11 + [4.25] * 5
    rng = np.random.default_rng(4)
    for turn_sd, counts in ((3.0, [16, 16]), (0.0, [16, 11, 5])):
        steps = [Step("A", Travel(d)) for d in distances]
        steps += [Step("A", Turn(round(90.0 + turn_sd * rng.standard_normal(), 1))) for _ in distances]
        _, types = travel_length_types(Tableau(tuple(steps) + (Step("A"),)))
        assert [t.count for t in types] == counts
        assert all(t.exact == (turn_sd == 0) for t in types)
    # Readings a step of their resolution apart may be one travel, however far apart in ratio the step makes
    # them (1.5 and 2.0 m to 50 cm).
    assert len(LengthTypes(resolution_m=0.5, noisy=True).fit([1.5] + [2.0] * 89).types_) == 1
    assert len(LengthTypes(resolution_m=0.01, noisy=True).fit([1.5] + [2.0] * 89).types_) == 2


@settings(max_examples=60, deadline=None)
@given(scale=st.floats(0.91, 1.09), turn_sd=st.floats(0.5, 3.0), n=st.integers(30, 300), wrapped=st.booleans(),
       seed=st.integers(0, 2**31))
def test_turns_read_a_few_per_cent_long_or_short_are_the_robots_turns(scale, turn_sd, n, wrapped, seed):
    # A gyro or a wheelbase read a little wrong scales every turn alike (real odometry: 6% short): a
    # turn-around read 190.8 degrees lies 10.8 from 180, beyond what a type may lie off its grid angle, and
    # read as a 15-degree grid's -165 it turned every heading after it. The scale is taken out.
    rng = np.random.default_rng(seed)
    true_turns = rng.choice([-90.0, 90.0, 180.0], size=n)
    read = [scale * a + turn_sd * rng.standard_normal() for a in true_turns]
    actions = [Turn(round(float((r + 180.0) % 360.0 - 180.0) if wrapped else r, 1)) for r in read]
    actions += [Travel(2.0, round(float(turn_sd / 3 * rng.standard_normal()), 1)) for _ in range(n)]
    m = MotionPrimitives().fit(actions)
    assert m.angles_[:n] == [int(a) for a in true_turns] and set(m.angles_[n:]) == {0}
    assert m.grid_deg_ == 90 and abs(m.turn_scale_ - 1.0) <= 0.1


def test_the_readings_show_their_resolution_or_are_continuous():
    assert reading_step([3.95, 4.06, 12.1]) == 0.01
    assert reading_step([-90.0, 91.3, 179.9]) == 0.1
    assert reading_step([2.0, 4.0]) == 1.0
    assert reading_step([2.0312345678, 4.0]) == 0.0
    # Exact: values repeat and are never neighbouring steps; noisy readings fill neighbouring steps.
    assert exact_readings([2.0, 2.2, 2.0, 2.2], 0.1)
    assert not exact_readings([2.0, 2.1, 2.0, 2.1], 0.1)
    assert not exact_readings([3.95, 3.96, 3.95, 4.06, 3.96, 4.05], 0.01)
    assert not exact_readings([4.0312, 3.9871, 4.0102], 0.0)  # continuous noise never repeats
    assert exact_readings([179.9, -90.0, 179.9, -90.0], 0.1) and not exact_readings([179.9, -180.0, 179.9, 180.0], 0.1, 360.0)


def _corridor_pair(second_m: float, resolution: dict | None = None) -> Tableau:
    """Two look-alike corridors (view A, then B) driven twice each: 2.00 m and ``second_m``."""
    steps = []
    for d in (2.0, second_m, 2.0, second_m):
        steps += [Step("A", Travel(d)), Step("B", Turn(180.0))]
    meta = {"resolution": resolution} if resolution else {}
    return Tableau(tuple(steps) + (Step("A"),), meta=meta)


def test_a_resolution_the_tableau_states_is_the_one_used(tmp_path, capsys):
    # 2.00 and 2.01 m, each read twice: at the centimetre the readings show, they are neighbouring steps,
    # one corridor read with noise; a tableau that states its odometry reads to the millimetre has two
    # exact lengths, ten steps apart.
    shown = LengthTypes().fit([2.0, 2.01, 2.0, 2.01])
    assert (shown.resolution_m_, shown.exact_, len(shown.types_)) == (0.01, False, 1)
    for resolution, lengths in ((None, 1), ({"distance_m": 0.001}, 2)):
        path = tmp_path / "t.json"
        path.write_text(_corridor_pair(2.01, resolution).dumps())
        assert main(["map", str(path), "--format", "json"]) == 0
        out = json.loads(capsys.readouterr().out)
        assert len(out["length_types"]) == lengths
        assert out["length_types"][0]["resolution_m"] == (0.001 if resolution else 0.01)


def test_the_map_records_the_resolution_of_its_action_types(tmp_path, capsys):
    rng = np.random.default_rng(5)
    tableau = with_odometry_noise(walk(random_world(rng, 3, 3, landmarks=0.4), 80, rng), 4, 2, rng, distance_sd=0.02)
    path = tmp_path / "t.json"
    path.write_text(tableau.dumps())
    assert main(["map", str(path), "--format", "json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert {(t["kind"], t["resolution_deg"], t["exact"]) for t in out["action_types"]} == \
        {("turn", 0.1, False), ("travel", 0.1, False)}
    assert [(t["length_dm"], t["resolution_m"], t["exact"]) for t in out["length_types"]] == [(20, 0.01, False)]
    assert main(["map", str(path)]) == 0
    assert ("readings: turn angles to 0.1 deg (noisy); travel angles to 0.1 deg (noisy); "
            "distances to 0.01 m (noisy)") in capsys.readouterr().out


@pytest.mark.parametrize("resolution, field", [({"distance_m": 0}, "distance_m"), ({"angle_deg": -0.1}, "angle_deg"),
                                               ({"distance_m": "1cm"}, "distance_m"), ({"metres": 0.01}, "metres")])
def test_a_bad_resolution_is_refused_naming_the_field(tmp_path, capsys, resolution, field):
    doc = json.loads(_corridor_pair(4.0).dumps())
    doc["meta"] = {"resolution": resolution}
    path = tmp_path / "t.json"
    path.write_text(json.dumps(doc))
    assert main(["map", str(path)]) == 2
    err = capsys.readouterr().err
    assert "meta.resolution" in err and field in err and "t.json" in err and "Traceback" not in err
