"""Object-level metrics: panoptic quality, coverage and the share of background-only clusters, per time window.

A *segment* is a set of detections.  A ground-truth segment is one annotated
object's detections inside one time window of one sequence; a predicted
segment is one cluster's.  Background (``labels_true == -1``) belongs to no
ground-truth segment, noise (``labels_pred == -1``) to no predicted segment.
Segments of different windows or sequences are never compared.

Every score is a ratio of sums and counts over segments, which add up over sequences: each
function here is the combination (:func:`~sklearn_radar.metrics._parts.combine_instance_parts`) of one part
(:func:`~sklearn_radar.metrics._parts.instance_parts`), the whole labelling.
"""

from __future__ import annotations

import warnings
from numbers import Real

import numpy as np
from sklearn.utils import Bunch
from sklearn.utils._param_validation import HasMethods, Interval, StrOptions, validate_params

from ._parts import combine_instance_parts, instance_parts
from ._segments import _times_and_groups

__all__ = [
    "background_share",
    "instance_coverage",
    "instance_scores",
    "make_instance_scorer",
    "panoptic_quality",
    "panoptic_quality_scorer",
]

#: Keys of :func:`panoptic_quality`, :func:`instance_coverage` and :func:`background_share`, parts of the Bunch of
#: :func:`instance_scores`.
_PQ_KEYS = ("pq", "sq", "rq", "precision", "recall", "tp", "fp", "fn")
_COVERAGE_KEYS = ("mcov", "mwcov")
_BACKGROUND_KEYS = ("background_segment_share", "background_cluster_share")
#: Scorer metric -> (key of instance_scores, sign).  Searches maximise, so the shares (lower is better) are negated.
_SCORER_METRICS = {
    "pq": ("pq", 1.0),
    "sq": ("sq", 1.0),
    "rq": ("rq", 1.0),
    "f1": ("rq", 1.0),
    "precision": ("precision", 1.0),
    "recall": ("recall", 1.0),
    "mcov": ("mcov", 1.0),
    "mwcov": ("mwcov", 1.0),
    "neg_background_segment_share": ("background_segment_share", -1.0),
    "neg_background_cluster_share": ("background_cluster_share", -1.0),
}

_CONSTRAINTS = {
    "labels_true": ["array-like"],
    "labels_pred": ["array-like"],
    "times": ["array-like", None],
    "groups": ["array-like", None],
    "window": [Interval(Real, 0, None, closed="neither"), None],
}


@validate_params(_CONSTRAINTS, prefer_skip_nested_validation=True)
def instance_scores(labels_true, labels_pred, *, times, groups=None, window=0.5):
    """Panoptic quality, coverage and background shares at once, from one segmentation of the detections.

    The union of :func:`panoptic_quality`, :func:`instance_coverage` and
    :func:`background_share` (see them for the formulas), which are parts of
    it; it segments the detections once: the choice for a report that shows
    them side by side.

    Read more in the :ref:`User Guide <user-guide-scoring>`.

    Parameters
    ----------
    labels_true : array-like of shape (n_detections,)
        Ground-truth instance per detection, -1 for background.
    labels_pred : array-like of shape (n_detections,)
        Predicted cluster per detection, -1 for noise.
    times : array-like of shape (n_detections,) or None
        Time of each detection in s (e.g. ``timestamp * 1e-6``).  None, or
        ``window=None``: every sequence is one window.
    groups : array-like of shape (n_detections,), default=None
        Sequence of each detection: equal labels in different sequences are
        different segments, and windows start at each sequence's first
        detection.  None: one sequence.
    window : float or None, default=0.5
        Length of a time window in s, > 0; detection ``i`` of sequence ``s``
        lies in window ``floor((times[i] - min(times of s)) / window)``.  The
        default, 500 ms, is the window of Scheiner et al. (2021).  None: one
        window per sequence ("per sequence" evaluation).

    Returns
    -------
    scores : Bunch
        The keys of :func:`panoptic_quality` (``pq``, ``sq``, ``rq``,
        ``precision``, ``recall``, ``tp``, ``fp``, ``fn``), of
        :func:`instance_coverage` (``mcov``, ``mwcov``) and of
        :func:`background_share` (``background_segment_share``,
        ``background_cluster_share``).

    Raises
    ------
    ValueError
        If the arrays are not 1-D of equal length or a time is not finite.

    Examples
    --------
    >>> from sklearn_radar.metrics import instance_scores
    >>> # Cluster 3 is object 0 exactly; cluster 4, background only, is a false positive: RQ = 1 / (1 + 1/2).
    >>> scores = instance_scores([0, 0, 0, -1], [3, 3, 3, 4], times=[0.0, 0.1, 0.2, 0.3])
    >>> round(scores.pq, 6), scores.mcov, scores.background_cluster_share
    (0.666667, 1.0, 0.5)
    """
    # The whole labelling as one part: one implementation of the scores for it and for merged parts.
    return combine_instance_parts([instance_parts(labels_true, labels_pred, times=times, groups=groups, window=window)])


