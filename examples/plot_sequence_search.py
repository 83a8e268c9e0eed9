"""
Tuning your own pipeline, one fit per sequence
==============================================

:func:`~sklearn_radar.model_selection.make_bayes_search` is the paper's
search as skopt's ``BayesSearchCV``: every candidate is fitted once per
training and once per test fold of each cross-validation split.
:class:`~sklearn_radar.model_selection.SequenceSearchCV` runs the same search
(same optimiser, same random state, same candidates in the same order, same
fold scores) the way ``python -m sklearn_radar reproduce`` runs it: a
radar clusterer never looks across recordings, so each candidate is fitted
once on each sequence, and a fold's score is combined from its sequences'
small summaries.  The steps before the tuned one (frame transform, filter)
run once per sequence for the whole search.

This example tunes a pipeline built by hand, not one of the paper's
experiments, with both searches, and compares their times and results.
"""

# %%
# A pipeline of your own
# ----------------------
# Frame transform, the Doppler-density filter (Eq. 1) and a Euclidean DBSCAN
# on position and radial velocity.  The search tunes the clusterer's radius
# ``eps_xyv`` (m, velocity scaled by ``vr_scale`` m/s to metres), its
# ``vr_scale`` and ``min_samples``.
import time

import numpy as np
from sklearn.pipeline import Pipeline
from threadpoolctl import threadpool_limits

from sklearn_radar import DopplerDensityFilter, FrameTransform, RadarDBSCAN
from sklearn_radar._skopt import Integer, Real
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import PIPELINE_COLUMNS
from sklearn_radar.metrics import precluster_target
from sklearn_radar.model_selection import SequenceSearchCV, make_bayes_search

pipeline = Pipeline(
    [
        ("frame", FrameTransform()),
        ("filter", DopplerDensityFilter()),
        ("cluster", RadarDBSCAN(metric="xyv", vr_min=0.2)),
    ]
)
space = {
    "cluster__eps_xyv": Real(0.3, 3.0),
    "cluster__vr_scale": Real(0.3, 10.0, prior="log-uniform"),
    "cluster__min_samples": Integer(2, 6),
}

scenes = make_scenes(n_sequences=4, duration=4.0, random_state=0)
X, groups = scenes.data[list(PIPELINE_COLUMNS)], scenes.groups
y = precluster_target(X, scenes.target)
print(f"{len(X)} detections in {len(np.unique(groups))} sequences")

# %%
# Both searches
# -------------
# 8 candidates (4 random, then 4 guided by the Gaussian process), 2 folds of
# whole sequences, the radar V-measure (Eq. 7), the same seed.
# ``threadpool_limits(1)`` keeps BLAS on one thread for the Gaussian process
# of ``BayesSearchCV`` (``SequenceSearchCV`` does it itself).
options = {"n_iter": 8, "n_initial_points": 4, "cv": 2, "random_state": 0}

start = time.perf_counter()
fast = SequenceSearchCV(pipeline, space, **options).fit(X, y, groups)
fast_seconds = time.perf_counter() - start

start = time.perf_counter()
with threadpool_limits(1):
    plain = make_bayes_search(pipeline, space, **options).fit(X, y, groups=groups)
plain_seconds = time.perf_counter() - start

print(
    f"make_bayes_search: {plain_seconds:.1f} s, SequenceSearchCV: {fast_seconds:.1f} s"
)
print(f"speed-up: {plain_seconds / fast_seconds:.1f}x")

# %%
# Most of what is left of ``SequenceSearchCV``'s time is the Gaussian process
# of the guided steps, the same in both; the fits it saves grow with the
# data (see ``benchmarks/bench_tuning.py --parts sequence``).

# %%
# The same search
# ---------------
# The candidates, in the order evaluated, with their mean fold scores.  A
# fold's score combined from its sequences may differ from the whole fold's
# in the last bit, nothing more.
fast_scores = fast.cv_results_["mean_test_score"]
plain_scores = plain.cv_results_["mean_test_score"]
for i, params in enumerate(fast.cv_results_["params"]):
    shown = ", ".join(
        f"{name.removeprefix('cluster__')}={value:.3g}"
        for name, value in params.items()
    )
    print(
        f"{i + 1}. {shown}: {fast_scores[i]:.4f} (BayesSearchCV {plain_scores[i]:.4f})"
    )

same = all(
    np.isclose(fast.best_params_[name], value, rtol=1e-9, atol=0.0)
    for name, value in plain.best_params_.items()
)
print(
    f"same best parameters: {same}; "
    f"best score {fast.best_score_:.4f} and {plain.best_score_:.4f}"
)
print("max score difference:", float(np.max(np.abs(fast_scores - plain_scores))))

# %%
# Like scikit-learn's searches, ``best_estimator_`` is the best candidate
# refitted on all the data (``refit=True``), ready to cluster:
labels = fast.best_estimator_[-1].labels_
print(
    f"{len(np.unique(labels[labels >= 0]))} clusters, "
    f"{np.mean(labels < 0):.0%} of the detections noise"
)
