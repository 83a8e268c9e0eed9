"""Cluster context of the causal links: its features against a reference, its time-by-time agglomeration, and
LinkClustering(cluster_window=...)."""

import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.base import clone
from sklearn.pipeline import Pipeline

from sklearn_radar import DopplerDensityFilter, FrameTransform
from sklearn_radar.cluster import LinkClustering
from sklearn_radar.cluster._causal_agglomeration import sequence_merges
from sklearn_radar.cluster._causal_link_features import causal_pairs
from sklearn_radar.cluster._cluster_context import CONTEXT_FEATURES, context_features, context_merges
from sklearn_radar.cluster._link_clustering import LINK_GRID, MIN_SIZE_GRID
from sklearn_radar.cluster._link_features import RIDGE, Detections
from sklearn_radar.cluster._link_training import cross_fit, fold_classifiers, positive_proba
from sklearn_radar.datasets import make_scenes

from .test_link_clustering_causal import FIXED, _scenes


def _reference(x, y, t, v, los, cluster, recent, first, i, j, now):
    """Each pair's context, from its definition: the members of the earlier end's cluster, a ridge least-squares
    velocity (numpy's solver), and the geometry."""
    out = np.empty((len(i), len(CONTEXT_FEATURES)))
    for e, (a, b) in enumerate(zip(i, j, strict=True)):
        members = recent[cluster[recent] == cluster[a]] if a < first else np.array([a])
        n = len(members)
        u = np.c_[np.cos(los[members]), np.sin(los[members])]
        mean_u = u.mean(axis=0) / np.linalg.norm(u.mean(axis=0))
        prior = v[members].mean() * mean_u
        velocity = np.linalg.solve(u.T @ u + RIDGE * np.eye(2), u.T @ v[members] + RIDGE * prior)
        residual = np.sqrt(np.mean((v[members] - u @ velocity) ** 2))
        centre = np.array([x[members].mean(), y[members].mean()]) + velocity * (now - t[members].mean())
        xs, ys = np.r_[x[members], x[b]], np.r_[y[members], y[b]]
        out[e] = (
            n,
            abs(v[b] - np.array([np.cos(los[b]), np.sin(los[b])]) @ velocity),
            residual,
            np.hypot(x[b] - centre[0], y[b] - centre[1]),
            np.hypot(np.ptp(xs), np.ptp(ys)),
            np.hypot(np.ptp(x[members]), np.ptp(y[members])),
            np.hypot(*velocity),
            now - t[members].min(),
        )
    return out


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), n_old=st.integers(1, 30), n_new=st.integers(1, 6))
def test_context_features_equal_their_definition(seed, n_old, n_new):
    rng = np.random.default_rng(seed)
    n = n_old + n_new
    x, y = rng.uniform(-10, 10, n), rng.uniform(-10, 10, n)
    t = np.r_[np.sort(rng.uniform(0, 1, n_old)), np.full(n_new, 1.2)]
    v, los = rng.normal(0, 5, n), rng.uniform(-np.pi, np.pi, n)
    cluster = np.r_[rng.integers(0, 4, n_old) * 7 + 3, np.full(n_new, -1)]  # any numbers
    recent = np.arange(n_old)
    i = np.r_[rng.integers(0, n, 12)]
    j = rng.integers(n_old, n, 12)
    i = np.minimum(i, j)
    expected = _reference(x, y, t, v, los, cluster, recent, n_old, i, j, 1.2)
    found = context_features(x, y, t, v, los, cluster, np.ones(n, dtype=bool), 0, n_old, 10.0, i, j, 1.2)
    np.testing.assert_allclose(found, expected, rtol=1e-9, atol=1e-6)  # (the RMS from sums: sqrt of a rounding)


