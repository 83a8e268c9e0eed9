"""V-measure for radar clustering: background may form clusters without penalty."""

from __future__ import annotations

import warnings
from numbers import Real

import numpy as np
from sklearn.metrics import homogeneity_completeness_v_measure
from sklearn.utils._param_validation import HasMethods, Interval, validate_params

__all__ = ["radar_homogeneity_completeness_v_measure", "radar_v_measure", "radar_v_measure_scorer"]


def _unique_per_group(labels, groups):
    """Labels made distinct across groups (sequences); -1 stays -1 in every group."""
    labels = np.asarray(labels)
    if groups is None:
        return labels
    groups = np.asarray(groups)
    if groups.shape != labels.shape:
        raise ValueError(f"groups has shape {groups.shape}, labels have {labels.shape}")
    _, group_code = np.unique(groups, return_inverse=True)
    _, label_code = np.unique(labels, return_inverse=True)
    combined = group_code.ravel().astype(np.int64) * (label_code.max() + 1 if len(labels) else 1) + label_code.ravel()
    return np.where(labels == -1, -1, combined)


_LABELS_CONSTRAINTS = {
    "labels_true": ["array-like"],
    "labels_pred": ["array-like"],
    "groups": ["array-like", None],
    "beta": [Interval(Real, 0, None, closed="left")],
}


@validate_params(_LABELS_CONSTRAINTS, prefer_skip_nested_validation=True)
def radar_homogeneity_completeness_v_measure(labels_true, labels_pred, *, groups=None, beta=1.0):
    """Homogeneity, completeness and V-measure with background handled as in Scheiner et al. 2019.

    The paper changes completeness "so that making clusters out of background
    detections is not penalised".  This reading computes

    * homogeneity ``1 - H(C|K) / H(C)`` over **all** detections, with the
      background (``labels_true == -1``) one class and the predicted noise
      (``labels_pred == -1``) one cluster, as scikit-learn does;
    * completeness ``1 - H(K|C) / H(K)`` over the detections of **labelled
      objects only** (``labels_true != -1``);
    * V-measure, their weighted harmonic mean.

    Hence: clustering background costs nothing (completeness never sees it,
    and background-only clusters are pure); background inside an object's
    cluster lowers homogeneity; an object split into several clusters, or
    partly into noise, lowers completeness; and without background the three
    values equal :func:`sklearn.metrics.homogeneity_completeness_v_measure`.

    Read more in the :ref:`User Guide <user-guide-scoring>`.

    Parameters
    ----------
    labels_true : array-like of shape (n_detections,)
        Ground-truth instance per detection, -1 for background.
    labels_pred : array-like of shape (n_detections,)
        Predicted cluster per detection, -1 for noise.
    groups : array-like of shape (n_detections,), default=None
        Sequence of each detection: equal ids in different sequences are
        different clusters (and instances).
    beta : float, default=1.0
        Weight of homogeneity in the V-measure, >= 0, as in scikit-learn.

    Returns
    -------
    homogeneity, completeness, v_measure : float
        The three scores, each in [0, 1].

    Raises
    ------
    ValueError
        If the label arrays (and ``groups``) are not 1-D of equal length.

    Examples
    --------
    >>> from sklearn_radar.metrics import radar_homogeneity_completeness_v_measure
    >>> radar_homogeneity_completeness_v_measure([0, 0, 1, 1], [0, 0, 0, 0])
    (0.0, 1.0, 0.0)
    """
    labels_true = _unique_per_group(labels_true, groups)
    labels_pred = _unique_per_group(labels_pred, groups)
    if labels_true.shape != labels_pred.shape or labels_true.ndim != 1:
        raise ValueError(
            f"labels_true and labels_pred must be 1-D of equal length, got {labels_true.shape} and {labels_pred.shape}"
        )
    homogeneity, _, _ = homogeneity_completeness_v_measure(labels_true, labels_pred)
    objects = labels_true != -1
    if objects.any():
        _, completeness, _ = homogeneity_completeness_v_measure(labels_true[objects], labels_pred[objects])
    else:
        completeness = 1.0
    if homogeneity + completeness == 0:
        return float(homogeneity), float(completeness), 0.0
    v_measure = (1 + beta) * homogeneity * completeness / (beta * homogeneity + completeness)
    return float(homogeneity), float(completeness), float(v_measure)


