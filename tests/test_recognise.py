"""Recognition of dstates from images: the online curve, shuffled CV curves, comparisons, the paper's ~90%."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.base import clone
from sklearn.discriminant_analysis import LinearDiscriminantAnalysis
from sklearn.model_selection import KFold
from sklearn.neighbors import KNeighborsClassifier, NearestCentroid

from bootmap.learners import AlignedDiscriminant, AlignedNearestMean, ChosenByFolds, DespikedDiscriminant
from bootmap.recognise import (Recogniser, compare_clusterers, compare_learners, default_learners, learning_curve_cv,
                               online_curve, online_hits)


def blobs(n_per=30, n_states=8, dim=180, spread=1.0, seed=0, order="circuits"):
    """Gaussian blobs in R^dim, one per dstate; pairs (0,1), (2,3), ... are close together.

    order="circuits" records dstate 0, 1, ..., n_states-1, 0, 1, ... (as the robot does);
    order="sorted" records all images of dstate 0, then all of dstate 1, ...
    """
    rng = np.random.default_rng(seed)
    centres = rng.normal(scale=3.0, size=(n_states, dim))
    centres[1::2] = centres[0::2] + rng.normal(scale=1.0, size=(n_states // 2, dim))  # close pairs
    if order == "circuits":
        y = np.tile(np.arange(n_states), n_per)
    else:
        y = np.repeat(np.arange(n_states), n_per)
    X = centres[y] + rng.normal(scale=spread, size=(len(y), dim))
    drop = rng.random(X.shape) < 0.002  # laser drop-outs at max range
    X[drop] = 8.0
    return X, y


def brute_online_hits(X, y):
    hits = [False]
    for i in range(1, len(X)):
        d = np.linalg.norm(X[:i] - X[i], axis=1)
        hits.append(y[np.argmin(d)] == y[i])
    return np.array(hits)


# -- online curve ------------------------------------------------------------------------------------

def test_online_1nn_equals_brute_force_reference():
    X, y = blobs(n_per=8, dim=20, spread=3.0, seed=3)
    np.testing.assert_array_equal(online_hits(X, y), brute_online_hits(X, y))


def test_online_1nn_fast_path_equals_refitted_sklearn():
    X, y = blobs(n_per=6, dim=30, spread=3.0, seed=4)
    fast = online_hits(X, y)
    slow = online_hits(X, y, make_learner=lambda: KNeighborsClassifier(1), stride=1)
    np.testing.assert_array_equal(fast, slow)


def test_online_1nn_blocked_distance_matrix_spans_blocks(monkeypatch):
    import bootmap.recognise as rec

    X, y = blobs(n_per=5, dim=10, spread=3.0, seed=5)
    monkeypatch.setattr(rec, "_BLOCK", 7)
    np.testing.assert_array_equal(online_hits(X, y), brute_online_hits(X, y))


def test_online_curve_first_image_is_a_miss_and_curve_rises():
    X, y = blobs(n_per=40, spread=1.0)
    curve = online_curve(X, y)
    assert curve[0] == 0.0
    assert curve.shape == (len(y),)
    assert curve[20] < curve[-1]
    assert curve[-1] > 0.9  # only the first image of each dstate must be missed
    windowed = online_curve(X, y, window=50)
    assert windowed[-1] == pytest.approx(1.0)


def test_online_curve_window_is_trailing_mean_of_hits():
    X, y = blobs(n_per=10, dim=20, spread=4.0, seed=6)
    hits = online_hits(X, y).astype(float)
    w = online_curve(X, y, window=5)
    expected = [hits[max(0, i - 4):i + 1].mean() for i in range(len(hits))]
    np.testing.assert_allclose(w, expected)


def test_online_general_learner_with_stride_never_sees_the_future():
    X, y = blobs(n_per=10, seed=7)
    hits = online_hits(X, y, make_learner=lambda: KNeighborsClassifier(1), stride=16)
    assert not hits[:8].any()  # images 1..7 predicted from image 0 alone (only dstate 0 seen)
    assert hits[-40:].mean() > 0.9


def test_online_rejects_nan_and_reads_inf_as_dropout():
    X, y = blobs(n_per=4, dim=10)
    X[3, 2] = np.inf
    assert online_hits(X, y).shape == (len(y),)
    X[3, 2] = np.nan
    with pytest.raises(ValueError, match="nan"):
        online_hits(X, y)


# -- cross-validated curves --------------------------------------------------------------------------

def test_cv_curve_rises_and_is_deterministic():
    X, y = blobs(n_per=25, spread=2.0)
    a = learning_curve_cv(X, y, sizes=(10, 30, 90), random_state=1)
    b = learning_curve_cv(X, y, sizes=(10, 30, 90), random_state=1)
    np.testing.assert_array_equal(a.scores, b.scores)
    other = learning_curve_cv(X, y, sizes=(10, 30, 90), random_state=2)  # other folds, other subsets
    assert not np.array_equal(a.scores, other.scores)
    assert a.sizes.tolist() == [10, 30, 90]
    assert a.scores.shape == (3, 10)
    assert a.at(10) < a.at(90)
    assert a.at(90) > 0.9


@pytest.mark.parametrize("learner", [None, DespikedDiscriminant(), AlignedDiscriminant()], ids=["1-NN", "despiked", "aligned"])
@pytest.mark.parametrize("seed", [0, 3])
def test_the_curve_scores_the_folds_as_scikit_learns_learning_curve(learner, seed):
    # The same folds, the same shuffled training subsets, the same test scores (without scoring every model
    # on its own training images, which scikit-learn's function does too).
    from sklearn.model_selection import KFold, learning_curve

    X, y = blobs(n_per=15, dim=40, spread=2.0, seed=seed)
    ours = learning_curve_cv(X, y, sizes=(10, 50, 90), learner=learner, random_state=seed)
    _, _, theirs = learning_curve(learner or KNeighborsClassifier(1), X, y, train_sizes=[10, 50, 90],
                                  cv=KFold(10, shuffle=True, random_state=seed), scoring="accuracy",
                                  shuffle=True, random_state=seed)
    np.testing.assert_array_equal(ours.scores, theirs)
    assert ours.sizes.tolist() == [10, 50, 90] and ours.fit_times.shape == (3, 10)


def test_cv_shuffling_matters_on_data_recorded_dstate_by_dstate():
    """Sorted by dstate, the first 30 images are all dstate 0 and 1: unshuffled prefixes would score
    about 2/8; the shuffled curve sees every dstate."""
    from sklearn.model_selection import KFold, learning_curve

    X, y = blobs(n_per=25, spread=1.0, order="sorted")
    shuffled = learning_curve_cv(X, y, sizes=(30,), random_state=0).at(30)
    _, _, test_scores = learning_curve(KNeighborsClassifier(1), X, y, train_sizes=[30],
                                       cv=KFold(10, shuffle=True, random_state=0), shuffle=False)
    prefix = test_scores.mean()
    assert shuffled > 0.9
    assert prefix < 0.5


def test_cv_sizes_beyond_training_folds_are_dropped():
    X, y = blobs(n_per=5)  # 40 images: training folds of 36
    curve = learning_curve_cv(X, y, sizes=(10, 36, 90))
    assert curve.sizes.tolist() == [10, 36]


# -- comparisons -------------------------------------------------------------------------------------

@pytest.mark.slow
def test_compare_learners_scores_every_learner_and_more_images_help():
    X, y = blobs(n_per=15, dim=40, spread=2.0)
    rows = compare_learners(X, y, at=(30, 90))
    assert [r["learner"] for r in rows] == ["1-NN", "3-NN", "logistic", "linear SVM", "RBF SVM", "MLP (32)",
                                          "despiked LDA", "aligned LDA", "aligned mean", "aligned by folds"]
    for r in rows:
        assert {"learner", "sizes", "accuracy", "accuracy_std", "fit_time",
                "acc@30", "acc@90"} <= r.keys()
        assert r["sizes"] == [30, 90] and "acc@60" not in r
        assert r["accuracy"] == [r["acc@30"], r["acc@90"]]
        # 8 dstates in 4 close pairs: telling only the pairs apart would score 1/2; every learner tells
        # the close dstates apart too, and better from 90 images than from 30. (The nearest aligned mean
        # reads the numbers as a laser's ranges, moving them as a stop's motion would: these blobs, some of
        # them negative, are no scans, and it is only asked to learn.)
        assert r["acc@90"] > r["acc@30"], r
        assert r["acc@90"] > 0.5 or r["learner"] == "aligned mean", r
    # fit_time times the fit: the grid-searched learners (15 settings x 3 folds) take longer than
    # nearest neighbour, which only stores the images.
    fit_at_90 = {r["learner"]: r["fit_time"][-1] for r in rows}
    assert 0 < fit_at_90["1-NN"] < min(fit_at_90["RBF SVM"], fit_at_90["MLP (32)"])
    # Seeded throughout, grid searches included: the same answer again (checked on two of them, at one
    # size, to keep the test quick), and another from another seed (other folds and training subsets).
    def at_30(seed, names):
        learners = {k: v for k, v in default_learners(seed).items() if k in names}
        return [r["accuracy"][0] for r in compare_learners(X, y, at=(30,), random_state=seed, learners=learners)]

    assert [r["accuracy"][0] for r in rows if r["learner"] in ("1-NN", "RBF SVM")] == pytest.approx(
        at_30(0, ("1-NN", "RBF SVM")))
    assert at_30(1, ("1-NN",)) != pytest.approx([r["accuracy"][0] for r in rows if r["learner"] == "1-NN"])


@pytest.mark.filterwarnings("ignore::sklearn.exceptions.ConvergenceWarning")
def test_rbf_svm_and_mlp_choose_their_settings_by_grid_search_inside_the_fit():
    from sklearn.model_selection import GridSearchCV

    learners = default_learners()
    X, y = blobs(n_per=10, dim=20, spread=1.0)
    for name in ("RBF SVM", "MLP (32)"):
        assert isinstance(learners[name], GridSearchCV)
        fitted = learners[name].fit(X[:60], y[:60])
        assert fitted.best_params_ and fitted.score(X[60:], y[60:]) > 0.5


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31), n=st.integers(4, 60), k=st.integers(2, 5), spread=st.floats(0.2, 3.0))
def test_the_learner_chosen_by_folds_is_the_best_on_the_inner_folds_refitted_on_every_image(seed, n, k, spread):
    rng = np.random.default_rng(seed)
    y = np.arange(n) % k
    X = rng.standard_normal((n, 6)) * spread + 2.0 * (y[:, None] == np.arange(6) % k)
    learners = [KNeighborsClassifier(5), KNeighborsClassifier(1), LinearDiscriminantAnalysis()]
    model = ChosenByFolds(learners, random_state=seed % 5).fit(X, y)
    if n < 9:  # too few to fold: the first learner, as it is
        assert model.scores_.size == 0 and model.chosen_.get_params() == learners[0].get_params()
        return
    # The candidates scored on the same three inner folds, by hand; the first of the best is chosen.
    folds = KFold(n_splits=3, shuffle=True, random_state=seed % 5)
    by_hand = []
    for learner in learners:
        hits = []
        for train, test in folds.split(X):
            try:
                hits.append(np.mean(clone(learner).fit(X[train], y[train]).predict(X[test]) == y[test]))
            except ValueError:  # a fold too small for the learner scores nothing
                hits.append(0.0)
        by_hand.append(np.mean(hits))
    assert model.scores_ == pytest.approx(by_hand)
    best = learners[int(np.argmax(by_hand))]
    assert type(model.chosen_) is type(best) and model.chosen_.get_params() == best.get_params()
    # ... refitted on every image: it predicts as that learner fitted on them all.
    probe = rng.standard_normal((20, 6)) * spread
    assert model.predict(probe).tolist() == clone(best).fit(X, y).predict(probe).tolist()


def test_the_aligned_nearest_mean_takes_out_a_stops_motion_before_comparing():
    # Two rooms that differ in one beam's 10 cm notch, each image read after a stop a few centimetres and
    # a degree off: the nearest mean as read confuses them, aligned it does not.
    from bootmap.alignment import reproject
    from bootmap.surfaces import beam_angles

    rng = np.random.default_rng(3)
    room = np.minimum(2.0 / np.abs(np.cos(beam_angles(90))), 6.0)
    notch = room + np.where(np.arange(90) == 60, 0.1, 0.0)
    y = np.repeat(["S0", "S1"], 40)
    poses = rng.normal(0.0, [0.02, 0.02, np.radians(1.0)], (80, 3))
    X = reproject(np.where(y[:, None] == "S0", room, notch), poses) + 0.005 * rng.standard_normal((80, 90))
    train, test = np.arange(80) % 2 == 0, np.arange(80) % 2 == 1
    aligned = AlignedNearestMean().fit(X[train], y[train])
    as_read = NearestCentroid().fit(X[train], y[train])
    assert aligned.score(X[test], y[test]) >= 0.95 > as_read.score(X[test], y[test]) + 0.1
    assert aligned.residuals(X[test]).shape == (40, 2)


def test_compare_clusterers_scores_views_against_dstates():
    X, y = blobs(n_per=15, dim=40, spread=0.5)
    rows = compare_clusterers(X, y, k=4, random_state=0)
    assert [r["clusterer"] for r in rows] == ["k-means", "Gaussian mixture (diag)", "agglomerative (ward)"]
    for r in rows:
        assert {"clusterer", "k", "U", "ari", "fit_time"} <= r.keys()
        assert r["U"] == 1.0  # close pairs merge: each dstate in one view
        assert 0.0 < r["ari"] < 1.0  # 4 views for 8 dstates
    # One view per dstate: every clusterer finds the 8 dstates themselves.
    for r in compare_clusterers(X, y, k=8, random_state=0):
        assert (r["k"], r["U"], r["ari"]) == (8, 1.0, pytest.approx(1.0)), r


# -- the estimator -----------------------------------------------------------------------------------

def test_recogniser_predicts_dstates_and_distance_to_nearest_image():
    X, y = blobs(n_per=10, dim=20, spread=0.5)
    r = Recogniser().fit(X, y)
    labels, dist = r.predict_with_distance(X[:5])
    np.testing.assert_array_equal(labels, y[:5])
    np.testing.assert_allclose(dist, 0.0, atol=1e-5)
    far = X[:1] + 100.0
    _, d = r.predict_with_distance(far)
    np.testing.assert_allclose(d[0], np.linalg.norm(X - far, axis=1).min(), rtol=1e-5)  # the nearest image
    assert r.score(X, y) == 1.0


def test_recogniser_unfitted_raises():
    from sklearn.exceptions import NotFittedError

    with pytest.raises(NotFittedError):
        Recogniser().predict(np.zeros((1, 3)))


# -- the paper's result, on the simulator ------------------------------------------------------------

@pytest.fixture(scope="module")
def notched_15():
    sim = pytest.importorskip("bootmap.sim")
    t = sim.simulate("notched_rectangle", policy="circuits", circuits=15, seed=1)
    X = np.array([s.image for s in t.steps])
    y = np.array([s.truth for s in t.steps])
    return X, y


def test_notched_rectangle_online_1nn_about_90_percent_after_90_images():
    # The paper's online protocol: predict each image's dstate from all earlier ones, then store it.
    # Once 90 images are stored, the next ones are recognised about 90% of the time. (The cumulative
    # curve at 90 is lower: it counts the unavoidable miss at the first sight of every dstate.) Scored
    # over the 110 images after the 90th: over 30 images, one seed's rate swings by +-0.1 by luck.
    sim = pytest.importorskip("bootmap.sim")
    t = sim.simulate("notched_rectangle", policy="circuits", circuits=25, seed=1)
    X, y = np.array([s.image for s in t.steps]), np.array([s.truth for s in t.steps])
    hits = online_hits(X, y)
    assert len(y) == 200
    assert hits[90:].mean() >= 0.85


def test_notched_rectangle_cv_curve_at_90_images(notched_15):
    # The paper's Figure 4: 10-fold cross-validated learning curve, about 90% at 90 images.
    X, y = notched_15
    curve = learning_curve_cv(X, y, sizes=(10, 30, 90), random_state=0)
    assert curve.at(90) >= 0.85


def test_notched_rectangle_recognition_beats_views_alone_and_learns(notched_15):
    """Whatever the notch, images tell the 4 views apart (1/2 of dstates), and more images help."""
    X, y = notched_15
    assert online_curve(X, y)[89] > 0.5
    curve = learning_curve_cv(X, y, sizes=(10, 30, 90), random_state=0)
    assert curve.at(10) < curve.at(90)
    assert curve.at(90) > 0.5
