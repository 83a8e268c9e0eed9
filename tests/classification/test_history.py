"""ClusterClassifier over a cluster's history (``history=``), and a frozen fitted clusterer."""

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.base import BaseEstimator, ClusterMixin
from sklearn.cluster import KMeans
from sklearn.frozen import FrozenEstimator
from sklearn.pipeline import make_pipeline
from sklearn.utils._param_validation import InvalidParameterError

from sklearn_radar import DopplerDensityFilter, FrameTransform, RadarDBSCAN
from sklearn_radar.classification import ClusterClassifier, cluster_features, road_user_class
from sklearn_radar.classification._history import with_history
from sklearn_radar.datasets import make_scenes

FEATURE_COLUMNS = ["x", "y", "v_r", "t", "sequence", "rcs", "range_sc", "azimuth_sc", "sensor_yaw", "sensor_id"]


@pytest.fixture(scope="module")
def fitted():
    """A classifier fitted on one simulated recording's clusters, the working detections of another, their labels."""
    train = make_scenes(n_sequences=2, duration=8.0, random_state=21).data
    test = make_scenes(n_sequences=2, duration=8.0, random_state=22).data
    front = make_pipeline(FrameTransform(), DopplerDensityFilter())
    clusterer = RadarDBSCAN(metric="xyv", eps_xyv=1.5, vr_scale=1.0, min_samples=2, vr_min=0.3, alpha_r=0.0)
    X_train = front.fit_transform(train)
    model = ClusterClassifier(clusterer).fit(X_train, road_user_class(X_train["label_id"]))
    X_test = front.fit_transform(test)
    # Long clusters: the ground-truth objects themselves, so that clusters span many windows.
    labels = np.asarray(pd.factorize(X_test["track_id"].where(X_test["track_id"] != "", None))[0], dtype=np.int64)
    return model, X_test, labels


def _brute_force_running_mean(X, labels, proba, later=False):
    """Per detection: its cluster's segment probabilities over the windows up to its own (``later``: all its
    cluster's windows), weighted by detections."""
    table, rows = cluster_features(X[["x", "y", "v_r", "t", "sequence"]], labels, window=0.5, return_rows=True)
    per_segment = np.zeros((len(table), proba.shape[1]))
    per_segment[rows[rows >= 0]] = proba[rows >= 0]
    expected = proba.copy()
    for i in np.flatnonzero(rows >= 0):
        segment = table.iloc[rows[i]]
        past = (
            (table["sequence"] == segment["sequence"])
            & (table["cluster"] == segment["cluster"])
            & ((table["window"] <= segment["window"]) | later)
        ).to_numpy()
        weights = table.loc[past, "n_detections"].to_numpy(dtype=float)
        expected[i] = (per_segment[past] * weights[:, None]).sum(axis=0) / weights.sum()
    return expected


def test_mean_proba_averages_the_segment_probabilities_over_the_windows_seen(fitted):
    model, X, labels = fitted
    single = model.predict_instances_of(X, labels)
    # history="mean_proba" changes prediction only (the classifier is trained on single windows).
    model.set_params(history="mean_proba")
    try:
        found = model.predict_instances_of(X, labels)
        proba = model._segments_of(X, labels)
    finally:
        model.set_params(history=None)
    single_proba = model._segments_of(X, labels)
    table, rows, history_proba = proba
    _, _, window_proba = single_proba
    per_detection = np.zeros((len(X), len(model.classes_)))
    per_detection[rows >= 0] = window_proba[rows[rows >= 0]]
    expected = _brute_force_running_mean(X, labels, per_detection)
    np.testing.assert_allclose(history_proba[rows[rows >= 0]], expected[rows >= 0], atol=1e-12)
    assert (table.groupby(["sequence", "cluster"]).size() > 4).any()  # clusters span several windows here
    assert not np.array_equal(found["class"], single["class"])  # the history changes some decisions
    np.testing.assert_allclose(found["confidence"][rows >= 0], expected[rows >= 0].max(axis=1), atol=1e-12)


def test_cluster_mean_proba_averages_over_all_the_windows_of_the_cluster(fitted):
    model, X, labels = fitted
    _, _, window_proba = model._segments_of(X, labels)
    model.set_params(history="cluster_mean_proba")
    try:
        found = model.predict_instances_of(X, labels)
        _, rows, cluster_proba = model._segments_of(X, labels)
    finally:
        model.set_params(history=None)
    per_detection = np.zeros((len(X), len(model.classes_)))
    per_detection[rows >= 0] = window_proba[rows[rows >= 0]]
    expected = _brute_force_running_mean(X, labels, per_detection, later=True)
    np.testing.assert_allclose(cluster_proba[rows[rows >= 0]], expected[rows >= 0], atol=1e-12)
    # One class per cluster and sequence: the same probabilities in every window.
    clustered = rows >= 0
    classes = pd.DataFrame({"sequence": X["sequence"].to_numpy(), "cluster": labels, "class": found["class"]})
    assert (classes[clustered].groupby(["sequence", "cluster"])["class"].nunique() == 1).all()
    assert not np.allclose(cluster_proba, window_proba)


