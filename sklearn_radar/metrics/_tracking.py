"""Tracking quality of object ids over time windows: ID switches, MOTA (CLEAR MOT) and IDF1 (identity measures).

Within each sequence time is cut into windows (as for the panoptic quality).
In a window, a ground-truth object is the set of its detections (a moving
road user, ``labels_true >= 0``) and a hypothesis the set of detections
carrying one predicted id; they match when their IoU exceeds 0.5, so that
each has at most one partner and no assignment is needed.  Then, summed
over windows (Bernardin and Stiefelhagen 2008; Ristani et al. 2016):

* ``misses``: ground-truth objects without a partner; ``false_positives``:
  hypotheses without one;
* ``id_switches``: matches whose hypothesis differs from the one the
  ground-truth object was last matched to;
* ``MOTA = 1 - (misses + false_positives + id_switches) / n_objects``;
* ``IDF1 = 2 IDTP / (2 IDTP + IDFP + IDFN)`` from the one-to-one
  assignment of whole ground-truth tracks to whole predicted tracks that
  maximises the windows in which they match (IDTP).
"""

from __future__ import annotations

from numbers import Real

import numpy as np
from scipy.optimize import linear_sum_assignment
from sklearn.utils._param_validation import Interval, validate_params

#: A ground-truth object and a hypothesis match in a window when their IoU exceeds this.
MATCH_IOU = 0.5


def _window_cells(times, groups, window):
    """Code of each detection's (sequence, window), ordered by sequence then window; and the sequence codes."""
    _, sequence = np.unique(groups, return_inverse=True)
    sequence = sequence.ravel()
    if window is None:
        return sequence, sequence
    start = np.full(sequence.max() + 1, np.inf)
    np.minimum.at(start, sequence, times)
    index = np.floor((times - start[sequence]) / window).astype(np.int64)
    _, cell = np.unique(np.c_[sequence, index], axis=0, return_inverse=True)
    return cell.ravel(), sequence


def _segments(cell, sequence, labels):
    """Per labelled detection: segment code (cell, label), its track code (sequence, label); per segment: cell."""
    rows = np.flatnonzero(labels >= 0)
    _, segment = np.unique(np.c_[cell[rows], labels[rows]], axis=0, return_inverse=True)
    _, track = np.unique(np.c_[sequence[rows], labels[rows]], axis=0, return_inverse=True)
    segment, track = segment.ravel(), track.ravel()
    n = segment.max() + 1 if len(rows) else 0
    segment_cell = np.zeros(n, dtype=np.int64)
    segment_track = np.zeros(n, dtype=np.int64)
    segment_cell[segment] = cell[rows]
    segment_track[segment] = track
    return rows, segment, segment_cell, segment_track


#: The arguments of the tracking scores, as validate_params checks them.
TRACKING_PARAMETERS = {
    "labels_true": ["array-like"],
    "labels_pred": ["array-like"],
    "times": ["array-like"],
    "groups": ["array-like", None],
    "window": [Interval(Real, 0, None, closed="neither"), None],
}


def _tracking_inputs(labels_true, labels_pred, times, groups):
    """The four per-detection arrays as 1-D arrays (one sequence without groups); ValueError if they disagree."""
    labels_true = np.asarray(labels_true).ravel()
    labels_pred = np.asarray(labels_pred).ravel()
    times = np.asarray(times, dtype=np.float64).ravel()
    groups = np.zeros(len(times)) if groups is None else np.asarray(groups).ravel()
    if not (len(labels_true) == len(labels_pred) == len(times) == len(groups)):
        raise ValueError(
            "labels_true, labels_pred, times and groups must have equal lengths, got "
            f"{len(labels_true)}, {len(labels_pred)}, {len(times)} and {len(groups)}"
        )
    if not np.isfinite(times).all():
        raise ValueError("times must be finite")
    return labels_true, labels_pred, times, groups


