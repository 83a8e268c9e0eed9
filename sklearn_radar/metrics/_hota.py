"""HOTA (Luiten et al. 2021): detection, association and localisation accuracy of object ids over time windows.

Within each sequence time is cut into windows (as for the panoptic quality
and :func:`~sklearn_radar.metrics.tracking_scores`).  In a window, a
ground-truth object is the set of its detections and a hypothesis the set of
detections carrying one predicted id; their similarity is the IoU of the two
sets.  For each localisation threshold ``alpha`` in 0.05, 0.10, ..., 0.95 the
window's objects and hypotheses are matched one-to-one (Hungarian method on
similarity times the global alignment of the two ids), a match counting when
its IoU is at least ``alpha``; then

* ``DetA = TP / (TP + FN + FP)``;
* ``AssA``: over the true positives, the mean Jaccard index of the two ids'
  window sets (matched windows / windows of either id);
* ``HOTA = sqrt(DetA * AssA)``, and the reported scores are the means over
  ``alpha``.

Sequences are combined as TrackEval does: TP, FN and FP summed, AssA and LocA
averaged with the true positives as weights.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment
from sklearn.utils._param_validation import validate_params

from ._tracking import TRACKING_PARAMETERS, _tracking_inputs, _window_cells

#: The localisation thresholds over which HOTA is averaged (TrackEval's).
ALPHAS = np.arange(0.05, 0.99, 0.05)

_EPS = np.finfo(float).eps


@validate_params(TRACKING_PARAMETERS, prefer_skip_nested_validation=True)
def hota_scores(labels_true, labels_pred, *, times, groups=None, window=0.5):
    """HOTA, DetA, AssA and LocA of predicted object ids against ground-truth objects, per time window.

    Read more in the :ref:`User Guide <user-guide-online>`.

    Parameters
    ----------
    labels_true : array-like of shape (n_detections,)
        Ground-truth object per detection: a moving road user's id (>= 0),
        -1 for everything else, as :func:`~sklearn_radar.instance_target`
        gives it.
    labels_pred : array-like of shape (n_detections,)
        Predicted object id per detection (e.g. the object ids of
        :class:`~sklearn_radar.online.OnlinePipeline`), -1 for noise.
    times : array-like of shape (n_detections,)
        Detection time, s.
    groups : array-like of shape (n_detections,), default=None
        Sequence of each detection; ids of different sequences are
        different tracks.  None: one sequence.
    window : float or None, default=0.5
        Window length, s; detection ``i`` of sequence ``s`` lies in window
        ``floor((times[i] - min(times of s)) / window)``.  None: one window
        per sequence.

    Returns
    -------
    scores : dict
        ``hota``, ``deta``, ``assa``, ``loca``, ``detre``, ``detpr``,
        ``assre`` and ``asspr`` (means over the thresholds ``alpha``), each
        also per threshold under the same key with ``_alpha`` appended
        (arrays of 19); ``alpha``, the thresholds.

    See Also
    --------
    tracking_scores : MOTA and IDF1 of the same ids, with matches at IoU > 0.5.

    Examples
    --------
    >>> from sklearn_radar.metrics import hota_scores
    >>> truth = [0, 0, 0, 0]
    >>> pred = [5, 5, 7, 7]  # the object changes id between the two windows
    >>> scores = hota_scores(truth, pred, times=[0.0, 0.1, 0.6, 0.7])
    >>> round(scores["deta"], 3), round(scores["assa"], 3), round(scores["hota"], 3)
    (1.0, 0.5, 0.707)
    """
    labels_true, labels_pred, times, groups = _tracking_inputs(labels_true, labels_pred, times, groups)
    totals = _Totals()
    if len(times):
        cell, sequence = _window_cells(times, groups, window)
        labels_true, labels_pred = labels_true.astype(np.int64), labels_pred.astype(np.int64)
        for number in np.unique(sequence):
            rows = np.flatnonzero(sequence == number)
            totals.add(_sequence_counts(cell[rows], labels_true[rows], labels_pred[rows]))
    return totals.scores()


def hota_counts(labels_true, labels_pred, times, window=0.5):
    """One sequence's HOTA counts (TP, FN, FP and the TP-weighted sums, per threshold): a part that adds up.

    :func:`combine_hota_counts` of the parts of several sequences equals :func:`hota_scores` with ``groups``.
    """
    labels_true, labels_pred, times, groups = _tracking_inputs(labels_true, labels_pred, times, None)
    if len(times) == 0:
        return _Totals().counts
    cell, _ = _window_cells(times, groups, window)
    return _sequence_counts(cell, labels_true.astype(np.int64), labels_pred.astype(np.int64))


def combine_hota_counts(parts):
    """The scores of :func:`hota_scores` from the :func:`hota_counts` of sequences."""
    totals = _Totals()
    for counts in parts:
        totals.add(counts)
    return totals.scores()


def _ids(labels):
    """Per detection: the 0-based id of its label (-1 for noise); and the number of ids."""
    out = np.full(len(labels), -1, dtype=np.int64)
    valid = labels >= 0
    codes, out[valid] = np.unique(labels[valid], return_inverse=True)
    return out, len(codes)


def _windows(cell, gt, tr):
    """Per window (in time order): the ground-truth ids, the hypothesis ids and their IoU matrix."""
    for code in np.unique(cell):
        rows = cell == code
        g, p = gt[rows], tr[rows]
        g_ids, p_ids = np.unique(g[g >= 0]), np.unique(p[p >= 0])
        g_size = np.array([np.sum(g == i) for i in g_ids])
        p_size = np.array([np.sum(p == j) for j in p_ids])
        both = (g >= 0) & (p >= 0)
        inter = np.zeros((len(g_ids), len(p_ids)))
        np.add.at(inter, (np.searchsorted(g_ids, g[both]), np.searchsorted(p_ids, p[both])), 1)
        union = g_size[:, None] + p_size[None, :] - inter
        yield g_ids, p_ids, np.divide(inter, union, out=np.zeros_like(inter), where=union > 0)


def _sequence_counts(cell, labels_true, labels_pred):
    """One sequence's TP, FN, FP, and the TP-weighted sums of AssA, AssRe, AssPr and LocA, per threshold."""
    gt, n_gt = _ids(labels_true)
    tr, n_tr = _ids(labels_pred)
    counts = {key: np.zeros(len(ALPHAS)) for key in ("tp", "fn", "fp", "assa", "assre", "asspr", "loca")}
    windows = list(_windows(cell, gt, tr))
    gt_dets = sum(len(g) for g, _, _ in windows)
    tr_dets = sum(len(p) for _, p, _ in windows)
    if gt_dets == 0 or tr_dets == 0:
        counts["fn"] += gt_dets
        counts["fp"] += tr_dets
        return counts
    potential = np.zeros((n_gt, n_tr))
    gt_count, tr_count = np.zeros((n_gt, 1)), np.zeros((1, n_tr))
    for g_ids, p_ids, similarity in windows:
        denominator = similarity.sum(0)[None, :] + similarity.sum(1)[:, None] - similarity
        share = np.divide(similarity, denominator, out=np.zeros_like(similarity), where=denominator > _EPS)
        potential[g_ids[:, None], p_ids[None, :]] += share
        gt_count[g_ids] += 1
        tr_count[0, p_ids] += 1
    alignment = potential / (gt_count + tr_count - potential)
    matches = np.zeros((len(ALPHAS), n_gt, n_tr))
    for g_ids, p_ids, similarity in windows:
        if len(g_ids) == 0 or len(p_ids) == 0:
            counts["fn"] += len(g_ids)
            counts["fp"] += len(p_ids)
            continue
        rows, cols = linear_sum_assignment(-(alignment[g_ids[:, None], p_ids[None, :]] * similarity))
        matched = similarity[rows, cols]
        for a, alpha in enumerate(ALPHAS):
            keep = matched >= alpha - _EPS
            counts["tp"][a] += keep.sum()
            counts["fn"][a] += len(g_ids) - keep.sum()
            counts["fp"][a] += len(p_ids) - keep.sum()
            counts["loca"][a] += matched[keep].sum()
            matches[a, g_ids[rows[keep]], p_ids[cols[keep]]] += 1
    union = np.maximum(1, gt_count + tr_count - matches)
    counts["assa"] = np.sum(matches * matches / union, axis=(1, 2))
    counts["assre"] = np.sum(matches * matches / np.maximum(1, gt_count), axis=(1, 2))
    counts["asspr"] = np.sum(matches * matches / np.maximum(1, tr_count), axis=(1, 2))
    return counts


class _Totals:
    """Counts summed over sequences, and the scores they give."""

    def __init__(self):
        self.counts = {key: np.zeros(len(ALPHAS)) for key in ("tp", "fn", "fp", "assa", "assre", "asspr", "loca")}

    def add(self, counts):
        for key, value in counts.items():
            self.counts[key] += value

    def scores(self):
        c = self.counts
        tp = c["tp"]
        per = {
            "deta": tp / np.maximum(1, tp + c["fn"] + c["fp"]),
            "detre": tp / np.maximum(1, tp + c["fn"]),
            "detpr": tp / np.maximum(1, tp + c["fp"]),
            "assa": c["assa"] / np.maximum(1, tp),
            "assre": c["assre"] / np.maximum(1, tp),
            "asspr": c["asspr"] / np.maximum(1, tp),
            "loca": np.maximum(1e-10, c["loca"]) / np.maximum(1e-10, tp),  # 1 where nothing matched
        }
        per["hota"] = np.sqrt(per["deta"] * per["assa"])
        out = {key: float(np.mean(value)) for key, value in per.items()}
        out.update({f"{key}_alpha": value for key, value in per.items()})
        out["alpha"] = ALPHAS.copy()
        return out
