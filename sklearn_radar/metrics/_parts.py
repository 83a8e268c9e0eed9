"""Mergeable per-sequence summaries of a labelling, for scoring a candidate one sequence at a time.

A distributed search scores a candidate with one task per sequence, on the
worker that holds the sequence.  Each task returns a small summary, a
*part*, instead of its labels; the main process combines the parts of a
cross-validation fold's sequences into the fold's score.  The combined score
equals the score of the concatenated sequences with ``groups`` (one group
per sequence):

* ``"v1"``: :func:`~sklearn_radar.metrics.radar_v_measure`.  A part is the
  sparse contingency table of the sequence (ground-truth instance x
  cluster), with the background row and the noise column identifiable:
  background is one class and noise one cluster over *all* sequences, so
  the merge pools them and keeps every other row and column distinct.
* ``"pq"``: :func:`~sklearn_radar.metrics.panoptic_quality`.  Segments never
  cross sequences, so a part is the counts TP, FP, FN and the sum of the
  matched IoUs; they add up.

A part's size grows with the number of distinct labels of its sequence
(for ``"v1"`` the non-zero cells of the contingency table, at most
``min(n_detections, (n_objects + 1) x (n_clusters + 1))``; for ``"pq"``
four numbers), never with the number of detections alone.

Every object-level score of :func:`~sklearn_radar.metrics.instance_scores`
at once: :func:`instance_parts` and :func:`combine_instance_parts`.  Each
score is a ratio of sums over segments, and segments never cross
sequences, so a part is ten sums and counts (:class:`InstanceParts`, a
:class:`PanopticParts` with six more), whatever the size of the sequence.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from math import log

import numpy as np
import scipy.sparse as sp
from sklearn.metrics import mutual_info_score

from ._segments import (
    COUNT_KEYS,
    _codes,
    _joint_codes,
    _panoptic,
    _scores_from_counts,
    _segment_counts,
    _times_and_groups,
)
from ._v_measure import _unique_per_group

#: The objectives a part can summarise.
OBJECTIVES = ("v1", "pq")


@dataclass(frozen=True, eq=False)
class VMeasureParts:
    """Contingency counts of one (or several merged) sequences' labelling, for the radar V-measure.

    Attributes
    ----------
    true : ndarray of int64 of shape (n_cells,)
        Row of each non-zero cell: -1 for the background, else the
        sequence's own object code ``0 .. n_objects - 1``.
    pred : ndarray of int64 of shape (n_cells,)
        Column of each cell: -1 for the noise, else the sequence's own
        cluster code ``0 .. n_clusters - 1``.
    count : ndarray of int64 of shape (n_cells,)
        Number of detections in the cell, > 0.
    """

    true: np.ndarray
    pred: np.ndarray
    count: np.ndarray

    @property
    def size(self):
        """Number of array elements the part holds (3 per non-zero cell)."""
        return int(self.true.size + self.pred.size + self.count.size)


@dataclass(frozen=True)
class PanopticParts:
    """Additive counts of one (or several) sequences' labelling, for panoptic quality.

    Attributes
    ----------
    tp, fp, fn : int
        Matched pairs, unmatched predicted and unmatched ground-truth
        segments (per time window) of :func:`~sklearn_radar.metrics.panoptic_quality`.
    iou_sum : float
        Sum of the IoUs of the matched pairs, in [0, tp].
    """

    tp: int
    fp: int
    fn: int
    iou_sum: float

    @property
    def size(self):
        """Number of values the part holds (4)."""
        return 4


@dataclass(frozen=True)
class InstanceParts(PanopticParts):
    """Additive sums and counts of one (or several) sequences' labelling, for every object-level score.

    Every score of :func:`~sklearn_radar.metrics.instance_scores` is a ratio
    of these: ``SQ = iou_sum / tp``, ``RQ = tp / (tp + fp/2 + fn/2)``,
    ``PQ = SQ x RQ``, ``precision = tp / (tp + fp)``,
    ``recall = tp / (tp + fn)``, ``mCov = cover_sum / (tp + fn)``,
    ``mWCov = weighted_cover_sum / n_object_detections``, the background
    segment share ``n_background_segments / (tp + fp)`` and the background
    cluster share ``n_background_clusters / n_clusters`` (0.0 for 0/0).
    Segments (per time window) and clusters never cross sequences, so each
    field adds up over the parts.  The means over objects (mCov, mWCov)
    therefore need no per-object array: the part is ten numbers, whatever
    the number of detections, objects or clusters.

    A :class:`PanopticParts` too: ``combine_parts("pq", ...)`` accepts it.

    Attributes
    ----------
    tp, fp, fn, iou_sum
        As in :class:`PanopticParts`.
    cover_sum : float
        Sum of the coverages (best IoU with any predicted segment) of the
        ``tp + fn`` ground-truth segments, in [0, tp + fn].
    weighted_cover_sum : float
        Sum of the coverages times the ground-truth segments' numbers of
        detections, in [0, n_object_detections].
    n_object_detections : int
        Detections of annotated objects (``labels_true != -1``).
    n_background_segments : int
        Predicted segments (of the ``tp + fp``) without an object detection.
    n_clusters : int
        Clusters (per sequence, over all its windows).
    n_background_clusters : int
        Clusters without an object detection.
    """

    cover_sum: float
    weighted_cover_sum: float
    n_object_detections: int
    n_background_segments: int
    n_clusters: int
    n_background_clusters: int

    @property
    def size(self):
        """Number of values the part holds (10)."""
        return len(COUNT_KEYS)


@dataclass(frozen=True)
class FailedPart:
    """The part of a sequence whose fit (or scoring) raised: its fold scores 0.0.

    Attributes
    ----------
    error : str
        The exception, in one line (``"ValueError: ..."``).
    """

    error: str


_PART_TYPES = {"v1": VMeasureParts, "pq": PanopticParts}


def _check_objective(objective):
    if not isinstance(objective, str) or objective not in OBJECTIVES:
        raise ValueError(f"objective must be one of {OBJECTIVES}, got {objective!r}")


def _local_codes(labels, missing):
    """Codes ``0 .. k - 1`` of the labels, -1 where ``missing`` (background or noise)."""
    codes = np.full(labels.shape[0], -1, dtype=np.int64)
    codes[~missing], k = _codes(labels[~missing])
    return codes, k


def score_parts(objective, labels_true, labels_pred, times=None, *, groups=None, window=0.5):
    """Small mergeable summary of one sequence's labelling, for :func:`combine_parts`.

    Parameters
    ----------
    objective : {"v1", "pq"}
        The score the part is for: the radar V-measure
        (:func:`~sklearn_radar.metrics.radar_v_measure`, the objective V1 of
        Scheiner et al. 2019) or panoptic quality per time window
        (:func:`~sklearn_radar.metrics.panoptic_quality`).
    labels_true : array-like of shape (n_detections,)
        Ground-truth instance per detection, -1 for background.
    labels_pred : array-like of shape (n_detections,)
        Predicted cluster per detection, -1 for noise.
    times : array-like of shape (n_detections,), default=None
        Time of each detection in s, for ``"pq"`` only (ignored for
        ``"v1"``): windows are counted from the sequence's first detection,
        ``floor((times - min(times)) / window)``.  None: the sequence is one
        window.
    groups : array-like of shape (n_detections,), default=None
        Sequence of each detection, when the labelling covers several
        sequences: the part then equals the merge of their parts.  None: one
        sequence.
    window : float or None, default=0.5
        Length of a time window in s, > 0, for ``"pq"``; None: one window per
        sequence.

    Returns
    -------
    part : VMeasureParts or PanopticParts
        A frozen, picklable summary: for ``"v1"`` the non-zero cells of the
        contingency table (background row and noise column coded -1), for
        ``"pq"`` the counts TP, FP, FN and the sum of the matched IoUs.

    Raises
    ------
    ValueError
        If ``objective`` is unknown, the arrays are not 1-D of equal length
        or a time is not finite.
    """
    _check_objective(objective)
    if objective == "pq":
        counts = _segment_counts(labels_true, labels_pred, times=times, groups=groups, window=window)
        return PanopticParts(**{key: counts[key] for key in ("tp", "fp", "fn", "iou_sum")})

    labels_true = np.asarray(labels_true)
    labels_pred = np.asarray(labels_pred)
    if labels_true.ndim != 1 or labels_true.shape != labels_pred.shape:
        raise ValueError(
            f"labels_true and labels_pred must be 1-D of equal length, got {labels_true.shape} and {labels_pred.shape}"
        )
    # Several sequences: labels made distinct per sequence, -1 shared, exactly as radar_v_measure does with groups.
    labels_true = _unique_per_group(labels_true, groups)
    labels_pred = _unique_per_group(labels_pred, groups)
    true, n_true = _local_codes(labels_true, labels_true == -1)
    pred, n_pred = _local_codes(labels_pred, labels_pred == -1)
    cell, n_cell = _joint_codes(true + 1, n_true + 1, pred + 1, n_pred + 1)  # +1: background/noise as code 0
    count = np.bincount(cell, minlength=n_cell).astype(np.int64)
    first = np.zeros(n_cell, dtype=np.int64)
    first[cell[::-1]] = np.arange(cell.shape[0])[::-1]  # one detection of each cell
    return VMeasureParts(true=true[first], pred=pred[first], count=count)


def _merged_cells(parts):
    """Rows, columns and counts of the merged contingency table, rows and columns compact and non-empty.

    Object rows and cluster columns of different parts are offset so as to
    stay distinct; the background row and the noise column (-1) are shared,
    so their cells pool over the parts.
    """
    rows, cols, counts = [], [], []
    row_offset = col_offset = 0
    for part in parts:
        rows.append(np.where(part.true == -1, -1, part.true + row_offset))
        cols.append(np.where(part.pred == -1, -1, part.pred + col_offset))
        counts.append(part.count)
        row_offset += int(part.true.max()) + 1 if part.true.size else 0
        col_offset += int(part.pred.max()) + 1 if part.pred.size else 0
    return (np.concatenate(a).astype(np.int64) for a in (rows, cols, counts))


def _entropy(counts):
    """Entropy (nats) of the positive ``counts``, with scikit-learn's conventions (0.0 for one label)."""
    if counts.size == 1:
        return 0.0
    pi = counts.astype(np.float64)
    total = pi.sum()
    return float(-np.sum((pi / total) * (np.log(pi) - log(total))))


