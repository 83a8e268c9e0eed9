"""The training target of a cluster: the class of the ground-truth instance it matches (IoU > 0.5), else background.

A predicted segment (one cluster's detections in one time window of one
sequence, :mod:`._features`) matches a ground-truth segment (one instance's
detections in the same window and sequence) when their intersection over
union exceeds 0.5, ``2 |g ∩ p| > |g ∪ p|`` in integers; at that threshold a
segment has at most one match (the rule of panoptic quality,
:func:`~sklearn_radar.metrics.panoptic_quality`).  The target of a matched
segment is the class of its instance, the most frequent class among all the
instance's detections (ties: the smaller code); an unmatched segment is
background.  Codes are hash-based (:func:`pandas.factorize`): no sort, no
Python loop over segments.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ._classes import BACKGROUND


def _codes(values):
    codes, uniques = pd.factorize(values, use_na_sentinel=False)
    return codes.astype(np.int64, copy=False), len(uniques)


def _pair_codes(a, b, n_b):
    """Compact codes of the pairs ``(a, b)`` of non-negative codes, ``b < n_b``."""
    return _codes(a * np.int64(n_b) + b)


def instance_classes(instances, classes):
    """The class of each instance: the most frequent among its detections (ties: the smaller code).

    Parameters
    ----------
    instances : ndarray of int64, shape (m,)
        Instance code of each object detection, 0 .. n_instances - 1.
    classes : ndarray of int64, shape (m,)
        Class code of each of those detections.

    Returns
    -------
    class_of_instance : ndarray of int64, shape (n_instances,)
    """
    n_instances = int(instances.max()) + 1 if len(instances) else 0
    class_code, class_values = pd.factorize(classes)
    class_code, n_classes = class_code.astype(np.int64), len(class_values)
    pair, n_pairs = _pair_codes(instances, class_code, n_classes)
    count = np.bincount(pair, minlength=n_pairs)
    first = np.zeros(n_pairs, dtype=np.int64)
    first[pair[::-1]] = np.arange(len(pair))[::-1]
    pair_instance, pair_class = instances[first], class_values[class_code[first]]
    # Per instance, the pair with the largest count, then the smallest class: sort and take the first.
    best = np.lexsort((pair_class, -count, pair_instance))
    leader = np.ones(len(best), dtype=bool)
    leader[1:] = pair_instance[best][1:] != pair_instance[best][:-1]
    result = np.full(n_instances, BACKGROUND, dtype=np.int64)
    result[pair_instance[best][leader]] = pair_class[best][leader]
    return result


def segment_targets(classes, instances, sequence, windows, rows, n_segments):
    """Target class of every predicted segment under the IoU > 0.5 rule.

    Parameters
    ----------
    classes : ndarray of int64, shape (n,)
        Class code of each detection (-1 background, -2 ignored, >= 0 road users).
    instances : ndarray of int64, shape (n,)
        Ground-truth instance of each detection, -1 for none; equal ids in
        different sequences are different instances.
    sequence : ndarray or None
        Sequence of each detection, None: one sequence.
    windows : ndarray of int64, shape (n,)
        Frame of each detection.
    rows : ndarray of int64, shape (n,)
        Predicted segment of each detection, -1 for noise.
    n_segments : int

    Returns
    -------
    targets : ndarray of int64, shape (n_segments,)
        The class of the matched instance, -1 (background) when none matches;
        -2 when the matched instance is of an ignored class.
    """
    targets = np.full(n_segments, BACKGROUND, dtype=np.int64)
    objects = np.flatnonzero(instances >= 0)
    if n_segments == 0 or len(objects) == 0:
        return targets
    seq_code = np.zeros(len(objects), dtype=np.int64) if sequence is None else _codes(sequence[objects])[0]
    inst_code, _ = _pair_codes(seq_code, _codes(instances[objects])[0], len(objects) + 1)
    class_of_instance = instance_classes(inst_code, classes[objects])
    window_code, n_windows = _codes(windows[objects])
    truth, n_truth = _pair_codes(inst_code, window_code, n_windows)  # ground-truth segment of each object detection
    truth_instance = np.zeros(n_truth, dtype=np.int64)
    truth_instance[truth] = inst_code
    truth_size = np.bincount(truth, minlength=n_truth)
    predicted_size = np.bincount(rows[rows >= 0], minlength=n_segments)

    both = rows[objects] >= 0
    pair_truth, pair_predicted = truth[both], rows[objects][both]
    pair, n_pairs = _pair_codes(pair_predicted, pair_truth, n_truth)
    inter = np.bincount(pair, minlength=n_pairs)
    first = np.zeros(n_pairs, dtype=np.int64)
    first[pair[::-1]] = np.arange(len(pair))[::-1]
    g, p = pair_truth[first], pair_predicted[first]
    matched = 2 * inter > truth_size[g] + predicted_size[p] - inter  # IoU > 0.5: one match per segment at most
    targets[p[matched]] = class_of_instance[truth_instance[g[matched]]]
    return targets
