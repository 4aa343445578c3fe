"""Recognition under a noisier laser: the despiked and aligned learners beside the paper's nearest neighbour, and
the choice between them by folds."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
import warnings

from sklearn.decomposition import PCA
from sklearn.discriminant_analysis import LinearDiscriminantAnalysis
from sklearn.model_selection import GridSearchCV, KFold
from sklearn.pipeline import make_pipeline
from threadpoolctl import threadpool_limits

from bootmap.learners import (AlignedDiscriminant, AlignedNearestMean, DespikedDiscriminant, components_by_folds,
                              despike)
from bootmap.recognise import default_learners, learning_curve_cv
from bootmap.sim import simulate
from bootmap.sim.world import load_world


@settings(max_examples=100, deadline=None)
@given(seed=st.integers(0, 2**31), n_beams=st.integers(8, 60), spikes=st.integers(1, 4))
def test_despiking_removes_isolated_drop_outs_and_keeps_the_rest_within_its_neighbours(seed, n_beams, spikes):
    rng = np.random.default_rng(seed)
    scan = 1.0 + np.cumsum(0.05 * rng.standard_normal(n_beams))  # a smooth wall, read with noise
    dropped = scan.copy()
    at = rng.choice(np.arange(1, n_beams - 1, 3), size=min(spikes, len(range(1, n_beams - 1, 3))), replace=False)
    dropped[at] = 8.0  # isolated drop-outs, read at maximum range
    out = despike([dropped])[0]
    assert out.max() < 8.0  # every drop-out is gone
    # Each beam lies among the wall's own readings around it (the drop-outs' beams included).
    for i in range(n_beams):
        around = scan[max(0, i - 2): i + 3]
        assert around.min() - 1e-12 <= out[i] <= around.max() + 1e-12


def _four_times_the_laser_noise(world: str, seed: int, **how):
    """Images and true dstates of a run with the laser's range noise and drop-outs four times the shipped."""
    spec = load_world(world, {"laser.noise_sd": 0.04, "laser.dropout": 0.004})
    tableau = simulate(spec, seed=seed, **how)
    return np.array([s.image for s in tableau.steps]), [s.truth for s in tableau.steps]


def _at_90(images, truth, learner=None) -> float:
    with threadpool_limits(1):  # small matrices: BLAS threads only wait on each other when a core is busy
        return learning_curve_cv(images, truth, sizes=(90,), learner=learner).at(90)


def test_with_four_times_the_laser_noise_in_the_paper_room_the_aligned_learners_recognise_the_notch():
    # The paper's room, with its laser's range noise and drop-outs four times the shipped ones: images of
    # diagonally opposite corners differ only where the 10 cm notch shows, under 4 cm of noise per beam,
    # and where a centimetre of the robot's stopping pose moves a corner across a beam: aligning each image
    # to the dstates' means takes that motion out. The corners' stops lie within an alignment's reach, and
    # the nearest aligned mean, which keeps every beam, sees the notch best; the folds choose it.
    images, truth = _four_times_the_laser_noise("notched_rectangle", 11, circuits=50)
    nn, despiked = _at_90(images, truth), _at_90(images, truth, DespikedDiscriminant())
    aligned, mean = _at_90(images, truth, AlignedDiscriminant()), _at_90(images, truth, AlignedNearestMean())
    chosen = _at_90(images, truth, default_learners()["aligned by folds"])
    assert despiked >= nn + 0.05, (despiked, nn)
    assert aligned >= despiked + 0.03, (aligned, despiked)
    assert mean >= aligned + 0.02, (mean, aligned)
    assert chosen >= aligned + 0.02, (chosen, aligned)


def test_in_taylor_hall_where_stops_scatter_along_corridors_the_folds_choose_the_discriminant():
    # Along a corridor the walls do not fix where the robot stops, and a dstate's images differ by more
    # than an alignment's prior allows: the nearest aligned mean goes astray, the discriminant weighs those
    # directions by how much they vary within a dstate, and the folds tell which is which.
    images, truth = _four_times_the_laser_noise("taylor_hall", 11, policy="explore", steps=100)
    aligned, mean = _at_90(images, truth, AlignedDiscriminant()), _at_90(images, truth, AlignedNearestMean())
    chosen = _at_90(images, truth, default_learners()["aligned by folds"])
    assert aligned >= mean + 0.15, (aligned, mean)
    assert chosen >= aligned - 0.01, (chosen, aligned)


def test_the_number_of_components_is_chosen_on_the_training_images_and_fits_small_sets():
    rng = np.random.default_rng(0)
    y = np.repeat(np.arange(5), 4)
    X = 2.0 + 0.05 * rng.standard_normal((20, 50)) + 0.2 * y[:, None] * (np.arange(50) < 5)
    model = DespikedDiscriminant().fit(X, y)
    assert model.n_components_ in (5, 10) and model.score(X, y) == 1.0
    tiny = DespikedDiscriminant().fit(X[:4], y[:4])  # fewer images than any candidate needs
    assert tiny.n_components_ <= 3 and tiny.predict(X[:4]).tolist() == y[:4].tolist()


def test_with_no_dstate_seen_twice_the_nearest_despiked_image_decides():
    # A learning curve's first point can hold fewer images than dstates: the discriminant is undefined
    # there, and the learner still answers.
    X = np.array([[1.0, 1.0, 8.0, 1.0], [2.0, 2.0, 2.0, 2.0], [3.0, 8.0, 3.0, 3.0]])
    model = DespikedDiscriminant().fit(X, ["S0", "S1", "S2"])
    assert model.n_components_ is None
    assert model.predict([[1.1, 1.0, 1.0, 1.0], [3.0, 2.9, 3.0, 3.0]]).tolist() == ["S0", "S2"]
    aligned = AlignedDiscriminant().fit(X, ["S0", "S1", "S2"])  # each image its dstate's mean
    assert aligned.predict([[1.1, 1.0, 1.0, 1.0], [3.0, 2.9, 3.0, 3.0]]).tolist() == ["S0", "S2"]


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31), n=st.integers(15, 80), k=st.integers(2, 8), spread=st.floats(0.0, 1.0))
def test_the_components_chosen_by_folds_are_a_grid_searchs(seed, n, k, spread):
    # One decomposition per fold gives the choice a grid search over PCA(d) + discriminant makes.
    rng = np.random.default_rng(seed)
    y = rng.integers(0, k, n)
    X = 0.5 * rng.standard_normal((n, 40)) + spread * (y[:, None] == np.arange(40) % k)
    dims = [d for d in (5, 10, 20, 30, 40) if d <= 2 * n // 3 - 1]
    folds = KFold(n_splits=3, shuffle=True, random_state=seed % 7)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        search = GridSearchCV(make_pipeline(PCA(svd_solver="full"), LinearDiscriminantAnalysis()),
                              {"pca__n_components": dims}, cv=folds, error_score=0.0).fit(X, y)
    assert components_by_folds(X, y, dims, folds) == search.best_params_["pca__n_components"]