def _homogeneity_completeness(rows, cols, counts):
    """Homogeneity and completeness of the cells, as by :func:`sklearn.metrics.homogeneity_completeness_v_measure`."""
    if counts.sum() == 0:  # no detection
        return 1.0, 1.0
    _, row = np.unique(rows, return_inverse=True)  # only the rows and columns that hold a detection
    _, col = np.unique(cols, return_inverse=True)
    row, col = row.ravel(), col.ravel()
    n_rows, n_cols = int(row.max()) + 1, int(col.max()) + 1
    contingency = sp.coo_matrix((counts, (row, col)), shape=(n_rows, n_cols)).tocsr()  # sums the pooled cells
    entropy_c = _entropy(np.bincount(row, weights=counts, minlength=n_rows).astype(np.int64))
    entropy_k = _entropy(np.bincount(col, weights=counts, minlength=n_cols).astype(np.int64))
    mutual_info = mutual_info_score(None, None, contingency=contingency)
    homogeneity = mutual_info / entropy_c if entropy_c else 1.0
    completeness = mutual_info / entropy_k if entropy_k else 1.0
    return homogeneity, completeness


def _combine_v_measure(parts, beta):
    rows, cols, counts = _merged_cells(parts)
    keep = counts > 0
    rows, cols, counts = rows[keep], cols[keep], counts[keep]
    homogeneity, _ = _homogeneity_completeness(rows, cols, counts)  # over all detections
    objects = rows != -1
    if objects.any():  # over the detections of labelled objects only (the paper's modified completeness)
        _, completeness = _homogeneity_completeness(rows[objects], cols[objects], counts[objects])
    else:
        completeness = 1.0
    if homogeneity + completeness == 0 or beta * homogeneity + completeness == 0:  # the latter: beta = 0, c = 0
        return 0.0
    return (1 + beta) * homogeneity * completeness / (beta * homogeneity + completeness)


