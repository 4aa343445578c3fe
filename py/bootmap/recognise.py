"""Recognition: learn image -> dstate directly, as in section 7 of the paper, and score it.

Once the map has labelled every image with its dstate, a supervised learner maps a new image straight
to a dstate. The paper uses nearest neighbour and scores it two ways, both reproduced here:

- :func:`online_curve` - the paper's protocol: for each image in recording order, predict its dstate
  from all earlier labelled images, record right or wrong, then store the image with its label.
- :func:`learning_curve_cv` - 10-fold cross-validation learning curves. The robot records circuit by
  circuit, so folds *and* training subsets are shuffled; unshuffled prefixes would measure the
  recording order (the first 10 images of a run cover only the first few dstates).

And the paper's future work: :func:`compare_learners` (k-NN, a linear model, SVMs, a small MLP, and
:class:`DespikedDiscriminant`, which tolerates a noisier laser, and :class:`AlignedDiscriminant`, which
also takes out the small motion between stops at one dstate) and :func:`compare_clusterers` (k-means,
Gaussian mixture, agglomerative) on the same data.
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
from sklearn.decomposition import PCA
from sklearn.discriminant_analysis import LinearDiscriminantAnalysis
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

from .alignment import Reference
from .errors import BadInput, BootmapError
from .images import as_images
from .tableau import Tableau
from .views import label_means

__all__ = [
    "AlignedDiscriminant",
    "AlignedNearestMean",
    "ChosenByFolds",
    "DespikedDiscriminant",
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


def _as_labels(dstates, n: int) -> np.ndarray:
    y = np.asarray(dstates)
    if y.shape != (n,):
        raise ValueError(f"dstates must have shape ({n},), got {y.shape}")
    return y


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
    y = _as_labels(dstates, len(X))
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
    y = _as_labels(dstates, len(X))
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
    y = _as_labels(dstates, len(X))
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
        y = _as_labels(dstates, len(X))
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


def despike(images, width: int = 3) -> np.ndarray:
    """Each range replaced by the median of ``width`` neighbouring beams: a drop-out (one beam read at
    maximum range) is gone, and range noise shrinks, while walls and corners wider than the window stay
    where they are.

    >>> despike([[1.0, 1.1, 8.0, 1.0, 0.9]]).tolist()
    [[1.0, 1.1, 1.1, 1.0, 0.9]]
    """
    from scipy.ndimage import median_filter

    X = as_images(images)
    return X if width <= 1 else median_filter(X, size=(1, width), mode="nearest")


def components_by_folds(X: np.ndarray, y: np.ndarray, dims: Sequence[int], folds: KFold) -> int:
    """The number of principal components (of ``dims``) whose linear discriminant scores best on the folds:
    the highest mean accuracy, the first of ``dims`` on a tie, a fit that fails scoring 0. What a grid
    search over ``PCA(d) + LinearDiscriminantAnalysis()`` chooses, with one decomposition per fold instead
    of one per candidate: the exact decomposition's first d components are those of ``PCA(d)``.

    >>> rng = np.random.default_rng(0)
    >>> y = np.repeat([0, 1, 2], 12)
    >>> X = rng.standard_normal((36, 20)) + y[:, None] * np.eye(20)[3]
    >>> components_by_folds(X, y, [2, 5, 10], KFold(3, shuffle=True, random_state=0))
    5
    """
    dims = list(dims)
    scores = np.zeros(len(dims))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # collinear directions and folds without some dstate warn
        for train, test in folds.split(X):
            pca = PCA(n_components=max(dims), svd_solver="full").fit(X[train])
            seen, unseen = pca.transform(X[train]), pca.transform(X[test])
            for i, d in enumerate(dims):
                try:
                    lda = LinearDiscriminantAnalysis().fit(seen[:, :d], y[train])
                except ValueError:
                    continue
                scores[i] += np.mean(lda.predict(unseen[:, :d]) == y[test])
    return dims[int(np.argmax(scores))]


class DespikedDiscriminant(ClassifierMixin, BaseEstimator):
    """Recognise dstates from noisy laser images: despiked ranges (:func:`despike`), their principal
    components, and linear discriminant analysis, which weighs each direction by how well it separates
    the dstates against how much images of one dstate vary (so the few beams that see a notch count, and
    beams that only carry noise do not); an image goes to the dstate whose mean it is nearest in that
    space. The number of components is chosen on the training images alone, by a 3-fold search.

    The paper's nearest neighbour compares an image with single stored images, each as noisy as itself;
    this compares it with what the images of each dstate share, and holds up far better as the laser's
    noise grows (docs/results/noise.md has the figures).

    Parameters
    ----------
    width : int
        Beams in the despiking median (1: none).
    dimensions : sequence of int
        Candidate numbers of principal components (those the training images can carry are tried).
    random_state : int
        Seeds the inner folds.

    Attributes
    ----------
    model_ : Pipeline
        The fitted PCA and discriminant.
    n_components_ : int or None
        The number of components chosen (None where no dstate was seen twice: then the nearest despiked
        image decides).
    classes_ : ndarray
        The dstates seen in training.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> y = np.repeat(["S0", "S1"], 20)
    >>> X = 2.0 + 0.04 * rng.standard_normal((40, 30)) + np.where(y == "S0", 0.0, 0.05)[:, None]
    >>> DespikedDiscriminant().fit(X[::2], y[::2]).score(X[1::2], y[1::2])
    1.0
    """

    def __init__(self, width: int = 3, dimensions: Sequence[int] = (5, 10, 20, 30, 40), random_state: int = 0):
        self.width = width
        self.dimensions = dimensions
        self.random_state = random_state

    def fit(self, images, dstates):
        X = despike(images, self.width)
        y = _as_labels(dstates, len(X))
        # A candidate must fit in the smallest inner training fold (two thirds of the images).
        room = min(2 * len(X) // 3 - 1, X.shape[1])
        dims = sorted({d for d in self.dimensions if 0 < d <= room}) or [max(1, min(len(X) - 1, X.shape[1]))]
        pipeline = make_pipeline(PCA(svd_solver="full"), LinearDiscriminantAnalysis())
        if len(X) <= len(np.unique(y)):
            # No dstate seen twice: there is no spread within a dstate to weigh directions by, and the
            # discriminant is undefined. Each image is its dstate's mean: the nearest one decides.
            self.model_ = KNeighborsClassifier(n_neighbors=1).fit(X, y)
        elif len(dims) == 1 or len(X) < 9:
            self.model_ = pipeline.set_params(pca__n_components=dims[0]).fit(X, y)
        else:
            inner = KFold(n_splits=3, shuffle=True, random_state=self.random_state)
            best = components_by_folds(X, y, dims, inner)
            self.model_ = pipeline.set_params(pca__n_components=best).fit(X, y)
        pca = getattr(self.model_, "named_steps", {}).get("pca")
        self.n_components_ = None if pca is None else int(pca.n_components_)
        self.classes_ = self.model_.classes_
        self.n_features_in_ = X.shape[1]
        return self

    def predict(self, images) -> np.ndarray:
        """The dstate of each image."""
        check_is_fitted(self, "model_")
        return self.model_.predict(despike(images, self.width))


class AlignedDiscriminant(ClassifierMixin, BaseEstimator):
    """Recognise dstates from noisy laser images, taking out the small motion between stops at a dstate.

    Two :class:`DespikedDiscriminant` fits judge each image together: one on the images as read, one on
    the images aligned to the nearest of the dstates' mean images (:mod:`bootmap.alignment`: the pose
    correction of a stop's scatter, fitted to the mean's surface); an image goes to the dstate whose log
    posteriors summed over the two is highest. Training images are aligned to their own dstate's mean,
    which is then taken again from the aligned images; a new image is aligned to each of the
    ``candidates`` means nearest to it and kept as aligned to the one it fits best, and so is every
    training image for the second fit, its own dstate's mean taken without it.

    Why both: where look-alike dstates differ in a few beams (the paper's notched rectangle), alignment
    brings out the difference a centimetre of motion hides; where a dstate has few images (Taylor Hall: five
    each in 100), its mean is noisy and so is an alignment to it; the images as read keep that in check.
    (docs/results/noise.md has the figures, beside the despiked discriminant alone.)

    Parameters
    ----------
    width : int
        Beams in the despiking median (1: none).
    dimensions : sequence of int
        Candidate numbers of principal components of each discriminant.
    candidates : int
        The dstate means, nearest first, a new image is aligned to.
    fov_deg : float
        The images' field of view (their bearings: :func:`bootmap.surfaces.beam_angles`).
    random_state : int
        Seeds the inner folds.

    Attributes
    ----------
    as_read_, aligned_ : DespikedDiscriminant
        The two fits.
    references_ : bootmap.alignment.Reference
        Each dstate's mean of its aligned training images, in the order of ``classes_``.
    range_max_ : float
        The largest range in the training images (a beam there saw nothing).
    classes_ : ndarray

    Examples
    --------
    >>> from bootmap.surfaces import beam_angles
    >>> rng = np.random.default_rng(0)
    >>> room = np.minimum(2.0 / np.abs(np.cos(beam_angles(60))), 6.0)  # a wall 2 m ahead
    >>> notch = room + np.where(np.arange(60) == 40, 0.1, 0.0)
    >>> y = np.repeat(["S0", "S1"], 20)
    >>> X = np.where(y[:, None] == "S0", room, notch) + 0.01 * rng.standard_normal((40, 60))
    >>> AlignedDiscriminant().fit(X[::2], y[::2]).score(X[1::2], y[1::2])
    1.0
    """

    def __init__(self, width: int = 3, dimensions: Sequence[int] = (5, 10, 20, 30, 40), candidates: int = 2,
                 fov_deg: float = 180.0, random_state: int = 0):
        self.width = width
        self.dimensions = dimensions
        self.candidates = candidates
        self.fov_deg = fov_deg
        self.random_state = random_state

    def fit(self, images, dstates):
        X = despike(images, self.width)
        y = _as_labels(dstates, len(X))
        self.range_max_ = float(X.max())
        self.as_read_ = DespikedDiscriminant(1, self.dimensions, self.random_state).fit(X, y)
        self.classes_ = self.as_read_.classes_
        own, means = label_means(X, y)  # own[i]: image i's dstate, an index into classes_ (both sorted)
        aligned = Reference(means, self.fov_deg, self.range_max_).align(X, own)[0]
        means = label_means(aligned, own)[1]
        self.references_ = Reference(means, self.fov_deg, self.range_max_)
        # A training image is aligned as a new one would be, but to its own dstate's mean without it: with
        # it, the mean leans towards the image (by a fifth at five images a dstate), the aligned images of a
        # dstate lie closer together than new ones will, and the aligned discriminant is overconfident.
        counts = np.bincount(own)[own]
        without = np.where((counts > 1)[:, None],
                           (means[own] * counts[:, None] - aligned) / np.maximum(counts - 1, 1)[:, None], means[own])
        # The aligned images vary less but along the same directions: as many components as the images as
        # read chose (the inner search is most of a fit's time).
        dims = (self.as_read_.n_components_,) if self.as_read_.n_components_ else self.dimensions
        self.aligned_ = DespikedDiscriminant(1, dims, self.random_state).fit(
            self._aligned(X, (own, self.references_.nearby(without, own))), y)
        self.n_features_in_ = X.shape[1]
        return self

    @property
    def chosen_params_(self) -> dict:
        """The settings this fit chose by its inner search (the number of components), as parameters: a
        learner choosing between this and others in folds of the same images keeps them
        (:class:`ChosenByFolds`)."""
        check_is_fitted(self, "as_read_")
        n = self.as_read_.n_components_
        return {} if n is None else {"dimensions": (n,)}

    def predict(self, images) -> np.ndarray:
        """The dstate of each image."""
        check_is_fitted(self, "references_")
        X = despike(images, self.width)
        tiny = np.finfo(float).tiny  # a nearest neighbour's (too few images) probabilities are 0 or 1
        score = np.log(np.maximum(self.as_read_.model_.predict_proba(X), tiny)) + np.log(
            np.maximum(self.aligned_.model_.predict_proba(self._aligned(X)), tiny))
        return self.classes_[np.argmax(score, axis=1)]

    def _aligned(self, X: np.ndarray, own_without: tuple[np.ndarray, Reference] | None = None) -> np.ndarray:
        """Each image aligned to whichever of its ``candidates`` nearest dstate means it fits best; for
        training images (``own_without``: each one's dstate, and its dstate's mean without it, image i's
        at row i), their own dstate's mean taken without them."""
        means = self.references_.means
        nearest = np.argsort(((X[:, None, :] - means[None]) ** 2).sum(axis=2), axis=1)[:, :self.candidates]
        rows, to = np.repeat(np.arange(len(X)), nearest.shape[1]), nearest.ravel()
        aligned, residual = np.empty((len(rows), X.shape[1])), np.empty(len(rows))
        mine = np.zeros(len(rows), dtype=bool) if own_without is None else to == own_without[0][rows]
        aligned[~mine], _, residual[~mine] = self.references_.align(X[rows[~mine]], to[~mine])
        if mine.any():
            aligned[mine], _, residual[mine] = own_without[1].align(X[rows[mine]], rows[mine])
        best = np.argmin(residual.reshape(nearest.shape), axis=1)
        return aligned.reshape(len(X), nearest.shape[1], -1)[np.arange(len(X)), best]


class AlignedNearestMean(ClassifierMixin, BaseEstimator):
    """Recognise dstates by the mean image an image fits best once the stop's motion is taken out.

    Each dstate's mean of its despiked training images, refined once as :class:`AlignedDiscriminant`
    refines it (the images aligned to their own mean, the mean taken again); a new image is aligned to
    the dstate means nearest to it (:meth:`bootmap.alignment.Reference.align`) and goes to the one it fits
    with the smallest residual, over the mean's usable beams.

    Every beam counts as it is: no principal components are chosen, so a difference of a few beams (the
    paper's notch) is never projected away, and the residual of a new image against its own dstate's
    mean is the sensor's noise alone once aligned. That is the right measure where a dstate's stops lie
    within the alignment's reach of each other (a corner, walls all round); where they scatter along a
    corridor further than a stop's prior allows, what varies within a dstate outweighs what tells them
    apart, and the discriminant, which learns those directions, is better (:class:`ChosenByFolds` picks
    between them by measurement).

    Parameters
    ----------
    width : int
        Beams in the despiking median (1: none).
    candidates : int
        The dstate means, nearest to the image as read first, it is aligned to (the others differ by
        more than a stop's motion).
    fov_deg : float
        The images' field of view.

    Attributes
    ----------
    references_ : bootmap.alignment.Reference
        Each dstate's mean image, in the order of ``classes_``.
    classes_ : ndarray

    Examples
    --------
    >>> from bootmap.surfaces import beam_angles
    >>> rng = np.random.default_rng(0)
    >>> room = np.minimum(2.0 / np.abs(np.cos(beam_angles(60))), 6.0)  # a wall 2 m ahead
    >>> notch = room + np.where(np.arange(60) == 40, 0.1, 0.0)
    >>> y = np.repeat(["S0", "S1"], 20)
    >>> X = np.where(y[:, None] == "S0", room, notch) + 0.01 * rng.standard_normal((40, 60))
    >>> AlignedNearestMean().fit(X[::2], y[::2]).score(X[1::2], y[1::2])
    1.0
    """

    def __init__(self, width: int = 3, candidates: int = 3, fov_deg: float = 180.0):
        self.width = width
        self.candidates = candidates
        self.fov_deg = fov_deg

    def fit(self, images, dstates):
        X = despike(images, self.width)
        y = _as_labels(dstates, len(X))
        self.classes_ = np.unique(y)
        self.range_max_ = float(X.max())
        own, means = label_means(X, y)
        aligned = Reference(means, self.fov_deg, self.range_max_).align(X, own)[0]
        self.references_ = Reference(label_means(aligned, own)[1], self.fov_deg, self.range_max_)
        self.n_features_in_ = X.shape[1]
        return self

    def predict(self, images) -> np.ndarray:
        """The dstate of each image."""
        check_is_fitted(self, "references_")
        return self.classes_[np.argmin(self.residuals(images), axis=1)]

    def residuals(self, images) -> np.ndarray:
        """Each image's residual (m, root mean square over the usable beams) aligned to each of the
        ``candidates`` dstate means nearest to it as read, one column per dstate in the order of
        ``classes_`` (infinite for the others)."""
        X = despike(images, self.width)
        means = self.references_.means
        k = min(self.candidates, len(means))
        nearest = np.argsort(((X[:, None, :] - means[None]) ** 2).sum(axis=2), axis=1, kind="stable")[:, :k]
        out = np.full((len(X), len(means)), np.inf)
        residual = self.references_.align(np.repeat(X, k, axis=0), nearest.ravel())[2]
        np.put_along_axis(out, nearest, residual.reshape(len(X), k), axis=1)
        return out


class ChosenByFolds(ClassifierMixin, BaseEstimator):
    """Of several learners, the one that recognises its own training images best by inner folds, refitted
    on them all: model selection by measurement, inside every fit, so a test fold never takes part.

    The learners are tried on the same ``n_splits`` shuffled folds of the training images (scikit-learn's
    :class:`~sklearn.model_selection.GridSearchCV` over the choice of learner); on a tie the first one
    listed is kept. Where the training images are too few to fold (fewer than ``3 * n_splits``), the first
    learner is used as it is.

    Parameters
    ----------
    learners : sequence of estimators
        The candidates, the default first (unfitted; each is cloned).
    n_splits : int
        Inner folds.
    random_state : int
        Seeds the inner folds.

    Attributes
    ----------
    chosen_ : estimator
        The learner chosen, fitted on every training image.
    scores_ : ndarray
        Each candidate's mean accuracy on the inner folds (empty where none were made).
    classes_ : ndarray

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> y = np.repeat(["S0", "S1"], 30)
    >>> X = rng.standard_normal((60, 4)) + np.where(y == "S0", 0.0, 3.0)[:, None]
    >>> chosen = ChosenByFolds([KNeighborsClassifier(1), LinearDiscriminantAnalysis()]).fit(X, y)
    >>> type(chosen.chosen_).__name__, chosen.score(X, y) > 0.9
    ('LinearDiscriminantAnalysis', True)
    """

    def __init__(self, learners: Sequence[object] = (), n_splits: int = 3, random_state: int = 0):
        self.learners = learners
        self.n_splits = n_splits
        self.random_state = random_state

    def fit(self, images, dstates):
        if not self.learners:
            raise ValueError("ChosenByFolds needs at least one learner")
        X = as_images(images)
        y = _as_labels(dstates, len(X))
        first = clone(self.learners[0]).fit(X, y)
        self.chosen_, self.scores_ = first, np.zeros(0)
        if len(self.learners) > 1 and len(X) >= 3 * self.n_splits:
            # The first learner's own settings, where it searched for them on these images (its
            # ``chosen_params_``), are kept in the inner folds: a search nested in every fold would mostly
            # choose them again, at several times the cost.
            candidates = [clone(self.learners[0]).set_params(**getattr(first, "chosen_params_", {}))]
            candidates += [clone(m) for m in self.learners[1:]]
            inner = KFold(n_splits=self.n_splits, shuffle=True, random_state=self.random_state)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # folds without some dstate, collinear directions
                search = GridSearchCV(_Choice(), {"learner": candidates}, cv=inner, error_score=0.0,
                                      refit=False).fit(X, y)
            self.scores_ = np.asarray(search.cv_results_["mean_test_score"])
            best = int(np.argmax(self.scores_))  # the first of the best, on a tie
            if best:
                self.chosen_ = clone(self.learners[best]).fit(X, y)
        self.classes_ = self.chosen_.classes_
        self.n_features_in_ = X.shape[1]
        return self

    def predict(self, images) -> np.ndarray:
        """The dstate of each image, by the learner chosen."""
        check_is_fitted(self, "chosen_")
        return self.chosen_.predict(as_images(images))


class _Choice(ClassifierMixin, BaseEstimator):
    """One learner as a parameter, for :class:`~sklearn.model_selection.GridSearchCV` to choose among."""

    def __init__(self, learner=None):
        self.learner = learner

    def fit(self, X, y):
        self.learner_ = clone(self.learner).fit(X, y)
        self.classes_ = self.learner_.classes_
        return self

    def predict(self, X):
        return self.learner_.predict(X)


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
