"""What both road-user classifiers share: the class target, the wrapped classifier and its probabilities."""

from __future__ import annotations

import numbers
import warnings

import numpy as np
import pandas as pd
from sklearn import get_config
from sklearn.base import clone
from sklearn.dummy import DummyClassifier
from sklearn.ensemble import HistGradientBoostingClassifier
from sklearn.utils import check_array, column_or_1d

from ..metrics import pointwise_macro_f1
from ._classes import BACKGROUND, IGNORED

#: The wrapped classifier's settings when none is given.  30 boosting iterations instead of scikit-learn's 100:
#: its prediction costs about 60 µs per tree and class, whatever the number of rows, which made 100 iterations
#: (600 trees for 6 classes) cost as much as stage 1 alone.  Measured (``benchmarks/bench_classifier.py
#: --accuracy``: 3 seeds, #8's clusters of 8 simulated sequences x 30 s for training and 8 others for testing),
#: 30 iterations give the same macro-F1 as 100 within the spread over seeds: point-wise 0.572 +- 0.018 against
#: 0.569 +- 0.013, per segment 0.785 +- 0.015 against 0.785 +- 0.006, at 17 ms instead of 58 ms per prediction.
#: Early stopping off: scikit-learn turns it on above 10,000 rows, and its stratified 10 % hold-out raised a
#: ValueError when a class had a single training row (a tuned setting's clusters can leave one); with 30
#: iterations the budget is fixed anyway, and the hold-out only took training rows away.
DEFAULT_CLASSIFIER_PARAMS = {"max_iter": 30, "random_state": 0, "early_stopping": False}


def default_classifier():
    """The wrapped classifier when none is given: histogram gradient boosting (it takes NaN as missing).

    Returns
    -------
    classifier : HistGradientBoostingClassifier
        With :data:`DEFAULT_CLASSIFIER_PARAMS`.
    """
    return HistGradientBoostingClassifier(**DEFAULT_CLASSIFIER_PARAMS)


def macro_f1_score(estimator, X, y):
    """``score`` of both classifiers: point-wise macro-F1 of ``estimator.predict(X)`` against the codes ``y``."""
    predicted = estimator.predict(X)
    y = check_class_target(y, len(predicted), f"{type(estimator).__name__}.score")
    return float(pointwise_macro_f1(y, predicted))


def check_class_target(y, n, where):
    """``y`` as int64 class codes (>= -2), one per row; the errors name ``y`` and the problem."""
    if y is None:
        raise ValueError(f"{where} requires y to be passed, but the target y is None")
    y = check_array(y, ensure_2d=False, dtype=None, input_name="y")
    y = column_or_1d(y, warn=True)
    if y.dtype.kind == "O" and all(isinstance(value, numbers.Integral) for value in y):
        y = y.astype(np.int64)  # integers held as Python objects
    if y.dtype.kind == "f" and np.all(y == np.round(y)):
        y = y.astype(np.int64)
    if y.dtype.kind not in "iu":
        raise ValueError(
            f"{where}: Unknown label type: y must hold integer class codes (-1 background, -2 ignored, >= 0 "
            f"road-user classes; see road_user_class), got dtype {y.dtype}"
        )
    if len(y) != n:
        raise ValueError(f"{where}: y has {len(y)} values for {n} detections")
    if len(y) and y.min() < IGNORED:
        raise ValueError(f"{where}: y holds the class code {y.min()}; codes are -2, -1 or >= 0")
    return y.astype(np.int64, copy=False)


def instance_column_of(X, name, where):
    """The ground-truth instance column ``name`` of the DataFrame X; a ValueError says what is missing."""
    if not isinstance(X, pd.DataFrame):
        raise ValueError(
            f"{where}: instance_column={name!r} needs X as a DataFrame with that column; a plain array holds no "
            "instance ids (set instance_column=None to take the class segments of each window as the instances)"
        )
    if name not in X.columns:
        raise ValueError(f"{where}: X has no instance column {name!r} (the ground-truth instance of each detection)")
    values = X[name].to_numpy()
    if values.dtype.kind == "f" and np.all(np.isfinite(values)) and np.all(values == np.round(values)):
        values = values.astype(np.int64)
    if values.dtype.kind not in "iuOUST":
        raise ValueError(f"{where}: instance column {name!r} must hold strings or integers, got dtype {values.dtype}")
    return values


def fit_classifier(classifier, features, targets, feature_names, owner, groups=None):
    """A fitted clone of ``classifier`` (default: :func:`default_classifier`) on the rows ``features``.

    With fewer than two classes among ``targets`` no classifier can learn:
    a :class:`~sklearn.dummy.DummyClassifier` predicts the one class (background
    when there is no row), with a UserWarning.  ``groups`` (one per row, e.g.
    its sequence) goes to the classifier's ``fit`` when scikit-learn's
    metadata routing is enabled and the classifier asks for ``groups`` (a
    ``CalibratedClassifierCV(cv=GroupKFold())``, a grouped search).
    """
    table = pd.DataFrame(features, columns=feature_names)
    present = np.unique(targets)
    if present.size < 2:
        constant = int(present[0]) if present.size else BACKGROUND
        warnings.warn(
            f"{type(owner).__name__}: the training examples hold {len(targets)} row(s) of one class only "
            f"({constant}); it predicts that class everywhere",
            UserWarning,
            stacklevel=3,
        )
        if not len(targets):
            table, targets = pd.DataFrame(np.zeros((1, len(feature_names))), columns=feature_names), [BACKGROUND]
        return DummyClassifier(strategy="constant", constant=constant).fit(table, targets)
    model = default_classifier() if classifier is None else clone(classifier)
    return model.fit(table, targets, **_routed_groups(model, groups))


def _routed_groups(model, groups):
    """``{"groups": groups}`` when metadata routing is on and ``model.fit`` consumes groups, else ``{}``."""
    if groups is None or not get_config()["enable_metadata_routing"]:
        return {}
    try:
        wanted = model.get_metadata_routing().consumes("fit", ["groups"])
    except AttributeError:  # not a scikit-learn estimator: it says nothing about routing
        return {}
    return {"groups": np.asarray(groups)} if wanted else {}


def class_proba(classifier, features, feature_names, classes):
    """``classifier.predict_proba`` of the rows ``features``, its columns placed at their codes in ``classes``."""
    proba = np.zeros((len(features), len(classes)))
    if len(features):
        known = np.searchsorted(classes, np.asarray(classifier.classes_, dtype=np.int64))
        proba[:, known] = classifier.predict_proba(pd.DataFrame(features, columns=feature_names))
    return proba