def _combine_panoptic(parts):
    tp = sum(part.tp for part in parts)
    fp = sum(part.fp for part in parts)
    fn = sum(part.fn for part in parts)
    iou_sum = float(sum(part.iou_sum for part in parts))
    return _panoptic(tp, fp, fn, iou_sum)[0]


def combine_parts(objective, parts, *, beta=1.0):
    """Score of the concatenation of sequences, from their parts; 0.0 if a part failed.

    Equal (up to rounding) to
    ``radar_v_measure(concat_true, concat_pred, groups=concat_groups, beta=beta)``
    for ``"v1"`` and to
    ``panoptic_quality(concat_true, concat_pred, times=concat_times, groups=concat_groups, window=window).pq``
    for ``"pq"``, each sequence a different group.  The order of the parts
    does not matter.

    Parameters
    ----------
    objective : {"v1", "pq"}
        The score, as given to :func:`score_parts`.
    parts : sequence of VMeasureParts, PanopticParts or FailedPart
        One part per sequence, from :func:`score_parts` or
        :func:`sequence_parts`; a :class:`FailedPart` marks a sequence whose
        fit failed.
    beta : float, default=1.0
        Weight of homogeneity in the V-measure, >= 0; ignored for ``"pq"``.

    Returns
    -------
    score : float
        The combined score in [0, 1]; 0.0 (the worst score, as the
        scorers :func:`~sklearn_radar.metrics.radar_v_measure_scorer` and
        :func:`~sklearn_radar.metrics.panoptic_quality_scorer` give) when a
        part failed or the score is not finite; also 0.0 for ``beta=0``
        with completeness 0, where the V-measure's formula divides by zero.

    Raises
    ------
    ValueError
        If ``objective`` is unknown, ``parts`` is empty, a part is of the
        other objective, or ``beta`` is negative.
    """
    _check_objective(objective)
    parts = list(parts)
    if not parts:
        raise ValueError("parts is empty: a fold needs at least one sequence's part")
    if not beta >= 0:
        raise ValueError(f"beta must be >= 0, got {beta!r}")
    if any(isinstance(part, FailedPart) for part in parts):
        return 0.0
    expected = _PART_TYPES[objective]
    for part in parts:
        if not isinstance(part, expected):
            raise ValueError(
                f"objective={objective!r} needs parts of type {expected.__name__}, got {type(part).__name__}"
            )
    score = _combine_v_measure(parts, beta) if objective == "v1" else _combine_panoptic(parts)
    return float(score) if np.isfinite(score) else 0.0


