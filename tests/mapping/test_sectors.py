"""A log's headings as the building's sectors (bootmap.mapping.sectors), and loop closing on a drive whose
turns are arcs: every visit faces where odometry says, and a turn's two ends are one place."""

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from bootmap.mapping.loops import LoopCloser
from bootmap.mapping.sectors import SECTOR_DEG, sector_angles, sectors
from bootmap.paths import main_axis
from bootmap.tableau import Tableau
from support.check import true_partition

FORMAT = "bootmap.tableau/1"

paths = st.lists(st.tuples(st.floats(-50, 50), st.floats(-50, 50), st.floats(-4 * math.pi, 4 * math.pi)),
                 min_size=2, max_size=12)


def _off_the_edges(poses, axis) -> bool:
    """No heading lies within a hair of a sector's edge, where rounding may fall either way."""
    share = (np.asarray([p[2] for p in poses]) - axis) / math.radians(SECTOR_DEG)
    return bool(np.all(np.abs(share - np.floor(share) - 0.5) > 0.01))


@given(paths)
@settings(max_examples=200, deadline=None)
def test_the_angles_are_changes_of_sector_and_add_up_to_where_odometry_faces(poses):
    angles = sector_angles(poses)
    assert len(angles) == len(poses) - 1 and set(angles) <= {0, 90, -90, 180}
    s = sectors(poses)
    # summed, the angles bring the first pose's sector to every later one's (modulo a full turn)
    assert all((sum(angles[:k]) - SECTOR_DEG * (s[k] - s[0])) % 360 == 0 for k in range(len(poses)))


@given(paths, st.floats(-math.pi, math.pi))
@settings(max_examples=200, deadline=None)
def test_turning_the_whole_drive_changes_no_angle(poses, turn):
    # The sectors are the building's, not the odometry frame's: rotate the frame, the building's axis turns too.
    c, s = math.cos(turn), math.sin(turn)
    turned = [(c * x - s * y, s * x + c * y, h + turn) for x, y, h in poses]
    assume(np.ptp([p[:2] for p in poses], axis=0).max() > 0.01)  # a path that goes somewhere has an axis
    assume(_off_the_edges(poses, main_axis(poses)) and _off_the_edges(turned, main_axis(turned)))
    assert sector_angles(turned) == sector_angles(poses)


def arc_drive(laps: int = 2, side_m: float = 12.0, seed: int = 0, off_deg: float = 15.0) -> Tableau:
    """Laps of a square hall driven as a real robot drives it, turning left through an arc at each corner:
    the turn ends 1 m after the corner and starts 1 m before it on the first lap, 4.5 m before it on the
    others (a wide arc: the two laps' turn starts lie further apart than odometry's radius, their turn
    ends close); odometry reads every heading up to ``off_deg`` off, so each turn and each travel's bend
    is read up to twice that off. Truth names the corner and which end of its turn."""
    rng = np.random.default_rng(seed)
    corners = [(0.0, 0.0), (side_m, 0.0), (side_m, side_m), (0.0, side_m)]
    turns = 4 * laps
    # where odometry says each turn starts and ends (unwrapped: the k-th left turn from 90 k degrees)
    starts = [math.radians(90 * k + rng.uniform(-off_deg, off_deg)) for k in range(turns + 1)]
    ends = [math.radians(90 * (k + 1) + rng.uniform(-off_deg, off_deg)) for k in range(turns)]
    steps = []
    for k in range(turns):
        c, early = k % 4, (1.0 if k < 4 else 4.5)
        h = math.radians(90 * c)
        x, y = corners[(c + 1) % 4]
        before = (x - early * math.cos(h), y - early * math.sin(h))
        after = (x - math.sin(h), y + math.cos(h))
        steps.append({"view": "v", "truth": f"c{c}:in", "odometry": [*before, starts[k]],
                      "action": {"type": "turn", "angle_deg": math.degrees(ends[k] - starts[k])}})
        steps.append({"view": "v", "truth": f"c{c}:out", "odometry": [*after, ends[k]],
                      "action": {"type": "travel", "distance_m": side_m - 1.0 - early,
                                 "heading_change_deg": math.degrees(starts[k + 1] - ends[k])}})
    steps[-1].pop("action")
    return Tableau.from_dict({"format": FORMAT, "steps": steps, "meta": {"passes_through": True}})


@pytest.mark.parametrize("seed", range(5))
def test_a_drive_that_turns_through_arcs_closes_its_loops(seed):
    # headings up to 30 degrees off: turns read 30-150 degrees, travels bending by up to 60
    drive = arc_drive(laps=2, seed=seed, off_deg=30.0)
    cmap = LoopCloser().resolve(drive)
    truth = true_partition(drive)
    # every visit in its true dstate: the two laps' visits of each corner joined, the corners kept apart
    assert len(set(cmap.dstate_of)) == len(set(truth)) == 8
    assert all((cmap.dstate_of[i] == cmap.dstate_of[j]) == (truth[i] == truth[j])
               for i in range(len(truth)) for j in range(len(truth)))
    assert cmap.n_places == 4
