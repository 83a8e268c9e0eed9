"""Semantic instance-segmentation metrics: class-aware panoptic quality, mAP, point-wise macro-F1, coverage.

The metrics of a classified segmentation, one road-user class per instance
(:mod:`sklearn_radar.classification`: car 0, large vehicle 1, two-wheeler 2,
pedestrian 3, pedestrian group 4, background -1, ignored -2).

*Segments.*  Within each sequence (``groups``) time is cut into windows of
``window`` seconds, starting at the sequence's first detection, as in
:func:`~sklearn_radar.metrics.panoptic_quality`.  A ground-truth segment is
one ground-truth instance (``instances_true >= 0``) restricted to a window;
its class is the majority of ``classes_true`` over its rows, ties going to
the smallest code.  A predicted segment is one predicted instance
(``instances_pred >= 0``) restricted to a window; its class is the majority
of ``classes_pred`` over its rows, ties going to the class with the highest
summed ``confidence`` (when given), then to the smallest code.  A segment
whose class is negative (background, ignored) is no road user and takes no
part in the instance metrics.  Detections whose ``classes_true`` is
IGNORED (-2) are left out of every metric after the windows are laid out.
Segments of different windows or sequences are never compared.

Everything is computed once and vectorised (:func:`_semantic_layout`): the
segment ids are integer codes of (window, instance), the intersections the
counts of (ground-truth segment, predicted segment) pairs, and a loop runs
only over the classes.
"""

from __future__ import annotations

import warnings
from numbers import Real

import numpy as np
import pandas as pd
from sklearn.utils import Bunch
from sklearn.utils._param_validation import Interval, StrOptions, validate_params

from .._schema import instance_target
from ._segments import _codes, _joint_codes, _panoptic, _times_and_groups, _window_cells

__all__ = [
    "class_panoptic_quality",
    "make_semantic_scorer",
    "mean_average_precision",
    "pointwise_macro_f1",
    "semantic_scores",
]

#: Class code of the detections left out of every metric (RadarScenes ANIMAL and OTHER).
_IGNORED = -2
#: Class code of background (static detections, noise).
_BACKGROUND = -1
#: The 101 recall points of COCO's interpolated precision (pycocotools ``COCOeval``: ``recThrs``).
_RECALL_POINTS = np.linspace(0.0, 1.0, 101)
#: Metrics of :func:`make_semantic_scorer`, keys of :func:`semantic_scores`.
_SCORER_METRICS = ("pq", "sq", "rq", "map", "macro_f1", "mcov")

_WINDOW = [Interval(Real, 0, None, closed="neither"), None]
_SEGMENT_CONSTRAINTS = {
    "classes_true": ["array-like"],
    "instances_true": ["array-like"],
    "classes_pred": ["array-like"],
    "instances_pred": ["array-like"],
    "times": ["array-like", None],
    "groups": ["array-like", None],
    "window": _WINDOW,
}


# ---------------------------------------------------------------------------------------------------------------
# Input checks
# ---------------------------------------------------------------------------------------------------------------
def _integer_codes(values, name):
    """``values`` as a 1-D int64 array; a ValueError names ``name`` when they are not integers."""
    array = np.asarray(values)
    if array.ndim != 1:
        raise ValueError(f"{name} must be 1-D, got shape {array.shape}")
    if array.dtype.kind == "O" and all(isinstance(value, (int, np.integer)) for value in array):
        array = array.astype(np.int64)
    if array.dtype.kind == "f" and np.isfinite(array).all() and np.all(array == np.round(array)):
        array = array.astype(np.int64)
    if array.dtype.kind == "f" and not array.size:
        array = array.astype(np.int64)
    if array.dtype.kind not in "iu":
        raise ValueError(f"{name} must hold integer codes, got dtype {array.dtype}")
    return array.astype(np.int64, copy=False)


def _check_lengths(arrays):
    """ValueError naming the first array whose length differs from the first one's."""
    (first, reference), *others = arrays.items()
    for name, array in others:
        if array is not None and (array.ndim != 1 or array.shape[0] != reference.shape[0]):
            raise ValueError(
                f"{name} must be 1-D with one value per detection like {first} ({reference.shape[0]}), "
                f"got shape {array.shape}"
            )


