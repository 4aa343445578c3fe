"""The learners that recognise dstates from noisy laser images, beyond the paper's nearest neighbour: small
scikit-learn estimators (fit/predict, parameters in the constructor, results as attributes).

- :class:`DespikedDiscriminant`: drop-outs removed (:func:`despike`), principal components, linear
  discriminant analysis.
- :class:`AlignedDiscriminant`: the same on the images as read and on the images aligned to the nearest
  dstates' mean images (:mod:`bootmap.alignment`), which takes out the small motion between stops.
- :class:`AlignedNearestMean`: the dstate mean an image fits best once aligned to it, every beam kept.
- :class:`ChosenByFolds`: of several learners, the one that recognises the training images best on inner
  folds (the experiment's learner chooses so between the last two).

:mod:`bootmap.recognise` scores them (learning curves, comparisons); docs/results/noise.md has the figures.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin, clone
from sklearn.decomposition import PCA
from sklearn.discriminant_analysis import LinearDiscriminantAnalysis
from sklearn.model_selection import GridSearchCV, KFold
from sklearn.neighbors import KNeighborsClassifier
from sklearn.pipeline import make_pipeline
from sklearn.utils.validation import check_is_fitted

from .alignment import Reference
from .images import as_images, as_labels
from .views import label_means

__all__ = ["AlignedDiscriminant", "AlignedNearestMean", "ChosenByFolds", "DespikedDiscriminant", "components_by_folds",
           "despike"]


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
        y = as_labels(dstates, len(X))
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
        y = as_labels(dstates, len(X))
        self.range_max_ = float(X.max())
        self.as_read_ = DespikedDiscriminant(1, self.dimensions, self.random_state).fit(X, y)
        self.classes_ = self.as_read_.classes_
        own, aligned, self.references_ = _refined_means(X, y, self.fov_deg, self.range_max_)
        means = self.references_.means
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
        nearest = _nearest_means(X, self.references_.means, self.candidates)
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
        y = as_labels(dstates, len(X))
        self.classes_ = np.unique(y)
        self.range_max_ = float(X.max())
        self.references_ = _refined_means(X, y, self.fov_deg, self.range_max_)[2]
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
        nearest = _nearest_means(X, means, self.candidates)
        k = nearest.shape[1]
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
        y = as_labels(dstates, len(X))
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


def _refined_means(X: np.ndarray, y: np.ndarray, fov_deg: float, range_max: float
                   ) -> tuple[np.ndarray, np.ndarray, Reference]:
    """Each dstate's mean image, refined once: the images aligned to their own dstate's mean, and the mean
    taken again from them. Returns each image's dstate (an index into the sorted labels), the images so
    aligned, and the refined means ready to align to."""
    own, means = label_means(X, y)
    aligned = Reference(means, fov_deg, range_max).align(X, own)[0]
    return own, aligned, Reference(label_means(aligned, own)[1], fov_deg, range_max)


def _nearest_means(X: np.ndarray, means: np.ndarray, k: int) -> np.ndarray:
    """For each image, the indices of the ``k`` means nearest to it as read (Euclidean), nearest first."""
    return np.argsort(((X[:, None, :] - means[None]) ** 2).sum(axis=2), axis=1, kind="stable")[:, :k]
