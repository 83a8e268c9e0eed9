"""scikit-learn's common estimator checks, with every expected failure and its reason in one table."""

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.utils.estimator_checks import parametrize_with_checks

from sklearn_radar import ClusterMerger, DopplerDensityFilter, FrameTransform, RadarDBSCAN, config_context
from sklearn_radar._skopt import Real
from sklearn_radar.classification import ClusterClassifier, PointClassifier
from sklearn_radar.cluster import (
    LinkClustering,
    SequenceDBSCAN,
    SequenceHDBSCAN,
    SlidingDBSCAN,
    WindowedDBSCAN,
    WindowedHDBSCAN,
)
from sklearn_radar.model_selection import SequenceSearchCV

#: A small search of RadarDBSCAN's eps_xy (m), two random candidates on two folds.
_SEARCH = SequenceSearchCV(
    RadarDBSCAN(metric="xy", vr_min=-np.inf), {"eps_xy": Real(0.5, 2.0)}, n_iter=2, n_initial_points=2, cv=2
)
_SEARCH_REPR = repr(_SEARCH)
#: {repr of the estimator below: {check name: reason}}.  Keep every entry justified.
_BY_DESIGN_NOISE = (
    "RadarDBSCAN's default vr_min = 0.4 m/s (the paper's expert setting) lets only moving detections be "
    "core points; the check's blobs have no Doppler column (v_r = 0), so every point is noise by design. "
    "The same check passes with vr_min=-inf (second RadarDBSCAN instance)."
)
_SEQUENCE_GATE_NOISE = (
    "The per-sequence and sliding-window baselines' default Doppler gate vr_min = 0.4 m/s (as the paper's "
    "expert) makes every detection with |v_r| <= 0.4 m/s noise; the check's blobs have no Doppler column "
    "(v_r = 0), so every point is noise by design. The same check passes with vr_min=-inf (second instance of each)."
)
_NEEDS_GROUPS = (
    "SequenceSearchCV.fit needs groups (the sequence of each detection: its folds are whole sequences, as "
    "GroupKFold's, which raises without groups too), and the checks call fit(X, y) without them: fit raises a "
    "ValueError naming groups before anything the check looks at.  As a meta-estimator it leaves X to the searched "
    "estimator (as scikit-learn's searches do), so the input checks' messages are not its own.  Its search is "
    "tested against BayesSearchCV in tests/model_selection/test_sequence_search.py."
)
_NEEDS_INSTANCES = (
    "LinkClustering learns from the ground-truth instances, so fit requires y (the instance of each detection) "
    "and the check calls fit(X) without it: fit raises a ValueError naming y (tested in "
    "tests/cluster/test_link_clustering.py)."
)
#: Given thresholds: the checks' arrays are one scan of one sequence, where the automatic tuning (on out-of-fold
#: predictions of other sequences or time spans) has nothing to hold out and raises, naming the parameters
#: (tests/cluster/test_link_clustering.py).
_LINK_CLUSTERING = LinkClustering(link_threshold=0.5, objectness_threshold=0.5, min_cluster_size=1, max_iter=5)
_CAUSAL_LINK_CLUSTERING = clone(_LINK_CLUSTERING).set_params(causal=True)
_CONTEXT_LINK_CLUSTERING = clone(_CAUSAL_LINK_CLUSTERING).set_params(cluster_window=0.5)
#: The checks LinkClustering fails by design, causal or not, with cluster context or not.
_LINK_CLUSTERING_FAILURES = {
    "check_clustering": _NEEDS_INSTANCES,
    "check_clustering(readonly_memmap=True)": _NEEDS_INSTANCES,
    "check_non_transformer_estimators_n_iter": (
        "max_iter is the number of boosting iterations of its two classifiers (scikit-learn's "
        "HistGradientBoostingClassifier, whose n_iter_ each fitted classifier has); the clustering itself "
        "does not iterate, so there is no n_iter_ of its own."
    ),
    "check_methods_sample_order_invariance": (
        "predict numbers the clusters 0, 1, ... in order of each cluster's first row (as labels_ of every "
        "clusterer here), so permuting the rows renames the clusters; the partition itself does not depend on "
        "the row order (tested with hypothesis in tests/cluster/test_link_clustering.py)."
    ),
    "check_methods_subset_invariance": (
        "A detection's features count its neighbours among the detections given to predict (as Eq. 1's "
        "filter does), so predicting a subset changes the features and hence the clusters, by design."
    ),
}
EXPECTED_FAILED_CHECKS = {
    "DopplerDensityFilter()": {
        "check_methods_subset_invariance": (
            "Eq. 1 counts each detection's neighbours among the detections given to transform, "
            "so transforming a subset changes the counts and hence the keep flags, by design."
        ),
    },
    "RadarDBSCAN()": {
        "check_clustering": _BY_DESIGN_NOISE,
        "check_clustering(readonly_memmap=True)": _BY_DESIGN_NOISE,
    },
    "SequenceDBSCAN()": {
        "check_clustering": _SEQUENCE_GATE_NOISE,
        "check_clustering(readonly_memmap=True)": _SEQUENCE_GATE_NOISE,
    },
    "SequenceHDBSCAN()": {
        "check_clustering": _SEQUENCE_GATE_NOISE,
        "check_clustering(readonly_memmap=True)": _SEQUENCE_GATE_NOISE,
    },
    "SlidingDBSCAN()": {
        "check_clustering": _SEQUENCE_GATE_NOISE,
        "check_clustering(readonly_memmap=True)": _SEQUENCE_GATE_NOISE,
    },
    _SEARCH_REPR: {
        "check_complex_data": _NEEDS_GROUPS,
        "check_dict_unchanged": _NEEDS_GROUPS,
        "check_dont_overwrite_parameters": _NEEDS_GROUPS,
        "check_dtype_object": _NEEDS_GROUPS,
        "check_estimator_sparse_array": _NEEDS_GROUPS,
        "check_estimator_sparse_matrix": _NEEDS_GROUPS,
        "check_estimator_sparse_tag": _NEEDS_GROUPS,
        "check_estimators_dtypes": _NEEDS_GROUPS,
        "check_estimators_empty_data_messages": _NEEDS_GROUPS,
        "check_estimators_fit_returns_self": _NEEDS_GROUPS,
        "check_estimators_nan_inf": _NEEDS_GROUPS,
        "check_estimators_overwrite_params": _NEEDS_GROUPS,
        "check_estimators_pickle": _NEEDS_GROUPS,
        "check_estimators_pickle(readonly_memmap=True)": _NEEDS_GROUPS,
        "check_f_contiguous_array_estimator": _NEEDS_GROUPS,
        "check_fit2d_1feature": _NEEDS_GROUPS,
        "check_fit2d_1sample": _NEEDS_GROUPS,
        "check_fit2d_predict1d": _NEEDS_GROUPS,
        "check_fit_check_is_fitted": _NEEDS_GROUPS,
        "check_fit_idempotent": _NEEDS_GROUPS,
        "check_fit_score_takes_y": _NEEDS_GROUPS,
        "check_methods_sample_order_invariance": _NEEDS_GROUPS,
        "check_methods_subset_invariance": _NEEDS_GROUPS,
        "check_n_features_in": _NEEDS_GROUPS,
        "check_n_features_in_after_fitting": _NEEDS_GROUPS,
        "check_pipeline_consistency": _NEEDS_GROUPS,
        "check_positive_only_tag_during_fit": _NEEDS_GROUPS,
        "check_readonly_memmap_input": _NEEDS_GROUPS,
    },
    **{
        repr(link_clustering): _LINK_CLUSTERING_FAILURES
        for link_clustering in (_LINK_CLUSTERING, _CAUSAL_LINK_CLUSTERING, _CONTEXT_LINK_CLUSTERING)
    },
    "ClusterMerger()": {
        "check_clustering": "Its default stage 1 is RadarDBSCAN() with vr_min = 0.4 m/s: " + _BY_DESIGN_NOISE,
        "check_clustering(readonly_memmap=True)": "Its default stage 1 is RadarDBSCAN(): " + _BY_DESIGN_NOISE,
    },
}