def _checked(classes_true, instances_true, classes_pred, instances_pred, confidence, times, groups):
    """The inputs as arrays of one length (int64 codes, float64 confidence and times); ValueErrors name them."""
    arrays = {
        "classes_true": _integer_codes(classes_true, "classes_true"),
        "instances_true": _integer_codes(instances_true, "instances_true"),
        "classes_pred": _integer_codes(classes_pred, "classes_pred"),
        "instances_pred": _integer_codes(instances_pred, "instances_pred"),
        "confidence": None if confidence is None else np.asarray(confidence, dtype=np.float64),
        "times": None if times is None else np.asarray(times, dtype=np.float64),
        "groups": None if groups is None else np.asarray(groups),
    }
    _check_lengths(arrays)
    if arrays["confidence"] is not None and not np.isfinite(arrays["confidence"]).all():
        raise ValueError("confidence must be finite")
    return arrays


# ---------------------------------------------------------------------------------------------------------------
# Segments
# ---------------------------------------------------------------------------------------------------------------
def _majority_class(segment, n_segments, classes, weights):
    """Class of each segment: the most frequent of its rows' ``classes``.

    Ties go to the highest summed ``weights`` (None: no weights), then to
    the smallest code.  The rows come in a canonical order (by weight:
    :func:`_semantic_layout`), so that the sums are the same floats for any
    order of the input rows.
    """
    result = np.full(n_segments, _BACKGROUND, dtype=np.int64)
    if not len(segment):
        return result
    class_code, n_classes = _codes(classes)
    pair, n_pairs = _joint_codes(segment, n_segments, class_code, n_classes)
    first = np.zeros(n_pairs, dtype=np.int64)
    first[pair[::-1]] = np.arange(len(pair))[::-1]
    pair_segment, pair_class = segment[first], classes[first]
    result[pair_segment] = pair_class  # right for the segments of one class, most of them
    mixed = np.bincount(pair_segment, minlength=n_segments)[pair_segment] > 1
    if mixed.any():
        count = np.bincount(pair, minlength=n_pairs)[mixed]
        weight = np.zeros(n_pairs) if weights is None else np.bincount(pair, weights=weights, minlength=n_pairs)
        mixed_segment, mixed_class = pair_segment[mixed], pair_class[mixed]
        order = np.lexsort((mixed_class, -weight[mixed], -count, mixed_segment))  # the winner first
        winner = order[np.r_[True, mixed_segment[order][1:] != mixed_segment[order][:-1]]]
        result[mixed_segment[winner]] = mixed_class[winner]
    return result


def _road_user_segments(cell, n_cell, instances, classes, weights):
    """Segment of each row (-1: none) and class of each segment, for the segments of a road-user class."""
    segment = np.full(len(instances), -1, dtype=np.int64)
    member = instances >= 0
    codes, n_segments = _joint_codes(cell[member], n_cell, *_codes(instances[member]))
    segment_class = _majority_class(codes, n_segments, classes[member], None if weights is None else weights[member])
    road_user = segment_class >= 0
    renumbered = np.cumsum(road_user) - 1
    segment[member] = np.where(road_user[codes], renumbered[codes], -1)
    return segment, segment_class[road_user]


def _semantic_layout(arrays, window):
    """Every segment and intersection of checked inputs (:func:`_checked`), as a Bunch.

    Keys: ``true_class`` and ``pred_class`` (class of each segment),
    ``pred_score`` (mean confidence of each predicted segment; None without
    confidence), ``pair_true``, ``pair_pred``, ``inter`` and ``union`` (the
    overlapping pairs of segments, their intersection and union sizes).
    """
    n = arrays["classes_true"].shape[0]
    _, _, cell, n_cell = _window_cells(n, arrays["times"], arrays["groups"], window)
    kept = np.flatnonzero(arrays["classes_true"] != _IGNORED)  # after the windows are laid out
    confidence = arrays["confidence"]
    if confidence is not None:  # in order of confidence: every sum of confidences is then the same float
        kept = kept[np.argsort(confidence[kept], kind="stable")]
        confidence = confidence[kept]
    cell = cell[kept]
    true_seg, true_class = _road_user_segments(
        cell, n_cell, arrays["instances_true"][kept], arrays["classes_true"][kept], None
    )
    pred_seg, pred_class = _road_user_segments(
        cell, n_cell, arrays["instances_pred"][kept], arrays["classes_pred"][kept], confidence
    )
    n_true, n_pred = len(true_class), len(pred_class)
    true_size = np.bincount(true_seg[true_seg >= 0], minlength=n_true)
    pred_size = np.bincount(pred_seg[pred_seg >= 0], minlength=n_pred)
    pred_score = None
    if confidence is not None:
        clustered = pred_seg >= 0
        pred_score = np.bincount(pred_seg[clustered], confidence[clustered], n_pred) / np.maximum(pred_size, 1)

    both = (true_seg >= 0) & (pred_seg >= 0)
    pair, n_pairs = _joint_codes(true_seg[both], n_true, pred_seg[both], n_pred)
    inter = np.bincount(pair, minlength=n_pairs)
    first = np.zeros(n_pairs, dtype=np.int64)
    first[pair[::-1]] = np.flatnonzero(both)[::-1]
    pair_true, pair_pred = true_seg[first], pred_seg[first]
    return Bunch(
        true_class=true_class,
        pred_class=pred_class,
        pred_score=pred_score,
        pair_true=pair_true,
        pair_pred=pair_pred,
        inter=inter,
        union=true_size[pair_true] + pred_size[pair_pred] - inter,
    )