def test_a_hand_computed_cluster():
    # Two detections of a car moving at (10, 0) m/s, seen along the x and y axes: Doppler 10 and 0.  With
    # Eq. 6's ridge (RIDGE towards the mean Doppler 5 along the mean line of sight (1, 1)/sqrt(2)), the velocity
    # solves (I + RIDGE I) V = (10, 0) + RIDGE 5 (1, 1)/sqrt(2).
    x, y = np.array([0.0, 1.0, 3.0]), np.array([0.0, 0.0, 0.0])
    t, v = np.array([0.0, 0.1, 0.2]), np.array([10.0, 0.0, 10.0])
    los = np.array([0.0, np.pi / 2, 0.0])
    node = np.ones(3, dtype=bool)
    found = context_features(x, y, t, v, los, np.array([0, 0, -1]), node, 0, 2, 1.0, [0], [2], 0.2)[0]
    velocity = (np.array([10.0, 0.0]) + RIDGE * 5 * np.array([1, 1]) / np.sqrt(2)) / (1 + RIDGE)
    assert found[0] == 2
    assert found[1] == pytest.approx(abs(10 - velocity[0]))
    assert found[3] == pytest.approx(np.hypot(3 - (0.5 + velocity[0] * 0.15), 0 - velocity[1] * 0.15))
    assert found[4] == pytest.approx(3.0) and found[5] == pytest.approx(1.0)
    assert found[6] == pytest.approx(np.hypot(*velocity)) and found[7] == pytest.approx(0.2)


def test_a_cluster_without_a_node_in_the_window_has_nan_context():
    x = y = v = los = np.zeros(2)
    t = np.array([0.0, 0.5])
    node = np.ones(2, dtype=bool)
    found = context_features(x, y, t, v, los, np.array([0, -1]), node, 0, 1, 0.1, [0], [1], 0.5)[0]
    assert found[0] == 0 and np.isnan(found[1:]).all()


def _sequence(seed):
    scenes = make_scenes(n_sequences=1, duration=2.0, difficulty="realistic", random_state=seed)
    X = Pipeline([("frame", FrameTransform()), ("filter", DopplerDensityFilter())]).fit_transform(scenes.data)
    order = np.argsort(X["t"].to_numpy(), kind="stable")
    X = X.iloc[order]
    los = (X["azimuth_sc"] + X["sensor_yaw"] + X["heading"]).to_numpy()
    d = Detections(
        *(X[c].to_numpy() for c in ("x", "y", "t", "v_r")), los, *(np.full(len(X), np.nan) for _ in range(4))
    )
    node = np.random.default_rng(seed).random(len(X)) < 0.7
    i, j = causal_pairs(d.x, d.y, d.t, node, 0, 3.0, 0.25)
    return d, node, i, j


@pytest.mark.parametrize("seed", [0, 1])
def test_links_that_ignore_the_context_merge_as_the_causal_agglomeration(seed):
    d, node, i, j = _sequence(seed)
    links = np.random.default_rng(seed).random(len(i))
    roots, sizes, context, given_back = context_merges(
        d, node, i, j, lambda rows, _context: links[rows], 0.25, 0.5, 0.5, 6.0
    )
    expected_roots, expected_sizes = sequence_merges(d.t, node, i, j, links, 0.25, 0.5, d.x, d.y, 6.0)
    np.testing.assert_array_equal(roots, expected_roots)
    np.testing.assert_array_equal(sizes, expected_sizes)
    np.testing.assert_array_equal(given_back, links)
    assert context.shape == (len(i), len(CONTEXT_FEATURES)) and (context[:, 0] >= 1).all()
    assert (context[:, 0] > 1).any()  # some pairs meet a cluster of several nodes


def test_the_context_of_a_pair_comes_from_the_past_only():
    # Links that depend on the context: the data truncated at a time gives the pairs up to it the same context.
    d, node, i, j = _sequence(2)

    def links_of(rows, context):
        return 1.0 / (1.0 + context[:, 1] + 0.1 * context[:, 3])

    _, _, context, links = context_merges(d, node, i, j, links_of, 0.25, 0.4, 0.5)
    cut = np.searchsorted(d.t, np.quantile(d.t, 0.5), side="right")
    short = Detections(*(a[:cut] for a in d))
    kept = j < cut
    _, _, early, early_links = context_merges(short, node[:cut], i[kept], j[kept], links_of, 0.25, 0.4, 0.5)
    np.testing.assert_array_equal(early, context[kept])
    np.testing.assert_array_equal(early_links, links[kept])


def test_fold_classifiers_give_cross_fit_its_out_of_fold_probabilities():
    rng = np.random.default_rng(0)
    features = [rng.normal(size=(300, 3)) for _ in range(3)]
    targets = [f[:, 0] + rng.normal(0, 0.5, len(f)) > 0 for f in features]
    folds = [np.full(len(f), k) for k, f in enumerate(features)]
    _, proba = cross_fit(features, targets, folds, 10, 0, 200, np.random.RandomState(1), out_of_fold=True)
    models = fold_classifiers(features, targets, folds, 10, 0, 200, np.random.RandomState(1))
    for k, f in enumerate(features):
        np.testing.assert_array_equal(proba[k], positive_proba(models[k], f))


