"""Where the panoptic quality goes: the missed and the false segments of a labelling, by cause.

Segments and matches are those of :func:`~sklearn_radar.metrics.panoptic_quality`: per time window of each
sequence, a ground-truth segment (one object's detections) and a predicted segment (one cluster's) match when
their IoU exceeds 0.5.  Every unmatched segment gets one cause.
"""

from __future__ import annotations

from numbers import Real

import numpy as np
from sklearn.utils._param_validation import Interval, validate_params

from ._segments import _segments

#: Causes of a missed ground-truth segment, in the order they are tested.
MISSED_CAUSES = ("noise", "merged_with_object", "merged_with_background", "split")
#: Causes of a false predicted segment.
FALSE_CAUSES = ("background", "part_of_object", "several_objects")


@validate_params(
    {
        "labels_true": ["array-like"],
        "labels_pred": ["array-like"],
        "times": ["array-like", None],
        "groups": ["array-like", None],
        "window": [Interval(Real, 0, None, closed="neither"), None],
    },
    prefer_skip_nested_validation=True,
)
def instance_errors(labels_true, labels_pred, *, times, groups=None, window=0.5):
    """The missed ground-truth segments and the false predicted segments of a clustering, by cause.

    A ground-truth segment that no predicted segment matches (IoU > 0.5) is
    missed because

    * ``noise``: more than half of its detections are noise;
    * ``merged_with_object``: one cluster holds more than half of it, and
      that cluster also holds another object's detections;
    * ``merged_with_background``: one cluster holds more than half of it,
      with background detections but no other object's;
    * ``split``: otherwise: its detections are spread over clusters (and
      noise), none holding more than half.

    A predicted segment that matches no ground-truth segment is false
    because it holds ``background`` only, ``part_of_object`` (detections of
    one object, too few of them or with too much background), or
    ``several_objects``.

    Read more in the :ref:`User Guide <user-guide-objects>`.

    Parameters
    ----------
    labels_true : array-like of shape (n_detections,)
        Ground-truth object per detection, -1 for background (as
        :func:`~sklearn_radar.instance_target` gives it).
    labels_pred : array-like of shape (n_detections,)
        Cluster per detection, -1 for noise.
    times : array-like of shape (n_detections,) or None
        Detection time, s.  None: one window per sequence.
    groups : array-like of shape (n_detections,), default=None
        Sequence of each detection; None: one sequence.
    window : float or None, default=0.5
        Window length, s.  None: one window per sequence.

    Returns
    -------
    errors : dict
        ``n_true`` and ``n_pred`` (segments), ``matched``; ``missed`` and one
        count per cause of :data:`MISSED_CAUSES` (they add up to ``missed``);
        ``false`` and one count per cause of :data:`FALSE_CAUSES`;
        ``median_size_matched`` and ``median_size_missed``, the median number
        of detections of the matched and of the missed ground-truth segments
        (NaN without any).

    See Also
    --------
    instance_scores : the panoptic quality and coverage of the same segments.

    Examples
    --------
    >>> from sklearn_radar.metrics import instance_errors
    >>> truth = [0, 0, 0, 1, 1, 1, -1, -1]
    >>> pred = [5, 5, 5, 5, -1, -1, 7, 7]  # object 1 mostly noise; cluster 7 is background
    >>> errors = instance_errors(truth, pred, times=None)
    >>> errors["matched"], errors["noise"], errors["background"]
    (1, 1, 1)
    """
    found = _segments(labels_true, labels_pred, times=times, groups=groups, window=window)
    labels_true, labels_pred = np.asarray(labels_true), np.asarray(labels_pred)
    n_true, n_pred = found.n_true, found.n_pred
    true_size, pair_true, pair_pred, inter = found.true_size, found.pair_true, found.pair_pred, found.inter
    matched_pair = 2 * inter > found.union
    true_matched = np.bincount(pair_true[matched_pair], minlength=n_true) > 0
    pred_matched = np.bincount(pair_pred[matched_pair], minlength=n_pred) > 0

    # Per ground-truth segment: its noise detections, and the cluster holding most of it.
    noise = np.bincount(found.true_seg[(labels_true != -1) & (labels_pred == -1)], minlength=n_true)
    order = np.lexsort((-inter, pair_true))  # per ground-truth segment, its largest overlap first
    first = order[np.r_[True, pair_true[order][1:] != pair_true[order][:-1]]] if len(order) else order
    largest = np.zeros(n_true, dtype=np.int64)
    holder = np.full(n_true, -1, dtype=np.int64)
    largest[pair_true[first]], holder[pair_true[first]] = inter[first], pair_pred[first]
    # Per predicted segment: how many objects it touches.
    objects_in = np.bincount(pair_pred, minlength=n_pred)

    missed = ~true_matched
    by_noise = missed & (2 * noise > true_size)
    held = missed & ~by_noise & (2 * largest > true_size)
    holds_others = np.zeros(n_true, dtype=bool)
    holds_others[holder >= 0] = objects_in[holder[holder >= 0]] > 1
    with_object = held & holds_others
    false = ~pred_matched
    errors = {
        "n_true": int(n_true),
        "n_pred": int(n_pred),
        "matched": int(true_matched.sum()),
        "missed": int(missed.sum()),
        "noise": int(by_noise.sum()),
        "merged_with_object": int(with_object.sum()),
        "merged_with_background": int((held & ~with_object).sum()),
        "split": int((missed & ~by_noise & ~held).sum()),
        "false": int(false.sum()),
        "background": int((false & (objects_in == 0)).sum()),
        "part_of_object": int((false & (objects_in == 1)).sum()),
        "several_objects": int((false & (objects_in > 1)).sum()),
    }
    for key, rows in (("matched", true_matched), ("missed", missed)):
        errors[f"median_size_{key}"] = float(np.median(true_size[rows])) if rows.any() else float("nan")
    return errors