# ---------------------------------------------------------------------------------------------------------------
# Scores of a layout
# ---------------------------------------------------------------------------------------------------------------
def _class_matches(layout, iou_threshold):
    """Mask of the pairs of one class with IoU above ``iou_threshold`` (>= 0.5, so each segment matches once)."""
    same_class = layout.true_class[layout.pair_true] == layout.pred_class[layout.pair_pred]
    if iou_threshold == 0.5:  # in integers: 2 |g ∩ p| > |g ∪ p|
        return same_class & (2 * layout.inter > layout.union)
    return same_class & (layout.inter > iou_threshold * layout.union)


def _mean(values):
    """Mean of the floats, 0.0 for none."""
    return float(np.mean(values)) if len(values) else 0.0


def _panoptic_of_layout(layout):
    """``pq``, ``sq``, ``rq`` (class means) and ``per_class`` of a layout."""
    matched = _class_matches(layout, 0.5)
    matched_class = layout.true_class[layout.pair_true[matched]]
    iou = layout.inter[matched] / layout.union[matched]
    per_class = {}
    for code in np.union1d(layout.true_class, layout.pred_class):
        in_class = matched_class == code
        tp = int(in_class.sum())
        fp = int(np.count_nonzero(layout.pred_class == code)) - tp
        fn = int(np.count_nonzero(layout.true_class == code)) - tp
        pq, sq, rq = _panoptic(tp, fp, fn, float(iou[in_class].sum()))
        per_class[int(code)] = Bunch(pq=pq, sq=sq, rq=rq, tp=tp, fp=fp, fn=fn)
    return Bunch(
        pq=_mean([c.pq for c in per_class.values()]),
        sq=_mean([c.sq for c in per_class.values()]),
        rq=_mean([c.rq for c in per_class.values()]),
        per_class=per_class,
    )


def _interpolated_precision(scores, hits, n_true):
    """COCO's interpolated precision of ranked predictions at its 101 recall points: their mean is the AP.

    0 beyond the highest recall reached; tied scores form one point.
    """
    if not len(scores):
        return np.zeros(len(_RECALL_POINTS))
    order = np.argsort(-scores, kind="stable")
    scores, hits = scores[order], hits[order]
    last_of_tie = np.r_[scores[1:] != scores[:-1], True]
    tp = np.cumsum(hits)[last_of_tie]
    fp = np.cumsum(~hits)[last_of_tie]
    recall = tp / n_true
    precision = np.maximum.accumulate((tp / (tp + fp))[::-1])[::-1]  # best precision at this recall or more
    point = np.searchsorted(recall, _RECALL_POINTS, side="left")
    reached = point < len(recall)
    return np.where(reached, precision[np.minimum(point, len(recall) - 1)], 0.0)


def _average_precision_of_layout(layout, iou_threshold):
    """``map`` and ``per_class`` (AP of each class present in the truth) of a layout with scores."""
    hit = np.zeros(len(layout.pred_class), dtype=bool)
    hit[layout.pair_pred[_class_matches(layout, iou_threshold)]] = True
    per_class, curves = {}, {}
    for code in np.unique(layout.true_class):
        predicted = layout.pred_class == code
        n_true = int(np.count_nonzero(layout.true_class == code))
        curves[int(code)] = _interpolated_precision(layout.pred_score[predicted], hit[predicted], n_true)
        per_class[int(code)] = float(curves[int(code)].mean())
    return Bunch(map=_mean(list(per_class.values())), per_class=per_class, curves=curves)


