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

The evaluation SLAM papers report, judged against the corrected poses:

- :func:`against_baselines`: the map's share of visits in their true dstate beside both baselines on
  the same visits (odometry alone, a dstate per visit), and whether it beats them.
- :func:`loop_closure`: precision and recall of the pairs of visits a map joins (puts in one dstate,
  or one place).
- :func:`place_recognition`: each visit's best match among the earlier visits under any score matrix,
  a threshold swept over the scores: precision-recall, recall at 95% and 99% precision, average
  precision. :func:`descriptor_scores` gives the scans' scores (negated distances).

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

from ..mapping.loops import LoopCloser
from ..mapping.loops.anchoring import Anchoring
from ..metrics import dstate_accuracy
from ..views import uncertainty_coefficient
from ..ingest.scans import Pose
from ..ingest.truth import true_dstates
from ..paths import main_axis

#: Descriptors :func:`nn_on_revisits` compares scans with.
DESCRIPTORS = ("raw", "shift")
#: How far odometry may drift per metre driven between two visits of one place: loop closing's bound.
DRIFT_SHARE = LoopCloser.drift_share
#: A match this strong is taken as a revisit, to re-anchor dead reckoning at (:func:`reanchored_reach`): loop
#: closing's own bar for a recognised revisit.
MATCH_SCORE = LoopCloser.match_score
#: Beams a shift-tolerant match may turn one scan against another (1 degree a beam: +-10 degrees).
MAX_SHIFT = 10


def place_of_truth(label: str) -> str:
    """The place of a true dstate label (``P3:N`` -> ``P3``)."""
    return str(label).split(":")[0]


def sector_of_truth(label: str) -> str:
    """The heading sector of a true dstate label (``P3:N`` -> ``N``)."""
    return str(label).split(":")[-1]


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


#: The target against the baselines: this share of visits in their true dstate at least, and at most
#: this share of the better baseline's error.
BASELINE_TARGET = {"accuracy": 0.90, "error_ratio": 0.5}


def against_baselines(accuracy: float, odometry_alone: float, own_dstate: float) -> dict:
    """The map's share of visits in their true dstate beside the baselines' on the same visits.

    ``beats_baselines`` is true when the map is strictly better than both; ``error_ratio`` is the map's
    error over the better baseline's (0 when the map makes none, None when the baseline makes none and
    the map does); the target is met at ``BASELINE_TARGET``'s accuracy or more with at most its share of
    the better baseline's error.

    >>> r = against_baselines(0.95, 0.8, 0.9)
    >>> r["beats_baselines"], r["better_baseline"], round(r["error_ratio"], 2), r["target_met"]
    (True, 'own_dstate', 0.5, True)
    """
    better = "odometry_alone" if odometry_alone >= own_dstate else "own_dstate"
    best = max(odometry_alone, own_dstate)
    error, best_error = 1.0 - accuracy, 1.0 - best
    ratio = 0.0 if error <= 1e-12 else (None if best_error <= 1e-12 else error / best_error)
    close = ratio is not None and ratio <= BASELINE_TARGET["error_ratio"] + 1e-9
    met = accuracy >= BASELINE_TARGET["accuracy"] and close
    return {"map": accuracy, "odometry_alone": odometry_alone, "own_dstate": own_dstate,
            "better_baseline": better, "beats_baselines": bool(accuracy > best), "error_ratio": ratio,
            "target": dict(BASELINE_TARGET), "target_met": bool(met)}


def _xy(poses) -> np.ndarray:
    return np.asarray(poses, dtype=float).reshape(len(poses), -1)[:, :2]


