"""Views: the internal measure M, the uncertainty coefficient U, the k sweep, and the paper's view table."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bootmap.views import (ViewClusterer, internal_measure, repair_dropouts, uncertainty_coefficient,
                           view_labels, view_table)

MAX_RANGE = 8.0


def aliased_blobs(seed=0, per_dstate=15, dim=180, noise=0.02):
    """4 well-separated blobs in R^180 and 8 dstates, dstates 2j and 2j+1 sharing blob j (aliasing)."""
    rng = np.random.default_rng(seed)
    centres = rng.uniform(0.5, 5.0, (4, dim))
    dstates = np.tile(np.arange(8), per_dstate)
    images = centres[dstates // 2] + rng.normal(0, noise, (len(dstates), dim))
    return images, dstates


# --- M -----------------------------------------------------------------------------------------------

def test_internal_measure_matches_hand_computation():
    images = [[0.0, 0.0], [2.0, 0.0], [5.0, 5.0], [5.0, 7.0], [5.0, 9.0]]
    labels = ["a", "a", "b", "b", "b"]
    # a: mean (1, 0), squared distances 1, 1 -> mean 1;  b: mean (5, 7), squared distances 4, 0, 4 -> 8/3
    expected = 1.0 / (2 * (1.0 + 8.0 / 3.0))
    assert internal_measure(images, labels) == pytest.approx(expected)


def test_internal_measure_single_cluster_is_inverse_mean_squared_spread():
    images = np.array([[0.0], [4.0]])
    assert internal_measure(images, [0, 0]) == pytest.approx(1.0 / 4.0)


def test_internal_measure_of_zero_spread_clustering_is_infinite():
    assert internal_measure([[1.0, 2.0], [1.0, 2.0], [3.0, 3.0]], [0, 0, 1]) == float("inf")


def test_internal_measure_rejects_mismatched_lengths():
    with pytest.raises(ValueError):
        internal_measure([[0.0], [1.0]], [0])


# --- U -----------------------------------------------------------------------------------------------

def test_uncertainty_is_one_when_views_are_a_function_of_dstates():
    dstates = ["S0", "S1", "S2", "S3", "S0", "S1", "S2", "S3"]
    views = [{"S0": "V0", "S1": "V1", "S2": "V0", "S3": "V1"}[s] for s in dstates]
    assert uncertainty_coefficient(views, dstates) == 1.0


def test_uncertainty_is_below_one_when_a_dstate_shows_two_views():
    dstates = ["S0", "S0", "S1", "S1"]
    views = ["V0", "V1", "V2", "V2"]
    assert uncertainty_coefficient(views, dstates) < 1.0


def test_uncertainty_argument_order_is_views_given_dstates():
    # Views are a function of dstates (aliasing: two dstates, one view) ...
    dstates = ["S0", "S1", "S2", "S3"]
    views = ["V0", "V0", "V1", "V1"]
    assert uncertainty_coefficient(views, dstates) == 1.0
    # ... but not the other way round: swapped arguments give U(S|V) = 1/2.
    assert uncertainty_coefficient(dstates, views) == pytest.approx(0.5)


def test_uncertainty_of_a_single_view_is_one_by_convention():
    assert uncertainty_coefficient(["V0"] * 4, ["S0", "S1", "S2", "S3"]) == 1.0


# --- the k sweep -------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def blobs():
    return aliased_blobs()


@pytest.fixture(scope="module")
def blob_model(blobs):
    images, dstates = blobs
    return ViewClusterer(k_max=6).fit(images, dstates)


def test_sweep_picks_four_views_of_eight_aliased_dstates(blob_model, blobs):
    _, dstates = blobs
    assert blob_model.k_ == 4
    assert int(np.argmax(blob_model.internal_)) + 1 == 4
    assert blob_model.largest_k_with_u1_ == 4
    assert blob_model.uncertainty_[3] == 1.0
    assert list(blob_model.ks_) == list(range(1, 7))
    assert blob_model.cluster_centers_.shape == (4, 180)
    # each view is exactly one pair of aliased dstates
    pairs = {frozenset(dstates[blob_model.labels_ == v] // 2) for v in range(4)}
    assert pairs == {frozenset([j]) for j in range(4)}


def test_sweep_without_dstates_has_no_uncertainty(blobs):
    images, _ = blobs
    model = ViewClusterer(k_max=5).fit(images)
    assert model.uncertainty_ is None and model.largest_k_with_u1_ is None
    assert model.k_ == 4


def test_predict_gives_the_training_views(blob_model, blobs):
    images, _ = blobs
    assert np.array_equal(blob_model.predict(images), blob_model.labels_)


def test_same_random_state_gives_same_views(blobs):
    images, dstates = blobs
    a = ViewClusterer(k_max=6, n_init=3, random_state=7).fit(images, dstates)
    b = ViewClusterer(k_max=6, n_init=3, random_state=7).fit(images, dstates)
    assert np.array_equal(a.internal_, b.internal_)
    assert all(np.array_equal(a.labels_per_k_[k], b.labels_per_k_[k]) for k in a.ks_)
    assert np.array_equal(a.cluster_centers_, b.cluster_centers_)


def test_constructor_only_stores_parameters():
    model = ViewClusterer(k_max=3, n_init=2, random_state=5, max_range=8.0, method="ward")
    assert vars(model) == {"k_max": 3, "n_init": 2, "random_state": 5, "max_range": 8.0, "method": "ward"}


@pytest.mark.parametrize("method", ["kmeans", "gaussian-mixture", "ward"])
def test_every_clustering_method_finds_the_four_views_and_m_chooses_four(blobs, method):
    images, dstates = blobs
    model = ViewClusterer(k_max=6, method=method).fit(images, dstates)
    assert model.k_ == 4 and model.largest_k_with_u1_ == 4  # eight aliased dstates, four views
    # every view's centre is the mean of its images, so predict puts each training image in its view
    assert np.array_equal(model.predict(images), model.labels_)


def test_an_unknown_clustering_method_is_refused_by_name(blobs):
    with pytest.raises(ValueError, match="unknown clustering method 'dbscan'; known: kmeans"):
        ViewClusterer(method="dbscan").fit(*blobs)


def test_drop_outs_do_not_change_the_chosen_k(blobs):
    images, dstates = blobs
    rng = np.random.default_rng(1)
    dropped = images.copy()
    dropped[rng.random(dropped.shape) < 0.002] = MAX_RANGE  # a drop-out in about one image in three
    assert (dropped == MAX_RANGE).sum() > 20
    model = ViewClusterer(k_max=6, max_range=MAX_RANGE).fit(dropped, dstates)
    assert model.k_ == 4
    assert model.largest_k_with_u1_ == 4


def test_a_few_beams_that_swing_by_metres_make_m_choose_one_view():
    # Why Taylor Hall's first images gave k = 1: 8 tight views, but in each a few beams (grazing a far
    # wall, passing the edge of an opening) swing by metres between visits. M, a mean of squared
    # distances, is ruled by those beams; U still finds the 8 views.
    rng = np.random.default_rng(0)
    views = np.repeat(np.arange(8), 12)
    clean = np.repeat(rng.uniform(0.5, 8.0, (8, 180)), 12, axis=0) + rng.normal(0, 0.01, (96, 180))
    assert ViewClusterer(k_max=12).fit(clean, views).k_ == 8
    swinging = clean.copy()
    for v in range(8):
        rows, beams = np.flatnonzero(views == v), rng.choice(180, 4, replace=False)
        swinging[np.ix_(rows, beams)] += rng.normal(0, 2.0, (len(rows), 4))
    model = ViewClusterer(k_max=12).fit(swinging, views)
    assert model.k_ == 1 and model.largest_k_with_u1_ == 8


def test_repair_keeps_open_directions_and_fills_single_drop_outs():
    scan = np.array([[9.5, 9.0, 8.5, 1.0, 8.0, 1.2, 2.0, 8.0]])
    assert repair_dropouts(scan, MAX_RANGE).tolist() == [[8.0, 8.0, 8.0, 1.0, 1.1, 1.2, 2.0, 2.0]]


@settings(max_examples=40, deadline=None)
@given(st.integers(2, 30), st.integers(1, 6), st.integers(0, 2**16))
def test_m_depends_only_on_the_clusters_spread(n, dim, seed):
    # M is a property of the partition and the images' geometry: renaming the views, or moving every
    # image by the same offset, leaves it as it is; scaling the images by s divides it by s^2.
    rng = np.random.default_rng(seed)
    images = rng.normal(size=(n, dim))
    labels = rng.integers(0, 4, n)
    m = internal_measure(images, labels)
    assert m > 0
    renamed = np.array(["V%d" % ((3 * x + 1) % 4) for x in labels])
    assert internal_measure(images, renamed) == pytest.approx(m, rel=1e-9)
    assert internal_measure(images + rng.normal(size=dim) * 10, labels) == pytest.approx(m, rel=1e-6)
    assert internal_measure(images * 3.0, labels) == pytest.approx(m / 9.0, rel=1e-9)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 5), st.integers(0, 3)), min_size=1, max_size=30))
def test_u_is_1_exactly_when_every_dstate_shows_one_view(pairs):
    # U(V|S) is 1 when the dstate determines the view (aliasing allowed: many dstates, one view), or there
    # is only one view; else some dstate shows two views and U is below 1.
    dstates, views = [f"S{s}" for s, _ in pairs], [f"V{v}" for _, v in pairs]
    u = uncertainty_coefficient(views, dstates)
    determined = all(len({v for s2, v in pairs if s2 == s}) == 1 for s, _ in pairs) or len(set(views)) == 1
    assert (u == 1.0) == determined


# --- naming and the view table -----------------------------------------------------------------------

def test_views_are_numbered_by_first_appearance():
    assert view_labels([3, 3, 1, 0, 1, 3]) == ["V0", "V0", "V1", "V2", "V1", "V0"]


def test_view_table_reads_left_front_right():
    beams = np.linspace(-90, 90, 181)
    near_left = np.where(beams > 45, 0.5, np.where(beams < -45, 4.5, 2.5))
    table = view_table([near_left, near_left + 0.1, near_left[::-1]], [7, 7, 2])
    assert [r["view"] for r in table] == ["V0", "V1"]
    assert table[0]["n"] == 2
    assert table[0]["left"] == pytest.approx(0.55)
    assert table[0]["front"] == pytest.approx(2.55)
    assert table[0]["right"] == pytest.approx(4.55)
    assert (table[1]["left"], table[1]["right"]) == pytest.approx((4.5, 0.5))


# --- the real thing: simulated notched rectangle -------------------------------------------------------

PAPER_TABLE = [(0.5, 0.5, 4.5), (0.5, 4.5, 2.5), (0.5, 0.5, 2.5), (0.5, 2.5, 4.5)]


@pytest.fixture(scope="module")
def notched():
    sim = pytest.importorskip("bootmap.sim")
    t = sim.simulate("notched_rectangle", policy="circuits", circuits=10, seed=1)
    images = np.array([s.image for s in t.steps], dtype=float)
    dstates = [s.truth for s in t.steps]
    return images, dstates, ViewClusterer(k_max=12, max_range=MAX_RANGE).fit(images, dstates)


def test_notched_rectangle_four_views_have_u_one(notched):
    _, _, model = notched
    assert model.uncertainty_[3] == 1.0


def test_notched_rectangle_view_table_matches_paper(notched):
    images, _, model = notched
    table = view_table(images, model.labels_per_k_[4])
    found = [np.array([r["left"], r["front"], r["right"]]) for r in table]
    assert len(found) == 4
    # up to renaming: every paper view is within 0.25 m of exactly one found view
    close = np.array([[np.abs(f - np.array(want)).max() <= 0.25 for f in found] for want in PAPER_TABLE])
    assert close.sum(axis=0).tolist() == [1, 1, 1, 1] and close.sum(axis=1).tolist() == [1, 1, 1, 1]
    assert table[0]["view"] == "V0"  # the first image (P0 heading north) is the paper's V0


def test_notched_rectangle_m_picks_four_and_four_is_largest_k_with_u_one(notched):
    _, _, model = notched
    assert model.k_ == 4
    assert model.largest_k_with_u1_ == 4


def test_dropout_runs_are_filled_from_look_alikes_and_open_directions_kept():
    # Four dstates seen ten times each; one image loses a run of three beams on a wall, another a run of
    # five; every visit of dstate 2 is open (max range) over beams 40-60, which must stay open.
    from bootmap.views import repair_dropouts

    rng = np.random.default_rng(11)
    beams = np.linspace(0, np.pi, 90)
    shapes = np.array([2.5 + np.sin(3 * beams + phase) for phase in rng.uniform(0, 6, 4)])  # smooth walls
    shapes[2, 40:60] = 8.0
    images = np.repeat(shapes, 10, axis=0) + rng.normal(0, 0.01, (40, 90))
    images[20:30, 40:60] = 8.0  # nothing within range: every beam reads the maximum
    broken = images.copy()
    broken[3, 10:13] = 8.0
    broken[15, 70:75] = 8.0
    fixed = repair_dropouts(broken, 8.0)
    assert np.abs(fixed[3, 10:13] - shapes[0, 10:13]).max() < 0.05
    assert np.abs(fixed[15, 70:75] - shapes[1, 70:75]).max() < 0.05
    assert (fixed[20:30, 40:60] == 8.0).all()  # the open direction of every visit of dstate 2
    untouched = np.ones(40, dtype=bool)
    untouched[[3, 15]] = False
    assert np.array_equal(fixed[untouched], np.minimum(broken, 8.0)[untouched])
