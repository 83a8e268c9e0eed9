"""PointClassifier: per-detection features and classes, and instances as connected components (slow reference)."""

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.metrics import f1_score
from sklearn.pipeline import make_pipeline

from sklearn_radar import FrameTransform
from sklearn_radar._labels import rank_by_first_appearance
from sklearn_radar.classification import POINT_FEATURES, PointClassifier, road_user_class
from sklearn_radar.datasets import make_scenes


class MovingIsPedestrian(ClassifierMixin, BaseEstimator):
    """Remembers what it is fitted on; pedestrian (3) with probability 0.5 + |v_r| / 10 (at most 1) if |v_r| > 0.5."""

    def fit(self, X, y):
        self.X_, self.y_ = X.copy(), np.asarray(y)
        self.classes_ = np.array([-1, 3])
        return self

    def predict_proba(self, X):
        speed = np.abs(X["v_r"].to_numpy())
        p = np.where(speed > 0.5, np.minimum(0.5 + speed / 10, 1.0), 0.0)
        return np.c_[1 - p, p]


def _components(X, classes, eps_xy, eps_t):
    """Connected components of the detections of each (sequence, class) other than -1, from all pairs."""
    n = len(X)
    x, y, t, s = (X[name].to_numpy() for name in ("x", "y", "t", "sequence"))
    i, j = np.triu_indices(n, 1)
    edge = (
        (classes[i] == classes[j])
        & (classes[i] != -1)
        & (s[i] == s[j])
        & (np.hypot(x[i] - x[j], y[i] - y[j]) < eps_xy)
        & (np.abs(t[i] - t[j]) <= eps_t)
    )
    graph = coo_matrix((np.ones(edge.sum()), (i[edge], j[edge])), shape=(n, n))
    _, component = connected_components(graph, directed=False)
    found = classes != -1
    result = np.full(n, -1)
    result[found] = rank_by_first_appearance(component[found])
    return result


@settings(max_examples=80, deadline=None)
@given(n=st.integers(2, 40), seed=st.integers(0, 2**31 - 1), eps_xy=st.floats(0.3, 3.0), eps_t=st.floats(0.0, 0.5))
def test_instances_are_the_connected_components_of_each_class(n, seed, eps_xy, eps_t):
    # Times lie on a 0.01 s grid (equal times happen); eps_t lies between grid steps, so that no pair sits at the
    # boundary, where |t_i - t_j| <= eps_t depends on how each side rounds (0.13 - 0.11 > 0.02 in floating point).
    eps_t = round(eps_t, 2) + 0.005
    rng = np.random.default_rng(seed)
    X = pd.DataFrame(
        {
            "x": rng.uniform(0, 6, n),
            "y": rng.uniform(0, 6, n),
            "v_r": rng.choice([0.0, 1.0, 3.0], n),
            "t": rng.uniform(0, 1, n).round(2),
            "sequence": rng.integers(1, 3, n),
        }
    )
    y = np.where(np.arange(n) % 2 == 0, -1, 3)  # two classes (the rule classifier ignores them)
    model = PointClassifier(MovingIsPedestrian(), eps_xy=eps_xy, eps_t=eps_t).fit(X, y)
    result = model.predict_instances(X)
    expected_class = np.where(np.abs(X["v_r"]) > 0.5, 3, -1)
    np.testing.assert_array_equal(result["class"], expected_class)
    np.testing.assert_array_equal(result["instance"], _components(X, expected_class, eps_xy, eps_t))
    # The confidence of an instance: the mean probability of its class over its detections.
    p = np.minimum(0.5 + np.abs(X["v_r"].to_numpy()) / 10, 1.0)
    for instance in np.unique(result["instance"][result["instance"] >= 0]):
        mine = (result["instance"] == instance).to_numpy()
        np.testing.assert_allclose(result["confidence"][mine], p[mine].mean())
    np.testing.assert_allclose(result["confidence"][expected_class == -1], 1.0)