def loop_closure(labels: Sequence[Hashable], poses, radius_m: float = 3.0,
                 sectors: Sequence[Hashable] | None = None) -> dict:
    """Precision and recall of the pairs of visits a map joins.

    Only pairs that could close a loop count: a visit and an earlier one the robot has left since
    (:func:`revisit_candidates`; a turn's two ends are one place by construction, not a closure). A
    *join* is such a pair the map gives one label (one dstate, or one place). A pair is *true* (should
    be joined) when the corrected poses of its two visits lie within ``radius_m`` of each other and,
    given ``sectors`` (the true heading sector of each visit, :func:`sector_of_truth`: for dstates),
    their sectors are the same.

    Parameters
    ----------
    labels : sequence
        The map's label of each visit, in time order.
    poses : array-like (n, 2 or 3)
        The corrected pose of each visit (only x and y are read).
    radius_m : float
        The place radius.
    sectors : sequence, optional
        The true heading sector of each visit; a dstate join must keep the sector.

    Returns
    -------
    dict
        ``joins``, ``true_joins``, ``should_join`` (true pairs), ``precision`` (true joins / joins, None
        without joins) and ``recall`` (true joins / true pairs, None without true pairs).

    Examples
    --------
    >>> r = loop_closure(["a", "b", "a", "a"], [(0, 0), (9, 0), (1, 0), (20, 0)])
    >>> r["joins"], r["true_joins"], r["should_join"], r["precision"], r["recall"]
    (2, 1, 1, 0.5, 1.0)
    """
    label = np.asarray([str(x) for x in labels])
    pairs = revisit_candidates(poses, radius_m)  # [j, i]: i earlier than j, left since
    joined = (label[:, None] == label[None, :]) & pairs
    true = (cdist(_xy(poses), _xy(poses)) <= radius_m) & pairs if len(label) else pairs
    if sectors is not None:
        sector = np.asarray([str(x) for x in sectors])
        true &= sector[:, None] == sector[None, :]
    joins, should, hits = int(joined.sum()), int(true.sum()), int((joined & true).sum())
    return {"joins": joins, "true_joins": hits, "should_join": should,
            "precision": hits / joins if joins else None, "recall": hits / should if should else None}


def revisit_candidates(poses, radius_m: float = 3.0) -> np.ndarray:
    """Which earlier visits each visit may be matched with: ``c[j, i]`` is true when ``i < j`` and the
    robot has left visit ``i``'s place since (some visit between ``i`` and ``j`` lies beyond
    ``radius_m`` of it). The visit just before at the same place (a turn's other end) is not a revisit."""
    xy = _xy(poses)
    n = len(xy)
    far = cdist(xy, xy) > radius_m if n else np.zeros((0, 0), dtype=bool)
    later = np.triu(far, 1)
    left = np.where(later.any(axis=1), np.argmax(later, axis=1), n)  # the first visit beyond i's radius
    return np.arange(n)[:, None] > left[None, :]


def within_reach(odometry, driven, radius_m: float = 3.0, drift_share: float = DRIFT_SHARE) -> np.ndarray:
    """Which pairs of visits odometry allows to be one place: ``allowed[j, i]`` when their dead-reckoned
    positions lie within ``radius_m`` plus ``drift_share`` of the metres driven between them. A loop closer
    searches for a revisit only there (Cartographer's constraint search window; bootmap's loop closing
    joins no visits farther apart, :class:`~bootmap.mapping.loops.LoopCloser`'s ``drift_share``), so that a
    place that looks like this one but lies across the building is never its match.

    Parameters
    ----------
    odometry : array-like (n, 2 or 3)
        Each visit's dead-reckoned position (the learning's own evidence, never the truth).
    driven : array-like (n,)
        The metres the robot had driven by each visit, by its odometry (both as loop closing reckons them:
        :func:`bootmap.mapping.loops.dead_reckoning`).

    Examples
    --------
    Visits 10 m apart after 10 m driven cannot be one place; after 190 m driven, 9 m apart can:

    >>> within_reach([(0, 0), (10, 0), (1, 0)], [0, 10, 200]).astype(int).tolist()
    [[1, 0, 1], [0, 1, 1], [1, 1, 1]]
    """
    xy = _xy(odometry)
    d = np.asarray(driven, dtype=float)
    reach = radius_m + drift_share * np.abs(d[:, None] - d[None, :])
    return cdist(xy, xy) <= reach if len(xy) else np.zeros((0, 0), dtype=bool)


