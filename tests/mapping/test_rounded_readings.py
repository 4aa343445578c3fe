"""Tableaux as robots record them: readings rounded to the centimetre and the tenth of a degree.

Each family of noisy experience is resolved twice, from the same walk and the same noise: unrounded, and
recorded as a log records it. Rounded readings repeat (a corridor read 3.95, 3.96, ... 4.06 m, each several
times); typing every repeated value as its own length or angle made every one of these tableaux need
hundreds of dstates. The map must be the truth either way.
"""

import numpy as np
import pytest

from bootmap.examples import notched_rectangle
from bootmap.mapping import Resolver
from bootmap.metrics import dstate_accuracy
from support.check import true_partition
from support.gridworld import random_world, walk
from support.noise import ROUNDINGS, Rounding, with_misreads, with_odometry_noise


def floor(steps: int, rng):
    """A 20-place floor (5 x 4 grid, landmarks on 40% of the places), explored."""
    return walk(random_world(rng, 5, 4, extra_edges=4, landmarks=0.4), steps, rng, policy="explore")


def halls_45(rng):
    """Halls whose corridors bend by multiples of 45 degrees."""
    return walk(random_world(rng, 4, 4, extra_edges=3, landmarks=0.4, bends=0.3, bend_deg=45), 600, rng,
                policy="explore")


FAMILIES = {
    "floor, 600 steps": (lambda rng: floor(600, rng), (3.0, 1.2, 0.03)),
    "floor, 3000 steps": (lambda rng: floor(3000, rng), (3.0, 1.2, 0.03)),
    "45-degree halls": (halls_45, (3.0, 1.2, 0.03)),
    "floor, turn sd 10": (lambda rng: floor(600, rng), (10.0, 4.0, 0.03)),
    "noisy rectangle": (lambda rng: notched_rectangle(50), (3.0, 1.5, 0.03)),
}


@pytest.mark.parametrize("rounding", ROUNDINGS, ids=["logged", "unrounded"])
@pytest.mark.parametrize("family", sorted(FAMILIES))
def test_each_family_is_exact_rounded_as_unrounded(family, rounding):
    make, (turn_sd, drift_sd, distance_sd) = FAMILIES[family]
    rng = np.random.default_rng(301)
    tableau = with_odometry_noise(make(rng), turn_sd, drift_sd, rng, distance_sd=distance_sd, rounding=rounding)
    truth = true_partition(tableau)
    cmap = Resolver(time_limit=120).resolve(tableau)
    assert cmap.minimal and cmap.n_dstates == len(set(truth)) and dstate_accuracy(truth, cmap.dstate_of) == 1.0
    assert all(not t.exact for t in cmap.action_types) and all(not t.exact for t in cmap.length_types)


#: Steps that are no power of ten: a log at 5 cm and half a degree, one at 25 cm and 2.5 degrees (coarser
#: than the noise: most readings of a corridor fall on one value), an encoder's tick.
GRIDS = {"5 cm, 0.5 deg": Rounding(0.05, 0.5), "25 cm, 2.5 deg": Rounding(0.25, 2.5),
         "a tick of 12.3 mm, 0.7 deg": Rounding(0.0123, 0.7)}


@pytest.mark.parametrize("grid", sorted(GRIDS))
@pytest.mark.parametrize("family", ["floor, 600 steps", "noisy rectangle"])
def test_each_family_is_exact_recorded_on_any_grid(family, grid):
    # Read as the coarsest decimal step the readings lie on (1 cm), a corridor read 3.95, 4.00 and 4.05 m
    # looked like three exact lengths, and no map was found. The readings show their grid.
    make, (turn_sd, drift_sd, distance_sd) = FAMILIES[family]
    rng = np.random.default_rng(302)
    tableau = with_odometry_noise(make(rng), turn_sd, drift_sd, rng, distance_sd=distance_sd,
                                  rounding=GRIDS[grid])
    truth = true_partition(tableau)
    cmap = Resolver(time_limit=120).resolve(tableau)
    assert cmap.minimal and cmap.n_dstates == len(set(truth)) and dstate_accuracy(truth, cmap.dstate_of) == 1.0


@pytest.mark.parametrize("rounding", ROUNDINGS, ids=["logged", "unrounded"])
def test_two_misclustered_views_in_the_papers_tableau_read_by_a_robot(rounding):
    rng = np.random.default_rng(5)
    noisy = with_odometry_noise(notched_rectangle(50), 3.0, 1.5, rng, distance_sd=0.03, rounding=rounding)
    tableau, wrong = with_misreads(noisy, 2 / len(noisy), rng)
    cmap = Resolver(time_limit=120).resolve(tableau)
    assert (cmap.n_dstates, cmap.n_places, cmap.n_paths) == (8, 4, 4)
    assert [s["t"] for s in cmap.suspect_steps] == wrong