@pytest.mark.parametrize("history", ["mean_proba", "features"])
def test_the_history_is_causal(fitted, history):
    """Dropping the detections after a time leaves every earlier decision as it was (a window reads its past only)."""
    model, X, labels = fitted
    model = ClusterClassifier(model.clusterer, history=history).fit(X, road_user_class(X["label_id"]))
    whole = model.predict_instances_of(X, labels)
    start = X.groupby("sequence")["t"].transform("min")
    early = (X["t"] - start < 3.0).to_numpy()  # windows 0-5 of each sequence (window starts stay the same)
    cut = model.predict_instances_of(X[early], labels[early])
    np.testing.assert_array_equal(cut["class"], whole["class"][early])
    np.testing.assert_allclose(cut["confidence"], whole["confidence"][early], atol=1e-12)
    assert early.sum() < len(X) and (whole["class"][early] >= 0).any()  # a cut, with road users before it


def test_history_features_are_trained_on_and_read_at_prediction(fitted):
    model, X, _ = fitted
    with_features = ClusterClassifier(model.clusterer, history="features").fit(X, road_user_class(X["label_id"]))
    names = list(with_features.feature_names_)
    assert names[: len(model.feature_names_)] == list(model.feature_names_)
    assert {"history_windows", "history_age", "mean_n_detections", "max_speed"} <= set(names)
    assert with_features.classifier_.n_features_in_ == len(names)
    assert with_features.predict(X).shape == (len(X),)


@settings(max_examples=30, deadline=None)
@given(
    st.lists(
        st.tuples(st.integers(0, 2), st.integers(0, 6), st.one_of(st.none(), st.floats(-5, 5))), min_size=1, max_size=25
    )
)
def test_history_features_match_a_brute_force_of_the_past_segments(segments):
    """Running means skip NaN, maxima too; windows seen and age count the cluster's segments at or before."""
    frame = pd.DataFrame(segments, columns=["cluster", "window", "speed"]).drop_duplicates(["cluster", "window"])
    frame = frame.sort_values(["cluster", "window"]).reset_index(drop=True)
    table = pd.DataFrame(
        {
            "sequence": 1,
            "cluster": frame["cluster"],
            "window": frame["window"],
            "n_detections": np.arange(len(frame)) % 4 + 1,
            "speed": frame["speed"].astype(float),
        }
    )
    found = with_history(table, 0.5)
    for i, row in table.iterrows():
        past = table[(table["cluster"] == row["cluster"]) & (table["window"] <= row["window"])]
        assert found.loc[i, "history_windows"] == len(past)
        assert found.loc[i, "history_age"] == pytest.approx(0.5 * (row["window"] - past["window"].min()))
        assert found.loc[i, "mean_n_detections"] == pytest.approx(past["n_detections"].mean())
        assert found.loc[i, "max_n_detections"] == past["n_detections"].max()
        speeds = past["speed"].dropna()
        for name, value in (("mean_speed", speeds.mean()), ("max_speed", speeds.max())):
            if len(speeds):
                assert found.loc[i, name] == pytest.approx(value)
            else:
                assert np.isnan(found.loc[i, name])


def test_a_bad_history_option_is_refused(fitted):
    model, X, _ = fitted
    with pytest.raises(InvalidParameterError, match="history"):
        ClusterClassifier(model.clusterer, history="tracks").fit(X, road_user_class(X["label_id"]))


class _CountingKMeans(ClusterMixin, BaseEstimator):
    """KMeans on x and y that counts its fits."""

    fits = 0

    def fit(self, X, y=None):
        type(self).fits += 1
        self.model_ = KMeans(n_clusters=4, n_init=1, random_state=0).fit(X[["x", "y"]])
        return self

    def predict(self, X):
        return self.model_.predict(X[["x", "y"]])


@pytest.mark.filterwarnings("ignore:ClusterClassifier. the training examples hold")
def test_a_frozen_fitted_clusterer_labels_by_predict_and_is_never_refitted(fitted):
    """Its clusters are those of its predict on the data (fitted elsewhere), in fit and in prediction."""
    _, X, _ = fitted
    other = make_scenes(n_sequences=1, duration=4.0, random_state=5).data
    frozen = _CountingKMeans().fit(FrameTransform().fit_transform(other))
    before = _CountingKMeans.fits
    model = ClusterClassifier(FrozenEstimator(frozen)).fit(X, road_user_class(X["label_id"]))
    found = model.predict_instances(X)
    assert _CountingKMeans.fits == before
    pd.testing.assert_frame_equal(found, model.predict_instances_of(X, frozen.predict(X)))
