"""LinkClustering: learned objectness and links with mean-link agglomeration, as a scikit-learn clusterer."""

import copy
import pickle

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from sklearn.exceptions import NotFittedError
from sklearn.pipeline import Pipeline
from threadpoolctl import threadpool_info, threadpool_limits

from sklearn_radar import DopplerDensityFilter, FrameTransform, instance_target
from sklearn_radar._validation import read_columns
from sklearn_radar.cluster import LinkClustering, _link_training
from sklearn_radar.cluster._link_clustering import LINK_GRID, LINK_READS, MIN_SIZE_GRID, OBJECTNESS_GRID, _sequences
from sklearn_radar.cluster._link_features import DETECTION_FEATURES
from sklearn_radar.datasets import make_scenes

#: Fixed thresholds: no tuning, so no out-of-fold fits (the cheap configuration of most tests).
FIXED = {"link_threshold": 0.5, "objectness_threshold": 0.3, "min_cluster_size": 2, "max_iter": 10}


def _same_partition(a, b):
    """Equal up to renaming (noise, -1, is a label like any other)."""
    a, b = np.asarray(a), np.asarray(b)
    return len(set(zip(a.tolist(), b.tolist(), strict=True))) == len(set(a.tolist())) == len(set(b.tolist()))


def _scenes(n_sequences=2, duration=3.0, random_state=0, difficulty="easy"):
    """Working detections through the front, and the instance of each (-1 background)."""
    scenes = make_scenes(n_sequences=n_sequences, duration=duration, difficulty=difficulty, random_state=random_state)
    front = Pipeline([("frame", FrameTransform()), ("filter", DopplerDensityFilter())])
    X = front.fit_transform(scenes.data)
    return X, instance_target(scenes.data["track_id"], scenes.data["sequence"])


@pytest.fixture(scope="module")
def data():
    return _scenes()


@pytest.fixture(scope="module")
def fitted(data):
    X, y = data
    return LinkClustering(max_iter=20).fit(X, y)


def test_fit_labels_every_row_and_predict_gives_the_same_labels(data, fitted):
    X, _ = data
    assert fitted.labels_.shape == (len(X),)
    np.testing.assert_array_equal(fitted.predict(X), fitted.labels_)
    assert fitted.labels_.max() >= 0  # it finds road users


def test_dropped_rows_are_noise(data, fitted):
    X, _ = data
    assert (~X["keep"]).any()
    assert np.all(fitted.labels_[~X["keep"].to_numpy()] == -1)


def test_no_cluster_spans_two_sequences(data, fitted):
    X, _ = data
    clustered = fitted.labels_ >= 0
    pairs = set(zip(fitted.labels_[clustered].tolist(), X["sequence"].to_numpy()[clustered].tolist(), strict=True))
    assert len(pairs) == len(set(fitted.labels_[clustered].tolist()))


def test_the_same_detections_in_two_sequences_never_share_a_cluster(data, fitted):
    X, _ = data
    one = X[X["sequence"] == X["sequence"].iloc[0]]
    twice = pd.concat([one, one.assign(sequence=one["sequence"] + 100)], ignore_index=True)
    labels = fitted.predict(twice)
    first, second = labels[: len(one)], labels[len(one) :]
    assert _same_partition(first, second)  # each sequence alone is clustered the same way ...
    assert not set(first[first >= 0].tolist()) & set(second[second >= 0].tolist())  # ... with its own ids


def test_tuned_settings_come_from_the_grids_and_clusters_respect_the_minimum_size(fitted):
    assert fitted.link_threshold_ in LINK_GRID
    assert fitted.objectness_threshold_ in OBJECTNESS_GRID
    assert fitted.min_cluster_size_ in MIN_SIZE_GRID
    assert 0.0 <= fitted.cv_score_ <= 1.0
    sizes = np.bincount(fitted.labels_[fitted.labels_ >= 0])
    assert sizes.min() >= fitted.min_cluster_size_


def test_given_thresholds_are_used_and_nothing_is_tuned(data):
    X, y = data
    model = LinkClustering(**FIXED).fit(X, y)
    assert (model.link_threshold_, model.objectness_threshold_, model.min_cluster_size_) == (0.5, 0.3, 2)
    assert np.isnan(model.cv_score_)


