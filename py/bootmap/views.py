"""Views: clustering the images seen at dstates (the paper's step 2, unsupervised).

The robot's images (one laser scan per dstate, a point in R^180) are clustered by k-means for every k from
1 to a bound. The paper's *internal* measure M(k) picks k; when the true dstate of every image is known, the
*external* uncertainty coefficient U(V|S) says whether the views are a function of the dstates (U = 1) and
which k is the largest that still is. See ``shared/paper/README.md``, "Equations, restored".

Drop-outs (a beam that misses its return reads the laser's maximum range) are handled by
:class:`ViewClusterer` when ``max_range`` is given: see :func:`repair_dropouts`.
"""

from __future__ import annotations

from typing import Hashable, Sequence

import numpy as np
from sklearn.cluster import AgglomerativeClustering, KMeans
from sklearn.metrics import completeness_score, pairwise_distances_argmin
from sklearn.utils import check_random_state

from .images import as_images

__all__ = ["CLUSTERERS", "OnlineViews", "ViewClusterer", "davies_bouldin_k", "internal_measure", "repair_dropouts",
           "uncertainty_coefficient", "view_labels", "view_table"]


def internal_measure(images, labels) -> float:
    """The paper's internal measure M(k) of a clustering (higher is better).

    ``M(k) = 1 / (k * sum_c (1/n_c) * sum_i |x_ci - mean_c|^2)``: k is the number of (non-empty) clusters,
    and each cluster contributes the mean squared Euclidean distance of its images to its mean. Tight
    clusters raise M; every extra cluster is penalised through the factor k.

    Parameters
    ----------
    images : array-like of shape (n_images, n_values)
    labels : array-like of shape (n_images,)
        Cluster of every image (any hashable labels).

    Returns
    -------
    float
        M(k) > 0. A perfect clustering with zero spread in every cluster (each cluster's images identical)
        has a zero denominator: M is then ``inf``, which is larger than any finite M, so such a k wins an
        argmax (the first such k, for a sweep in increasing k).

    Examples
    --------
    Two clusters, {0, 2} (mean 1, mean squared distance 1) and {10} (0): M = 1 / (2 * (1 + 0)).

    >>> internal_measure([[0.0], [2.0], [10.0]], [0, 0, 1])
    0.5
    >>> internal_measure([[1.0, 1.0], [1.0, 1.0]], ["a", "a"])
    inf
    """
    x = as_images(images)
    labels = np.asarray(labels)
    if len(labels) != len(x):
        raise ValueError(f"{len(x)} images but {len(labels)} labels")
    if len(x) == 0:
        raise ValueError("no images")
    _, idx = np.unique(labels, return_inverse=True)
    idx = idx.ravel()
    k = int(idx.max()) + 1
    n = np.bincount(idx, minlength=k).astype(float)
    sums = np.zeros((k, x.shape[1]))
    np.add.at(sums, idx, x)
    means = sums / n[:, None]
    sq = ((x - means[idx]) ** 2).sum(axis=1)
    spread = float((np.bincount(idx, weights=sq, minlength=k) / n).sum())
    if spread <= 0.0:
        return float("inf")
    return 1.0 / (k * spread)