_RAW_RANDOM_IS_IMPLAUSIBLE = (
    "FrameTransform reads raw measurements by position (range_sc, azimuth_sc, vr, timestamp, mounting, odometry): "
    "the checks' random columns give negative ranges, azimuths beyond +-pi rad and timestamps a fraction of a "
    "microsecond apart, which no radar produces, so the plausibility check rightly refuses them. Its checks run "
    "with sklearn_radar.config_context(check_plausibility=False); that they would fail otherwise is tested below."
)
#: {repr of the estimator: reason} of the estimators whose common checks run with the plausibility checks off.
#: Every other estimator runs them with the checks on (the default).
PLAUSIBILITY_OFF = {
    "FrameTransform()": _RAW_RANDOM_IS_IMPLAUSIBLE,
    "FrameTransform(frame='car')": _RAW_RANDOM_IS_IMPLAUSIBLE,
}


def _expected_failed_checks(estimator):
    return EXPECTED_FAILED_CHECKS.get(repr(estimator), {})


def _strict(parametrize):
    """The same parametrization with every expected failure strict: a check that passes fails the run.

    (scikit-learn >= 1.8 has ``xfail_strict=True``; rewriting the marks works with every version we support.)
    """
    argnames, params = parametrize.args
    strict = []
    for param in params:
        marks = [
            pytest.mark.xfail(reason=mark.kwargs.get("reason", ""), strict=True) if mark.name == "xfail" else mark
            for mark in getattr(param, "marks", ())
        ]
        strict.append(pytest.param(*param.values, marks=marks, id=param.id) if marks else param)
    return pytest.mark.parametrize(argnames, strict, **parametrize.kwargs)


