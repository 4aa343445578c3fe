"""A visit's local map rendered all round (bootmap.ingest.local_maps): what the robot saw while it passed
through a place, from odometry alone; two visits from opposite directions match where their scans do not."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bootmap.errors import BadInput
from bootmap.ingest.local_maps import local_images
from bootmap.ingest.scans import Scan, compose
from bootmap.scan_match import ScanMatcher
from support.raycast import cast, polygon_walls

# A corridor 2 m wide along x with a room opening off it at x = 6..9 (north), driven east then back west.
WALLS = np.vstack([polygon_walls([(0, 0), (14, 0), (14, 2), (9, 2), (9, 5), (6, 5), (6, 2), (0, 2)])])


def drive(odometry_frame=(0.0, 0.0, 0.0)) -> list[Scan]:
    """East along y = 1 from x = 1 to 13, a turn on the spot, back west: a scan each 0.25 m (each 30
    degrees in the turn), the odometry exact but in a frame of its own (a rigid motion of the truth)."""
    out = [(x, 1.0, 0.0) for x in np.arange(1.0, 13.0, 0.25)]
    out += [(13.0, 1.0, math.radians(a)) for a in range(30, 180, 30)]
    out += [(x, 1.0, math.pi) for x in np.arange(13.0, 0.99, -0.25)]
    return [Scan(float(k), cast(WALLS, pose, max_range=81.9), -math.pi / 2, math.pi / 179, 81.9,
                 compose(odometry_frame, pose), truth=pose) for k, pose in enumerate(out)]


def at(scans, x, heading):
    """The scan taken at ``x`` facing ``heading``."""
    return next(k for k, s in enumerate(scans) if abs(s.truth[0] - x) < 1e-9 and abs(s.truth[2] - heading) < 1e-9)


def test_two_visits_from_opposite_directions_match_by_their_local_maps_not_their_scans():
    scans = drive()
    east, west = at(scans, 7.5, 0.0), at(scans, 7.5, math.pi)
    images = local_images(scans, [east, west])
    local = ScanMatcher(fov_deg=360.0).match(images[0], images[1])
    single = ScanMatcher().match(scans[east].ranges.clip(0, 20), scans[west].ranges.clip(0, 20))
    assert local.score > 0.7 and single.score < 0.5 * local.score, (local.score, single.score)
    # The local maps align as the two poses lie: the same spot, turned half round.
    assert math.dist(local.transform[:2], (0.0, 0.0)) < 0.1
    assert abs(abs(local.transform[2]) - math.pi) < math.radians(2)
    # A place elsewhere in the corridor (no room off it) matches clearly worse.
    other = local_images(scans, [at(scans, 2.5, math.pi)])[0]
    assert ScanMatcher(fov_deg=360.0).match(images[0], other).score < local.score - 0.2


@settings(max_examples=15, deadline=None)
@given(st.floats(-50, 50), st.floats(-50, 50), st.floats(-math.pi, math.pi))
def test_a_local_map_depends_on_odometry_only_up_to_its_frame(x, y, theta):
    """Odometry in any frame (a rigid motion of the whole drive) gives the same local maps: only the
    motions between scans count."""
    visits = [5, 30, 60]  # (a reach off the 0.25 m grid of the scans: no scan on its boundary)
    base = local_images(drive(), visits, reach_m=2.9)
    moved = local_images(drive((x, y, theta)), visits, reach_m=2.9)
    assert np.allclose(base, moved, atol=1e-6)


def test_a_reach_of_nothing_is_the_visits_own_scan():
    """With no travel either way only the visit's scan is drawn: its 180 degrees ahead hold its returns,
    behind reads max_range."""
    scans = drive()
    k = at(scans, 7.5, 0.0)
    image = local_images(scans, [k], reach_m=0.0, max_range=20.0)[0]
    ahead, behind = image[90:271], np.concatenate([image[:89], image[272:]])
    assert np.all(behind == 20.0)
    assert np.allclose(np.sort(ahead[ahead < 20]), np.sort(scans[k].ranges[scans[k].ranges < 20]), atol=0.05)


@pytest.mark.parametrize("reach, beams", [(-1.0, 360), (float("nan"), 360), (3.0, 0)])
def test_bad_settings_are_refused(reach, beams):
    with pytest.raises(BadInput, match="reach_m"):
        local_images(drive()[:3], [1], reach_m=reach, beams=beams)