def sequence_parts(estimator, X, y, objective, window=0.5):
    """Scorer-like task: ``fit_predict`` on one sequence's detections, then its part; a FailedPart if the fit fails.

    The per-sequence counterpart of
    :func:`~sklearn_radar.metrics.radar_v_measure_scorer` (``"v1"``) and
    :func:`~sklearn_radar.metrics.panoptic_quality_scorer` (``"pq"``): the
    clusterer is fitted on the data it is scored on, with warnings silenced,
    and a failing fit gives a :class:`FailedPart`, which :func:`combine_parts`
    scores 0.0 for the whole fold.

    Parameters
    ----------
    estimator : estimator with ``fit_predict``
        The clusterer (or pipeline ending in one) to score; it is fitted on
        ``X``.
    X : DataFrame of shape (n_detections, n_columns)
        The detections of one sequence.  For ``"pq"`` (with ``window`` not
        None) it needs a ``t`` column (s) or else ``timestamp`` (µs).  With a
        ``sequence`` column holding several sequences, each is its own group.
    y : array-like of shape (n_detections,)
        Ground-truth instance per detection, -1 for background.
    objective : {"v1", "pq"}
        The score the part is for.
    window : float or None, default=0.5
        Length of a time window in s, > 0, for ``"pq"``; None: one window per
        sequence.

    Returns
    -------
    part : VMeasureParts, PanopticParts or FailedPart
        The part of :func:`score_parts`, or a FailedPart when ``fit_predict`` (or
        the scoring of its labels) raised.

    Raises
    ------
    ValueError
        If ``objective`` is unknown or, for ``"pq"``, X has no time column:
        mistakes in the set-up rather than a failing candidate, raised before
        any fit.
    """
    _check_objective(objective)
    times, groups = _times_and_groups(X, window if objective == "pq" else None)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            labels = estimator.fit_predict(X)
        return score_parts(objective, np.asarray(y), np.asarray(labels), times, groups=groups, window=window)
    except Exception as error:  # a search must go on; the fold scores 0.0, as the scorers' error_score
        text = str(error).strip().splitlines()
        return FailedPart(f"{type(error).__name__}: {text[0] if text else ''}")


