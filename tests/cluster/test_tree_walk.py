"""The compiled walk of a fitted binary HistGradientBoostingClassifier against scikit-learn's predict_proba."""

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from sklearn.ensemble import HistGradientBoostingClassifier, HistGradientBoostingRegressor
from sklearn.linear_model import LogisticRegression

from sklearn_radar.cluster._tree_walk import boosting_proba, compile_boosting


def _data(n, n_features, seed, nan_fraction=0.1):
    """Random rows with NaN, a boolean target that depends on them (NaN included), and test rows with NaN and inf."""
    rng = np.random.RandomState(seed)
    X = rng.normal(size=(n, n_features))
    X[rng.uniform(size=X.shape) < nan_fraction] = np.nan
    score = np.nan_to_num(X[:, 0], nan=1.0) + np.nan_to_num(X[:, -1] ** 2, nan=-1.0) - 0.8
    y = score + rng.normal(scale=0.7, size=n) > 0
    test = rng.normal(scale=1.5, size=(400, n_features))
    test[rng.uniform(size=test.shape) < 0.2] = np.nan
    test[0, 0], test[1, -1] = np.inf, -np.inf
    return X, y, test


def _same_as_sklearn(classifier, X):
    """The walk equals predict_proba on X and on its rows without NaN (a batch without NaN walks another loop)."""
    compiled = compile_boosting(classifier)
    assert compiled is not None
    finite = X[~np.isnan(X).any(axis=1)]
    assert len(finite)
    for batch in (X, finite):
        expected = classifier.predict_proba(batch)[:, 1]
        np.testing.assert_allclose(boosting_proba(compiled, batch), expected, rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    "params",
    [
        {"max_iter": 150},
        {"max_iter": 1},
        {"max_iter": 20, "max_leaf_nodes": 2},
        {"max_iter": 40, "max_leaf_nodes": 63, "max_depth": 4},
        {"max_iter": 300, "early_stopping": True, "n_iter_no_change": 3},
        {"max_iter": 50, "l2_regularization": 1.0, "min_samples_leaf": 100},
    ],
)
def test_equal_to_predict_proba(params):
    X, y, test = _data(2000, 6, seed=0)
    classifier = HistGradientBoostingClassifier(random_state=0, **params).fit(X, y)
    _same_as_sklearn(classifier, test)
    _same_as_sklearn(classifier, X)


def test_early_stopping_keeps_the_trees_it_fitted():
    X, y, test = _data(3000, 4, seed=1)
    classifier = HistGradientBoostingClassifier(
        max_iter=500, early_stopping=True, n_iter_no_change=2, random_state=0
    ).fit(X, y)
    assert classifier.n_iter_ < 500
    assert len(compile_boosting(classifier).offset) == classifier.n_iter_ + 1
    _same_as_sklearn(classifier, test)


def test_one_feature():
    X, y, test = _data(1000, 1, seed=2)
    _same_as_sklearn(HistGradientBoostingClassifier(max_iter=30, random_state=0).fit(X, y), test)


def test_missing_values_never_seen_in_training_go_where_sklearn_sends_them():
    X, y, test = _data(1000, 3, seed=3, nan_fraction=0.0)
    assert not np.isnan(X).any() and np.isnan(test).any()
    _same_as_sklearn(HistGradientBoostingClassifier(max_iter=30, random_state=0).fit(X, y), test)


def test_string_classes_give_the_probability_of_the_second_class():
    X, y, test = _data(800, 3, seed=4)
    labels = np.where(y, "road user", "background")  # classes_ sorted: P("road user")
    _same_as_sklearn(HistGradientBoostingClassifier(max_iter=20, random_state=0).fit(X, labels), test)


def test_constant_model_and_empty_batch():
    np.testing.assert_array_equal(boosting_proba(0.25, np.zeros((3, 2))), [0.25, 0.25, 0.25])
    X, y, _ = _data(500, 3, seed=5)
    compiled = compile_boosting(HistGradientBoostingClassifier(max_iter=5, random_state=0).fit(X, y))
    out = boosting_proba(compiled, np.zeros((0, 3)))
    assert out.shape == (0,) and out.dtype == np.float64


def test_wrong_number_of_columns_raises():
    X, y, _ = _data(500, 3, seed=6)
    compiled = compile_boosting(HistGradientBoostingClassifier(max_iter=5, random_state=0).fit(X, y))
    with pytest.raises(ValueError, match="3 features"):
        boosting_proba(compiled, np.zeros((4, 2)))


def test_what_the_walk_does_not_cover_gives_none():
    X, y, _ = _data(600, 3, seed=7)
    assert compile_boosting(HistGradientBoostingClassifier()) is None  # not fitted
    assert compile_boosting(0.5) is None
    assert compile_boosting(LogisticRegression().fit(np.nan_to_num(X), y)) is None
    assert compile_boosting(HistGradientBoostingRegressor(max_iter=5).fit(X, y.astype(float))) is None
    three = np.where(y, 2, np.arange(len(y)) % 2)
    assert compile_boosting(HistGradientBoostingClassifier(max_iter=5).fit(X, three)) is None
    codes = np.where(np.isnan(X[:, 1]), 0, (X[:, 1] > 0) + 1)
    categorical = np.column_stack([X[:, 0], codes])
    fitted = HistGradientBoostingClassifier(max_iter=5, categorical_features=[1]).fit(categorical, y)
    assert compile_boosting(fitted) is None
    frame = pd.DataFrame({"a": X[:, 0], "b": pd.Categorical(codes)})
    assert compile_boosting(HistGradientBoostingClassifier(max_iter=5).fit(frame, y)) is None


def test_broken_private_structure_gives_none():
    X, y, _ = _data(600, 3, seed=8)
    classifier = HistGradientBoostingClassifier(max_iter=5, random_state=0).fit(X, y)
    nodes = classifier._predictors[0][0].nodes
    classifier._predictors[0][0].nodes = nodes[["value", "left", "right", "is_leaf"]]  # fields missing
    assert compile_boosting(classifier) is None
    classifier._predictors[0][0].nodes = nodes.copy()
    split = np.flatnonzero(~nodes["is_leaf"].astype(bool))[0]
    classifier._predictors[0][0].nodes["left"][split] = len(nodes) + 5  # a child outside its tree
    assert compile_boosting(classifier) is None


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 2**16),
    n_features=st.integers(1, 5),
    max_iter=st.integers(1, 40),
    max_leaf_nodes=st.integers(2, 40),
    nan_fraction=st.sampled_from([0.0, 0.05, 0.5]),
)
def test_equal_to_predict_proba_for_any_fit(seed, n_features, max_iter, max_leaf_nodes, nan_fraction):
    X, y, test = _data(300, n_features, seed, nan_fraction)
    if y.all() or not y.any():
        y[0] = not y[0]
    classifier = HistGradientBoostingClassifier(max_iter=max_iter, max_leaf_nodes=max_leaf_nodes, random_state=0)
    _same_as_sklearn(classifier.fit(X, y), test)