@validate_params(_CONSTRAINTS, prefer_skip_nested_validation=True)
def panoptic_quality(labels_true, labels_pred, *, times, groups=None, window=0.5):
    """Panoptic quality (Kirillov et al. 2019) of the clusters, one "thing" class, per time window.

    Within each sequence (``groups``) time is cut into windows of ``window``
    seconds.  A ground-truth segment ``g`` is one object's detections inside
    a window, a predicted segment ``p`` one cluster's.  Over all windows and
    sequences:

    * a pair matches when ``IoU(g, p) = |g ∩ p| / |g ∪ p| > 0.5``; with this
      threshold every segment has at most one match;
    * TP = matched pairs, FP = unmatched predicted segments (clusters of
      background only included), FN = unmatched ground-truth segments;
    * ``SQ = Σ_TP IoU / TP`` (segmentation quality),
      ``RQ = TP / (TP + FP/2 + FN/2)`` (recognition quality, the F1 score),
      ``PQ = SQ × RQ``, ``precision = TP / (TP + FP)``,
      ``recall = TP / (TP + FN)``.

    Unlike the radar V-measure, clustering static background costs here:
    every background-only cluster is a false positive in each window it
    spans.  Degenerate input never raises: a ratio 0/0 (no segment at all,
    or no match for SQ) is 0.0, never NaN.

    Read more in the :ref:`User Guide <user-guide-scoring>`.

    Parameters
    ----------
    labels_true, labels_pred, times, groups, window
        As in :func:`instance_scores`: ground truth (-1 background),
        clusters (-1 noise), times (s), sequences and window length (s).

    Returns
    -------
    scores : Bunch
        ``pq``, ``sq``, ``rq``, ``precision``, ``recall`` (floats in
        [0, 1]) and the counts ``tp``, ``fp``, ``fn`` (ints).

    See Also
    --------
    instance_scores : all object-level scores at once, and the errors it raises.
    panoptic_quality_scorer : PQ as a scorer for parameter searches.

    References
    ----------
    .. [1] A. Kirillov, K. He, R. Girshick, C. Rother and P. Dollár,
       "Panoptic Segmentation", CVPR 2019.
    .. [2] N. Scheiner, F. Kraus, N. Appenrodt, J. Dickmann and B. Sick,
       "Object detection for automotive radar point clouds – a comparison",
       AI Perspectives 3, 2021 (windows of 500 ms).

    Examples
    --------
    >>> from sklearn_radar.metrics import panoptic_quality
    >>> # One object of 4 detections; the cluster takes 3 of them and 1 background detection: IoU = 3/5.
    >>> scores = panoptic_quality([0, 0, 0, 0, -1], [7, 7, 7, -1, 7], times=[0.0, 0.1, 0.2, 0.3, 0.4])
    >>> round(scores.pq, 6), scores.tp, scores.fp, scores.fn
    (0.6, 1, 0, 0)
    """
    scores = instance_scores(labels_true, labels_pred, times=times, groups=groups, window=window)
    return Bunch(**{key: scores[key] for key in _PQ_KEYS})