def _coverage_of_layout(layout):
    """Mean over the ground-truth segments of their best IoU with a predicted segment, whatever the classes."""
    cover = np.zeros(len(layout.true_class))
    np.maximum.at(cover, layout.pair_true, layout.inter / np.maximum(layout.union, 1))
    return _mean(cover)


def _per_class_f1(classes_true, classes_pred, include_background):
    """``{code: F1}`` over detections, for the classes present in truth or prediction."""
    codes = np.union1d(classes_true, classes_pred)
    if not include_background:
        codes = codes[codes != _BACKGROUND]
    true_index = np.searchsorted(codes, classes_true)
    pred_index = np.searchsorted(codes, classes_pred)
    n_codes = len(codes)
    in_true = np.bincount(true_index[np.isin(classes_true, codes)], minlength=n_codes)
    in_pred = np.bincount(pred_index[np.isin(classes_pred, codes)], minlength=n_codes)
    agree = (classes_true == classes_pred) & np.isin(classes_true, codes)
    tp = np.bincount(true_index[agree], minlength=n_codes)
    f1 = 2 * tp / np.maximum(in_true + in_pred, 1)
    return {int(code): float(value) for code, value in zip(codes, f1, strict=True)}


# ---------------------------------------------------------------------------------------------------------------
# Public functions
# ---------------------------------------------------------------------------------------------------------------
@validate_params({**_SEGMENT_CONSTRAINTS, "confidence": ["array-like", None]}, prefer_skip_nested_validation=True)
def class_panoptic_quality(
    classes_true, instances_true, classes_pred, instances_pred, *, times, groups=None, window=0.5, confidence=None
):
    """Class-aware panoptic quality (Kirillov et al. 2019) per time window: per road-user class, and their mean.

    The segments are those of the module (:mod:`sklearn_radar.metrics._semantic`):
    ground-truth and predicted instances restricted to each window of
    ``window`` seconds of each sequence, each with the majority class of its
    rows.  For each class ``c``:

    * a ground-truth segment ``g`` and a predicted segment ``p`` of class
      ``c`` match when ``IoU(g, p) = |g ∩ p| / |g ∪ p| > 0.5`` (over
      detections, whatever the classes of single rows); with this threshold
      every segment has at most one match;
    * ``TP_c`` = matched pairs, ``FP_c`` = unmatched predicted segments of
      class ``c`` (including a segment of the right object with the wrong
      class), ``FN_c`` = unmatched ground-truth segments of class ``c``;
    * ``SQ_c = Σ IoU / TP_c``, ``RQ_c = TP_c / (TP_c + FP_c/2 + FN_c/2)``,
      ``PQ_c = SQ_c × RQ_c``.

    ``pq``, ``sq`` and ``rq`` are the means over the road-user classes
    present in the truth or the prediction (codes >= 0).  Degenerate input
    never raises: a ratio 0/0 is 0.0, and so is a mean over no class (no
    road user in truth or prediction).

    Read more in the :ref:`User Guide <user-guide-classification>`.

    Parameters
    ----------
    classes_true : array-like of int, shape (n_detections,)
        True class of each detection: >= 0 a road-user class, -1 background,
        -2 ignored (left out of every metric).
    instances_true : array-like of int, shape (n_detections,)
        Ground-truth instance of each detection, -1 for none.
    classes_pred : array-like of int, shape (n_detections,)
        Predicted class of each detection (-1 background).
    instances_pred : array-like of int, shape (n_detections,)
        Predicted instance of each detection, -1 for none (noise).
    times : array-like of shape (n_detections,) or None
        Time of each detection in s.  None, or ``window=None``: every
        sequence is one window.
    groups : array-like of shape (n_detections,), default=None
        Sequence of each detection; None: one sequence.
    window : float or None, default=0.5
        Length of a time window in s, > 0 (Scheiner et al. 2021: 500 ms);
        None: one window per sequence.
    confidence : array-like of float, shape (n_detections,), default=None
        Confidence of each detection's predicted class, used only to break a
        tie of the majority vote of a predicted segment (highest sum wins;
        then the smallest code).

    Returns
    -------
    scores : Bunch
        ``pq``, ``sq``, ``rq`` (floats in [0, 1], means over the classes)
        and ``per_class``: ``{code: Bunch(pq, sq, rq, tp, fp, fn)}`` for
        each road-user class present in truth or prediction.

    Raises
    ------
    ValueError
        If an argument is not 1-D with one value per detection (the message
        names it), codes are not integers, or a time or confidence is not
        finite.

    See Also
    --------
    semantic_scores : all semantic metrics at once.
    sklearn_radar.metrics.panoptic_quality : the class-agnostic PQ of clusters.

    References
    ----------
    .. [1] A. Kirillov, K. He, R. Girshick, C. Rother and P. Dollár,
       "Panoptic Segmentation", CVPR 2019.

    Examples
    --------
    >>> from sklearn_radar.metrics import class_panoptic_quality
    >>> # Instance 0 (a car, 3 detections) predicted as instance 5 with 2 of them (IoU 2/3), class car.
    >>> scores = class_panoptic_quality([0, 0, 0], [0, 0, 0], [0, 0, -1], [5, 5, -1], times=[0.0, 0.1, 0.2])
    >>> round(scores["pq"], 6), scores["per_class"][0]["tp"]
    (0.666667, 1)
    """
    arrays = _checked(classes_true, instances_true, classes_pred, instances_pred, confidence, times, groups)
    return _panoptic_of_layout(_semantic_layout(arrays, window))


