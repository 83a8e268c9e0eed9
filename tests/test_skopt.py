"""The scikit-optimize shim works with the installed scikit-learn and numpy, and skopt behaves as it relies on."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.cluster import DBSCAN
from sklearn.datasets import make_blobs
from sklearn.metrics import v_measure_score
from sklearn.model_selection import GroupKFold

from sklearn_radar._skopt import BayesSearchCV, Categorical, Integer, Real


def _fit_predict_v_measure(estimator, X, y):
    return v_measure_score(y, estimator.fit_predict(X))


def test_bayes_search_tunes_a_clusterer_with_grouped_cv():
    X, y = make_blobs(n_samples=240, centers=3, cluster_std=0.5, random_state=0)
    groups = np.arange(len(X)) % 3
    search = BayesSearchCV(
        DBSCAN(),
        {"eps": Real(0.05, 3.0), "min_samples": Integer(2, 10)},
        n_iter=8,
        cv=GroupKFold(n_splits=3),
        scoring=_fit_predict_v_measure,
        optimizer_kwargs={"n_initial_points": 4},
        error_score=0.0,
        random_state=0,
    )
    search.fit(X, y, groups=groups)
    results = search.cv_results_
    assert len(results["params"]) == 8
    # Every candidate's score is its mean V-measure over the grouped folds, recomputed here with plain
    # scikit-learn: DBSCAN fitted on each test fold (a clusterer scores what it clusters).
    folds = [test for _, test in GroupKFold(n_splits=3).split(X, y, groups)]
    for params, score in zip(results["params"], results["mean_test_score"], strict=True):
        expected = np.mean([v_measure_score(y[test], DBSCAN(**params).fit_predict(X[test])) for test in folds])
        assert score == pytest.approx(expected, abs=1e-12)
        assert 0.05 <= params["eps"] <= 3.0 and 2 <= params["min_samples"] <= 10
    assert search.best_score_ == max(results["mean_test_score"])
    assert search.best_params_ == results["params"][int(np.argmax(results["mean_test_score"]))]


def test_a_single_candidate_step_fits_one_gaussian_process(monkeypatch):
    # skopt's own ask(n_points=1) refits the GP on a copy and once more on a discarded "lie": 3 fits per guided
    # step.  The shim's optimiser proposes the point its last tell chose, so the search fits one GP per tell
    # from the end of the random phase on: n_iter - n_initial_points + 1 fits.
    from skopt.learning import GaussianProcessRegressor

    fits = []
    original = GaussianProcessRegressor.fit

    def counting_fit(self, X, y):
        fits.append(len(X))
        return original(self, X, y)

    monkeypatch.setattr(GaussianProcessRegressor, "fit", counting_fit)
    X, y = make_blobs(n_samples=120, centers=3, cluster_std=0.5, random_state=0)
    search = BayesSearchCV(
        DBSCAN(),
        {"eps": Real(0.05, 3.0), "min_samples": Integer(2, 10)},
        n_iter=8,
        cv=GroupKFold(n_splits=2),
        scoring=_fit_predict_v_measure,
        optimizer_kwargs={"n_initial_points": 4},
        error_score=0.0,
        random_state=0,
    )
    search.fit(X, y, groups=np.arange(len(X)) % 2)
    assert fits == [4, 5, 6, 7, 8]
    # Each guided candidate is the point the previous tell chose, so none is evaluated twice.
    points = [tuple(p.values()) for p in search.cv_results_["params"]]
    assert len(set(points)) == len(points)


def _objective(point):
    return float(np.sin(3 * point[0]) + 0.1 * point[1])


@pytest.mark.parametrize("n_initial", [2, 5])
def test_random_points_asked_at_once_are_those_of_one_at_a_time(n_initial):
    from sklearn_radar._skopt import Optimizer

    space = [Real(0.0, 2.0), Integer(1, 9)]
    one_at_a_time = Optimizer(space, n_initial_points=n_initial, random_state=3)
    asked = []
    for _ in range(n_initial + 2):  # the random points, then two guided ones
        point = one_at_a_time.ask(n_points=1)[0]
        asked.append(point)
        one_at_a_time.tell([point], [_objective(point)])

    at_once = Optimizer(space, n_initial_points=n_initial, random_state=3)
    assert at_once.n_random_left == n_initial
    points = at_once.ask_random(n_initial)
    for point in points:
        at_once.tell([point], [_objective(point)])
    assert at_once.n_random_left == 0
    for _ in range(2):
        point = at_once.ask(n_points=1)[0]
        points.append(point)
        at_once.tell([point], [_objective(point)])
    assert points == asked


def test_more_random_points_than_are_ahead_is_an_error():
    from sklearn_radar._skopt import Optimizer

    optimizer = Optimizer([Real(0.0, 1.0)], n_initial_points=3, random_state=0)
    with pytest.raises(ValueError, match="n_points=4"):
        optimizer.ask_random(4)


def test_the_internals_are_relied_on_only_with_the_pinned_release():
    # A new skopt must fail here first: then check that the tests below still hold and raise the version.
    import skopt

    from sklearn_radar import _skopt

    assert skopt.__version__ == _skopt.SUPPORTED_VERSION == "0.10.2"
    assert _skopt.RELIES_ON_INTERNALS


@settings(max_examples=8, deadline=None)  # a guided point costs a Gaussian process fit (about 1 s)
@given(seed=st.integers(0, 2**31 - 1), n_initial=st.integers(1, 6), n_guided=st.integers(0, 1))
def test_the_random_phase_asked_at_once_is_plain_skopts_ask_and_tell(seed, n_initial, n_guided):
    # The behaviour ask_random reads from skopt's internals: its points (then the guided ones) are those of a
    # plain skopt.Optimizer asked and told one point at a time with the same seed.
    import skopt

    from sklearn_radar._skopt import Optimizer

    space = [Real(0.0, 2.0), Integer(1, 9), Categorical(["a", "b", "c"])]
    plain = skopt.Optimizer(space, n_initial_points=n_initial, random_state=seed, acq_optimizer="sampling")
    expected = []
    for _ in range(n_initial + n_guided):
        point = plain.ask()
        expected.append(point)
        plain.tell(point, _categorical_objective(point))

    ours = Optimizer(space, n_initial_points=n_initial, random_state=seed, acq_optimizer="sampling")
    points = ours.ask_random(n_initial)
    for point in points:
        ours.tell(point, _categorical_objective(point))
    for _ in range(n_guided):
        (point,) = ours.ask(n_points=1)
        points.append(point)
        ours.tell(point, _categorical_objective(point))
    assert points == expected


def _categorical_objective(point):
    return _objective(point[:2]) + {"a": 0.0, "b": 0.3, "c": -0.2}[point[2]]


def test_without_the_pinned_release_random_points_are_asked_one_at_a_time(monkeypatch):
    from sklearn_radar import _skopt

    monkeypatch.setattr(_skopt, "RELIES_ON_INTERNALS", False)
    optimizer = _skopt.Optimizer([Real(0.0, 1.0)], n_initial_points=3, random_state=0)
    assert optimizer.n_random_left == 0
    with pytest.raises(ValueError, match="n_points=1"):
        optimizer.ask_random(1)
    assert len(optimizer.ask(n_points=1)) == 1


def _ask_and_tell_a_two_point_space(optimizer_class, n_points):
    """Ask and tell until the model proposes the space's points again (its two points are told first)."""
    optimizer = optimizer_class([Integer(0, 1)], n_initial_points=2, random_state=0)
    for _ in range(4):
        points = optimizer.ask(n_points=n_points)
        optimizer.tell(points, [float(point[0]) for point in points])