# ------------------------------------------------------------------ LinkClustering(cluster_window=...)


@pytest.fixture(scope="module")
def data():
    return _scenes()


@pytest.fixture(scope="module")
def fitted(data):
    X, y = data
    return LinkClustering(**FIXED, cluster_window=0.5).fit(X, y)


def test_the_link_classifier_sees_the_context(data, fitted):
    X, _ = data
    assert list(fitted.context_feature_names_) == list(CONTEXT_FEATURES)
    n_pair = len(fitted.pair_feature_names_)
    assert fitted.link_classifier_.n_features_in_ == n_pair + len(CONTEXT_FEATURES)
    labels = fitted.predict(X)
    np.testing.assert_array_equal(labels, fitted.labels_)
    assert labels.max() >= 0 and np.all(labels[~X["keep"].to_numpy()] == -1)
    without = LinkClustering(**FIXED).fit(*data)
    assert len(without.context_feature_names_) == 0
    assert not np.array_equal(without.predict(X), labels)


def test_the_labels_do_not_depend_on_the_row_order(data, fitted):
    X, y = data
    permutation = np.random.default_rng(1).permutation(len(X))
    back = np.empty(len(X), dtype=np.int64)
    back[permutation] = fitted.predict(X.iloc[permutation])
    refit = np.empty(len(X), dtype=np.int64)
    refit[permutation] = clone(fitted).fit(X.iloc[permutation], y[permutation]).labels_
    for labels in (back, refit):
        np.testing.assert_array_equal(labels >= 0, fitted.labels_ >= 0)
        pairs = set(zip(labels.tolist(), fitted.labels_.tolist(), strict=True))
        assert len(pairs) == len(set(labels.tolist())) == len(set(fitted.labels_.tolist()))


def test_the_labels_up_to_a_time_come_from_the_past_only(data, fitted):
    X, _ = data
    labels = fitted.predict(X)
    cut = np.quantile(X["t"], 0.5)
    upto = (X["t"] <= cut).to_numpy()
    early = fitted.predict(X[upto])
    np.testing.assert_array_equal(early < 0, labels[upto] < 0)
    clustered = early >= 0
    pairs = set(zip(early[clustered].tolist(), labels[upto][clustered].tolist(), strict=True))
    assert len(pairs) == len(set(early[clustered].tolist()))


def test_fit_tunes_the_link_threshold_and_confirmation_with_the_context(monkeypatch):
    X, y = _scenes(n_sequences=2, duration=1.5, random_state=2)
    from sklearn_radar.cluster import _link_clustering

    called = []
    original = _link_clustering.tune_context
    monkeypatch.setattr(_link_clustering, "tune_context", lambda *a, **k: called.append(1) or original(*a, **k))
    model = LinkClustering(max_iter=5, causal=True, objectness_threshold=0.3, cluster_window=0.5).fit(X, y)
    assert called
    assert model.link_threshold_ in LINK_GRID and model.min_cluster_size_ in MIN_SIZE_GRID
    assert 0.0 <= model.cv_score_ <= 1.0
    np.testing.assert_array_equal(model.predict(X), model.labels_)


def test_cluster_window_requires_causal_and_a_positive_length(data):
    X, y = data
    with pytest.raises(ValueError, match="cluster_window requires causal=True"):
        LinkClustering(**{**FIXED, "causal": False, "cluster_window": 0.5}).fit(X, y)
    with pytest.raises(ValueError, match="cluster_window"):
        LinkClustering(**FIXED, cluster_window=0.0).fit(X, y)


def test_clone_pickle_and_a_model_pickled_before_cluster_window_existed(data, fitted):
    X, y = data
    restored = pickle.loads(pickle.dumps(fitted))
    np.testing.assert_array_equal(restored.predict(X), fitted.predict(X))
    assert clone(fitted).get_params()["cluster_window"] == 0.5
    plain = LinkClustering(**FIXED).fit(X, y)
    old = clone(plain)
    old.__dict__.update(plain.__dict__)
    del old.__dict__["cluster_window"], old.__dict__["context_feature_names_"]  # as pickled before it existed
    loaded = pickle.loads(pickle.dumps(old))
    assert loaded.cluster_window is None and len(loaded.context_feature_names_) == 0
    np.testing.assert_array_equal(loaded.predict(X), plain.predict(X))
