"""Places from the laser: a junction, a corner and a dead end are places wherever the robot drives
through them; a corridor, with its doors, is a path; every pass through a place is a visit to it.

The scans are ray-cast in a building of 2 m corridors drawn as wall segments (support.raycast): a
crossing at the origin of two corridors 30 m long, an L-shaped corner, and a corridor with doors.
"""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bootmap.ingest.dstates import odometry_track
from bootmap.ingest.ingest import log_tableau
from bootmap.ingest.places import PATH, PLACE, PlaceDetector, find_visits, gateways, local_topology
from bootmap.ingest.scans import Scan
from support.raycast import cast, polygon_walls

BEAMS = 181
ANGLES = np.linspace(-math.pi / 2, math.pi / 2, BEAMS)
RANGE_MAX = 50.0


def _segments(*pairs) -> np.ndarray:
    return np.array([(*a, *b) for a, b in pairs], dtype=float)


# Two corridors 2 m wide crossing at the origin, each 30 m long, closed at their ends.
CROSSING = _segments(((-15, 1), (-1, 1)), ((1, 1), (15, 1)), ((-15, -1), (-1, -1)), ((1, -1), (15, -1)),
                     ((1, 1), (1, 15)), ((-1, 1), (-1, 15)), ((1, -1), (1, -15)), ((-1, -1), (-1, -15)),
                     ((-15, -1), (-15, 1)), ((15, -1), (15, 1)), ((-1, 15), (1, 15)), ((-1, -15), (1, -15)))
# A corridor 2 m wide along x from 0 to 30, with 0.9 m doors into rooms on both sides every 5 m.
DOORS = [5.0, 10.0, 15.0, 20.0, 25.0]


def _with_doors() -> np.ndarray:
    walls = []
    for y, room in ((1.0, 4.0), (-1.0, -4.0)):
        xs = [0.0] + [v for d in DOORS for v in (d - 0.45, d + 0.45)] + [30.0]
        walls += [((a, y), (b, y)) for a, b in zip(xs[::2], xs[1::2])]
        walls += [((0, room), (30, room))] + [((d + 2.5, y), (d + 2.5, room)) for d in [0.0] + DOORS]
    walls += [((0, -1), (0, 1)), ((30, -1), (30, 1))]
    return _segments(*walls)


L_CORNER = polygon_walls([(0, 0), (12, 0), (12, 10), (10, 10), (10, 2), (0, 2)])


def scan_at(walls, pose) -> Scan:
    ranges = cast(walls, pose, beams=BEAMS, max_range=RANGE_MAX)
    return Scan(0.0, ranges, -math.pi / 2, math.pi / BEAMS * BEAMS / (BEAMS - 1), RANGE_MAX, tuple(pose), tuple(pose))


def topology(walls, pose, detector=PlaceDetector()) -> str:
    return local_topology(cast(walls, pose, beams=BEAMS, max_range=RANGE_MAX), ANGLES, RANGE_MAX, detector)


def test_a_corridor_is_a_path_and_its_crossing_a_place_from_every_side():
    for heading in (0, 90, 180, 270):
        h = math.radians(heading)
        far = (-8 * math.cos(h), -8 * math.sin(h), h)     # 8 m before the crossing, facing it
        assert topology(CROSSING, far) == PATH
        at = (-0.3 * math.cos(h), -0.3 * math.sin(h), h)  # in the crossing
        assert topology(CROSSING, at) == PLACE
        # Two ways on besides straight ahead: left and right.
        sides = sorted(round(g.direction_deg / 90) for g in gateways(cast(CROSSING, at, BEAMS, RANGE_MAX),
                                                                      ANGLES, RANGE_MAX))
        assert sides == [-1, 0, 1]


def test_a_corner_and_a_dead_end_are_places():
    assert topology(L_CORNER, (5.0, 1.0, 0.0)) == PATH
    assert topology(L_CORNER, (10.8, 1.0, 0.0)) == PLACE       # the way ahead closes, one opens left
    assert topology(CROSSING, (13.5, 0.0, 0.0)) == PLACE       # the corridor's closed end


def test_doors_along_a_corridor_are_no_places_but_a_narrower_gateway_makes_them_places():
    walls = _with_doors()
    poses = [(x, 0.0, 0.0) for x in np.arange(2.0, 24.0, 0.5)]
    assert {topology(walls, p) for p in poses} == {PATH}
    doorway = PlaceDetector(gateway_m=0.8)
    assert PLACE in {topology(walls, p, doorway) for p in poses}


def _drive(points, step=0.5):
    """Poses along straight legs through ``points``, facing along each leg (a turn on the spot between)."""
    poses = []
    for a, b in zip(points, points[1:]):
        a, b = np.asarray(a, float), np.asarray(b, float)
        h = math.atan2(*(b - a)[::-1])
        n = max(int(round(np.hypot(*(b - a)) / step)), 1)
        poses += [(*(a + (b - a) * k / n), h) for k in range(n)]
    last = np.asarray(points[-1], float)
    return poses + [(*last, poses[-1][2])]


