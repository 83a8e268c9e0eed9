"""LinkClustering(causal=True): features from the past only, the same pairs, the time-by-time agglomeration."""

import pickle

import numpy as np
import pandas as pd
import pytest
from sklearn.base import clone
from sklearn.pipeline import Pipeline

from sklearn_radar import DopplerDensityFilter, FrameTransform, instance_target
from sklearn_radar.cluster import LinkClustering
from sklearn_radar.cluster._link_clustering import LINK_GRID, MIN_SIZE_GRID, OBJECTNESS_GRID
from sklearn_radar.datasets import make_scenes

#: Fixed thresholds (no tuning): the cheap configuration.
FIXED = {"link_threshold": 0.5, "objectness_threshold": 0.3, "min_cluster_size": 3, "max_iter": 10, "causal": True}


def _same_partition(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return len(set(zip(a.tolist(), b.tolist(), strict=True))) == len(set(a.tolist())) == len(set(b.tolist()))


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


def test_max_links_per_detection_requires_causal(data):
    X, y = data
    with pytest.raises(ValueError, match="max_links_per_detection requires causal=True"):
        LinkClustering(**{**FIXED, "causal": False, "max_links_per_detection": 4}).fit(X, y)


def test_max_extent_requires_causal_and_a_positive_length(data):
    X, y = data
    with pytest.raises(ValueError, match="max_extent requires causal=True"):
        LinkClustering(**{**FIXED, "causal": False, "max_extent": 10.0}).fit(X, y)
    with pytest.raises(ValueError, match="max_extent"):
        LinkClustering(**{**FIXED, "max_extent": 0.0}).fit(X, y)


@pytest.mark.parametrize(
    "name",
    [
        "max_links_per_detection",  # formed every candidate pair
        "max_extent",  # merged clusters of any length
    ],
)
def test_a_model_pickled_before_a_limit_existed_loads_without_it(data, fitted, name):
    X, _ = data
    old = clone(fitted)
    old.__dict__.update(fitted.__dict__)
    del old.__dict__[name]  # as pickled by the version without the parameter
    loaded = pickle.loads(pickle.dumps(old))
    assert getattr(loaded, name) is None
    np.testing.assert_array_equal(loaded.predict(X), fitted.predict(X))


def test_a_model_pickled_before_max_leaf_nodes_had_trees_of_31_leaves_and_any_depth(data, fitted):
    X, _ = data
    old = clone(fitted)
    old.__dict__.update(fitted.__dict__)
    del old.__dict__["max_leaf_nodes"], old.__dict__["max_depth"]  # as pickled by the version without them
    loaded = pickle.loads(pickle.dumps(old))
    assert loaded.max_leaf_nodes == 31 and loaded.max_depth is None
    assert loaded.link_classifier_.max_leaf_nodes == 31 and loaded.link_classifier_.max_depth is None
    np.testing.assert_array_equal(loaded.predict(X), fitted.predict(X))


def test_max_leaf_nodes_reaches_both_classifiers(data):
    X, y = data
    model = LinkClustering(**{**FIXED, "max_leaf_nodes": 7}).fit(X, y)
    for classifier in (model.objectness_classifier_, model.link_classifier_):
        assert classifier.max_leaf_nodes == 7
        assert max(predictor[0].get_n_leaf_nodes() for predictor in classifier._predictors) <= 7


def test_max_depth_reaches_both_classifiers(data):
    X, y = data
    model = LinkClustering(**{**FIXED, "max_depth": 3}).fit(X, y)
    for classifier in (model.objectness_classifier_, model.link_classifier_):
        assert classifier.max_depth == 3
        assert max(predictor[0].get_max_depth() for predictor in classifier._predictors) <= 3
    unlimited = LinkClustering(**FIXED).fit(X, y).link_classifier_
    assert max(predictor[0].get_max_depth() for predictor in unlimited._predictors) > 3  # the cap bites here