def uncertainty_coefficient(views: Sequence[Hashable], dstates: Sequence[Hashable]) -> float:
    """The uncertainty coefficient U(V|S) = (H(V) - H(V|S)) / H(V) of views V given dstates S.

    U = 1 when the dstate determines the view (every dstate always looks the same), and it falls towards 0
    as the same dstate shows different views. It is asymmetric: many dstates sharing one view (perceptual
    aliasing, as in the paper) still give U = 1.

    Computed as ``sklearn.metrics.completeness_score(labels_true=dstates, labels_pred=views)``, which equals
    ``homogeneity_score(labels_true=views, labels_pred=dstates)``; the argument order matters.

    Parameters
    ----------
    views : sequence of shape (n_images,)
        View (cluster) of every image.
    dstates : sequence of shape (n_images,)
        True dstate of every image.

    Returns
    -------
    float
        U in [0, 1]. When there is a single view, H(V) = 0 and U is undefined (0/0); this returns 1.0, as
        scikit-learn does, since the dstate then trivially determines the view. Values within 1e-12 of 1
        or 0 (rounding in the entropies) are returned as exactly 1.0 or 0.0.

    Examples
    --------
    Four dstates, two views, diagonally opposite dstates sharing a view: the dstate still determines the
    view.

    >>> uncertainty_coefficient(["V0", "V1", "V0", "V1"], ["S0", "S1", "S2", "S3"])
    1.0

    One dstate seen as two views: the dstate says nothing about the view.

    >>> uncertainty_coefficient(["V0", "V1"], ["S0", "S0"])
    0.0
    """
    views = np.asarray(views)
    dstates = np.asarray(dstates)
    if len(views) != len(dstates):
        raise ValueError(f"{len(views)} views but {len(dstates)} dstates")
    u = float(completeness_score(labels_true=dstates, labels_pred=views))
    # entropies are sums of logs: an exact 1 or 0 can come out one rounding step off, so snap it
    if abs(u - 1.0) < 1e-12:
        return 1.0
    if abs(u) < 1e-12:
        return 0.0
    return min(max(u, 0.0), 1.0)


def repair_dropouts(images, max_range: float) -> np.ndarray:
    """Clip readings to ``max_range`` and fill in drop-outs, single beams and runs of any length.

    A laser beam that misses its return reads the maximum range. Clipping makes an open direction (nothing
    within range) and a drop-out read the same value; they are told apart in two ways:

    1. A single beam at ``max_range`` whose neighbouring beams both read less is a drop-out and is replaced
       by the mean of its two neighbours (an edge beam by its one neighbour).
    2. A run of beams at ``max_range`` inside a surface the image sees (a beam read on either side) is an
       open direction if any of the images most like this one (its three nearest) is open there too; where
       all three see every beam of it, and what they see continues the surface on either side, well
       within range, it is a drop-out, and takes their median reading. The robot comes back to its dstates, so an image with a drop-out has
       look-alikes that read those beams: drop-outs do not repeat, open directions do.

    Clipping alone is not enough: one drop-out changes one reading by several metres, a squared distance
    larger than all the rest of the image's variation, and M (a mean of squared distances) then rewards
    splitting the images with drop-outs off into clusters of their own.

    Parameters
    ----------
    images : array-like of shape (n_images, n_beams)
        Range scans, beams in angular order.
    max_range : float
        The laser's maximum range.

    Returns
    -------
    ndarray of shape (n_images, n_beams)
        A repaired copy.

    Examples
    --------
    >>> repair_dropouts([[1.0, 8.0, 2.0, 8.0, 8.0, 9.0]], 8.0)
    array([[1. , 1.5, 2. , 8. , 8. , 8. ]])
    >>> repair_dropouts([[8.0, 0.5, 0.5]], 8.0)
    array([[0.5, 0.5, 0.5]])

    Three look-alikes read a wall at 3 m where the fourth has lost two beams:

    >>> looks = [[3.0, 3.1, 3.0, 3.1], [3.0, 3.0, 3.1, 3.0], [3.1, 3.0, 3.0, 3.1], [3.0, 8.0, 8.0, 3.0]]
    >>> repair_dropouts(looks, 8.0)[3]
    array([3., 3., 3., 3.])
    """
    x = np.minimum(as_images(images), float(max_range))
    if x.shape[1] < 2:
        return x
    at = x >= max_range
    left_at = np.zeros_like(at)
    left_at[:, 1:] = at[:, :-1]
    right_at = np.zeros_like(at)
    right_at[:, :-1] = at[:, 1:]
    isolated = at & ~left_at & ~right_at
    left = np.empty_like(x)
    left[:, 1:] = x[:, :-1]
    left[:, 0] = x[:, 1]
    right = np.empty_like(x)
    right[:, :-1] = x[:, 1:]
    right[:, -1] = x[:, -2]
    x = np.where(isolated, 0.5 * (left + right), x)
    return _fill_from_lookalikes(x, x >= max_range, float(max_range))