def instance_parts(labels_true, labels_pred, *, times, window=0.5, groups=None):
    """Small mergeable summary of one sequence's labelling, for every score of :func:`combine_instance_parts`.

    Parameters
    ----------
    labels_true, labels_pred, times, window, groups
        As in :func:`~sklearn_radar.metrics.instance_scores`, for one
        sequence; with ``groups``, for several, and the part then equals the
        merge of their parts.

    Returns
    -------
    part : InstanceParts
        Ten sums and counts, frozen and picklable; their size does not grow
        with the sequence.

    Raises
    ------
    ValueError
        If the arrays are not 1-D of equal length, a time is not finite or
        ``window`` is not > 0.
    """
    if window is not None and not window > 0:
        raise ValueError(f"window must be > 0 s or None, got {window!r}")
    return InstanceParts(**_segment_counts(labels_true, labels_pred, times=times, groups=groups, window=window))


def combine_instance_parts(parts):
    """Every score of :func:`~sklearn_radar.metrics.instance_scores` of the concatenated sequences, from their parts.

    Equal (up to rounding, about 1e-15) to
    ``instance_scores(concat_true, concat_pred, times=concat_times, groups=concat_groups, window=window)``,
    each part's sequence a group of its own (equal labels in different parts
    are different objects and clusters), with the ``window`` the parts were
    made with.  The sums and counts of :class:`InstanceParts` add up, and the
    scores are formed from the totals by the same code as
    :func:`~sklearn_radar.metrics.instance_scores`: means over objects
    (mCov, mWCov) weigh every object of every sequence alike, never a mean
    of per-sequence means.  The order of the parts does not matter.

    Parameters
    ----------
    parts : iterable of InstanceParts
        One part per sequence (or per block of sequences), from
        :func:`instance_parts`, all with the same ``window``.  Empty: the
        scores of no detection.

    Returns
    -------
    scores : Bunch
        A dict with the keys of
        :func:`~sklearn_radar.metrics.instance_scores`: ``pq``, ``sq``,
        ``rq``, ``precision``, ``recall``, ``mcov``, ``mwcov``,
        ``background_segment_share``, ``background_cluster_share`` (floats
        in [0, 1], 0.0 for a ratio 0/0, never NaN) and ``tp``, ``fp``,
        ``fn`` (ints).

    Raises
    ------
    ValueError
        If a part is not an :class:`InstanceParts` (e.g. a
        :class:`FailedPart`, whose error it names).
    """
    totals = dict.fromkeys(COUNT_KEYS, 0)
    for part in parts:
        if not isinstance(part, InstanceParts):
            detail = f": {part.error}" if isinstance(part, FailedPart) else ""
            raise ValueError(f"parts must be InstanceParts, got {type(part).__name__}{detail}")
        for key in COUNT_KEYS:
            totals[key] += getattr(part, key)
    totals["iou_sum"] = float(totals["iou_sum"])
    totals["cover_sum"] = float(totals["cover_sum"])
    totals["weighted_cover_sum"] = float(totals["weighted_cover_sum"])
    return _scores_from_counts(**totals)