def test_every_pass_through_a_place_is_a_visit_and_a_turn_there_gives_two_dstates():
    # West to east straight through, back east to west, then in from the west and up the north arm.
    poses = _drive([(-12, 0), (12, 0), (-12, 0), (0, 0), (0, 12)])
    scans = [scan_at(CROSSING, p) for p in poses]
    distance, heading = odometry_track([s.odometry for s in scans])
    visits = find_visits(scans, distance, heading)
    at_crossing = [v for v in visits if math.dist(scans[(v.first + v.last) // 2].truth[:2], (0, 0)) < 2.0]
    assert len(at_crossing) == 3
    passes, turn = at_crossing[:2], at_crossing[2]
    assert [len(v.dstates(45.0)) for v in passes] == [1, 1]
    assert turn.dstates(45.0) == (turn.first, turn.last) and turn.angle_deg == pytest.approx(90.0, abs=1.0)
    tableau = log_tableau(scans, places=PlaceDetector(), source="crossing")
    places = {s.truth.split(":")[0] for s, i in zip(tableau.steps, tableau.meta["dstates"]["scans"])
              if math.dist(scans[i].truth[:2], (0, 0)) < 2.0}
    assert len(places) == 1                                     # one place, visited three times
    assert tableau.meta["dstates"]["places"]["gateway_m"] == PlaceDetector.gateway_m


def test_a_log_with_fewer_than_two_places_is_refused():
    from bootmap.errors import LogError

    scans = [scan_at(_with_doors(), (x, 0.0, 0.0)) for x in np.arange(3.0, 20.0, 0.5)]
    with pytest.raises(LogError, match=r"corridor: the laser shows 0 place\(s\) in 34 scans"):
        log_tableau(scans, places=PlaceDetector(), source="corridor")


@settings(max_examples=40, deadline=None)
@given(x=st.floats(-11.0, -4.0), offset=st.floats(-0.4, 0.4), turned=st.floats(-20.0, 20.0))
def test_anywhere_along_a_corridor_facing_along_it_is_a_path(x, offset, turned):
    """Off the corridor's axis by up to 0.4 m and turned by up to 20 degrees, away from the crossing."""
    assert topology(CROSSING, (x, offset, math.radians(turned))) == PATH


def test_a_visit_that_wandered_is_judged_where_its_dstates_are(monkeypatch):
    """A visit that turns has two dstates, where it arrives and where it leaves, and its true place is
    theirs: this one arrives at a hall's door facing east, wanders 17 m into the hall and back, and leaves
    by the door facing west. A pass by the door later, facing east, is one true dstate with its arrival;
    judged at the scan halfway through the visit (17 m into the hall) it was another place, and the true
    map then joined visits 'farther apart than a place' by the positions loop closures are judged at."""
    from bootmap.experiments.evaluate import loop_closure, sector_of_truth
    from bootmap.ingest.ingest import turn_ends
    from bootmap.ingest.places import Visit
    from bootmap.ingest.truth import visit_positions

    east, west = 0.0, math.pi
    poses = ([(0.0, 0.0, east)] + [(x, 0.0, east) for x in (2, 5, 9, 13, 17)]       # in at the door, into the hall
             + [(x, 0.0, west) for x in (13, 9, 5, 2, 0.5)]                          # back, out by the door
             + [(x, 0.0, west) for x in (-3, -7, -11)]                               # away west
             + [(-15.0, 0.0, west), (-15.5, 0.0, math.pi / 2), (-15.0, 0.0, east)]  # a turn at the far end
             + [(x, 0.0, east) for x in (-11, -7, -3)] + [(0.3, 0.2, east), (3.0, 0.0, east)])  # past the door
    scans = [Scan(float(k), np.full(180, 5.0), -math.pi / 2, math.pi / 179, 30.0, p, truth=p)
             for k, p in enumerate(poses)]
    visits = [Visit(0, 10, 180.0), Visit(14, 16, 180.0), Visit(19, 21, 0.0)]
    monkeypatch.setattr("bootmap.ingest.ingest.find_visits", lambda *args, **kwargs: visits)
    tableau = log_tableau(scans, places=PlaceDetector(), source="hall", calibrate=False)
    assert tableau.meta["dstates"]["scans"] == [0, 10, 14, 16, 20]
    truth = [s.truth for s in tableau.steps]
    assert truth[0] == truth[4] != truth[1]  # the door facing east, twice; facing west once
    assert truth[0].split(":")[0] != truth[2].split(":")[0]  # the far end is another place
    positions = visit_positions([s.pose for s in tableau.steps], turn_ends(tableau.actions))
    loops = loop_closure(truth, positions, 3.0, [sector_of_truth(d) for d in truth])
    assert loops["precision"] in (None, 1.0) and loops["true_joins"] == 1