_LOOKALIKES = 3
_SURFACE_M = 0.25  # how far a filled run may leave the line between the readings either side of it
_WITHIN = 0.9      # a filled run reads at most this share of the laser's maximum range


def _fill_from_lookalikes(x: np.ndarray, at_max: np.ndarray, max_range: float) -> np.ndarray:
    """Holes at the maximum range that all three of an image's nearest look-alikes read: their median
    reading (see :func:`repair_dropouts`)."""
    rows = np.flatnonzero(at_max.any(axis=1))
    if len(rows) == 0 or len(x) <= _LOOKALIKES:
        return x
    from sklearn.neighbors import NearestNeighbors

    # Plain distances (clipped readings): a look-alike that is open where this image reads the maximum
    # range pays nothing there, so the visits of one place, open in the same directions, come first.
    _, found = NearestNeighbors(n_neighbors=_LOOKALIKES + 1).fit(x).kneighbors(x[rows])
    out = x.copy()
    for i, candidates in zip(rows, found):
        near = [j for j in candidates if j != i][:_LOOKALIKES]  # not its own look-alike
        out[i] = _filled(x[i], at_max[i], x[near], at_max[near], max_range)
    return out


def _filled(image: np.ndarray, at_max: np.ndarray, looks: np.ndarray, looks_at_max: np.ndarray,
            max_range: float) -> np.ndarray:
    """One image with its holes filled from its look-alikes, where they are drop-outs."""
    out = image.copy()
    seen_by_all = ~looks_at_max.any(axis=0)
    for a, b in _holes(at_max):
        if not seen_by_all[a:b].all():
            continue  # a look-alike is open there too: an open direction
        fill = np.median(looks[:, a:b], axis=0)
        # A drop-out on a surface: what the look-alikes read there continues the surface the image reads
        # on either side (an opening would not), and lies well within range (a wall at the range's edge
        # flickers in and out of it from visit to visit: that is the laser's reach, not a drop-out).
        across = np.interp(np.arange(a, b), [a - 1, b], [image[a - 1], image[b]])
        if np.abs(fill - across).max() <= _SURFACE_M and fill.max() <= _WITHIN * max_range:
            out[a:b] = fill
    return out