@validate_params(_LABELS_CONSTRAINTS, prefer_skip_nested_validation=True)
def radar_v_measure(labels_true, labels_pred, *, groups=None, beta=1.0):
    """V-measure of :func:`radar_homogeneity_completeness_v_measure`, in [0, 1].

    Background (``labels_true == -1``) may form clusters without penalty;
    see :func:`radar_homogeneity_completeness_v_measure` for the exact
    reading of the paper's modified completeness.

    Read more in the :ref:`User Guide <user-guide-scoring>`.

    Parameters
    ----------
    labels_true, labels_pred, groups, beta
        As in :func:`radar_homogeneity_completeness_v_measure`.

    Returns
    -------
    v_measure : float
        Weighted harmonic mean of homogeneity and completeness, in [0, 1].

    See Also
    --------
    radar_homogeneity_completeness_v_measure : all three scores.
    radar_v_measure_scorer : the score as a scorer for parameter searches.

    Examples
    --------
    >>> from sklearn_radar.metrics import radar_v_measure
    >>> round(radar_v_measure([0, 0, -1, -1], [5, 5, 7, 8]), 6)  # clustered background costs nothing
    1.0
    """
    return radar_homogeneity_completeness_v_measure(labels_true, labels_pred, groups=groups, beta=beta)[2]


# Not skipping nested validation: the scorer fits ``estimator``, whose parameters
# (a search's candidate) must still be validated by its own fit.
@validate_params(
    {"estimator": [HasMethods(["fit_predict"])], "X": ["array-like"], "y": ["array-like"]},
    prefer_skip_nested_validation=False,
)
def radar_v_measure_scorer(estimator, X, y):
    """Scorer for every scikit-learn search: ``fit_predict`` on X, radar V-measure against y.

    Clusterers have no out-of-sample ``predict``, so the estimator is fitted
    on the data it is scored on.  Sequences come from the ``sequence``
    column of X when it has one.  Once its arguments are valid it never
    raises and never returns NaN: a failing fit or a degenerate labelling
    scores 0.0, which keeps Bayesian optimisation (whose Gaussian process
    cannot take NaN) running.

    Read more in the :ref:`User Guide <user-guide-scoring>`.

    Parameters
    ----------
    estimator : estimator with ``fit_predict``
        The clusterer (or pipeline ending in one) to score; it is fitted on
        ``X``.
    X : DataFrame or array-like of shape (n_detections, n_columns)
        The detections it clusters.
    y : array-like of shape (n_detections,)
        Target instance per detection, -1 for background (e.g.
        :func:`precluster_target`).

    Returns
    -------
    score : float
        :func:`radar_v_measure` of the predicted clusters against ``y``, in
        [0, 1]; 0.0 when the fit fails or the score is not finite.

    Raises
    ------
    InvalidParameterError
        If ``estimator`` has no ``fit_predict`` or ``X`` or ``y`` is not
        array-like: a mistake in the search set-up rather than a failing
        candidate.

    See Also
    --------
    sklearn_radar.model_selection.make_bayes_search : uses this scorer by default.
    """
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            labels = estimator.fit_predict(X)
        groups = X["sequence"].to_numpy() if hasattr(X, "columns") and "sequence" in X.columns else None
        score = radar_v_measure(np.asarray(y), labels, groups=groups)
    except Exception:  # a search must go on; error_score=0 documents the same choice
        return 0.0
    return float(score) if np.isfinite(score) else 0.0
