"""LinkClustering(causal=True): features from the past only, the same pairs, the time-by-time agglomeration."""

import pickle

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.base import clone
from sklearn.pipeline import Pipeline

from sklearn_radar import DopplerDensityFilter, FrameTransform, instance_target
from sklearn_radar.cluster import LinkClustering
from sklearn_radar.cluster._causal_agglomeration import confirmed_roots, new_state, sequence_merges, step
from sklearn_radar.cluster._causal_link_features import causal_detection_features, causal_pairs
from sklearn_radar.cluster._link_clustering import LINK_GRID, MIN_SIZE_GRID, OBJECTNESS_GRID
from sklearn_radar.cluster._link_features import Detections, detection_features, pairs_within
from sklearn_radar.datasets import make_scenes

#: Fixed thresholds (no tuning): the cheap configuration.
FIXED = {"link_threshold": 0.5, "objectness_threshold": 0.3, "min_cluster_size": 3, "max_iter": 10, "causal": True}


def _same_partition(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return len(set(zip(a.tolist(), b.tolist(), strict=True))) == len(set(a.tolist())) == len(set(b.tolist()))


def _random_detections(n, rng, times=12):
    t = np.sort(rng.integers(0, times, n) * 0.04)
    return Detections(
        x=rng.uniform(0, 8, n),
        y=rng.uniform(0, 8, n),
        t=t,
        v=rng.normal(0, 3, n),
        los=rng.uniform(-np.pi, np.pi, n),
        rcs=rng.normal(0, 5, n),
        range=rng.uniform(5, 80, n),
        sensor=rng.integers(1, 5, n).astype(float),
        ego=np.full(n, 8.0),
    )


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**16), st.integers(1, 120))
def test_causal_features_are_the_offline_features_of_the_data_truncated_at_each_time(seed, n):
    # The reference: the offline (past and future) features computed on the detections up to each time; for the
    # detections of that last time, their whole neighbourhood is then the past.
    d = _random_detections(n, np.random.default_rng(seed))
    features, local = causal_detection_features(d)
    for time in np.unique(d.t):
        upto = d.t <= time
        truncated = Detections(*(values[upto] for values in d))
        expected, expected_local = detection_features(truncated)
        last = truncated.t == time
        np.testing.assert_allclose(features[upto][last], expected[last], rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(local.vx[upto][last], expected_local.vx[last], rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(local.count[upto][last], expected_local.count[last])


def test_features_from_a_start_are_those_of_the_whole_run():
    # The online path computes the new scan's features against a window of the past: the same numbers.
    d = _random_detections(200, np.random.default_rng(3), times=40)
    whole, whole_local = causal_detection_features(d)
    start = int(np.searchsorted(d.t, d.t[120]))
    tail, tail_local = causal_detection_features(d, start)
    np.testing.assert_array_equal(tail, whole[start:])
    np.testing.assert_array_equal(tail_local.vx, whole_local.vx[start:])


@settings(max_examples=50, deadline=None)
@given(st.integers(0, 2**16), st.integers(0, 80), st.sampled_from([0.0, 0.04, 0.25]), st.sampled_from([1.0, 3.0]))
def test_causal_pairs_are_the_offline_pairs_in_arrival_order(seed, n, window, radius):
    rng = np.random.default_rng(seed)
    d = _random_detections(n, rng)
    node = rng.random(n) < 0.7
    i, j = causal_pairs(d.x, d.y, d.t, node, 0, radius, window)
    ref_i, ref_j = pairs_within(d.x, d.y, d.t, radius, window, node)
    assert set(zip(i.tolist(), j.tolist(), strict=True)) == set(zip(ref_i.tolist(), ref_j.tolist(), strict=True))
    assert len(i) == len(ref_i)
    assert np.all(np.diff(j * (n + 1) + i) > 0)  # in the order of j, then i
    start = n // 2
    later = j >= start
    tail_i, tail_j = causal_pairs(d.x, d.y, d.t, node, start, radius, window)
    np.testing.assert_array_equal(tail_i, i[later])
    np.testing.assert_array_equal(tail_j, j[later])


def test_the_causal_merges_worked_by_hand():
    # Nodes 0, 1 at 0 s; 2 at 0.1 s; 3 at 0.2 s; 4 at 0.6 s; pair window 0.25 s, threshold 0.5.
    #   0 s: (0, 1) 0.9 -> {0, 1}.
    #   0.1 s: (0, 2) 0.2, (1, 2) 0.3: mean 0.25 -> 2 alone.
    #   0.2 s: (0, 3) 0.8, (1, 3) 0.9, (2, 3) 0.9.  Means: {0,1}-3 0.85, 2-3 0.9: 3 joins 2 (the older);
    #          then {0,1}-{2,3}: (0.2 + 0.3 + 0.8 + 0.9) / 4 = 0.55 > 0.5: the old clusters merge, 0 survives.
    #   0.6 s: node 4, no pair; cluster 0 (last node at 0.2 s) retires.
    t = np.array([0.0, 0.0, 0.1, 0.2, 0.6])
    node = np.ones(5, dtype=bool)
    i = np.array([0, 0, 1, 0, 1, 2])
    j = np.array([1, 2, 2, 3, 3, 3])
    links = np.array([0.9, 0.2, 0.3, 0.8, 0.9, 0.9])
    roots, sizes = sequence_merges(t, node, i, j, links, 0.25, 0.5)
    np.testing.assert_array_equal(roots, [0, 0, 0, 0, 4])
    np.testing.assert_array_equal(sizes, [2, 2, 1, 4, 1])
    np.testing.assert_array_equal(confirmed_roots(roots, sizes, 2), [0, 0, -1, 0, -1])
    # The same, step by step: the merges in order, the older survives, and the retired cluster is forgotten.
    state = new_state()
    step(state, 0.0, [0, 1], [0], [1], [0.9], 0.25, 0.5)
    clusters, counts, child, survivor = step(state, 0.1, [2], [0, 1], [2, 2], [0.2, 0.3], 0.25, 0.5)
    assert clusters.tolist() == [2] and counts.tolist() == [1] and len(child) == 0
    clusters, counts, child, survivor = step(state, 0.2, [3], [0, 1, 2], [3, 3, 3], [0.8, 0.9, 0.9], 0.25, 0.5)
    assert clusters.tolist() == [0] and counts.tolist() == [4]
    assert list(zip(child.tolist(), survivor.tolist(), strict=True)) == [(3, 2), (2, 0)]
    step(state, 0.6, [4], [], [], [], 0.25, 0.5)
    total, _, size, *_ = state
    assert sorted(size.keys()) == [4] and sorted(total.keys()) == [4]


def test_a_low_mean_stops_the_merging_and_a_node_below_objectness_is_noise():
    t = np.array([0.0, 0.0, 0.0])
    node = np.array([True, True, False])
    roots, sizes = sequence_merges(t, node, np.array([0]), np.array([1]), np.array([0.5]), 0.25, 0.5)
    np.testing.assert_array_equal(roots, [0, 1, -1])  # 0.5 does not exceed 0.5
    np.testing.assert_array_equal(sizes, [1, 1, 0])


def _scenes(n_sequences=2, duration=2.0, random_state=0):
    scenes = make_scenes(n_sequences=n_sequences, duration=duration, random_state=random_state)
    front = Pipeline([("frame", FrameTransform()), ("filter", DopplerDensityFilter())])
    return front.fit_transform(scenes.data), instance_target(scenes.data["track_id"], scenes.data["sequence"])


@pytest.fixture(scope="module")
def data():
    return _scenes()


@pytest.fixture(scope="module")
def fitted(data):
    X, y = data
    return LinkClustering(**FIXED).fit(X, y)


def test_rows_in_rows_out_dropped_rows_noise_and_no_cluster_across_sequences(data, fitted):
    X, _ = data
    labels = fitted.predict(X)
    assert labels.shape == (len(X),)
    np.testing.assert_array_equal(labels, fitted.labels_)
    assert labels.max() >= 0
    assert np.all(labels[~X["keep"].to_numpy()] == -1)
    clustered = labels >= 0
    pairs = set(zip(labels[clustered].tolist(), X["sequence"].to_numpy()[clustered].tolist(), strict=True))
    assert len(pairs) == len(set(labels[clustered].tolist()))


def test_the_labels_do_not_depend_on_the_row_order(data, fitted):
    X, y = data
    permutation = np.random.default_rng(0).permutation(len(X))
    back = np.empty(len(X), dtype=np.int64)
    back[permutation] = fitted.predict(X.iloc[permutation])
    assert _same_partition(back, fitted.labels_)
    refit = np.empty(len(X), dtype=np.int64)
    refit[permutation] = clone(fitted).fit(X.iloc[permutation], y[permutation]).labels_
    assert _same_partition(refit, fitted.labels_)


def test_the_labels_up_to_a_time_come_from_the_past_only(data, fitted):
    # Labelling the data truncated at a time: the same detections are noise, and each cluster found then lies
    # within one cluster of the whole run (later merges only join clusters).  Offline (causal=False) differs.
    X, _ = data
    labels = fitted.predict(X)
    offline = LinkClustering(**{**FIXED, "causal": False}).fit(X, data[1])
    offline_labels = offline.predict(X)
    offline_differs = False
    for cut in np.quantile(X["t"], [0.3, 0.6]):
        upto = (X["t"] <= cut).to_numpy()
        early = fitted.predict(X[upto])
        np.testing.assert_array_equal(early < 0, labels[upto] < 0)
        clustered = early >= 0
        assert len(set(zip(early[clustered].tolist(), labels[upto][clustered].tolist(), strict=True))) == len(
            set(early[clustered].tolist())
        )
        offline_differs |= not np.array_equal(offline.predict(X[upto]) < 0, offline_labels[upto] < 0)
    assert offline_differs


def test_the_same_detections_in_two_sequences_never_share_a_cluster(data, fitted):
    X, _ = data
    one = X[X["sequence"] == X["sequence"].iloc[0]]
    twice = pd.concat([one, one.assign(sequence=one["sequence"] + 100)], ignore_index=True)
    labels = fitted.predict(twice)
    first, second = labels[: len(one)], labels[len(one) :]
    assert _same_partition(first, second)
    assert not set(first[first >= 0].tolist()) & set(second[second >= 0].tolist())


def test_a_detection_is_labelled_once_its_cluster_is_confirmed(data):
    X, y = data
    base = LinkClustering(**{**FIXED, "min_cluster_size": 1}).fit(X, y)
    every = base.predict(X)
    confirmed = base.set_params(min_cluster_size=6).fit(X, y).predict(X)
    assert np.all((confirmed >= 0) <= (every >= 0))  # confirmation only removes labels ...
    assert (confirmed < 0).sum() > (every < 0).sum()
    clustered = confirmed >= 0  # ... and keeps the clusters
    assert len(set(zip(confirmed[clustered].tolist(), every[clustered].tolist(), strict=True))) == len(
        set(confirmed[clustered].tolist())
    )


def test_clone_and_pickle(data, fitted):
    X, _ = data
    assert clone(fitted).get_params()["causal"] is True
    restored = pickle.loads(pickle.dumps(fitted))
    np.testing.assert_array_equal(restored.predict(X), fitted.predict(X))


def test_fit_tunes_the_thresholds_with_the_causal_agglomeration(monkeypatch):
    X, y = _scenes(n_sequences=2, duration=1.5, random_state=2)
    from sklearn_radar.cluster import _link_clustering

    called = []
    original = _link_clustering.tune_causal
    monkeypatch.setattr(_link_clustering, "tune_causal", lambda *a, **k: called.append(1) or original(*a, **k))
    model = LinkClustering(max_iter=5, causal=True, objectness_threshold=0.3).fit(X, y)
    assert called
    assert model.link_threshold_ in LINK_GRID and model.objectness_threshold_ in OBJECTNESS_GRID
    assert model.min_cluster_size_ in MIN_SIZE_GRID
    assert 0.0 <= model.cv_score_ <= 1.0
    np.testing.assert_array_equal(model.predict(X), model.labels_)


def test_causal_must_be_a_boolean(data):
    X, y = data
    with pytest.raises(ValueError, match="causal"):
        LinkClustering(causal="yes").fit(X, y)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**16), st.integers(2, 80), st.booleans())
def test_compiled_pair_features_equal_the_numpy_ones(seed, n, measured):
    # The reference: the offline (numpy) pair features, on the same detections and pairs.
    from sklearn_radar.cluster._causal_link_features import causal_pair_features
    from sklearn_radar.cluster._link_features import pair_features

    rng = np.random.default_rng(seed)
    d = _random_detections(n, rng)
    if not measured:  # absent measurements are NaN, and so are the features that need them
        d = d._replace(los=np.full(n, np.nan), rcs=np.full(n, np.nan), sensor=np.full(n, np.nan))
    _, local = causal_detection_features(d)
    objectness = rng.random(n)
    i, j = causal_pairs(d.x, d.y, d.t, np.ones(n, dtype=bool), 0, 3.0, 0.25)
    np.testing.assert_allclose(
        causal_pair_features(d, local, objectness, i, j),
        pair_features(d, local, objectness, i, j),
        rtol=1e-9,
        atol=1e-9,
    )