def reanchored_reach(odometry, driven, scores, radius_m: float = 3.0, drift_share: float = DRIFT_SHARE,
                     accept: float = MATCH_SCORE) -> np.ndarray:
    """:func:`within_reach` as a loop closer reckons it going along the drive: each visit's reach is that of
    dead reckoning re-anchored at the revisits recognised before it (:mod:`bootmap.mapping.loops.anchoring`),
    and a visit whose best match within that reach scores ``accept`` or more is taken as a revisit of that
    place, to re-anchor at from then on.

    So a loop closed early keeps the later visits of its places within a tight reach, where the drive alone
    would have drifted far enough to admit a look-alike place down the corridor. A revisit counts as the
    drive over which odometry may drift a place radius (``radius_m / drift_share``): through it, two visits
    may lie ``radius_m`` further apart, as through any place. Only earlier visits and their matches decide
    a visit's reach (causal: what a robot knows when it gets there). With no match reaching ``accept`` this
    is :func:`within_reach`.

    Parameters
    ----------
    odometry, driven : array-like
        As :func:`within_reach`: each visit's dead-reckoned position and the metres driven by it.
    scores : numpy.ndarray (n, n)
        ``scores[j, i]``: how alike visit ``j`` and an earlier visit ``i`` are (only ``i < j`` is read).
    accept : float
        The score from which a visit's best match is taken as a revisit.

    Returns
    -------
    numpy.ndarray (n, n) of bool
        ``allowed[j, i]`` for ``i < j``: visit ``i`` is within the re-anchored reach of visit ``j``.

    Examples
    --------
    A corridor driven out and back, then out again: visit 3 recognises visit 0 (score 0.9). Visit 4 is dead-
    reckoned 10 m from visit 1 after 240 m of drive, within the drive's reach (3 m + 12 m), but not within
    the re-anchored one: from visit 4 back to visit 3 (20 m), through the revisit (a radius: 60 m of drive)
    and on to visit 1 (20 m), odometry puts them 9.5 m apart, farther than 3 m + 5 m:

    >>> xy, along = [(0, 0), (20, 0), (0, 0), (0.5, 0), (30, 0)], [0, 20, 200, 240, 260]
    >>> s = np.zeros((5, 5)); s[3, 0] = 0.9
    >>> bool(within_reach(xy, along)[4, 1]), bool(reanchored_reach(xy, along, s)[4, 1])
    (True, False)
    """
    s = np.asarray(scores, dtype=float)

    def recognised(j: int, reach: np.ndarray) -> int | None:
        candidates = np.flatnonzero(reach)
        if not len(candidates):
            return None
        i = int(candidates[np.argmax(s[j, candidates])])
        return i if s[j, i] >= accept else None

    n = len(_xy(odometry))
    if s.shape != (n, n):
        raise ValueError(f"scores of shape {s.shape} for {n} visits")
    return _reach_going_along(odometry, driven, recognised, radius_m, drift_share)


def reach_after_joins(odometry, driven, labels: Sequence[Hashable], radius_m: float = 3.0,
                      drift_share: float = DRIFT_SHARE) -> np.ndarray:
    """:func:`within_reach` re-anchored, for each visit, at the joins a map made among the visits before it
    (visits of one label are one dstate or place; :func:`reanchored_reach` for how a join re-anchors).

    >>> xy, along = [(0, 0), (20, 0), (0, 0), (0.5, 0), (30, 0)], [0, 20, 200, 240, 260]
    >>> bool(reach_after_joins(xy, along, ["a", "b", "c", "a", "d"])[4, 1])
    False
    """
    labels = list(labels)
    first: dict[Hashable, int] = {}  # each label's first visit

    def joined(j: int, reach: np.ndarray) -> int | None:
        i = first.setdefault(labels[j], j)
        return None if i == j else i

    n = len(_xy(odometry))
    if len(labels) != n:
        raise ValueError(f"{len(labels)} labels for {n} visits")
    return _reach_going_along(odometry, driven, joined, radius_m, drift_share)


def _reach_going_along(odometry, driven, revisit, radius_m: float, drift_share: float) -> np.ndarray:
    """Each visit's reach, going along the drive, on dead reckoning re-anchored at the revisits before it:
    ``revisit(j, reach)`` names the earlier visit that visit ``j`` revisits (None: a new place), given the
    earlier visits within its reach."""
    from scipy.cluster.hierarchy import DisjointSet  # here: tens of ms to import, for this alone

    xy = _xy(odometry)
    d = np.asarray(driven, dtype=float)
    n = len(xy)
    if d.shape != (n,):
        raise ValueError(f"{d.shape[0] if d.ndim else 0} distances for {n} visits")
    allowed = np.zeros((n, n), dtype=bool)
    places = DisjointSet(range(n))  # the visits taken as revisits of one place so far
    anchoring = None
    for j in range(n):
        if anchoring is None:  # made again only once a revisit is taken: its joins are all before j
            joined = [sorted(s) for s in places.subsets() if len(s) > 1]
            anchoring = Anchoring(d, xy, joined, radius_m / drift_share)
        metres, displacement = anchoring.rows([j])
        reach = np.hypot(displacement[0, :j, 0], displacement[0, :j, 1]) <= radius_m + drift_share * metres[0, :j]
        allowed[j, :j] = reach
        i = revisit(j, reach)
        if i is not None and places.merge(i, j):
            anchoring = None
    return allowed


