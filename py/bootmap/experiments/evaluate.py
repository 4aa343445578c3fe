"""How a map learned from a log compares with the log's own poses (truth from the data, not from us).

Every figure here reads the true dstates that :mod:`bootmap.ingest.truth` made from the log's poses
(``P3:N``: a place within a radius, a heading sector aligned to the building's axis); the learning
never saw them.

- :func:`map_against_truth`: dstates, places and paths found against the true ones; the share of
  visits the map puts in their true dstate (best one-to-one renaming), beside the share a map that
  gives every visit a dstate of its own would get (most dstates of a log are seen once).
- :func:`views_against_truth`: U(V|S) of the views at every k, beside U of the same views against
  shuffled true dstates: views that help say more about the dstate than chance does.
- :func:`dead_reckoned_dstates`: a baseline that uses no image at all, only the robot's own odometry:
  the rule that makes true dstates from true poses, applied to the dead-reckoned poses. It tests the
  odometry's "local metrical consistency": it drifts over the whole log, but not between visits close
  in time.
- :func:`nn_on_revisits`: nearest-neighbour recognition of true dstates, leave one out, with raw scans
  or a shift-tolerant distance (:func:`shift_tolerant_distances`), on the visits whose true dstate is
  seen more than once; a visit to a dstate seen once has nothing to be recognised by (the ceiling).

Example
-------
A scan and the same scan turned by four beams are far apart beam by beam, and the same scan to a
shift-tolerant distance:

>>> scan = np.linspace(1.0, 5.0, 40) ** 1.5
>>> turned = np.roll(scan, 4); turned[:4] = scan[0]
>>> raw = np.abs(scan - turned).mean()
>>> bool(shift_tolerant_distances(scan[None], turned[None], max_shift=10)[0, 0] < raw / 10)
True
"""

from __future__ import annotations

from collections import Counter, defaultdict
from typing import Hashable, Sequence

import numpy as np
from scipy.spatial.distance import cdist

from ..metrics import dstate_accuracy
from ..views import uncertainty_coefficient
from ..ingest.scans import Pose
from ..ingest.truth import main_axis, true_dstates

#: Descriptors :func:`nn_on_revisits` compares scans with.
DESCRIPTORS = ("raw", "shift")
#: Beams a shift-tolerant match may turn one scan against another (1 degree a beam: +-10 degrees).
MAX_SHIFT = 10


def place_of_truth(label: str) -> str:
    """The place of a true dstate label (``P3:N`` -> ``P3``)."""
    return str(label).split(":")[0]


def map_against_truth(truth: Sequence[str], cmap) -> dict:
    """The map's dstates and places against the true ones (keys as the simulated experiment's map section,
    where the meaning is the same)."""
    merged, split = defaultdict(set), defaultdict(set)
    for t, d in zip(truth, cmap.dstate_of):
        merged[d].add(t)
        split[t].add(d)
    true_places = [place_of_truth(t) for t in truth]
    found_places = [cmap.place_of.get(d, d) for d in cmap.dstate_of]
    return {"dstates": cmap.n_dstates, "places": cmap.n_places, "paths": cmap.n_paths, "unique": cmap.unique,
            "true_dstates": len(set(truth)), "true_places": len(set(true_places)), "true_paths": None,
            "dstate_accuracy": dstate_accuracy(truth, cmap.dstate_of),
            # The figure to beat: most dstates of a log are seen once, so a map that tells every visit
            # apart already puts those visits in a true dstate of their own.
            "every_visit_own_dstate_accuracy": dstate_accuracy(truth, [str(i) for i in range(len(truth))]),
            "place_accuracy": dstate_accuracy(true_places, found_places),
            "merged_true_dstates": {d: sorted(ts) for d, ts in merged.items() if len(ts) > 1},
            "split_true_dstates": {t: sorted(ds) for t, ds in split.items() if len(ds) > 1},
            "solve_s": cmap.stats.total_s}


