"""World files: every shipped world loads and validates; malformed ones fail naming file, field, problem."""

import math

import numpy as np
import pytest

from bootmap.errors import BootmapError, WorldError
from bootmap.sim.world import MotionNoise, World, heading_sector, load_world, loads_world, world_names, worlds_dir

MINIMAL = """
format = "bootmap.world/1"
name = "box"
[boundary]
points = [[0, 0], [4, 0], [4, 3], [0, 3]]
[robot]
start = [1, 1, 0]
[laser]
range_max = 8.0
[[places]]
id = "P0"
rect = [0, 0, 2, 2]
"""


@pytest.mark.parametrize("name", world_names())
def test_every_shipped_world_loads_and_its_ground_truth_is_consistent(name):
    w = load_world(name)
    assert w.name == name
    assert w.places and w.truth_dstates
    assert w.in_free_space(np.array(w.robot.start[:2]))[0]
    ids = {p.id for p in w.places}
    assert all(set(path.places) <= ids for path in w.paths)


def test_the_four_required_worlds_are_shipped():
    assert {"notched_rectangle", "taylor_hall", "loop", "plus"} <= set(world_names())


def test_taylor_hall_truth_is_the_papers_topology():
    w = load_world("taylor_hall")
    assert (len(w.places), len(w.paths), w.truth_dstates) == (7, 4, 20)
    xs = w.boundary[:, 0]
    assert xs.max() - xs.min() == pytest.approx(80, abs=0.05)  # 80 m, and a door recessed in the east end


def test_a_world_can_be_named_or_given_as_a_path():
    assert load_world(worlds_dir() / "plus.toml").name == load_world("plus").name == "plus"


def test_true_dstate_is_place_and_heading_sector():
    w = load_world("notched_rectangle")
    assert w.true_dstate((0.5, 2.5, math.pi / 2)) == "P0:N"
    assert w.true_dstate((4.5, 0.5, -math.pi + 0.1)) == "P2:W"
    assert w.true_dstate((2.5, 1.5, 0.0)) is None  # between places
    assert [heading_sector(math.radians(a)) for a in (0, 44, 46, 180, -90, 359)] == list("EENWSE")


def test_minimal_world_gets_defaults():
    w = loads_world(MINIMAL, "box.toml")
    assert isinstance(w, World)
    assert w.laser.beams == 180 and w.laser.noise_sd == pytest.approx(0.01)
    assert w.robot.radius == pytest.approx(0.25)
    # a real robot's odometry unless the file says otherwise (worlds/README.md, the noise model)
    assert w.motion_noise == MotionNoise(slip_v=0.06, slip_omega=0.06, turn_scale=0.05, turn_scale_time_s=5.0,
                                         drift_deg_s=0.15, drift_time_s=60.0)


def test_motion_noise_fields_are_read_and_the_rest_keep_their_defaults():
    w = loads_world(MINIMAL + "[motion_noise]\nturn_scale = 0\ndrift_deg_s = 0.5\n", "box.toml")
    assert (w.motion_noise.turn_scale, w.motion_noise.drift_deg_s) == (0.0, 0.5)
    assert w.motion_noise.slip_v == MotionNoise().slip_v


def test_settings_override_the_file_and_are_validated_like_it():
    w = load_world("notched_rectangle", {"laser.noise_sd": 0.02, "motion_noise.turn_scale": 0.0})
    assert (w.laser.noise_sd, w.motion_noise.turn_scale) == (0.02, 0.0)
    with pytest.raises(WorldError, match=r"with laser.dropout=0.9\): laser.dropout: must be <= 0.5"):
        load_world("notched_rectangle", {"laser.dropout": 0.9})
    with pytest.raises(WorldError, match="laser.nosie_sd: unknown field"):
        load_world("notched_rectangle", {"laser.nosie_sd": 0.02})
    with pytest.raises(WorldError, match="a setting is section.field"):
        load_world("notched_rectangle", {"laser.x.y": 1})