def place_recognition(scores: np.ndarray, poses, radius_m: float = 3.0,
                      allowed: np.ndarray | None = None) -> dict:
    """Place recognition as precision-recall, for any descriptor.

    Each visit ``j`` takes its best match among the earlier visits it may be matched with
    (:func:`revisit_candidates`): the ``i`` of the highest ``scores[j, i]``. A threshold is swept over
    those best scores: a visit whose best score reaches it is a detection, a true positive when its match
    lies within ``radius_m`` of it (corrected poses); a visit with a candidate within ``radius_m`` (a true
    revisit) counts in recall's denominator. Given ``allowed`` (:func:`within_reach`), the best match is
    sought among the allowed candidates only, and a visit with none makes no detection (a true revisit
    odometry rules out is a miss).

    Parameters
    ----------
    scores : numpy.ndarray (n, n)
        ``scores[j, i]``: how alike visits ``j`` and ``i`` are (higher = more alike), visits in time
        order; only ``i < j`` is read.
    poses : array-like (n, 2 or 3)
        The corrected pose of each visit.
    radius_m : float
        The place radius.
    allowed : numpy.ndarray (n, n) of bool, optional
        The pairs a match may join (``allowed[j, i]``); every candidate when None.

    Returns
    -------
    dict
        ``visits``, ``queries`` (visits with an earlier candidate), ``revisits`` (recall's denominator),
        ``best_correct`` (revisits whose best match is right: the highest recall),
        ``recall_at_95_precision`` and ``recall_at_99_precision`` (the highest recall at that precision
        or more; 0 when none reaches it, None without revisits), ``average_precision`` (the sum of
        precision times the rise in recall) and ``curve`` (threshold, precision, recall at each distinct
        best score, highest first).

    Examples
    --------
    >>> poses = [(0, 0), (10, 0), (20, 0), (0.5, 0), (20, 1)]
    >>> near = np.array([[float(np.hypot(a[0] - b[0], a[1] - b[1]) <= 3) for b in poses] for a in poses])
    >>> r = place_recognition(near, poses)
    >>> r["revisits"], r["recall_at_99_precision"], r["average_precision"]
    (2, 1.0, 1.0)
    """
    s = np.asarray(scores, dtype=float)
    xy = _xy(poses)
    if s.shape != (len(xy), len(xy)):
        raise ValueError(f"scores of shape {s.shape} for {len(xy)} visits")
    near = cdist(xy, xy) <= radius_m if len(xy) else np.zeros((0, 0), dtype=bool)
    candidates = revisit_candidates(xy, radius_m)
    searched = candidates if allowed is None else candidates & np.asarray(allowed, dtype=bool)
    best, correct, revisit, queries = [], [], 0, 0
    for j in np.flatnonzero(candidates.any(axis=1)):
        queries += 1
        revisit += bool(near[j, candidates[j]].any())
        cand = np.flatnonzero(searched[j])
        if not len(cand):
            continue
        i = cand[np.argmax(s[j, cand])]
        best.append(s[j, i])
        correct.append(bool(near[j, i]))
    curve = _pr_curve(np.asarray(best), np.asarray(correct, dtype=bool), revisit)
    return {"visits": len(xy), "queries": queries, "revisits": revisit, "best_correct": int(sum(correct)),
            "recall_at_95_precision": recall_at_precision(curve, 0.95, revisit),
            "recall_at_99_precision": recall_at_precision(curve, 0.99, revisit),
            "average_precision": average_precision(curve, revisit), "curve": curve}


def _pr_curve(best: np.ndarray, correct: np.ndarray, positives: int) -> list[dict]:
    """Precision and recall at each distinct best score taken as the threshold, highest first."""
    if not len(best):
        return []
    order = np.argsort(-best, kind="stable")
    best, correct = best[order], correct[order]
    hits = np.cumsum(correct)
    last = np.flatnonzero(np.append(best[1:] != best[:-1], True))  # a tie is one threshold
    return [{"threshold": float(best[k]), "precision": float(hits[k] / (k + 1)),
             "recall": float(hits[k] / positives) if positives else 0.0} for k in last]


def recall_at_precision(curve: list[dict], precision: float, positives: int = 1) -> float | None:
    """The highest recall on ``curve`` at ``precision`` or more (0 when no point reaches it; None
    without positives)."""
    if not positives:
        return None
    return max((p["recall"] for p in curve if p["precision"] >= precision - 1e-12), default=0.0)


def average_precision(curve: list[dict], positives: int = 1) -> float | None:
    """Precision summed over the curve, each point weighted by the recall it adds (None without
    positives)."""
    if not positives:
        return None
    recall = np.array([0.0] + [p["recall"] for p in curve])
    return float(sum(np.diff(recall) * np.array([p["precision"] for p in curve])))


def descriptor_scores(images, descriptor: str = "raw", max_shift: int = MAX_SHIFT) -> np.ndarray:
    """How alike each pair of scans is by a descriptor of :data:`DESCRIPTORS`: the negated distance."""
    return -_distances(np.asarray(images, dtype=float), descriptor, max_shift)