@validate_params(TRACKING_PARAMETERS, prefer_skip_nested_validation=True)
def tracking_scores(labels_true, labels_pred, *, times, groups=None, window=0.5):
    """ID switches, MOTA and IDF1 of predicted object ids against ground-truth objects, per time window.

    Read more in the :ref:`User Guide <user-guide-online>`.

    Parameters
    ----------
    labels_true : array-like of shape (n_detections,)
        Ground-truth object per detection: a moving road user's id (>= 0),
        -1 for everything else (static background, clutter), as
        :func:`~sklearn_radar.instance_target` gives it.
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
        ``mota``, ``idf1``, ``id_switches``, ``misses``, ``false_positives``,
        ``n_objects`` (ground-truth objects summed over windows),
        ``n_matches``, ``idtp``, ``idfp``, ``idfn`` and ``n_windows``.
        ``mota`` and ``idf1`` are NaN without any ground-truth object (and
        without hypotheses for ``idf1``).

    Examples
    --------
    >>> from sklearn_radar.metrics import tracking_scores
    >>> truth = [0, 0, 0, 0]
    >>> pred = [5, 5, 7, 7]  # the object changes id between the two windows
    >>> scores = tracking_scores(truth, pred, times=[0.0, 0.1, 0.6, 0.7])
    >>> scores["id_switches"], scores["mota"], scores["idf1"]
    (1, 0.5, 0.5)
    """
    labels_true, labels_pred, times, groups = _tracking_inputs(labels_true, labels_pred, times, groups)
    if len(times) == 0:
        return _scores(0, 0, 0, 0, 0, 0, 0, 0)
    cell, sequence = _window_cells(times, groups, window)
    g_rows, g_segment, g_cell, g_track = _segments(cell, sequence, labels_true.astype(np.int64))
    p_rows, p_segment, p_cell, p_track = _segments(cell, sequence, labels_pred.astype(np.int64))
    n_g, n_p = len(g_cell), len(p_cell)
    g_of_row = np.full(len(times), -1)
    p_of_row = np.full(len(times), -1)
    g_of_row[g_rows], p_of_row[p_rows] = g_segment, p_segment
    both = (g_of_row >= 0) & (p_of_row >= 0)
    pair, inter = np.unique(np.c_[g_of_row[both], p_of_row[both]], axis=0, return_counts=True)
    g_size, p_size = np.bincount(g_segment, minlength=n_g), np.bincount(p_segment, minlength=n_p)
    pair = pair.reshape(-1, 2)
    iou = inter / (g_size[pair[:, 0]] + p_size[pair[:, 1]] - inter) if len(pair) else np.zeros(0)
    matched = pair[iou > MATCH_IOU]
    switches = _id_switches(g_cell[matched[:, 0]], g_track[matched[:, 0]], p_track[matched[:, 1]])
    idtp = _identity_true_positives(g_track[matched[:, 0]], p_track[matched[:, 1]])
    n_windows = len(np.unique(cell))
    return _scores(n_g, n_p, len(matched), switches, idtp, n_g - idtp, n_p - idtp, n_windows)


def _id_switches(cell, g_track, p_track):
    """Matches whose predicted track differs from the ground-truth track's previous match (cells in time order)."""
    order = np.lexsort((cell, g_track))
    g, p = g_track[order], p_track[order]
    return int(np.sum((g[1:] == g[:-1]) & (p[1:] != p[:-1])))


def _identity_true_positives(g_track, p_track):
    """IDTP: the most matched windows a one-to-one assignment of ground-truth to predicted tracks keeps."""
    if len(g_track) == 0:
        return 0
    pair, count = np.unique(np.c_[g_track, p_track], axis=0, return_counts=True)
    g_codes, g_index = np.unique(pair[:, 0], return_inverse=True)
    p_codes, p_index = np.unique(pair[:, 1], return_inverse=True)
    weight = np.zeros((len(g_codes), len(p_codes)))
    weight[g_index.ravel(), p_index.ravel()] = count
    rows, cols = linear_sum_assignment(weight, maximize=True)
    return int(weight[rows, cols].sum())


def _scores(n_objects, n_hypotheses, n_matches, switches, idtp, idfn, idfp, n_windows):
    misses, false_positives = n_objects - n_matches, n_hypotheses - n_matches
    mota = 1.0 - (misses + false_positives + switches) / n_objects if n_objects else np.nan
    denominator = 2 * idtp + idfp + idfn
    return {
        "mota": float(mota),
        "idf1": float(2 * idtp / denominator) if denominator else np.nan,
        "id_switches": int(switches),
        "misses": int(misses),
        "false_positives": int(false_positives),
        "n_objects": int(n_objects),
        "n_matches": int(n_matches),
        "idtp": int(idtp),
        "idfp": int(idfp),
        "idfn": int(idfn),
        "n_windows": int(n_windows),
    }