@validate_params(
    {**_SEGMENT_CONSTRAINTS, "confidence": ["array-like"], "iou_threshold": [Interval(Real, 0.5, 1, closed="left")]},
    prefer_skip_nested_validation=True,
)
def mean_average_precision(
    classes_true,
    instances_true,
    classes_pred,
    instances_pred,
    confidence,
    *,
    times,
    groups=None,
    window=0.5,
    iou_threshold=0.5,
):
    """Mean average precision of the predicted instances per time window, ranked by confidence (mAP@0.5).

    The segments are those of :func:`class_panoptic_quality`.  For each
    class ``c`` present in the truth, its predicted segments are ranked by
    their score, the mean ``confidence`` of their rows; a predicted segment
    is a true positive when its IoU with a ground-truth segment of class
    ``c`` exceeds ``iou_threshold``, else a false positive.  Greedy matching
    in rank order to the unmatched ground-truth segments (COCO's rule)
    needs no order here: at thresholds >= 0.5 a segment can overlap only one
    other by more than half the union.  The average precision is COCO's
    (Lin et al. 2014; pycocotools ``COCOeval``): the precision, made
    non-increasing in recall (the best precision at this recall or more),
    read at the 101 recall points 0, 0.01, ..., 1 (0 beyond the highest
    recall reached), and averaged.  This is the mAP@0.5 with which the
    instance-segmentation papers on RadarScenes rank their models (e.g.
    Liu et al. 2022, 86.97 % on real data).  One deviation, so that the
    result does not depend on the order of the rows: predicted segments of
    equal score form one point of the precision-recall curve (as
    :func:`sklearn.metrics.average_precision_score` treats ties), where
    COCO ranks them in input order.

    ``map`` is the mean AP over the classes present in the truth (COCO
    leaves out the others); a class with ground truth but no prediction has
    AP 0.  No ground-truth segment at all: ``map`` is 0.0 (never NaN).

    Read more in the :ref:`User Guide <user-guide-classification>`.

    Parameters
    ----------
    classes_true, instances_true, classes_pred, instances_pred
        As in :func:`class_panoptic_quality`: integer codes per detection
        (-2 ignored, -1 background / no instance).
    confidence : array-like of float, shape (n_detections,)
        Confidence of each detection's predicted class (e.g. the
        ``confidence`` of ``predict_instances``), the ranking score; it also
        breaks ties of the majority vote, as in :func:`class_panoptic_quality`.
    times : array-like of shape (n_detections,) or None
        Time of each detection in s; None: every sequence is one window.
    groups : array-like of shape (n_detections,), default=None
        Sequence of each detection; None: one sequence.
    window : float or None, default=0.5
        Length of a time window in s, > 0; None: one window per sequence.
    iou_threshold : float, default=0.5
        IoU a true positive must exceed, in [0.5, 1).

    Returns
    -------
    scores : Bunch
        ``map`` (float in [0, 1]) and ``per_class``: ``{code: AP}`` for each
        road-user class present in the truth.

    Raises
    ------
    ValueError
        As :func:`class_panoptic_quality`.

    See Also
    --------
    semantic_scores : all semantic metrics at once.

    References
    ----------
    .. [1] T.-Y. Lin et al., "Microsoft COCO: Common Objects in Context",
       ECCV 2014; the evaluation of pycocotools (``COCOeval``, 101 recall
       points).
    .. [2] J. Liu, W. Xiong, L. Bai, Y. Xia, T. Huang, W. Ouyang and B. Zhu,
       "Deep instance segmentation with automotive radar detection points",
       IEEE Transactions on Intelligent Vehicles, 2022.

    Examples
    --------
    >>> from sklearn_radar.metrics import mean_average_precision
    >>> # Two cars; the surer prediction (0.9) finds car 0, the other (0.6) is a false positive.
    >>> scores = mean_average_precision(
    ...     [0, 0, 0, 0], [0, 0, 1, 1], [0, 0, 0, 0], [7, 7, 8, -1], [0.9, 0.9, 0.6, 0.6], times=None
    ... )
    >>> round(scores["map"], 6)  # precision 1 up to recall 1/2: 51 of the 101 points
    0.50495
    """
    arrays = _checked(classes_true, instances_true, classes_pred, instances_pred, confidence, times, groups)
    found = _average_precision_of_layout(_semantic_layout(arrays, window), iou_threshold)
    return Bunch(map=found.map, per_class=found.per_class)