def test_trained_on_the_kept_detections_of_known_classes():
    X = pd.DataFrame(
        {
            "x": [0.0, 1.0, 2.0, 3.0],
            "y": 0.0,
            "v_r": [2.0, 0.0, 1.0, 3.0],
            "t": 0.0,
            "keep": [1, 1, 0, 1],
            "rcs": [1.0, 2.0, 3.0, 4.0],
        }
    )
    model = PointClassifier(MovingIsPedestrian()).fit(X, [3, -1, 3, -2])
    np.testing.assert_array_equal(model.classifier_.X_.to_numpy(), [[2.0, 1.0], [0.0, 2.0]])  # rows 0 and 1
    assert model.classifier_.y_.tolist() == [3, -1]
    assert model.feature_names_.tolist() == ["v_r", "rcs"]  # no range or line of sight in X
    # A detection the filter removed is background whatever its features.
    assert model.predict(X).tolist() == [3, -1, -1, 3]
    np.testing.assert_allclose(model.predict_proba(X)[2], [1.0, 0.0])


class GroupedMovingIsPedestrian(MovingIsPedestrian):
    """Also remembers the groups its fit is given (asked for when metadata routing is on)."""

    def fit(self, X, y, groups=None):
        self.groups_ = None if groups is None else np.asarray(groups)
        return super().fit(X, y)


def test_a_classifier_asking_for_groups_gets_each_detections_sequence_when_routing_is_on():
    import sklearn

    X = pd.DataFrame(
        {"x": [0.0, 1.0, 2.0, 3.0], "y": 0.0, "v_r": [2.0, 0.0, 1.0, 3.0], "t": 0.0, "sequence": [4, 4, 5, 5]}
    )
    with sklearn.config_context(enable_metadata_routing=True):
        asking = GroupedMovingIsPedestrian().set_fit_request(groups=True)
        model = PointClassifier(asking).fit(X, [3, -1, -2, 3])
    assert model.classifier_.groups_.tolist() == [4, 4, 5]  # the ignored detection (-2) is left out
    assert PointClassifier(GroupedMovingIsPedestrian()).fit(X, [3, -1, -2, 3]).classifier_.groups_ is None


@pytest.fixture(scope="module")
def scenes():
    return make_scenes(n_sequences=3, duration=8.0, random_state=21), make_scenes(1, duration=8.0, random_state=22)


def test_every_feature_from_the_detection_table_and_a_prediction_per_detection(scenes):
    train, test = scenes
    model = make_pipeline(FrameTransform(), PointClassifier()).fit(train.data, road_user_class(train.data["label_id"]))
    assert model[-1].feature_names_.tolist() == list(POINT_FEATURES)
    Xt = model[0].transform(test.data)
    predicted = model.predict(test.data)
    # A detection's class does not depend on the others: predicting a half gives that half of the whole.
    half = np.arange(len(Xt)) % 2 == 0
    np.testing.assert_array_equal(model[-1].predict(Xt[half]), predicted[half])
    y = road_user_class(test.data["label_id"])
    present = np.unique(y[y >= 0])
    assert f1_score(y, predicted, labels=present, average="macro") > 0.15  # it learns something per detection
    result = model[-1].predict_instances(Xt)
    np.testing.assert_array_equal(result["class"], predicted)
    assert ((result["instance"] == -1) == (result["class"] == -1)).all()


def test_bad_targets_name_the_problem():
    X = pd.DataFrame({"x": [0.0, 1.0], "y": 0.0, "v_r": 1.0, "t": 0.0})
    with pytest.raises(ValueError, match="y has 1 values for 2 detections"):
        PointClassifier().fit(X, [0])
    with pytest.raises(ValueError, match="Unknown label type"):
        PointClassifier().fit(X, [0.5, 1.0])