@pytest.mark.parametrize("n_points", [1, 2])
def test_skopts_warning_of_a_point_evaluated_before_does_not_leak(n_points):
    import warnings

    import skopt

    from sklearn_radar._skopt import REPEATED_POINT_WARNING, Optimizer

    with warnings.catch_warnings(record=True) as plain:
        warnings.simplefilter("always")
        _ask_and_tell_a_two_point_space(skopt.Optimizer, n_points)
    assert any(REPEATED_POINT_WARNING in str(w.message) for w in plain)  # skopt warns: the check below can fail
    with warnings.catch_warnings(record=True) as ours:
        warnings.simplefilter("always")
        _ask_and_tell_a_two_point_space(Optimizer, n_points)
    assert [str(w.message) for w in ours] == []


def test_a_search_of_a_small_space_leaks_no_warning():
    import warnings

    X, y = make_blobs(n_samples=60, centers=2, cluster_std=0.5, random_state=0)
    search = BayesSearchCV(
        DBSCAN(),
        {"min_samples": Integer(2, 3)},
        n_iter=5,
        cv=GroupKFold(n_splits=2),
        scoring=_fit_predict_v_measure,
        optimizer_kwargs={"n_initial_points": 2},
        random_state=0,
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        search.fit(X, y, groups=np.arange(len(X)) % 2)
    assert [str(w.message) for w in caught] == []


def test_only_the_repeated_point_warning_is_silenced(monkeypatch):
    import warnings

    import skopt

    from sklearn_radar._skopt import Optimizer

    def warns(self):
        warnings.warn("another warning of skopt", UserWarning, stacklevel=1)
        return [0]

    monkeypatch.setattr(skopt.Optimizer, "_ask", warns)
    with pytest.warns(UserWarning, match="another warning of skopt"):
        Optimizer([Integer(0, 1)], n_initial_points=2, random_state=0).ask(n_points=1)