@pytest.mark.parametrize("edit, where, words", [
    (lambda s: s.replace("range_max = 8.0", "range_max = -1"), "laser.range_max", "must be > 0"),
    (lambda s: s.replace("range_max = 8.0", 'range_max = "far"'), "laser.range_max", "must be a number"),
    (lambda s: s.replace("range_max = 8.0\n", ""), "laser.range_max", "missing"),
    (lambda s: s.replace("range_max = 8.0", "range_max = 8.0\nbemas = 3"), "laser.bemas", "unknown field"),
    (lambda s: s.replace("start = [1, 1, 0]", "start = [1, 1]"), "robot.start", "array of 3 numbers"),
    (lambda s: s.replace("start = [1, 1, 0]", "start = [0.1, 1, 0]"), "robot.start", "does not fit"),
    (lambda s: s.replace("start = [1, 1, 0]", "start = [9, 1, 0]"), "robot.start", "does not fit"),
    (lambda s: s.replace("[0, 0, 2, 2]", "[2, 0, 0, 2]"), "places[0].rect", "xmin < xmax"),
    (lambda s: s + '[[places]]\nid = "P0"\nrect = [3, 2, 4, 3]\n', "places[1].id", "duplicate place id"),
    (lambda s: s + '[[paths]]\nid = "a"\nplaces = ["P0", "P9"]\n', "paths[0].places", "unknown place 'P9'"),
    (lambda s: s.replace('"bootmap.world/1"', '"bootmap.world/9"'), "format", "unsupported format"),
    (lambda s: s.replace("[[0, 0], [4, 0], [4, 3], [0, 3]]", "[[0, 0], [4, 0]]"), "boundary.points",
     "at least 3"),
    (lambda s: s + "[[discs]]\ncenter = [1, 2]\nradius = 0\n", "discs[0].radius", "must be > 0"),
    (lambda s: s + "[[boxes]]\ncenter = [1, 2]\nsize = [1, 1]\njitter = 5\n", "boxes[0].jitter", "<= 2"),
    (lambda s: s.replace('name = "box"', 'name = "box"\npolicy = "teleport"'), "policy", "unknown policy"),
    (lambda s: s + "[motion_noise]\nturn_scale = 0.9\n", "motion_noise.turn_scale", "<= 0.5"),
    (lambda s: s + "[motion_noise]\nslip_v = -0.1\n", "motion_noise.slip_v", ">= 0"),
    (lambda s: s + "[motion_noise]\ndrift_deg_s = 11\n", "motion_noise.drift_deg_s", "<= 10"),
    (lambda s: s + "[motion_noise]\ndrift_time_s = 0\n", "motion_noise.drift_time_s", "must be > 0"),
    (lambda s: s + "[motion_noise]\nturn_scale_time_s = \"slow\"\n", "motion_noise.turn_scale_time_s",
     "must be a number"),
    (lambda s: s + "[motion_noise]\ngyro_bias = 0.1\n", "motion_noise.gyro_bias", "unknown field"),
])
def test_bad_world_names_file_field_and_problem(edit, where, words):
    with pytest.raises(WorldError) as err:
        loads_world(edit(MINIMAL), "bad.toml")
    msg = str(err.value)
    assert msg.startswith(f"bad.toml: {where}: "), msg
    assert words in msg
    assert isinstance(err.value, BootmapError)


def test_invalid_toml_and_missing_file_are_world_errors(tmp_path):
    bad = tmp_path / "broken.toml"
    bad.write_text("format = [unclosed\n")
    with pytest.raises(WorldError, match=r"broken.toml: not valid TOML"):
        load_world(bad)
    with pytest.raises(WorldError, match="no such world file or name; known worlds: .*notched_rectangle"):
        load_world("no_such_world")


def test_clearance_and_free_space():
    w = load_world("notched_rectangle")
    assert w.clearance(np.array([[2.5, 1.5]]))[0] == pytest.approx(1.5)
    assert w.in_free_space(np.array([[0.5, 0.5], [0.1, 1.0], [6.0, 1.0]])).tolist() == [True, False, False]