@validate_params(
    {"classes_true": ["array-like"], "classes_pred": ["array-like"], "include_background": ["boolean"]},
    prefer_skip_nested_validation=True,
)
def pointwise_macro_f1(classes_true, classes_pred, *, include_background=True):
    """Point-wise macro-F1 over the classes: the semantic-segmentation figure.

    For each class ``c`` present in the truth or the prediction,
    ``F1_c = 2 TP_c / (2 TP_c + FP_c + FN_c)`` over detections; the score is
    their mean.  Detections whose true class is ignored (-2) are left out.
    This is :func:`sklearn.metrics.f1_score` with ``average="macro"`` on the
    other detections (with ``labels`` leaving out -1 when
    ``include_background=False``: a road user predicted as background still
    costs its class recall).  No class at all: 0.0.

    Read more in the :ref:`User Guide <user-guide-classification>`.

    Parameters
    ----------
    classes_true : array-like of int, shape (n_detections,)
        True class of each detection (-1 background, -2 ignored).
    classes_pred : array-like of int, shape (n_detections,)
        Predicted class of each detection (-1 background).
    include_background : bool, default=True
        Whether background (-1) is one of the averaged classes.

    Returns
    -------
    macro_f1 : float
        In [0, 1].

    Raises
    ------
    ValueError
        If the arrays differ in length (the message names them) or hold no
        integer codes.

    Examples
    --------
    >>> from sklearn_radar.metrics import pointwise_macro_f1
    >>> # Car F1 = 2 / 3, background F1 = 2 / 3.
    >>> round(pointwise_macro_f1([0, 0, -1, -1], [0, -1, -1, 0]), 6)
    0.5
    """
    classes_true = _integer_codes(classes_true, "classes_true")
    classes_pred = _integer_codes(classes_pred, "classes_pred")
    _check_lengths({"classes_true": classes_true, "classes_pred": classes_pred})
    kept = classes_true != _IGNORED
    return _mean(list(_per_class_f1(classes_true[kept], classes_pred[kept], include_background).values()))


