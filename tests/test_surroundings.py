"""Place matches verified by their surroundings (bootmap.surroundings), on a hand ray-cast corridor with
the real small_gicp: two junctions alike within the laser's range, told apart by what lies 6 m on."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bootmap.errors import BadInput
from bootmap.ingest.local_maps import local_images
from bootmap.ingest.scans import Scan
from bootmap.scan_match import ScanMatcher
from bootmap.surroundings import SurroundingsCheck
from support.raycast import cast

#: The laser's range here (m): short, so that a junction's local map shows the junction alone.
RANGE = 4.0


def box(x0, y0, x1, y1):
    return [(x0, y0, x1, y0), (x1, y0, x1, y1), (x1, y1, x0, y1), (x0, y1, x0, y0)]


def corridor() -> np.ndarray:
    """A corridor 2 m wide along x from 0 to 60; side rooms opening north at x = 15 and x = 40 (alike);
    a pillar in the corridor at x = 21 only, 6 m past the first junction."""
    walls = [(0, -1, 60, -1), (0, 1, 14, 1), (16, 1, 39, 1), (41, 1, 60, 1), (0, -1, 0, 1), (60, -1, 60, 1)]
    for x in (15, 40):  # a side room 2 m wide and 2 m deep behind each opening
        walls += [(x - 1, 1, x - 1, 3), (x - 1, 3, x + 1, 3), (x + 1, 3, x + 1, 1)]
    walls += box(20.6, -0.6, 21.4, 0.2)
    return np.array(walls, dtype=float)


def drive() -> list[Scan]:
    """East along the corridor from x = 1 to 59, a turn on the spot, and back west: a scan every 0.5 m
    (and every 30 degrees of the turn), odometry exact."""
    poses = [(x, 0.0, 0.0) for x in np.arange(1.0, 59.01, 0.5)]
    poses += [(59.0, 0.0, math.radians(a)) for a in range(30, 180, 30)]
    poses += [(x, 0.0, math.pi) for x in np.arange(59.0, 0.99, -0.5)]
    walls = corridor()
    step = math.pi / 179
    return [Scan(float(k), cast(walls, p, max_range=20.0), -math.pi / 2, step, 20.0, p, p)
            for k, p in enumerate(poses)]


def at(scans, x, heading):
    return next(k for k, s in enumerate(scans) if abs(s.odometry[0] - x) < 0.01 and abs(s.odometry[2] - heading) < 0.01)


@pytest.fixture(scope="module")
def corridor_drive():
    scans = drive()
    visits = [at(scans, 15.0, 0.0), at(scans, 40.0, 0.0), at(scans, 40.0, math.pi)]
    matcher = ScanMatcher(max_range=RANGE, fov_deg=360.0)
    scores = matcher.scores(local_images(scans, visits, max_range=RANGE))
    return scans, visits, matcher, scores


def test_the_two_junctions_look_alike_on_their_own(corridor_drive):
    _, _, _, scores = corridor_drive
    # The second junction, driven back through, matches its own first visit and the other junction alike.
    assert scores[2, 1] > 0.5 and scores[2, 0] > 0.5
    assert abs(scores[2, 1] - scores[2, 0]) < 0.2


def test_the_surroundings_tell_the_look_alike_from_the_revisit(corridor_drive):
    scans, visits, matcher, scores = corridor_drive
    V = SurroundingsCheck(matcher).verify(scans, visits, scores)
    # 6 m on from the look-alike stands a pillar the revisit's surroundings do not have.
    assert V[2, 1] > V[2, 0] + 0.1
    assert V[2, 1] > 0.5
    # Only earlier visits the robot has left are checked: nothing above the diagonal, nothing for the first.
    assert (np.triu(V) == 0).all() and (V[0] == 0).all()


def test_only_the_likeliest_and_allowed_are_checked(corridor_drive):
    scans, visits, matcher, scores = corridor_drive
    one = SurroundingsCheck(matcher, top=1).verify(scans, visits, scores)
    assert np.count_nonzero(one[2]) == 1 and one[2].argmax() == int(np.argmax(scores[2, :2]))
    allowed = np.ones((3, 3), dtype=bool)
    allowed[2, 0] = False
    V = SurroundingsCheck(matcher).verify(scans, visits, scores, allowed)
    assert V[2, 0] == 0 and V[2, 1] > 0


def test_the_check_is_the_same_in_two_processes_as_in_one(corridor_drive):
    scans, visits, matcher, scores = corridor_drive
    alone = SurroundingsCheck(matcher).verify(scans, visits, scores)
    shared = SurroundingsCheck(ScanMatcher(max_range=RANGE, fov_deg=360.0, n_jobs=2)).verify(scans, visits, scores)
    assert np.array_equal(alone, shared)


@pytest.mark.parametrize("kwargs, message", [({"offset_m": 0.0}, "offset_m > 0"), ({"top": 0}, "top >= 1")])
def test_a_check_needs_a_distance_and_a_count(kwargs, message):
    with pytest.raises(BadInput, match=message):
        SurroundingsCheck(ScanMatcher(fov_deg=360.0), **kwargs)


def test_bad_visits_or_scores_are_refused(corridor_drive):
    scans, visits, matcher, scores = corridor_drive
    check = SurroundingsCheck(matcher)
    with pytest.raises(BadInput, match="scores of shape"):
        check.verify(scans, visits, scores[:2])
    with pytest.raises(BadInput, match="in time order"):
        check.verify(scans, visits[::-1], scores)
    with pytest.raises(BadInput, match="allowed of shape"):
        check.verify(scans, visits, scores, np.ones((2, 2), dtype=bool))