def test_the_labels_do_not_depend_on_the_row_order(data, fitted):
    X, y = data
    permutation = np.random.default_rng(0).permutation(len(X))
    model = LinkClustering(max_iter=20).fit(X.iloc[permutation], y[permutation])
    labels = np.empty(len(X), dtype=np.int64)
    labels[permutation] = model.labels_
    assert _same_partition(labels, fitted.labels_)
    assert (model.link_threshold_, model.objectness_threshold_) == (
        fitted.link_threshold_,
        fitted.objectness_threshold_,
    )
    back = np.empty(len(X), dtype=np.int64)
    back[permutation] = fitted.predict(X.iloc[permutation])
    assert _same_partition(back, fitted.labels_)


@st.composite
def _small_frames(draw):
    """Two sequences of a few moving objects (several detections per scan) and static clutter."""
    rng = np.random.default_rng(draw(st.integers(0, 2**16)))
    rows = []
    for sequence in (1, 2):
        for scan in range(draw(st.integers(2, 6))):
            t = 0.06 * scan
            for obj in range(3):
                centre = np.array([10.0 * obj, 5.0]) + np.array([8.0, 0.0]) * t
                for _ in range(rng.integers(2, 5)):
                    x, y = centre + rng.normal(0, 0.4, 2)
                    rows.append((x, y, 8.0 + rng.normal(0, 0.2), t, sequence, 1, 20.0, obj))
            for _ in range(rng.integers(0, 6)):
                rows.append((*rng.uniform(-5, 30, 2), rng.normal(0, 0.1), t, sequence, rng.integers(0, 2), 20.0, -1))
    table = pd.DataFrame(rows, columns=["x", "y", "v_r", "t", "sequence", "keep", "range_sc", "target"])
    return table.round(3)


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(_small_frames(), st.randoms(use_true_random=False))
def test_hypothesis_row_order_and_rows_in_rows_out(frame, random):
    X, y = frame.drop(columns="target"), frame["target"].to_numpy()
    if X.duplicated().any():  # rows equal in every column are interchangeable: their labels may swap
        X = X.drop_duplicates()
        y = y[X.index]
        X = X.reset_index(drop=True)
    model = LinkClustering(link_threshold="auto", objectness_threshold=0.3, min_cluster_size=1, max_iter=5)
    labels = model.fit_predict(X, y)
    assert labels.shape == (len(X),)
    assert np.all(labels[X["keep"].to_numpy() == 0] == -1)
    permutation = np.arange(len(X))
    random.shuffle(permutation)
    again = np.empty(len(X), dtype=np.int64)
    again[permutation] = LinkClustering(**model.get_params()).fit_predict(X.iloc[permutation], y[permutation])
    assert _same_partition(labels, again)


def test_pickle_round_trip_gives_identical_labels(data, fitted):
    X, _ = data
    restored = pickle.loads(pickle.dumps(fitted))
    np.testing.assert_array_equal(restored.predict(X), fitted.predict(X))


def test_new_sequences_are_clustered_with_what_was_learned(fitted):
    X_new, _ = _scenes(n_sequences=1, duration=2.0, random_state=5)
    labels = fitted.predict(X_new)
    assert labels.shape == (len(X_new),)
    assert labels.max() >= 0