@validate_params({**_SEGMENT_CONSTRAINTS, "confidence": ["array-like"]}, prefer_skip_nested_validation=True)
def semantic_scores(
    classes_true, instances_true, classes_pred, instances_pred, confidence, *, times, groups=None, window=0.5
):
    """Every semantic instance-segmentation metric at once, from one segmentation of the detections.

    The union of :func:`class_panoptic_quality`, :func:`mean_average_precision`
    (at IoU 0.5), :func:`pointwise_macro_f1` (background included) and the
    class-agnostic coverage, computed on one layout of the segments.

    ``mcov`` is the mean over the ground-truth segments (of a road-user
    class) of their best IoU with a predicted segment (of a road-user class,
    whatever it is), 0 when none overlaps, as
    :func:`~sklearn_radar.metrics.instance_coverage` computes it; without
    ground-truth segments it is 0.0.

    Read more in the :ref:`User Guide <user-guide-classification>`.

    Parameters
    ----------
    classes_true, instances_true, classes_pred, instances_pred, confidence
        As in :func:`mean_average_precision`.
    times : array-like of shape (n_detections,) or None
        Time of each detection in s; None: every sequence is one window.
    groups : array-like of shape (n_detections,), default=None
        Sequence of each detection; None: one sequence.
    window : float or None, default=0.5
        Length of a time window in s, > 0; None: one window per sequence.

    Returns
    -------
    scores : Bunch
        ``pq``, ``sq``, ``rq`` (class means), ``map``, ``macro_f1``,
        ``mcov`` (floats in [0, 1]) and ``per_class``:
        ``{code: Bunch(pq, ap, f1)}`` for every class any of them averages
        over; NaN where a class takes no part in that metric (``pq`` and
        ``ap`` of background, ``ap`` of a class absent from the truth); and
        ``precision_at_recall``: ``{code: ndarray of shape (101,)}`` for
        each class present in the truth, the interpolated precision at
        recall 0, 0.01, ..., 1 (0 beyond the highest recall reached), the
        precision-recall curve whose mean is the class's ``ap``.

    Raises
    ------
    ValueError
        As :func:`class_panoptic_quality`.

    See Also
    --------
    make_semantic_scorer : one of these scores as a scorer for searches.

    Examples
    --------
    >>> from sklearn_radar.metrics import semantic_scores
    >>> scores = semantic_scores([0, 0, -1], [0, 0, -1], [0, 0, -1], [3, 3, -1], [0.8, 0.8, 1.0], times=None)
    >>> scores["pq"], scores["map"], scores["macro_f1"], scores["mcov"]
    (1.0, 1.0, 1.0, 1.0)
    """
    arrays = _checked(classes_true, instances_true, classes_pred, instances_pred, confidence, times, groups)
    layout = _semantic_layout(arrays, window)
    panoptic = _panoptic_of_layout(layout)
    precision = _average_precision_of_layout(layout, 0.5)
    kept = arrays["classes_true"] != _IGNORED
    f1 = _per_class_f1(arrays["classes_true"][kept], arrays["classes_pred"][kept], True)
    codes = sorted(set(panoptic.per_class) | set(precision.per_class) | set(f1))
    nan = float("nan")
    per_class = {
        code: Bunch(
            pq=panoptic.per_class[code].pq if code in panoptic.per_class else nan,
            ap=precision.per_class.get(code, nan),
            f1=f1.get(code, nan),
        )
        for code in codes
    }
    return Bunch(
        pq=panoptic.pq,
        sq=panoptic.sq,
        rq=panoptic.rq,
        map=precision.map,
        macro_f1=_mean(list(f1.values())),
        mcov=_coverage_of_layout(layout),
        per_class=per_class,
        precision_at_recall=precision.curves,
    )


# ---------------------------------------------------------------------------------------------------------------
# Scorer
# ---------------------------------------------------------------------------------------------------------------
def _true_instances(X, instance_column, groups, classes):
    """Ground-truth instance of each detection of X (-1 none); a set-up mistake raises a ValueError."""
    if instance_column is None:  # one instance per road-user class (and window: the segments split it)
        return np.where(classes >= 0, classes, -1)
    if not isinstance(X, pd.DataFrame) or instance_column not in X.columns:
        raise ValueError(
            f"make_semantic_scorer: X must be a DataFrame with the instance column {instance_column!r} (the "
            "ground-truth instance of each detection), or use instance_column=None"
        )
    values = X[instance_column].to_numpy()
    if values.dtype.kind in "OUST":
        return instance_target(values, groups)
    return _integer_codes(values, f"X[{instance_column!r}]")


def _predicted_instances(estimator, X):
    """``estimator.predict_instances(X)``; of a pipeline's last step after its other steps' ``transform``."""
    from ..classification import predict_instances  # the classifiers import this package

    return predict_instances(estimator, X)