CHECKS = _strict(
    parametrize_with_checks(
        [
            FrameTransform(),
            FrameTransform(frame="car"),
            DopplerDensityFilter(),
            RadarDBSCAN(),
            # alpha_r > 0 (Eq. 2) and mode="velocity" (Eq. 6) need range_sc and the line of sight, which the
            # checks' generic arrays cannot hold: both raise on them by design (tests/test_validation.py).
            RadarDBSCAN(metric="xyv", vr_scale=2.0, vr_min=-np.inf),
            RadarDBSCAN(metric="xy", causal=True, vr_min=-np.inf),
            ClusterMerger(),
            ClusterMerger(stage1=RadarDBSCAN(metric="xy", vr_min=-np.inf)),
            WindowedDBSCAN(),
            WindowedHDBSCAN(),
            SequenceDBSCAN(),
            SequenceDBSCAN(vr_min=-np.inf),
            SequenceHDBSCAN(),
            SequenceHDBSCAN(vr_min=-np.inf),
            SlidingDBSCAN(),
            SlidingDBSCAN(vr_min=-np.inf),
            _SEARCH,
            # A plain array holds no instance ids (the default instance_column="track_id" needs the DataFrame):
            # the checks' arrays use the class segments of each frame as the instances, as documented.
            ClusterClassifier(RadarDBSCAN(metric="xy", vr_min=-np.inf), instance_column=None),
            PointClassifier(),
            PointClassifier(radius=2.0),
            PointClassifier(radius=2.0, causal=True),
            _LINK_CLUSTERING,
            _CAUSAL_LINK_CLUSTERING,
            _CONTEXT_LINK_CLUSTERING,
        ],
        expected_failed_checks=_expected_failed_checks,
    )
)


@CHECKS
def test_sklearn_compatible_estimator(estimator, check):
    with config_context(check_plausibility=repr(estimator) not in PLAUSIBILITY_OFF):
        check(estimator)


@pytest.mark.parametrize("name", sorted(PLAUSIBILITY_OFF))
def test_an_estimator_run_without_plausibility_checks_needs_it(name):
    # The table entry is justified: on the checks' kind of data (make_blobs, values within +-10) it raises.
    estimator = {repr(e): e for e in (FrameTransform(), FrameTransform(frame="car"))}[name]
    X = np.random.default_rng(0).normal(scale=5.0, size=(30, 4))
    with pytest.raises(ValueError, match="implausible input"):
        estimator.fit(X)
    with config_context(check_plausibility=False):
        estimator.fit(X)


def test_every_expected_failure_is_strict_and_matches_a_check():
    # One strict xfail per table entry: a misspelt check name would leave a check unmarked (and failing), a
    # fixed estimator would turn its xfail into a failure instead of a quiet XPASS.
    marks = [mark for param in CHECKS.args[1] for mark in getattr(param, "marks", ()) if mark.name == "xfail"]
    assert len(marks) == sum(len(checks) for checks in EXPECTED_FAILED_CHECKS.values())
    assert all(mark.kwargs["strict"] is True for mark in marks)
