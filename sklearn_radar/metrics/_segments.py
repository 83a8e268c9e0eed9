"""Segments of a labelling per time window, and the sums and counts every object-level score is a ratio of.

A *segment* is a set of detections.  A ground-truth segment is one annotated
object's detections inside one time window of one sequence; a predicted
segment is one cluster's.  Background (``labels_true == -1``) belongs to no
ground-truth segment, noise (``labels_pred == -1``) to no predicted segment.
Segments of different windows or sequences are never compared.

:func:`_segment_counts` computes everything once, vectorised: the
(sequence, window, label) triples are encoded as integer segment ids, the
intersections are the counts of the (ground-truth id, predicted id) pairs of
the detections that belong to both kinds of segment, and
``IoU = |g ∩ p| / (|g| + |p| - |g ∩ p|)``.  No Python loop runs over segments.
The counts add up over sequences; :func:`_scores_from_counts` forms the
ratios of :func:`~sklearn_radar.metrics.instance_scores` from them.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from sklearn.utils import Bunch

#: The sums and counts of which every score of :func:`~sklearn_radar.metrics.instance_scores` is a ratio.
COUNT_KEYS = (
    "tp",
    "fp",
    "fn",
    "iou_sum",
    "cover_sum",
    "weighted_cover_sum",
    "n_object_detections",
    "n_background_segments",
    "n_clusters",
    "n_background_clusters",
)


def _codes(values):
    """Integer codes 0, 1, ... of the distinct values (hash-based, order of first appearance) and their number."""
    codes, uniques = pd.factorize(values, use_na_sentinel=False)
    return codes.astype(np.int64, copy=False), len(uniques)


def _joint_codes(a, n_a, b, n_b):
    """Compact codes of the pairs (a, b), for codes ``0 <= a < n_a`` and ``0 <= b < n_b``."""
    if n_a * n_b < 2**62:  # Python integers: no overflow in the test itself
        return _codes(a * np.int64(n_b) + b)
    _, inverse = np.unique(np.stack([a, b], axis=1), axis=0, return_inverse=True)
    inverse = inverse.ravel().astype(np.int64)
    return inverse, int(inverse.max()) + 1


def _ratio(numerator, denominator):
    """``numerator / denominator`` as a float, 0.0 when the denominator is 0."""
    return float(numerator / denominator) if denominator else 0.0


def _window_cells(n, times, groups, window):
    """Sequence and (sequence, window) codes of n detections: ``(seq, n_seq, cell, n_cell)``.

    Detection ``i`` of sequence ``s`` lies in window ``floor((times[i] - min(times of s)) / window)``; with
    ``times`` or ``window`` None every sequence is one window.  ``times`` (s) and ``groups`` are 1-D arrays of
    length n or None.
    """
    seq, n_seq = _codes(groups) if groups is not None else (np.zeros(n, dtype=np.int64), 1 if n else 0)
    if times is None or window is None:  # one window per sequence
        return seq, n_seq, seq, n_seq
    if not np.isfinite(times).all():
        raise ValueError("times must be finite")
    start = np.full(n_seq, np.inf)
    np.minimum.at(start, seq, times)
    window_index, n_window = _codes(np.floor((times - start[seq]) / window))
    cell, n_cell = _joint_codes(seq, n_seq, window_index, n_window)
    return seq, n_seq, cell, n_cell


def _segments(labels_true, labels_pred, *, times=None, groups=None, window=0.5):
    """The segments of both labellings and their overlaps, vectorised.

    Returns a Bunch: ``seq``, ``n_seq``, per detection; ``true_seg``, ``pred_seg`` (segment id per detection, -1
    for background or noise), ``n_true``, ``n_pred``, ``true_size``, ``pred_size``; and per overlapping pair of
    segments ``pair_true``, ``pair_pred``, ``inter``, ``union`` and ``iou``.
    """
    labels_true = np.asarray(labels_true)
    labels_pred = np.asarray(labels_pred)
    n = labels_true.shape[0] if labels_true.ndim == 1 else -1
    arrays = {"labels_true": labels_true, "labels_pred": labels_pred}
    if groups is not None:
        arrays["groups"] = groups = np.asarray(groups)
    if times is not None:
        arrays["times"] = times = np.asarray(times, dtype=np.float64)
    for array in arrays.values():
        if array.ndim != 1 or array.shape[0] != n:
            shapes = {key: value.shape for key, value in arrays.items()}
            raise ValueError(f"{', '.join(arrays)} must be 1-D of equal length, got shapes {shapes}")

    seq, n_seq, cell, n_cell = _window_cells(n, times, groups, window)

    # Segment ids: (sequence, window, label) -> 0 .. n_segments - 1; -1 for background and noise.
    is_object = labels_true != -1
    is_cluster = labels_pred != -1
    true_seg = np.full(n, -1, dtype=np.int64)
    pred_seg = np.full(n, -1, dtype=np.int64)
    true_seg[is_object], n_true = _joint_codes(cell[is_object], n_cell, *_codes(labels_true[is_object]))
    pred_seg[is_cluster], n_pred = _joint_codes(cell[is_cluster], n_cell, *_codes(labels_pred[is_cluster]))
    true_size = np.bincount(true_seg[is_object], minlength=n_true)
    pred_size = np.bincount(pred_seg[is_cluster], minlength=n_pred)

    # Intersections: the distinct (ground-truth segment, predicted segment) pairs and their counts.
    both = is_object & is_cluster
    pair_code, n_pairs = _joint_codes(true_seg[both], n_true, pred_seg[both], n_pred)
    inter = np.bincount(pair_code, minlength=n_pairs)
    first = np.zeros(n_pairs, dtype=np.int64)
    first[pair_code[::-1]] = np.flatnonzero(both)[::-1]  # one row of each pair (which one does not matter)
    pair_true, pair_pred = true_seg[first], pred_seg[first]
    union = true_size[pair_true] + pred_size[pair_pred] - inter
    return Bunch(
        seq=seq,
        n_seq=n_seq,
        true_seg=true_seg,
        pred_seg=pred_seg,
        n_true=n_true,
        n_pred=n_pred,
        true_size=true_size,
        pred_size=pred_size,
        pair_true=pair_true,
        pair_pred=pair_pred,
        inter=inter,
        union=union,
        iou=inter / np.maximum(union, 1),
    )


def _segment_counts(labels_true, labels_pred, *, times=None, groups=None, window=0.5):
    """The sums and counts of :data:`COUNT_KEYS` of a labelling, in one pass, as a dict."""
    found = _segments(labels_true, labels_pred, times=times, groups=groups, window=window)
    labels_true, labels_pred = np.asarray(labels_true), np.asarray(labels_pred)
    is_object, is_cluster = labels_true != -1, labels_pred != -1
    seq, n_seq, n_true, n_pred = found.seq, found.n_seq, found.n_true, found.n_pred
    true_size, inter, union, iou = found.true_size, found.inter, found.union, found.iou
    pair_true, pair_pred = found.pair_true, found.pair_pred

    # Panoptic quality: IoU > 0.5, i.e. 2 |g ∩ p| > |g ∪ p| in integers, makes every match unique.
    matched = 2 * inter > union
    tp = int(matched.sum())

    # Coverage: best IoU of each ground-truth segment with any predicted segment (0 when none overlaps).
    cover = np.zeros(n_true)
    np.maximum.at(cover, pair_true, iou)

    # Background-only predicted segments (per window) and clusters (per sequence).
    pred_has_object = np.bincount(pair_pred, minlength=n_pred) > 0
    cluster, n_clusters = _joint_codes(seq[is_cluster], n_seq, *_codes(labels_pred[is_cluster]))
    cluster_has_object = np.bincount(cluster[is_object[is_cluster]], minlength=n_clusters) > 0

    return dict(
        tp=tp,
        fp=int(n_pred - tp),
        fn=int(n_true - tp),
        iou_sum=float(iou[matched].sum()),
        cover_sum=float(cover.sum()),
        weighted_cover_sum=float(true_size @ cover),
        n_object_detections=int(true_size.sum()),
        n_background_segments=int(n_pred - pred_has_object.sum()),
        n_clusters=int(n_clusters),
        n_background_clusters=int(n_clusters - cluster_has_object.sum()),
    )


def _panoptic(tp, fp, fn, iou_sum):
    """``(PQ, SQ, RQ)`` of the counts: ``SQ = iou_sum / tp``, ``RQ = tp / (tp + fp/2 + fn/2)``, ``PQ = SQ x RQ``."""
    sq = _ratio(iou_sum, tp)
    rq = _ratio(tp, tp + 0.5 * fp + 0.5 * fn)
    return sq * rq, sq, rq


def _scores_from_counts(
    *,
    tp,
    fp,
    fn,
    iou_sum,
    cover_sum,
    weighted_cover_sum,
    n_object_detections,
    n_background_segments,
    n_clusters,
    n_background_clusters,
):
    """Every score of :func:`~sklearn_radar.metrics.instance_scores` from the sums and counts it is made of.

    The one place the ratios are formed, from the counts of one sequence or
    their sums over several (:func:`~sklearn_radar.metrics._parts.combine_instance_parts`).

    Parameters
    ----------
    tp, fp, fn : int
        Matched pairs, unmatched predicted and unmatched ground-truth
        segments (per time window).
    iou_sum : float
        Sum of the IoUs of the matched pairs, in [0, tp].
    cover_sum : float
        Sum of the coverages of the ``tp + fn`` ground-truth segments.
    weighted_cover_sum : float
        Sum of the coverages, each times its segment's number of detections.
    n_object_detections : int
        Detections of annotated objects, the sum of the ground-truth
        segments' sizes.
    n_background_segments : int
        Predicted segments (of the ``tp + fp``) without an object detection.
    n_clusters, n_background_clusters : int
        Clusters, per sequence, and those without an object detection.

    Returns
    -------
    scores : Bunch
        The keys of :func:`~sklearn_radar.metrics.instance_scores`, in its order.
    """
    n_true, n_pred = tp + fn, tp + fp
    pq, sq, rq = _panoptic(tp, fp, fn, iou_sum)
    return Bunch(
        pq=pq,
        sq=sq,
        rq=rq,
        precision=_ratio(tp, n_pred),
        recall=_ratio(tp, n_true),
        tp=tp,
        fp=fp,
        fn=fn,
        mcov=_ratio(cover_sum, n_true),
        mwcov=_ratio(weighted_cover_sum, n_object_detections),
        background_segment_share=_ratio(n_background_segments, n_pred),
        background_cluster_share=_ratio(n_background_clusters, n_clusters),
    )


def _times_and_groups(X, window):
    """Times in s and sequences of the detection table X, for the scorers."""
    columns = getattr(X, "columns", ())
    groups = X["sequence"].to_numpy() if "sequence" in columns else None
    if window is None:
        return None, groups
    if "t" in columns:
        return X["t"].to_numpy(dtype=np.float64), groups
    if "timestamp" in columns:
        stamps = X["timestamp"].to_numpy()
        return (stamps - stamps.min()) * 1e-6 if len(stamps) else stamps.astype(np.float64), groups
    raise ValueError(
        "per-window instance scores need the time of each detection: X must be a DataFrame with a 't' (s) or "
        "'timestamp' (µs) column, or use window=None"
    )