def _semantic_score(estimator, X, y, metric, window, instance_column):
    """The scorer's body: predict the instances of X, then one score; 0.0 on any failure."""
    times, groups = _times_and_groups(X, window)  # set-up mistakes raise before any prediction
    classes_true = _integer_codes(y, "y")
    instances_true = _true_instances(X, instance_column, groups, classes_true)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            found = _predicted_instances(estimator, X)
        predicted = [np.asarray(found[column]) for column in ("class", "instance", "confidence")]
        if metric == "macro_f1":
            score = pointwise_macro_f1(classes_true, predicted[0])
        else:
            arrays = _checked(classes_true, instances_true, *predicted, times, groups)
            score = _layout_score(_semantic_layout(arrays, window), metric)
    except Exception:  # a search must go on; a failing prediction scores the worst value
        return 0.0
    return float(score) if np.isfinite(score) else 0.0


def _layout_score(layout, metric):
    """One instance metric of a layout: ``pq``, ``sq``, ``rq``, ``map`` or ``mcov``."""
    if metric == "map":
        return _average_precision_of_layout(layout, 0.5).map
    if metric == "mcov":
        return _coverage_of_layout(layout)
    return _panoptic_of_layout(layout)[metric]


class _SemanticScorer:
    """A scorer ``(estimator, X, y) -> float`` of :func:`make_semantic_scorer` (a class, so that it pickles)."""

    def __init__(self, metric, window, instance_column):
        self.metric = metric
        self.window = window
        self.instance_column = instance_column

    def __call__(self, estimator, X, y):
        return _semantic_score(estimator, X, y, self.metric, self.window, self.instance_column)

    def __repr__(self):
        return (
            f"make_semantic_scorer(metric={self.metric!r}, window={self.window!r}, "
            f"instance_column={self.instance_column!r})"
        )


@validate_params(
    {"metric": [StrOptions(set(_SCORER_METRICS))], "window": _WINDOW, "instance_column": [str, None]},
    prefer_skip_nested_validation=True,
)
def make_semantic_scorer(metric="pq", *, window=0.5, instance_column="track_id"):
    """A scorer ``(estimator, X, y) -> float`` of one semantic metric, for searches and ``cross_val_score``.

    The estimator is fitted (by the search) and scored with its
    ``predict_instances(X)`` (a DataFrame with ``class``, ``instance`` and
    ``confidence`` columns, as
    :meth:`~sklearn_radar.classification.ClusterClassifier.predict_instances`);
    a :class:`~sklearn.pipeline.Pipeline` without that method is scored
    with its last step's ``predict_instances`` on the ``transform`` of the
    others.  ``y`` is the class code of each detection
    (:func:`~sklearn_radar.classification.road_user_class`), the
    ground-truth instances the ``instance_column`` of X (strings are
    numbered per sequence by :func:`~sklearn_radar.instance_target`, ``""``
    for none; integers -1 for none), the times and sequences come from X as
    for :func:`~sklearn_radar.metrics.make_instance_scorer` (``t`` in s or
    ``timestamp`` in µs, ``sequence``).

    Once X has the columns it needs, it never raises and never returns NaN:
    a failing prediction scores 0.0, and a degenerate labelling what the
    function gives it, 0.0 for a ratio 0/0 or a mean over no class (no road
    user in truth or prediction scores 0.0 for PQ, SQ, RQ and mCov; no road
    user in truth 0.0 for mAP).

    Read more in the :ref:`User Guide <user-guide-classification>`.

    Parameters
    ----------
    metric : str, default="pq"
        The score, a key of :func:`semantic_scores`: ``"pq"``, ``"sq"``,
        ``"rq"`` (class means of :func:`class_panoptic_quality`), ``"map"``
        (:func:`mean_average_precision` at IoU 0.5), ``"macro_f1"``
        (:func:`pointwise_macro_f1`, background included) or ``"mcov"``.
    window : float or None, default=0.5
        Length of a time window in s, > 0; None: one window per sequence (X
        then needs no time column).
    instance_column : str or None, default="track_id"
        Column of X with the ground-truth instance of each detection.  None:
        the detections of one road-user class in one window of one sequence
        are one instance (the rule of
        :class:`~sklearn_radar.classification.ClusterClassifier` with
        ``instance_column=None``).

    Returns
    -------
    scorer : callable
        ``scorer(estimator, X, y)``; it pickles.

    See Also
    --------
    semantic_scores : all these scores at once.

    Examples
    --------
    >>> from sklearn_radar.metrics import make_semantic_scorer
    >>> make_semantic_scorer("map")
    make_semantic_scorer(metric='map', window=0.5, instance_column='track_id')
    """
    return _SemanticScorer(metric, window, instance_column)