@validate_params(_CONSTRAINTS, prefer_skip_nested_validation=True)
def instance_coverage(labels_true, labels_pred, *, times, groups=None, window=0.5):
    """Mean coverage mCov and weighted mean coverage mWCov of the ground-truth segments, per time window.

    The coverage of a ground-truth segment ``g`` (one object's detections
    inside one window, as in :func:`panoptic_quality`) is its best IoU with a
    predicted segment of the same window, 0 when no cluster overlaps it:
    ``cov(g) = max_p |g ∩ p| / |g ∪ p|``.  Then ``mCov = Σ_g cov(g) / G``
    over the G ground-truth segments and
    ``mWCov = Σ_g |g| cov(g) / Σ_g |g|``, which weights each segment by its
    number of detections, as radar instance-segmentation papers report them
    (e.g. Liu et al. 2022).  Coverage does not penalise extra clusters
    (background-only ones included): report it beside
    :func:`panoptic_quality`, not instead of it.  Without ground-truth
    segments both are 0.0 (never NaN).

    Read more in the :ref:`User Guide <user-guide-scoring>`.

    Parameters
    ----------
    labels_true, labels_pred, times, groups, window
        As in :func:`instance_scores`: ground truth (-1 background),
        clusters (-1 noise), times (s), sequences and window length (s).

    Returns
    -------
    scores : Bunch
        ``mcov`` and ``mwcov``, floats in [0, 1].

    See Also
    --------
    instance_scores : all object-level scores at once, and the errors it raises.

    References
    ----------
    .. [1] J. Liu, W. Xiong, L. Bai, Y. Xia, T. Huang, W. Ouyang and B. Zhu,
       "Deep instance segmentation with automotive radar detection points",
       IEEE Transactions on Intelligent Vehicles, 2022.

    Examples
    --------
    >>> from sklearn_radar.metrics import instance_coverage
    >>> # Object 0 (4 detections) split 2 + 2: cov 1/2; object 1 (2 detections) found whole: cov 1.
    >>> scores = instance_coverage([0, 0, 0, 0, 1, 1], [1, 1, 2, 2, 3, 3], times=None)
    >>> float(scores.mcov), float(scores.mwcov)
    (0.75, 0.6666666666666666)
    """
    scores = instance_scores(labels_true, labels_pred, times=times, groups=groups, window=window)
    return Bunch(**{key: scores[key] for key in _COVERAGE_KEYS})


@validate_params(_CONSTRAINTS, prefer_skip_nested_validation=True)
def background_share(labels_true, labels_pred, *, times=None, groups=None, window=0.5):
    """Share of the predicted segments (per window) and of the clusters (per sequence) that hold background only.

    A predicted segment, one cluster's detections inside one window as in
    :func:`panoptic_quality`, or a whole cluster of one sequence, is
    background-only when none of its detections belongs to an annotated
    object (``labels_true == -1`` for all of them).  The shares make the
    cost of clustering static background visible, which the radar V-measure
    ignores by design.  Without clusters both are 0.0 (never NaN).

    Read more in the :ref:`User Guide <user-guide-scoring>`.

    Parameters
    ----------
    labels_true, labels_pred, times, groups, window
        As in :func:`instance_scores`: ground truth (-1 background),
        clusters (-1 noise), times (s), sequences and window length (s);
        here ``times`` may be left out (None: every sequence is one window).

    Returns
    -------
    scores : Bunch
        ``background_segment_share`` (per window; equal to the cluster share
        when ``times`` or ``window`` is None) and
        ``background_cluster_share`` (per sequence), floats in [0, 1].

    See Also
    --------
    instance_scores : all object-level scores at once, and the errors it raises.

    Examples
    --------
    >>> from sklearn_radar.metrics import background_share
    >>> # Cluster 5 holds object 0, cluster 6 only background.
    >>> scores = background_share([0, 0, -1, -1, -1], [5, 5, 5, 6, 6])
    >>> scores.background_cluster_share
    0.5
    """
    scores = instance_scores(labels_true, labels_pred, times=times, groups=groups, window=window)
    return Bunch(**{key: scores[key] for key in _BACKGROUND_KEYS})


def _instance_score(estimator, X, y, metric, window):
    """The scorers' body: ``fit_predict`` on X, then one score; the worst value on any failure."""
    key, sign = _SCORER_METRICS[metric]
    times, groups = _times_and_groups(X, window)  # a set-up mistake: raises before any fit
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            labels = estimator.fit_predict(X)
        scores = combine_instance_parts(
            [instance_parts(np.asarray(y), np.asarray(labels), times=times, groups=groups, window=window)]
        )
        score = sign * scores[key]
    except Exception:  # a search must go on; error_score=0 documents the same choice
        return min(0.0, sign)
    return float(score) if np.isfinite(score) else min(0.0, sign)


