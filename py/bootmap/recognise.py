"""Recognition: learn image -> dstate directly, as in section 7 of the paper, and score it.

Once the map has labelled every image with its dstate, a supervised learner maps a new image straight
to a dstate. The paper uses nearest neighbour and scores it two ways, both reproduced here:

- :func:`online_curve` - the paper's protocol: for each image in recording order, predict its dstate
  from all earlier labelled images, record right or wrong, then store the image with its label.
- :func:`learning_curve_cv` - 10-fold cross-validation learning curves. The robot records circuit by
  circuit, so folds *and* training subsets are shuffled; unshuffled prefixes would measure the
  recording order (the first 10 images of a run cover only the first few dstates).

And the paper's future work: :func:`compare_learners` (k-NN, a linear model, SVMs, a small MLP, and the
learners of :mod:`bootmap.learners`, which tolerate a noisier laser) and :func:`compare_clusterers`
(k-means, Gaussian mixture, agglomerative) on the same data.
:class:`Recogniser` is a small estimator for the service: dstate plus distance to the nearest stored
image, a measure of how familiar the image is.

Images may contain laser drop-outs (beams read at maximum range). They are kept as they are: they
are finite, and at the sensor's drop-out rate they barely move Euclidean distances. Non-finite
readings (``inf``) are read as drop-outs at the largest finite range in the data; ``nan`` is an error.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin, clone
from sklearn.cluster import AgglomerativeClustering, KMeans
from sklearn.exceptions import ConvergenceWarning
from sklearn.linear_model import LogisticRegression
from sklearn.metrics import adjusted_rand_score
from sklearn.mixture import GaussianMixture
from sklearn.model_selection import GridSearchCV, KFold
from sklearn.neighbors import KNeighborsClassifier
from sklearn.neural_network import MLPClassifier
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVC
from sklearn.utils import check_random_state
from sklearn.utils.validation import check_is_fitted

from .errors import BadInput, BootmapError
from .images import as_images, as_labels
from .learners import AlignedDiscriminant, AlignedNearestMean, ChosenByFolds, DespikedDiscriminant
from .tableau import Tableau

__all__ = [
    "LearningCurve",
    "NoImages",
    "Recogniser",
    "TooFewImages",
    "compare_clusterers",
    "compare_learners",
    "default_learners",
    "fitting_sizes",
    "learning_curve_cv",
    "online_curve",
    "online_hits",
    "recogniser_for_map",
]

_BLOCK = 1024  # rows of the distance matrix computed at once: memory O(_BLOCK * n)


# ---------------------------------------------------------------------------------------------------
# The online curve (the paper's Figure 4)
# ---------------------------------------------------------------------------------------------------

def _online_hits_1nn(X: np.ndarray, y: np.ndarray) -> np.ndarray:
    """1-NN online hits from one pass over a lower-triangular squared-distance matrix, in row blocks.

    Ties between equally near earlier images go to the earliest one (``argmin``).
    """
    n = len(X)
    hits = np.zeros(n, dtype=bool)
    sq = np.einsum("ij,ij->i", X, X)
    for start in range(1, n, _BLOCK):
        stop = min(start + _BLOCK, n)
        # squared distances from rows start..stop-1 to all earlier images 0..stop-2
        d = sq[start:stop, None] + sq[None, :stop - 1] - 2.0 * X[start:stop] @ X[:stop - 1].T
        rows = np.arange(start, stop)
        d[rows[:, None] <= np.arange(stop - 1)[None, :]] = np.inf  # only images recorded before i
        nearest = np.argmin(d, axis=1)
        hits[start:stop] = y[nearest] == y[start:stop]
    return hits


def _online_hits_refit(X: np.ndarray, y: np.ndarray, make_learner: Callable[[], object],
                       stride: int) -> np.ndarray:
    """Online hits for any learner: refit on all earlier images every ``stride`` images."""
    n = len(X)
    hits = np.zeros(n, dtype=bool)
    for start in range(1, n, stride):
        stop = min(start + stride, n)
        seen = np.unique(y[:start])
        if len(seen) == 1:  # most learners refuse one class; the only answer is that class
            pred = np.full(stop - start, seen[0], dtype=y.dtype)
        else:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ConvergenceWarning)
                pred = make_learner().fit(X[:start], y[:start]).predict(X[start:stop])
        hits[start:stop] = pred == y[start:stop]
    return hits


def online_hits(images, dstates, make_learner: Callable[[], object] | None = None,
                stride: int = 1) -> np.ndarray:
    """Right or wrong, image by image, predicting each image's dstate from the earlier ones.

    The paper's protocol (section 7): in recording order, propose the dstate of the nearest stored
    image, record whether it was right, then store the image with its true label.

    Parameters
    ----------
    images : array-like, shape (n_images, n_beams)
        Images in recording order.
    dstates : array-like, shape (n_images,)
        The dstate of each image (true, or resolved by the map).
    make_learner : callable returning a classifier, optional
        ``None`` (the default) is 1-nearest-neighbour with Euclidean distance, computed exactly and
        incrementally from one distance matrix. Any other factory (e.g.
        ``lambda: KNeighborsClassifier(3)``) is refitted on all earlier images every ``stride``
        images.
    stride : int
        Refit interval for a general learner: images ``i .. i+stride-1`` are predicted by a model
        fitted on images ``0 .. i-1`` (never on later ones). Ignored for the default 1-NN.

    Returns
    -------
    hits : ndarray of bool, shape (n_images,)
        ``hits[i]`` is True when image ``i`` was recognised. ``hits[0]`` is always False: nothing is
        stored yet, so the first image is counted as a miss (as is the first image of every dstate,
        which no learner can name before it has seen it).

    Examples
    --------
    >>> X = [[0.0], [0.1], [5.0], [5.1], [0.05]]
    >>> online_hits(X, ["a", "a", "b", "b", "a"]).tolist()
    [False, True, False, True, True]
    """
    X = as_images(images)
    y = as_labels(dstates, len(X))
    if stride < 1:
        raise ValueError("stride must be at least 1")
    if len(X) == 0:
        return np.zeros(0, dtype=bool)
    if make_learner is None:
        return _online_hits_1nn(X, y)
    return _online_hits_refit(X, y, make_learner, stride)


def online_curve(images, dstates, make_learner: Callable[[], object] | None = None,
                 window: int | None = None, stride: int = 1) -> np.ndarray:
    """Online recognition accuracy after each image (the paper's Figure 4).

    Parameters
    ----------
    images, dstates, make_learner, stride
        As in :func:`online_hits`.
    window : int, optional
        ``None`` (the default): cumulative accuracy, ``curve[i]`` = fraction of images ``0..i``
        recognised - the paper's "rate of correct answers as a function of the number of images
        experienced". An integer: the fraction recognised among the last ``window`` images (fewer at
        the start), which shows the current rate rather than the history.

    Returns
    -------
    curve : ndarray of float, shape (n_images,)
        Accuracy after each image; the first image is counted as a miss, so ``curve[0] == 0``.

    Examples
    --------
    >>> X = [[0.0], [0.1], [5.0], [5.1], [0.05]]
    >>> online_curve(X, ["a", "a", "b", "b", "a"]).round(2).tolist()
    [0.0, 0.5, 0.33, 0.5, 0.6]
    >>> online_curve(X, ["a", "a", "b", "b", "a"], window=2).tolist()
    [0.0, 0.5, 0.5, 0.5, 1.0]
    """
    hits = online_hits(images, dstates, make_learner, stride).astype(float)
    total = np.cumsum(hits)
    count = np.arange(1, len(hits) + 1)
    if window is None:
        return total / count
    if window < 1:
        raise ValueError("window must be at least 1")
    before = np.concatenate([np.zeros(window), total])[: len(hits)]  # hits up to i - window
    return (total - before) / np.minimum(count, window)


# ---------------------------------------------------------------------------------------------------
# Cross-validated learning curves
# ---------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class LearningCurve:
    """Cross-validated accuracy against training-set size.

    Attributes
    ----------
    sizes : ndarray of int, shape (n_sizes,)
        Numbers of training images.
    scores : ndarray of float, shape (n_sizes, n_splits)
        Test accuracy per size and fold.
    fit_times : ndarray of float, shape (n_sizes, n_splits)
        Seconds to fit, per size and fold.
    """

    sizes: np.ndarray
    scores: np.ndarray
    fit_times: np.ndarray

    @property
    def mean(self) -> np.ndarray:
        """Mean accuracy per size."""
        return self.scores.mean(axis=1)

    @property
    def std(self) -> np.ndarray:
        """Standard deviation of the accuracy over folds, per size."""
        return self.scores.std(axis=1)

    def at(self, n: int) -> float:
        """Mean accuracy with ``n`` training images (``n`` must be one of :attr:`sizes`)."""
        hit = np.flatnonzero(self.sizes == n)
        if not hit.size:
            raise KeyError(f"no size {n} in {self.sizes.tolist()}")
        return float(self.mean[hit[0]])


class TooFewImages(BadInput, ValueError):
    """Too few images for a cross-validated curve: ``images`` were given, ``needed`` are the fewest
    that would do."""

    def __init__(self, message: str, images: int, needed: int):
        self.images, self.needed = images, needed
        super().__init__(message)


def fitting_sizes(n_images: int, sizes: Sequence[int] | None = None, n_splits: int = 10) -> np.ndarray:
    """The training-set sizes of ``sizes`` that every training fold of ``n_splits``-fold
    cross-validation on ``n_images`` images can hold (default 10, 20, 30, ... up to that).

    Parameters
    ----------
    n_images : int
    sizes : sequence of int, optional
    n_splits : int

    Returns
    -------
    ndarray of int
        The sizes that fit, sorted, without repeats; never empty.

    Raises
    ------
    ValueError
        ``n_splits`` below 2.
    TooFewImages
        Fewer images than folds, or no size fits in the smallest training fold.

    Examples
    --------
    >>> fitting_sizes(25).tolist()
    [10, 20]
    >>> fitting_sizes(11)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    bootmap.recognise.TooFewImages: 11 images: the training folds of 10-fold cross-validation hold 9, ...
    """
    if n_splits < 2:
        raise ValueError(f"cross-validation needs at least 2 folds, got {n_splits}")
    if n_images < n_splits:
        raise TooFewImages(f"{n_images} images: {n_splits}-fold cross-validation needs at least {n_splits}",
                           n_images, n_splits)
    n_train = n_images - -(-n_images // n_splits)  # the smallest training set over the folds
    wanted = range(10, n_train + 1, 10) if sizes is None else [int(s) for s in sizes]
    fits = np.unique([s for s in wanted if 0 < s <= n_train]).astype(int)
    if not fits.size:
        smallest = min((s for s in wanted if s > 0), default=10)
        needed = -(-smallest * n_splits // (n_splits - 1))  # the fewest images whose folds hold it
        raise TooFewImages(f"{n_images} images: the training folds of {n_splits}-fold cross-validation hold "
                           f"{n_train}, fewer than the smallest training size, {smallest}", n_images, needed)
    return fits


def learning_curve_cv(images, dstates, sizes: Sequence[int] | None = None, learner=None,
                      n_splits: int = 10, random_state: int = 0) -> LearningCurve:
    """k-fold cross-validated learning curve, with shuffled folds and shuffled training subsets.

    For each fold, the held-out fold is the test set, the training folds are permuted at random, and
    for each size ``n`` the learner is fitted on the first ``n`` images of that permutation - ``n``
    images drawn at random from the training folds (subsets nested across sizes). This is
    :func:`sklearn.model_selection.learning_curve` with ``KFold(shuffle=True)`` and ``shuffle=True``.
    Unshuffled, the folds and prefixes would follow the recording order: data recorded dstate by
    dstate (or circuit by circuit) would train small models on only the first few dstates. (The same
    folds, permutations and test scores as scikit-learn's function, which also scores every model on its
    own training images: a second prediction per fit that nothing here reports, as costly as the first
    for a learner that aligns each image it is shown.)

    Parameters
    ----------
    images : array-like, shape (n_images, n_beams)
    dstates : array-like, shape (n_images,)
    sizes : sequence of int, optional
        Training-set sizes. Default 10, 20, 30, ... up to the size of the training folds. Sizes larger
        than the training folds are dropped.
    learner : classifier, optional
        An unfitted scikit-learn classifier (cloned for every fit); default 1-nearest-neighbour.
    n_splits : int
        Number of folds (the paper: 10).
    random_state : int
        Seeds the folds and the training permutations: same seed, same curve.

    Returns
    -------
    LearningCurve

    Raises
    ------
    TooFewImages
        Fewer images than folds, or training folds too small for every size
        (:func:`fitting_sizes`).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> y = np.repeat(np.arange(4), 30)
    >>> X = rng.normal(size=(120, 5)) + 10 * y[:, None]
    >>> learning_curve_cv(X, y, sizes=(50, 100)).mean.tolist()
    [1.0, 1.0]
    """
    X = as_images(images)
    y = as_labels(dstates, len(X))
    learner = KNeighborsClassifier(n_neighbors=1) if learner is None else learner
    sizes = np.asarray(fitting_sizes(len(X), sizes, n_splits))
    folds = KFold(n_splits=n_splits, shuffle=True, random_state=random_state).split(X)
    permute = check_random_state(random_state).permutation  # one generator through the folds, as sklearn's
    scores, fit_times = np.empty((len(sizes), n_splits)), np.empty((len(sizes), n_splits))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        # 10 images of 20 dstates are a fair training set here, not a regression problem in disguise
        warnings.filterwarnings("ignore", message="The number of unique classes is greater than 50%")
        for fold, (train, test) in enumerate(folds):
            train = permute(train)
            for i, n in enumerate(sizes):
                start = time.perf_counter()
                model = clone(learner).fit(X[train[:n]], y[train[:n]])
                fit_times[i, fold] = time.perf_counter() - start
                scores[i, fold] = np.mean(model.predict(X[test]) == y[test])
    return LearningCurve(sizes, scores, fit_times)


# ---------------------------------------------------------------------------------------------------
# Comparisons: the paper's future work
# ---------------------------------------------------------------------------------------------------

def default_learners(random_state: int = 0) -> dict[str, object]:
    """The learners :func:`compare_learners` compares, by name (unfitted scikit-learn estimators).

    All of them see the ranges in metres, as the nearest neighbour of the paper does. The RBF SVM and
    the MLP choose their own settings on the data they are given, by a small grid search (3-fold, inside
    every fit, so the test fold never takes part): the SVM's ``C`` and ``gamma``, the MLP's weight decay
    ``alpha``. The MLP also centres the beams (subtracts each beam's mean) and is trained by L-BFGS,
    which suits a few dozen images far better than stochastic gradient descent.

    Standardising the beams (``StandardScaler``) was tried again with the grid searches and still hurts
    badly on range images (RBF SVM 0.58 and MLP 0.59 at 90 images on notched_rectangle): dividing by
    each beam's spread gives the near-constant beams, whose spread is sensor noise and drop-outs, as much
    weight as the few beams that see the notch, which alone separate diagonally opposite dstates.
    Centring keeps the beams' relative scale. The logistic and linear-SVM regularisation (``C=100``)
    were set on notched_rectangle.
    """
    inner = KFold(n_splits=3, shuffle=True, random_state=random_state)
    return {
        "1-NN": KNeighborsClassifier(n_neighbors=1),
        "3-NN": KNeighborsClassifier(n_neighbors=3),
        "logistic": LogisticRegression(C=100.0, max_iter=5000),
        "linear SVM": SVC(kernel="linear", C=100.0),
        "RBF SVM": GridSearchCV(SVC(kernel="rbf"), {"C": [10.0, 100.0, 1000.0],
                                                    "gamma": [0.001, 0.003, 0.01, 0.03]}, cv=inner),
        "MLP (32)": GridSearchCV(
            make_pipeline(StandardScaler(with_std=False),
                          MLPClassifier(hidden_layer_sizes=(32,), solver="lbfgs", max_iter=200,
                                        random_state=random_state)),
            {"mlpclassifier__alpha": [1e-3, 1e-2, 1e-1]}, cv=inner),
        "despiked LDA": DespikedDiscriminant(random_state=random_state),
        "aligned LDA": AlignedDiscriminant(random_state=random_state),
        "aligned mean": AlignedNearestMean(),
        "aligned by folds": ChosenByFolds([AlignedDiscriminant(random_state=random_state), AlignedNearestMean()],
                                          random_state=random_state),
    }


def compare_learners(images, dstates, at: Sequence[int] = (30, 60, 90), random_state: int = 0,
                     learners: dict[str, object] | None = None, n_splits: int = 10) -> list[dict]:
    """Cross-validated accuracy of several learners at a few training-set sizes, and fit times.

    Each learner gets the same shuffled folds and training subsets (:func:`learning_curve_cv` with the
    same ``random_state``).

    Parameters
    ----------
    images : array-like, shape (n_images, n_beams)
    dstates : array-like, shape (n_images,)
    at : sequence of int
        Training-set sizes (sizes beyond the training folds are dropped).
    random_state : int
    learners : dict of name -> unfitted classifier, optional
        Default :func:`default_learners`.
    n_splits : int

    Returns
    -------
    rows : list of dict
        One per learner: ``learner`` (name), ``sizes`` (list of int), ``accuracy`` and
        ``accuracy_std`` (lists, one per size, over folds), ``fit_time`` (mean seconds per fit, one per
        size), and flat ``acc@N`` entries per size for tables.
    """
    from threadpoolctl import threadpool_limits

    learners = default_learners(random_state) if learners is None else learners
    rows = []
    for name, learner in learners.items():
        # One BLAS/OpenMP thread, as in run_experiment: a few hundred images gain nothing from threads, and
        # beside a busy core the threads wait on each other (its test took 80 s in the loaded suite, 15 s so).
        with threadpool_limits(limits=1):
            curve = learning_curve_cv(images, dstates, sizes=at, learner=learner, n_splits=n_splits,
                                      random_state=random_state)
        row = {"learner": name, "sizes": curve.sizes.tolist(), "accuracy": curve.mean.tolist(),
               "accuracy_std": curve.std.tolist(), "fit_time": curve.fit_times.mean(axis=1).tolist()}
        row.update({f"acc@{n}": float(a) for n, a in zip(curve.sizes, curve.mean)})
        rows.append(row)
    return rows


def compare_clusterers(images, dstates, k: int, random_state: int = 0) -> list[dict]:
    """Cluster images into ``k`` views with several methods and score each against the dstates.

    Parameters
    ----------
    images : array-like, shape (n_images, n_beams)
    dstates : array-like, shape (n_images,)
        True dstates S.
    k : int
        Number of clusters (views).
    random_state : int

    Returns
    -------
    rows : list of dict
        One per clusterer: ``clusterer``, ``k``, ``U`` - the uncertainty coefficient U(V|S) of the
        paper, 1 when the dstate determines the view (``completeness_score(labels_true=S,
        labels_pred=V)``), ``ari`` - adjusted Rand index of the views against the dstates (below 1
        whenever several dstates share a view, as they must when views are fewer than dstates), and
        ``fit_time`` in seconds. U is :func:`bootmap.views.uncertainty_coefficient`, the one
        :class:`~bootmap.views.ViewClusterer` reports: exactly 1.0 when the dstate determines the view.
    """
    from .views import uncertainty_coefficient

    X = as_images(images)
    y = as_labels(dstates, len(X))
    clusterers = {
        "k-means": KMeans(n_clusters=k, n_init=10, random_state=random_state),
        "Gaussian mixture (diag)": GaussianMixture(n_components=k, covariance_type="diag", n_init=3,
                                                   reg_covar=1e-4, random_state=random_state),
        "agglomerative (ward)": AgglomerativeClustering(n_clusters=k, linkage="ward"),
    }
    rows = []
    for name, model in clusterers.items():
        start = time.perf_counter()
        views = model.fit_predict(X)
        elapsed = time.perf_counter() - start
        rows.append({"clusterer": name, "k": k,
                     "U": uncertainty_coefficient(views, y),
                     "ari": float(adjusted_rand_score(y, views)), "fit_time": elapsed})
    return rows


# ---------------------------------------------------------------------------------------------------
# The recogniser estimator (for the service)
# ---------------------------------------------------------------------------------------------------

class Recogniser(ClassifierMixin, BaseEstimator):
    """Nearest-neighbour recognition of dstates from images, with the distance to the nearest image.

    Parameters
    ----------
    n_neighbors : int
        Neighbours that vote (the paper: 1).

    Attributes
    ----------
    knn_ : KNeighborsClassifier
        The fitted classifier.
    classes_ : ndarray
        The dstates seen in training.
    n_features_in_ : int
        Beams per image.

    Examples
    --------
    >>> r = Recogniser().fit([[0.0, 0.0], [5.0, 5.0]], ["S0", "S1"])
    >>> labels, dist = r.predict_with_distance([[0.0, 1.0]])
    >>> labels.tolist(), dist.round(2).tolist()
    (['S0'], [1.0])
    """

    def __init__(self, n_neighbors: int = 1):
        self.n_neighbors = n_neighbors

    def fit(self, images, dstates):
        """Store the labelled images. Returns self."""
        X = as_images(images)
        y = as_labels(dstates, len(X))
        self.knn_ = KNeighborsClassifier(n_neighbors=self.n_neighbors).fit(X, y)
        self.classes_ = self.knn_.classes_
        self.n_features_in_ = X.shape[1]
        return self

    def predict(self, images) -> np.ndarray:
        """The dstate of each image."""
        check_is_fitted(self, "knn_")
        return self.knn_.predict(as_images(images))

    def predict_with_distance(self, images) -> tuple[np.ndarray, np.ndarray]:
        """The dstate of each image and the Euclidean distance to the nearest stored image.

        A large distance means an unfamiliar image: the prediction deserves less trust.
        """
        check_is_fitted(self, "knn_")
        X = as_images(images)
        dist, _ = self.knn_.kneighbors(X, n_neighbors=1)
        return self.knn_.predict(X), dist[:, 0]


class NoImages(BootmapError):
    """A tableau of view labels only: there are no images to recognise by."""


def recogniser_for_map(tableau: Tableau, dstate_of: Sequence[str], n_neighbors: int = 1) -> Recogniser:
    """A recogniser of the dstates a map gives the tableau's images (``dstate_of[t]`` for time point t):
    the paper's section 7, once abduction has labelled every image. Steps without an image are left out;
    :class:`NoImages` if none has one."""
    if len(dstate_of) != len(tableau):
        raise ValueError(f"{len(dstate_of)} dstates for a tableau of {len(tableau)} steps")
    labelled = [(s.image, d) for s, d in zip(tableau.steps, dstate_of) if s.image is not None]
    if not labelled:
        raise NoImages("this tableau has view labels but no images, so there is nothing to recognise by; "
                       "post a tableau whose steps carry images")
    images, dstates = zip(*labelled)
    return Recogniser(n_neighbors).fit(list(images), list(dstates))