def test_the_classifiers_run_with_the_threads_they_are_given(data, monkeypatch):
    X, y = data
    seen = []
    original = _link_training._fit

    def spy(*args):
        seen.append([lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "openmp"])
        return original(*args)

    monkeypatch.setattr(_link_training, "_fit", spy)
    with threadpool_limits(limits=4):
        LinkClustering(**FIXED).fit(X, y)
        LinkClustering(**FIXED, n_jobs=2).fit(X, y)
    assert seen and all(seen)
    assert all(threads == [1] * len(threads) for threads in seen[: len(seen) // 2])
    assert all(threads == [2] * len(threads) for threads in seen[len(seen) // 2 :])


@pytest.mark.parametrize("walk_rows", [0, 10**9], ids=["predict_proba", "tree walk"])
def test_labels_do_not_depend_on_how_the_classifiers_are_evaluated(data, fitted, monkeypatch, walk_rows):
    X, _ = data
    monkeypatch.setattr(_link_training, "WALK_ROWS", walk_rows)
    np.testing.assert_array_equal(fitted.predict(X), fitted.labels_)


def test_positive_proba_walks_small_batches_and_follows_a_refit(data, fitted, monkeypatch):
    X, _ = data
    sequence = _sequences(read_columns(fitted, X, LINK_READS, reset=False)[1])[0]
    rows = sequence.features[:50][:, np.isin(list(DETECTION_FEATURES), fitted.detection_feature_names_)]
    model = copy.deepcopy(fitted.objectness_classifier_)  # refit below: not the fixture's
    calls = []
    original = type(model).predict_proba
    monkeypatch.setattr(type(model), "predict_proba", lambda self, Z: calls.append(len(Z)) or original(self, Z))
    np.testing.assert_array_equal(_link_training.positive_proba(model, rows), original(model, rows)[:, 1])
    assert calls == []  # walked, not predict_proba
    model.fit(rows, np.arange(len(rows)) % 3 == 0)  # the same object, new trees
    np.testing.assert_array_equal(_link_training.positive_proba(model, rows), original(model, rows)[:, 1])
    monkeypatch.setattr(_link_training, "WALK_ROWS", 10)
    _link_training.positive_proba(model, rows)
    assert calls == [len(rows)]  # a large batch goes through predict_proba


# ---------------------------------------------------------------------------------------------- bad input


def test_fit_without_y_names_y(data):
    X, _ = data
    with pytest.raises(ValueError, match="requires y"):
        LinkClustering(**FIXED).fit(X, None)
    with pytest.raises(ValueError, match="requires y"):
        LinkClustering(**FIXED).fit_predict(X)


@pytest.mark.parametrize(
    "make_y, match",
    [
        (lambda y: y[:-1], "y has"),
        (lambda y: np.full(len(y), -1), "no instance"),
        (lambda y: np.where(y >= 0, y, -3), "-1 \\(background\\) or >= 0"),
        (lambda y: y.astype(str), "integer instance ids"),
    ],
    ids=["length", "all background", "negative", "strings"],
)
def test_bad_y_raises_naming_y(data, make_y, match):
    X, y = data
    with pytest.raises(ValueError, match=match):
        LinkClustering(**FIXED).fit(X, make_y(y))


def test_tuning_on_one_instant_raises_naming_the_parameters():
    X = pd.DataFrame({"x": [0.0, 0.5, 5.0, 5.5], "y": 0.0, "v_r": 5.0, "t": 0.0})
    with pytest.raises(ValueError, match="link_threshold and objectness_threshold and min_cluster_size='auto'"):
        LinkClustering().fit(X, [0, 0, 1, 1])
    with pytest.raises(ValueError, match=r"^LinkClustering: min_cluster_size='auto'"):
        LinkClustering(link_threshold=0.5, objectness_threshold=0.5).fit(X, [0, 0, 1, 1])
    labels = LinkClustering(**FIXED).fit_predict(X, [0, 0, 1, 1])  # fixed thresholds: nothing to tune
    assert labels.shape == (4,)


@pytest.mark.parametrize(
    "parameter, value",
    [("link_threshold", 1.5), ("objectness_threshold", "high"), ("min_cluster_size", 0), ("pair_radius", 0)],
)
def test_bad_parameters_raise_naming_them(data, parameter, value):
    X, y = data
    with pytest.raises(ValueError, match=parameter):
        LinkClustering(**{parameter: value}).fit(X, y)


def test_predict_before_fit_and_with_other_columns_raise(data, fitted):
    X, _ = data
    with pytest.raises(NotFittedError):
        LinkClustering().predict(X)
    with pytest.raises(ValueError, match="feature names"):
        fitted.predict(X.drop(columns="rcs"))


def test_the_detections_of_a_sequence_are_numbered_free_of_the_row_order(data):
    # The agglomeration breaks ties by detection number; the numbers must come from the detections, not the rows.
    X, _ = data
    X = X[X["sequence"] == X["sequence"].iloc[0]].reset_index(drop=True)
    permutation = np.random.default_rng(1).permutation(len(X))
    model = LinkClustering()
    (forward,) = _sequences(read_columns(model, X, LINK_READS, reset=True)[1])
    (shuffled,) = _sequences(read_columns(model, X.iloc[permutation], LINK_READS, reset=True)[1])
    np.testing.assert_array_equal(permutation[shuffled.rows], forward.rows)  # the same detection at each number
    for name in forward.detections._fields:
        np.testing.assert_array_equal(getattr(shuffled.detections, name), getattr(forward.detections, name))
    np.testing.assert_array_equal(shuffled.features, forward.features)


def test_best_of_takes_the_first_maximum_in_the_grids_order_and_never_a_nan():
    grids = ((0.1, 0.2), (0.01, 0.5), (1, 3))  # link thresholds, objectness thresholds, minimum sizes
    surface = np.array([[[0.2, 0.7], [0.7, 0.1]], [[0.1, 0.7], [0.3, 0.2]]])  # (objectness, link, size)
    assert _link_training.best_of(surface, grids) == ((0.1, 0.01, 3), 0.7)
    surface[0, 0, 0] = np.nan
    assert _link_training.best_of(surface, grids) == ((0.1, 0.01, 3), 0.7)