def _neighbourhood_reference(X, radius, time_window, causal):
    """The neighbourhood features of each kept detection from all pairs, detection by detection."""
    kept = X["keep"].to_numpy() != 0
    rows = []
    for i in np.flatnonzero(kept):
        near = (
            kept
            & (X["sequence"] == X["sequence"].iloc[i]).to_numpy()
            & (np.hypot(X["x"] - X["x"].iloc[i], X["y"] - X["y"].iloc[i]) <= radius).to_numpy()
            & (np.abs(X["t"] - X["t"].iloc[i]) <= time_window).to_numpy()
        )
        if causal:
            near &= (X["t"] <= X["t"].iloc[i]).to_numpy()
        mine = X[near]
        spread = np.sqrt(mine["x"].var(ddof=0) + mine["y"].var(ddof=0))
        doppler = [mine["v_r"].mean(), mine["v_r"].std(ddof=0)]
        rows.append([len(mine), spread, *doppler, mine["rcs"].mean(), mine["rcs"].std(ddof=0), mine["rcs"].max()])
    return np.asarray(rows)


@settings(max_examples=60, deadline=None)
@given(n=st.integers(2, 40), seed=st.integers(0, 2**31 - 1), causal=st.booleans())
def test_neighbourhood_features_match_a_pair_by_pair_reference(n, seed, causal):
    # Positions on a 0.1 m grid and times on a 0.01 s grid; the radius and the window lie between grid steps, so
    # that no pair sits exactly at a boundary.
    rng = np.random.default_rng(seed)
    X = pd.DataFrame(
        {
            "x": rng.integers(0, 40, n) / 10,
            "y": rng.integers(0, 40, n) / 10,
            "v_r": rng.normal(0.0, 3.0, n),
            "t": rng.integers(0, 100, n) / 100,
            "sequence": rng.integers(1, 3, n),
            "keep": rng.integers(0, 2, n),
            "rcs": rng.normal(0.0, 5.0, n),
        }
    )
    X.loc[[0, 1], "keep"] = 1  # two kept detections of two classes: a classifier is fitted
    radius, time_window = 1.23, 0.205
    model = PointClassifier(MovingIsPedestrian(), radius=radius, time_window=time_window, causal=causal)
    model.fit(X, np.where(np.arange(n) % 2 == 0, 3, -1))
    features = model.classifier_.X_  # the kept detections' rows, in order
    names = ["nb_count", "nb_spread", "nb_vr_mean", "nb_vr_std", "nb_rcs_mean", "nb_rcs_std", "nb_rcs_max"]
    assert model.feature_names_.tolist() == ["v_r", "rcs", *names]
    np.testing.assert_allclose(
        features[names].to_numpy(), _neighbourhood_reference(X, radius, time_window, causal), atol=1e-9
    )


def test_neighbourhood_without_rcs_leaves_its_features_out():
    X = pd.DataFrame({"x": [0.0, 0.5, 5.0], "y": 0.0, "v_r": [1.0, 3.0, 2.0], "t": [0.0, 0.1, 0.1]})
    model = PointClassifier(MovingIsPedestrian(), radius=1.0).fit(X, [3, -1, 3])
    assert model.feature_names_.tolist() == ["v_r", "nb_count", "nb_spread", "nb_vr_mean", "nb_vr_std"]
    assert model.classifier_.X_["nb_count"].tolist() == [2, 2, 1]


def test_neighbourhood_rows_in_rows_out_in_any_order(scenes):
    train, test = scenes
    model = make_pipeline(FrameTransform(), PointClassifier(radius=1.5))
    model.fit(train.data, road_user_class(train.data["label_id"]))
    Xt = model[0].transform(test.data)
    proba = model[-1].predict_proba(Xt)
    assert proba.shape == (len(Xt), len(model[-1].classes_))
    order = np.random.default_rng(0).permutation(len(Xt))
    np.testing.assert_allclose(model[-1].predict_proba(Xt.iloc[order]), proba[order])


@pytest.mark.parametrize(
    ("params", "name"), [({"radius": -1.0}, "radius"), ({"radius": 1.0, "time_window": 0.0}, "time_window")]
)
def test_bad_neighbourhood_parameters_are_named(params, name):
    X = pd.DataFrame({"x": [0.0, 1.0], "y": 0.0, "v_r": 1.0, "t": 0.0})
    with pytest.raises(ValueError, match=name):
        PointClassifier(**params).fit(X, [3, -1])