def dead_reckoned_dstates(odometry: Sequence[Pose], track: Sequence[Pose], radius_m: float = 3.0,
                          turn_ends: Sequence[tuple[int, int]] | None = None,
                          travel_ends: Sequence[tuple[int, int]] = ()) -> list[str]:
    """Dstates from odometry alone, as the truth is made from the true poses: dstates whose dead-reckoned
    positions lie within ``radius_m`` are one place (a turn's two ends too: ``turn_ends``, by default
    every pair, as when the chosen dstates alternate turn start, turn end; a travel's two ends never),
    and a place with a heading sector aligned to the main axis of the dead-reckoned ``track`` is a
    dstate."""
    if turn_ends is None:
        turn_ends = [(k, k + 1) for k in range(0, len(odometry) - 1, 2)]
    return true_dstates(list(odometry), radius_m, main_axis(list(track)), list(turn_ends), list(travel_ends))


def shuffled_uncertainty(views: Sequence[Hashable], truth: Sequence[Hashable], repeats: int = 20,
                         seed: int = 0) -> float:
    """Mean U(V|S) of the views against the true dstates shuffled: what U is by chance alone (with many
    dstates seen once, that is far above 0)."""
    rng = np.random.default_rng(seed)
    truth = np.asarray(truth)
    return float(np.mean([uncertainty_coefficient(views, rng.permutation(truth)) for _ in range(repeats)]))


def views_against_truth(clusterer, truth: Sequence[str], seed: int = 0) -> dict:
    """U(V|S) at every k tried, and U against shuffled truth at the same k."""
    return {"U_shuffled": [shuffled_uncertainty(clusterer.labels_per_k_[int(k)], truth, seed=seed)
                           for k in clusterer.ks_]}


def shift_tolerant_distances(a: np.ndarray, b: np.ndarray, max_shift: int = MAX_SHIFT) -> np.ndarray:
    """Pairwise distances between scans ``a`` (n, beams) and ``b`` (m, beams): the least mean absolute
    difference over the beams two scans share when one is turned by up to ``max_shift`` beams.

    A robot never stops twice at exactly one heading; a turn of a few degrees shifts its scan by as many
    beams, which beam-by-beam (raw) distances read as a different place.
    """
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    n = a.shape[1]
    best = np.full((len(a), len(b)), np.inf)
    for s in range(-max_shift, max_shift + 1):
        lo, hi = max(0, s), n + min(0, s)  # a's beams lo..hi-1 against b's beams lo-s..hi-s-1
        d = cdist(a[:, lo:hi], b[:, lo - s:hi - s], "cityblock") / (hi - lo)
        np.minimum(best, d, out=best)
    return best


def _distances(images: np.ndarray, descriptor: str, max_shift: int) -> np.ndarray:
    if descriptor == "raw":
        return cdist(images, images)
    if descriptor == "shift":
        return shift_tolerant_distances(images, images, max_shift)
    raise ValueError(f"unknown scan descriptor {descriptor!r}; known: {', '.join(DESCRIPTORS)}")


def nn_on_revisits(images, truth: Sequence[str], descriptor: str = "raw", max_shift: int = MAX_SHIFT) -> dict:
    """Leave-one-out nearest-neighbour recognition of true dstates.

    Each visit is labelled by the true dstate of its nearest other visit. ``revisited`` is the accuracy
    on visits whose true dstate is seen more than once (where recognition is possible at all);
    ``all_visits`` the accuracy on every visit, whose ``ceiling`` is the share of visits on revisited
    dstates.
    """
    x = np.asarray(images, dtype=float)
    truth = np.asarray([str(t) for t in truth])
    d = _distances(x, descriptor, max_shift)
    np.fill_diagonal(d, np.inf)
    hit = truth[np.argmin(d, axis=1)] == truth if len(x) > 1 else np.zeros(len(x), dtype=bool)
    counts = Counter(truth.tolist())
    again = np.array([counts[t] > 1 for t in truth])
    return {"descriptor": descriptor, "visits": int(len(x)), "revisited_visits": int(again.sum()),
            "revisited_dstates": int(sum(c > 1 for c in counts.values())),
            "revisited": float(hit[again].mean()) if again.any() else None,
            "all_visits": float(hit.mean()) if len(x) else None,
            "ceiling": float(again.mean()) if len(x) else None}
