"""Where the class-aware panoptic quality goes: a confusion matrix of matched segments and, per class, the errors.

Segments are those of :func:`~sklearn_radar.metrics.class_panoptic_quality`: per time window of each sequence,
a ground-truth segment is one instance's detections and a predicted segment one predicted instance's (one
cluster's), each with the majority class of its rows.  Here a predicted segment takes part whatever its
class, background included, and segments match *class-agnostically*: when their IoU exceeds 0.5 (at most one
match per segment).  So every error of the class-aware PQ has one place: a ground-truth segment of class
``c`` that the class-aware PQ misses was either not found by the grouping (no predicted segment matches it)
or found with another class; a false predicted segment of class ``c`` either matches no road user or
matches one of another class.
"""

from __future__ import annotations

from numbers import Real

import numpy as np
import pandas as pd
from sklearn.utils import Bunch
from sklearn.utils._param_validation import Interval, validate_params

from ._segments import _segments
from ._semantic import _BACKGROUND, _IGNORED, _checked, _majority_class

__all__ = ["class_errors"]


@validate_params(
    {
        "classes_true": ["array-like"],
        "instances_true": ["array-like"],
        "classes_pred": ["array-like"],
        "instances_pred": ["array-like"],
        "times": ["array-like", None],
        "groups": ["array-like", None],
        "window": [Interval(Real, 0, None, closed="neither"), None],
        "confidence": ["array-like", None],
    },
    prefer_skip_nested_validation=True,
)
def class_errors(
    classes_true, instances_true, classes_pred, instances_pred, *, times, groups=None, window=0.5, confidence=None
):
    """The confusion matrix of matched segments and, per road-user class, where its panoptic quality goes.

    The segments are those of :func:`class_panoptic_quality` (one
    instance's detections in one window of ``window`` seconds, with the
    majority class of its rows; detections whose true class is ignored, -2,
    left out), except that a predicted segment whose class is background
    (-1) takes part too.  A ground-truth segment of a road-user class and a
    predicted segment *match* when their IoU exceeds 0.5, whatever their
    classes (class-agnostically).

    * ``confusion``: the number of matched pairs per true class (rows) and
      predicted class (columns, -1 background first).  Its diagonal is the
      true positives of :func:`class_panoptic_quality`.
    * For each class ``c``, its ground-truth segments are ``tp`` (matched,
      class ``c``), ``misclassified`` (matched, another class or
      background) or ``missed`` (no predicted segment matches it: the
      grouping did not find it), and ``fn = misclassified + missed``; its
      predicted segments are ``tp``, ``wrong_class`` (matched to a road user
      of another class) or ``false`` (matched to no road user: background,
      part of an object or several objects), and ``fp = wrong_class +
      false``.  ``tp``, ``fp`` and ``fn`` are those of
      :func:`class_panoptic_quality`.

    Pass the grouping's own labels as ``instances_pred`` (every cluster,
    also those the classifier calls background) to tell a road user
    classified as background (``misclassified``, column -1) from one the
    grouping missed: with the ``instance`` of
    :meth:`~sklearn_radar.classification.ClusterClassifier.predict_instances`,
    which is -1 where the class is background, both are ``missed``.

    Read more in the :ref:`User Guide <classification-errors>`.

    Parameters
    ----------
    classes_true : array-like of int, shape (n_detections,)
        True class of each detection: >= 0 a road-user class, -1
        background, -2 ignored (left out).
    instances_true : array-like of int, shape (n_detections,)
        Ground-truth instance of each detection, negative for none.
    classes_pred : array-like of int, shape (n_detections,)
        Predicted class of each detection (-1 background).
    instances_pred : array-like of int, shape (n_detections,)
        Predicted instance (cluster) of each detection, negative for none.
    times : array-like of shape (n_detections,) or None
        Time of each detection in s.  None, or ``window=None``: every
        sequence is one window.
    groups : array-like of shape (n_detections,), default=None
        Sequence of each detection; None: one sequence.
    window : float or None, default=0.5
        Length of a time window in s, > 0; None: one window per sequence.
    confidence : array-like of float, shape (n_detections,), default=None
        Confidence of each detection's predicted class; breaks a tie of the
        majority vote of a predicted segment, as in
        :func:`class_panoptic_quality`.

    Returns
    -------
    errors : Bunch
        ``confusion``: a DataFrame of int64 counts, indexed by the road-user
        classes present in the truth or the predicted segments (sorted),
        with the columns -1 and those classes; ``per_class``: ``{code:
        Bunch(n_true, tp, misclassified, missed, fn, n_pred, wrong_class,
        false, fp)}`` for each of those classes (segment counts).

    Raises
    ------
    ValueError
        If an argument is not 1-D with one value per detection (the message
        names it), codes are not integers, or a time or confidence is not
        finite.

    See Also
    --------
    class_panoptic_quality : the class-aware PQ these errors cost.
    instance_errors : the causes of the grouping's missed and false segments.

    Examples
    --------
    >>> from sklearn_radar.metrics import class_errors
    >>> # A car found as a pedestrian; a pedestrian missed (noise); a background cluster called a car.
    >>> errors = class_errors(
    ...     [0, 0, 3, 3, -1, -1], [0, 0, 1, 1, -1, -1], [3, 3, -1, -1, 0, 0], [5, 5, -1, -1, 6, 6], times=None
    ... )
    >>> errors["confusion"].loc[0].to_dict()  # the car's row: found once, as a pedestrian
    {-1: 0, 0: 0, 3: 1}
    >>> errors["per_class"][3]["missed"], errors["per_class"][0]["false"]
    (1, 1)
    """
    arrays = _checked(classes_true, instances_true, classes_pred, instances_pred, confidence, times, groups)
    classes_true, classes_pred = arrays["classes_true"], arrays["classes_pred"]
    kept = classes_true != _IGNORED  # left out after the windows are laid out, as class_panoptic_quality does
    labels_true = np.where(kept & (arrays["instances_true"] >= 0), arrays["instances_true"], -1)
    labels_pred = np.where(kept & (arrays["instances_pred"] >= 0), arrays["instances_pred"], -1)
    found = _segments(labels_true, labels_pred, times=arrays["times"], groups=arrays["groups"], window=window)

    member = np.flatnonzero(found.true_seg >= 0)
    true_class = _majority_class(found.true_seg[member], found.n_true, classes_true[member], None)
    member = np.flatnonzero(found.pred_seg >= 0)
    weights = arrays["confidence"]
    if weights is not None:  # in order of confidence, so that the sums are the same floats for any row order
        member = member[np.argsort(weights[member], kind="stable")]
        weights = weights[member]
    pred_class = _majority_class(found.pred_seg[member], found.n_pred, classes_pred[member], weights)

    road_user = true_class >= 0
    matched = (2 * found.inter > found.union) & road_user[found.pair_true]
    matched_true = true_class[found.pair_true[matched]]
    matched_pred = np.maximum(pred_class[found.pair_pred[matched]], _BACKGROUND)
    codes = np.union1d(true_class[road_user], pred_class[pred_class >= 0]).astype(np.int64)
    columns = np.r_[_BACKGROUND, codes].astype(np.int64)
    counts = np.zeros((len(codes), len(columns)), dtype=np.int64)
    np.add.at(counts, (np.searchsorted(codes, matched_true), np.searchsorted(columns, matched_pred)), 1)
    confusion = pd.DataFrame(counts, index=pd.Index(codes, name="true"), columns=pd.Index(columns, name="predicted"))

    per_class = {}
    for code in codes:
        tp = int(confusion.loc[code, code])
        n_true = int(np.count_nonzero(true_class == code))
        n_pred = int(np.count_nonzero(pred_class == code))
        found_true, found_pred = int(confusion.loc[code].sum()), int(confusion[code].sum())
        per_class[int(code)] = Bunch(
            n_true=n_true,
            tp=tp,
            misclassified=found_true - tp,
            missed=n_true - found_true,
            fn=n_true - tp,
            n_pred=n_pred,
            wrong_class=found_pred - tp,
            false=n_pred - found_pred,
            fp=n_pred - tp,
        )
    return Bunch(confusion=confusion, per_class=per_class)