class _InstanceScorer:
    """A scorer ``(estimator, X, y) -> float`` of :func:`make_instance_scorer` (a class, so that it pickles)."""

    def __init__(self, metric, window):
        self.metric = metric
        self.window = window

    def __call__(self, estimator, X, y):
        return _instance_score(estimator, X, y, self.metric, self.window)

    def __repr__(self):
        return f"make_instance_scorer(metric={self.metric!r}, window={self.window!r})"


# Not skipping nested validation: the scorer fits ``estimator``, whose parameters
# (a search's candidate) must still be validated by its own fit.
@validate_params(
    {"estimator": [HasMethods(["fit_predict"])], "X": ["array-like"], "y": ["array-like"]},
    prefer_skip_nested_validation=False,
)
def panoptic_quality_scorer(estimator, X, y):
    """Scorer for every scikit-learn search: ``fit_predict`` on X, panoptic quality per 0.5 s window against y.

    The scorer of ``make_instance_scorer("pq", window=0.5)``: see
    :func:`make_instance_scorer` for how it fits the estimator, reads the
    times and sequences of X and scores a failing fit (0.0).

    Read more in the :ref:`User Guide <user-guide-scoring>`.

    Parameters
    ----------
    estimator : estimator with ``fit_predict``
        The clusterer (or pipeline ending in one) to score; it is fitted on
        ``X``.
    X : DataFrame of shape (n_detections, n_columns)
        The detections it clusters, with a ``t`` or ``timestamp`` column.
    y : array-like of shape (n_detections,)
        Ground-truth instance per detection, -1 for background (e.g.
        :func:`sklearn_radar.instance_target`).

    Returns
    -------
    score : float
        PQ of :func:`panoptic_quality` with ``window=0.5``, in [0, 1]; 0.0
        when the fit fails.

    Raises
    ------
    InvalidParameterError
        If ``estimator`` has no ``fit_predict`` or ``X`` or ``y`` is not
        array-like.
    ValueError
        If X has neither a ``t`` nor a ``timestamp`` column: a mistake in
        the search set-up rather than a failing candidate.

    See Also
    --------
    make_instance_scorer : a scorer for any of the object-level scores and window lengths.
    """
    return _instance_score(estimator, X, y, "pq", 0.5)


@validate_params(
    {"metric": [StrOptions(set(_SCORER_METRICS))], "window": [Interval(Real, 0, None, closed="neither"), None]},
    prefer_skip_nested_validation=True,
)
def make_instance_scorer(metric="pq", *, window=0.5):
    """A scorer ``(estimator, X, y) -> float`` of one object-level score, for every scikit-learn search.

    Clusterers have no out-of-sample ``predict``, so the estimator is fitted
    on the data it is scored on, as by
    :func:`~sklearn_radar.metrics.radar_v_measure_scorer`.  X is the
    detection table: the times come from its ``t`` column (s) or else from
    ``timestamp`` (µs), the sequences from ``sequence`` when it has one.
    Once its arguments are valid and X has the time column it needs, it
    never raises and never returns NaN: a failing fit scores the worst value
    (0.0; -1.0 for a negated share), a degenerate labelling what the
    function gives it (0.0 for a ratio 0/0).

    Read more in the :ref:`User Guide <user-guide-scoring>`.

    Parameters
    ----------
    metric : str, default="pq"
        The score: ``"pq"``, ``"sq"``, ``"rq"`` (or its name ``"f1"``),
        ``"precision"``, ``"recall"``, ``"mcov"``, ``"mwcov"`` (the keys of
        :func:`instance_scores`), or ``"neg_background_segment_share"`` or
        ``"neg_background_cluster_share"``: searches maximise, so the
        background shares are negated, in [-1, 0].
    window : float or None, default=0.5
        Length of a time window in s, > 0; None: one window per sequence (X
        then needs no time column).

    Returns
    -------
    scorer : callable
        ``scorer(estimator, X, y)``, fitting ``estimator`` with
        ``fit_predict`` on X and scoring its clusters against y; it pickles.

    See Also
    --------
    panoptic_quality_scorer : the scorer of ``metric="pq", window=0.5``.

    Examples
    --------
    >>> from sklearn_radar.metrics import make_instance_scorer
    >>> make_instance_scorer("mwcov", window=None)
    make_instance_scorer(metric='mwcov', window=None)
    """
    return _InstanceScorer(metric, window)