def _holes(at_max: np.ndarray) -> list[tuple[int, int]]:
    """Runs [a, b) of beams at the maximum range with a beam read on both sides: holes in a surface the
    image sees, not the edge of an open direction (whose extent moves with the robot's pose)."""
    edges = np.diff(np.concatenate([[0], at_max.astype(int), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    return [(a, b) for a, b in zip(starts, ends) if a > 0 and b < len(at_max)]


def _kmeans(x: np.ndarray, k: int, n_init: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    km = KMeans(n_clusters=k, n_init=n_init, algorithm="lloyd", random_state=seed).fit(x)
    return km.labels_.astype(int), km.cluster_centers_


def _gaussian_mixture(x: np.ndarray, k: int, n_init: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    from sklearn.mixture import GaussianMixture

    # Diagonal covariances: 180 beams and a few hundred images are too few for full ones; reg_covar keeps
    # the near-constant beams (wall at the same distance in every image) from collapsing a component.
    model = GaussianMixture(n_components=k, covariance_type="diag", n_init=max(1, n_init // 3), reg_covar=1e-4,
                            random_state=seed)
    return label_means(x, model.fit_predict(x))


def _ward(x: np.ndarray, k: int, n_init: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    return label_means(x, AgglomerativeClustering(n_clusters=k, linkage="ward").fit_predict(x))  # deterministic


def label_means(x: np.ndarray, labels) -> tuple[np.ndarray, np.ndarray]:
    """Labels renumbered 0..n-1 in the order of the distinct labels sorted (a mixture can leave a component
    empty), and each label's mean image: a cluster's centre, the one :meth:`ViewClusterer.predict`
    assigns new images to, or a dstate's mean image."""
    labels = np.unique(labels, return_inverse=True)[1].astype(int)
    return labels, np.array([x[labels == c].mean(axis=0) for c in range(int(labels.max()) + 1)])


#: How images are clustered into views for a given k (``ViewClusterer(method=...)``); k is then chosen by M
#: whichever clusters them. The paper's is k-means.
CLUSTERERS = {"kmeans": _kmeans, "gaussian-mixture": _gaussian_mixture, "ward": _ward}


class ViewClusterer:
    """Cluster dstate images into views by k-means, choosing k by the paper's internal measure M.

    k-means (scikit-learn, Lloyd's algorithm) runs for every k in 1..``k_max`` (bounded by the number of
    distinct images); M(k) is computed for each, and the views are the clustering at the k where M is
    largest (the smallest such k on a tie). Given the true dstates, U(V|S) is computed for every k too.

    Parameters
    ----------
    k_max : int, default=12
        Largest number of views tried.
    n_init : int, default=10
        k-means restarts per k (the best inertia is kept).
    random_state : int, RandomState instance or None, default=0
        Seeds k-means; an int gives the same views on every run.
    method : {"kmeans", "gaussian-mixture", "ward"}, default="kmeans"
        How images are clustered for each k (:data:`CLUSTERERS`): the paper's k-means, a diagonal
        Gaussian mixture, or agglomerative clustering with Ward linkage. k is chosen by M for every method.
    max_range : float, optional
        The laser's maximum range. When given, readings are clipped to it and isolated drop-outs are filled
        in before clustering (and before :meth:`predict`), see :func:`repair_dropouts`. Without it the
        images are clustered as they are, and drop-outs can pull k up or down.

    Attributes
    ----------
    ks_ : ndarray of int
        The k values tried, 1..min(k_max, number of distinct images).
    internal_ : ndarray of float
        M(k) for every k in ``ks_``.
    uncertainty_ : ndarray of float or None
        U(V|S) for every k in ``ks_`` (None when fit without dstates).
    k_ : int
        The chosen number of views, argmax of M.
    labels_ : ndarray of int
        View (0..k_-1) of every training image at ``k_``.
    cluster_centers_ : ndarray of shape (k_, n_values)
        Mean image of every view.
    largest_k_with_u1_ : int or None
        Largest k with U = 1 (within 1e-9); None without dstates or when no k has U = 1.
    labels_per_k_ : dict of int to ndarray
        The clustering at every k tried.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> centres = rng.uniform(0.5, 5.0, (3, 20))
    >>> images = np.repeat(centres, 10, axis=0) + rng.normal(0, 0.01, (30, 20))
    >>> model = ViewClusterer(k_max=6).fit(images, dstates=np.repeat([0, 1, 2], 10))
    >>> model.k_, model.largest_k_with_u1_
    (3, 3)
    >>> view_labels(model.predict(images[::10]))
    ['V0', 'V1', 'V2']
    """

    U_TOLERANCE = 1e-9

    def __init__(self, k_max: int = 12, n_init: int = 10, random_state=0, max_range: float | None = None,
                 method: str = "kmeans"):
        self.k_max = k_max
        self.n_init = n_init
        self.random_state = random_state
        self.max_range = max_range
        self.method = method

    def prepare(self, images) -> np.ndarray:
        """The images as the clusterer reads them: checked, drop-outs repaired."""
        x = as_images(images)
        if self.max_range is not None:
            x = repair_dropouts(x, self.max_range)
        return x

    def fit(self, images, dstates: Sequence[Hashable] | None = None) -> "ViewClusterer":
        """Sweep k, measure M (and U given dstates), and keep the clustering with the largest M.

        Parameters
        ----------
        images : array-like of shape (n_images, n_values)
        dstates : sequence of shape (n_images,), optional
            True dstate of every image, for U(V|S).

        Returns
        -------
        self
        """
        if self.k_max < 1:
            raise ValueError(f"k_max must be at least 1, got {self.k_max}")
        if self.method not in CLUSTERERS:
            raise ValueError(f"unknown clustering method {self.method!r}; known: {', '.join(CLUSTERERS)}")
        x = self.prepare(images)
        if len(x) == 0:
            raise ValueError("no images")
        if dstates is not None and len(dstates) != len(x):
            raise ValueError(f"{len(x)} images but {len(dstates)} dstates")
        n_distinct = len(np.unique(x, axis=0))
        ks = np.arange(1, min(self.k_max, n_distinct) + 1)
        rng = check_random_state(self.random_state)
        seeds = rng.randint(np.iinfo(np.int32).max, size=len(ks))
        internal = np.empty(len(ks))
        labels_per_k: dict[int, np.ndarray] = {}
        centers_per_k: dict[int, np.ndarray] = {}
        for i, (k, seed) in enumerate(zip(ks, seeds)):
            if k == 1:  # nothing to search: one cluster, the mean image
                labels = np.zeros(len(x), dtype=int)
                centers = x.mean(axis=0, keepdims=True)
            else:
                labels, centers = CLUSTERERS[self.method](x, int(k), self.n_init, int(seed))
            labels_per_k[int(k)] = labels
            centers_per_k[int(k)] = centers
            internal[i] = internal_measure(x, labels)
        self.ks_ = ks
        self.internal_ = internal
        self.labels_per_k_ = labels_per_k
        self.k_ = int(ks[int(np.argmax(internal))])
        self.labels_ = labels_per_k[self.k_]
        self.cluster_centers_ = centers_per_k[self.k_]
        if dstates is None:
            self.uncertainty_ = None
            self.largest_k_with_u1_ = None
        else:
            self.uncertainty_ = np.array([uncertainty_coefficient(labels_per_k[int(k)], dstates) for k in ks])
            ones = ks[self.uncertainty_ >= 1.0 - self.U_TOLERANCE]
            self.largest_k_with_u1_ = int(ones.max()) if len(ones) else None
        return self

    def predict(self, images) -> np.ndarray:
        """View (index into ``cluster_centers_``) of each image: its nearest view centre.

        Parameters
        ----------
        images : array-like of shape (n_images, n_values)

        Returns
        -------
        ndarray of int, shape (n_images,)
        """
        if not hasattr(self, "cluster_centers_"):
            raise RuntimeError("ViewClusterer is not fitted yet; call fit first")
        x = self.prepare(images)
        return pairwise_distances_argmin(x, self.cluster_centers_)

    def fit_predict(self, images, dstates: Sequence[Hashable] | None = None) -> np.ndarray:
        """Fit and return ``labels_``."""
        return self.fit(images, dstates).labels_


def davies_bouldin_k(clusterer: "ViewClusterer", images) -> tuple[int | None, list[float | None]]:
    """The k whose clustering (of a fitted :class:`ViewClusterer`) has the lowest Davies-Bouldin index
    (scikit-learn), and the index at every k tried.

    M = 1/(k * SSE) can fall steadily with k on real scans, where no k gives tight clusters, and then
    picks k = 1 or 2. The Davies-Bouldin index compares each cluster's spread with its distance to the
    nearest other cluster, so it does not reward fewer clusters for their own sake: a criterion that does
    not degenerate there.

    Parameters
    ----------
    clusterer : ViewClusterer
        Fitted on ``images``.
    images : array-like of shape (n_images, n_values)

    Returns
    -------
    k : int or None
        The k of the lowest index; None when the index is defined at no k tried (fewer than three
        images, or only k = 1 tried).
    scores : list of float or None
        The index at every k of ``clusterer.ks_``; None where it is undefined: fewer than two clusters,
        or a cluster per image (the index needs 2 <= clusters <= images - 1), as with ``k_max`` at or
        above the number of images.

    Examples
    --------
    Three images, k_max above their number: at k = 3 each image is a cluster of its own.

    >>> x = np.array([[0.0], [0.1], [5.0]])
    >>> k, scores = davies_bouldin_k(ViewClusterer(k_max=12).fit(x), x)
    >>> k, [None if s is None else round(s, 3) for s in scores]
    (2, [None, 0.01, None])
    """
    x = clusterer.prepare(images)
    scores = [_davies_bouldin(x, clusterer.labels_per_k_[int(k)]) for k in clusterer.ks_]
    known = [(s, int(k)) for s, k in zip(scores, clusterer.ks_) if s is not None]
    return (min(known)[1] if known else None), scores


def _davies_bouldin(x: np.ndarray, labels: np.ndarray) -> float | None:
    """scikit-learn's Davies-Bouldin index of one clustering, None where it is undefined."""
    from sklearn.metrics import davies_bouldin_score

    clusters = len(np.unique(labels))
    if not 2 <= clusters <= len(x) - 1:
        return None
    return float(davies_bouldin_score(x, labels))


def view_labels(labels: Sequence[Hashable]) -> list[str]:
    """Name views "V0", "V1", ... in order of first appearance (the first image's view is V0).

    Examples
    --------
    >>> view_labels([2, 2, 0, 1, 0])
    ['V0', 'V0', 'V1', 'V2', 'V1']
    """
    names: dict = {}
    return [names.setdefault(v, f"V{len(names)}") for v in np.asarray(labels).tolist()]


def view_table(images, labels: Sequence[Hashable], angle_min_deg: float = -90.0, angle_max_deg: float = 90.0,
               beams: int = 5) -> list[dict]:
    """The paper's view table: mean distance to the robot's left, front and right, per view.

    The beams are taken as evenly spaced from ``angle_min_deg`` (first value) to ``angle_max_deg`` (last
    value), counter-clockwise positive, so left is +90 deg, front 0 deg and right -90 deg. For each image
    the distance in a direction is the median of the ``beams`` beams nearest that angle (robust to a
    drop-out); the table gives its mean over the view's images.

    Parameters
    ----------
    images : array-like of shape (n_images, n_beams)
    labels : sequence of shape (n_images,)
        View of every image. String labels are kept; other labels are named by :func:`view_labels`.
    angle_min_deg, angle_max_deg : float
        Angles of the first and last beam.
    beams : int, default=5
        Beams per direction.

    Returns
    -------
    list of dict
        One row per view, in order of first appearance: ``{"view", "n", "left", "front", "right"}``
        (distances in the images' unit).

    Examples
    --------
    >>> scan = np.linspace(4.5, 0.5, 181)  # right wall far, left wall near
    >>> [{k: round(v, 2) if isinstance(v, float) else v for k, v in row.items()}
    ...  for row in view_table([scan, scan], ["V0", "V0"])]
    [{'view': 'V0', 'n': 2, 'left': 0.54, 'front': 2.5, 'right': 4.46}]
    """
    x = as_images(images)
    labels = np.asarray(labels)
    if len(labels) != len(x):
        raise ValueError(f"{len(x)} images but {len(labels)} labels")
    names = labels.tolist() if all(isinstance(v, str) for v in labels.tolist()) else view_labels(labels)
    angles = np.linspace(angle_min_deg, angle_max_deg, x.shape[1])
    per_image = {}
    for side, target in (("left", 90.0), ("front", 0.0), ("right", -90.0)):
        nearest = np.argsort(np.abs(angles - target), kind="stable")[:max(1, min(beams, x.shape[1]))]
        per_image[side] = np.median(x[:, np.sort(nearest)], axis=1)
    names_arr = np.asarray(names, dtype=object)
    rows = []
    for name in dict.fromkeys(names):
        mask = names_arr == name
        row = {"view": name, "n": int(mask.sum())}
        for side in ("left", "front", "right"):
            row[side] = float(per_image[side][mask].mean())
        rows.append(row)
    return rows


def tableau_with_views(tableau):
    """A tableau of images only (e.g. from ``bootmap simulate``) with its views found as the paper finds
    them: k-means, k chosen by the internal measure M. Returns ``(tableau, k)``.

    A tableau whose steps are all labelled, or that mixes labelled and unlabelled steps, comes back as it
    is with ``k = None``: the resolver's ``require_views`` then names the step that lacks a view.

    Examples
    --------
    >>> from bootmap.tableau import Tableau
    >>> steps = [{"image": [x, 1.0], "action": {"type": "turn", "angle_deg": -90}} for x in (1.0, 5.0, 1.0)]
    >>> images_only = Tableau.from_dict({"format": "bootmap.tableau/1", "steps": steps + [{"image": [5.0, 1.0]}]})
    >>> t, k = tableau_with_views(images_only)
    >>> k, t.views
    (2, ['V0', 'V1', 'V0', 'V1'])
    """
    if tableau.labelled or any(s.image is None for s in tableau.steps):
        return tableau, None
    clusterer = ViewClusterer(random_state=0, max_range=_range_max(tableau.meta))
    clusterer.fit(np.array([s.image for s in tableau.steps]))
    return tableau.with_views(view_labels(clusterer.labels_)), clusterer.k_


def _range_max(meta: dict) -> float | None:
    """A laser's drop-outs read its maximum range; a run that says what that is (``meta.laser.range_max``,
    as ``bootmap simulate`` writes it) lets them be repaired."""
    import math

    from .errors import TableauError

    laser = meta.get("laser")
    value = laser.get("range_max") if isinstance(laser, dict) else None
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (math.isfinite(value) and value > 0):
        raise TableauError(f"{value!r} is not a positive number of metres", "meta.laser.range_max")
    return float(value)


class OnlineViews:
    """Views labelled one image at a time, as a robot exploring must: leader clustering (Hartigan 1975).

    An image takes the view of the nearest earlier *prototype* (the first image of each view) if it lies
    within ``threshold``; otherwise it becomes the prototype of a new view. A label, once given, never
    changes, so a map built on the labels so far stays a map of the same experience as more arrives
    (k-means on all images so far would relabel earlier steps whenever k or a centre moves). The
    distance is the mean absolute difference in metres over the beams, ranges capped at ``max_range``.

    At the shipped worlds' dstates, images of one true dstate differ by at most 0.19 m (seeds 0-3, 150
    explored steps each, loop, Taylor Hall, plus), and 0.4 m labels every true dstate with one view:
    8 views in Taylor Hall (the paper's 8), 8 in the loop, 3 in the plus.

    Parameters
    ----------
    threshold : float
        Metres of mean absolute range difference within which an image shows a known view.
    max_range : float, optional
        The laser's maximum range (drop-outs read it); ranges beyond are capped.

    Attributes
    ----------
    prototypes_ : list of ndarray
        The first image of every view, in the order the views were met (view ``V{i}`` is the i-th).

    Examples
    --------
    >>> ov = OnlineViews(threshold=0.4)
    >>> [ov.label(x) for x in ([1.0, 2.0], [1.1, 2.1], [5.0, 5.0], [1.0, 1.9])]
    ['V0', 'V0', 'V1', 'V0']
    """

    def __init__(self, threshold: float = 0.4, max_range: float | None = None):
        if not threshold > 0:
            raise ValueError(f"threshold must be > 0 metres, got {threshold!r}")
        self.threshold, self.max_range = threshold, max_range
        self.prototypes_: list[np.ndarray] = []

    def label(self, image) -> str:
        """The view of one image (a new view if no known one is within the threshold)."""
        x = np.asarray(image, dtype=float)
        if self.max_range is not None:
            x = np.minimum(x, self.max_range)
        if self.prototypes_:
            d = np.mean(np.abs(np.array(self.prototypes_) - x), axis=1)
            i = int(np.argmin(d))
            if d[i] < self.threshold:
                return f"V{i}"
        self.prototypes_.append(x)
        return f"V{len(self.prototypes_) - 1}"

    def labels(self, images) -> list[str]:
        """The views of a sequence of images, labelled in order."""
        return [self.label(x) for x in images]
