"""The scikit-optimize shim works with the installed scikit-learn and numpy."""

import numpy as np
from sklearn.cluster import DBSCAN
from sklearn.datasets import make_blobs
from sklearn.metrics import v_measure_score
from sklearn.model_selection import GroupKFold

from sklearn_radar._skopt import BayesSearchCV, Integer, Real


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
    assert len(search.cv_results_["params"]) == 8
    assert 0.0 < search.best_score_ <= 1.0
    assert 0.05 <= search.best_params_["eps"] <= 3.0
