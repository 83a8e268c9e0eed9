"""A compiled walk of a fitted binary HistGradientBoostingClassifier, for fast inference on small batches (numba).

scikit-learn's ``predict_proba`` validates its input, starts OpenMP threads
and calls one Cython routine per tree: about a tenth of a millisecond of
overhead per call, whatever the batch.  Scan by scan, where a batch holds a
few dozen rows, that overhead is most of the time.  :func:`compile_boosting`
copies the trees of a fitted classifier into flat arrays once;
:func:`boosting_proba` walks them in one compiled loop.

The walk is the one of scikit-learn's ``_predict_from_raw_data`` for
numeric splits: a missing value (NaN) goes to the side that
``missing_go_to_left`` gives, a value at or below ``num_threshold`` goes
left, any other right.  The raw score is the baseline plus the leaf values
of the trees in their order (the order of scikit-learn's sum), and
P(class 1) is its logistic function.  Classifiers that this walk does not
cover (categorical splits, more than two classes, a structure of private
attributes that differs from scikit-learn 1.6-1.9's) give None, and the
caller keeps ``predict_proba``.
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

#: The node fields the walk reads (of scikit-learn's ``PREDICTOR_RECORD_DTYPE``).
_FIELDS = ("value", "feature_idx", "num_threshold", "missing_go_to_left", "left", "right", "is_leaf")


class CompiledBoosting(NamedTuple):
    """The trees of a binary classifier as flat arrays; node ``k`` of tree ``m`` is row ``offset[m] + k``.

    Attributes
    ----------
    feature_idx : ndarray of int64
        Feature of each split node.
    num_threshold : ndarray of float64
        Its threshold: values at or below it go left.
    missing_go_to_left : ndarray of bool
        Where NaN goes.
    left, right : ndarray of int64
        Children, numbered within their tree.
    is_leaf : ndarray of bool
        Leaves.
    value : ndarray of float64
        Leaf values (raw score, log-odds).
    offset : ndarray of int64, shape (n_trees + 1,)
        First row of each tree, then the number of rows.
    baseline : float
        Raw score before the first tree.
    n_features : int
        Columns the classifier was fitted on.
    """

    feature_idx: np.ndarray
    num_threshold: np.ndarray
    missing_go_to_left: np.ndarray
    left: np.ndarray
    right: np.ndarray
    is_leaf: np.ndarray
    value: np.ndarray
    offset: np.ndarray
    baseline: float
    n_features: int


def compile_boosting(classifier):
    """The trees of a fitted binary classifier as flat arrays, or None when the walk does not cover it.

    Parameters
    ----------
    classifier : object
        Typically a fitted :class:`~sklearn.ensemble.HistGradientBoostingClassifier`.

    Returns
    -------
    compiled : CompiledBoosting or None
        None unless ``classifier`` is a fitted binary histogram gradient
        boosting classifier with numeric features only, whose private
        structure is the one this walk reads.
    """
    from sklearn.ensemble import HistGradientBoostingClassifier  # on first use: the cluster package stays light

    if not isinstance(classifier, HistGradientBoostingClassifier):
        return None
    try:
        if len(classifier.classes_) != 2 or classifier.n_trees_per_iteration_ != 1:
            return None
        if classifier.is_categorical_ is not None and np.any(classifier.is_categorical_):
            return None
        if getattr(classifier, "_preprocessor", None) is not None:
            return None
        if type(classifier._loss).__name__ != "HalfBinomialLoss":
            return None
        baseline = np.asarray(classifier._baseline_prediction, dtype=np.float64)
        if baseline.size != 1:
            return None
        trees = []
        for predictors in classifier._predictors:
            if len(predictors) != 1:
                return None
            nodes = predictors[0].nodes
            names = nodes.dtype.names or ()
            if not set(_FIELDS) <= set(names):
                return None
            if "is_categorical" in names and np.any(nodes["is_categorical"]):
                return None
            trees.append(nodes)
        n_features = int(classifier.n_features_in_)
    except AttributeError:  # not fitted, or another version's private structure
        return None
    sizes = [len(nodes) for nodes in trees]
    if any(size == 0 for size in sizes):
        return None

    def column(field, dtype):
        if not trees:
            return np.zeros(0, dtype=dtype)
        return np.concatenate([nodes[field] for nodes in trees]).astype(dtype)

    compiled = CompiledBoosting(
        feature_idx=column("feature_idx", np.int64),
        num_threshold=column("num_threshold", np.float64),
        missing_go_to_left=column("missing_go_to_left", np.bool_),
        left=column("left", np.int64),
        right=column("right", np.int64),
        is_leaf=column("is_leaf", np.bool_),
        value=column("value", np.float64),
        offset=np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64),
        baseline=float(baseline.ravel()[0]),
        n_features=n_features,
    )
    if not _well_formed(compiled):
        return None
    return compiled


def _well_formed(c):
    """Every split's feature in range and children within its tree: the walk cannot leave the arrays."""
    split = ~c.is_leaf
    if np.any((c.feature_idx[split] < 0) | (c.feature_idx[split] >= c.n_features)):
        return False
    size = np.repeat(np.diff(c.offset), np.diff(c.offset))
    return not np.any(split & ((c.left < 0) | (c.left >= size) | (c.right < 0) | (c.right >= size)))


def boosting_proba(compiled, X):
    """P(class 1) of each row of ``X`` by the compiled trees, or by a constant probability.

    Parameters
    ----------
    compiled : CompiledBoosting or float
        Of :func:`compile_boosting`, or a constant probability.
    X : array-like of shape (n, n_features)
        The rows, in the columns the classifier was fitted on; NaN is a missing value.

    Returns
    -------
    proba : ndarray of float64, shape (n,)

    Raises
    ------
    ValueError
        If ``X`` does not have the classifier's number of columns.
    """
    X = np.asarray(X, dtype=np.float64)
    if isinstance(compiled, float):
        return np.full(len(X), compiled)
    if X.ndim != 2 or X.shape[1] != compiled.n_features:
        raise ValueError(f"X has shape {X.shape}; the classifier was fitted on {compiled.n_features} features")
    return _walk(
        np.ascontiguousarray(X),
        compiled.feature_idx,
        compiled.num_threshold,
        compiled.missing_go_to_left,
        compiled.left,
        compiled.right,
        compiled.is_leaf,
        compiled.value,
        compiled.offset,
        compiled.baseline,
    )


@numba.njit(cache=True, nogil=True)
def _walk(X, feature_idx, num_threshold, missing_go_to_left, left, right, is_leaf, value, offset, baseline):
    n_trees = len(offset) - 1
    raw = np.full(X.shape[0], baseline)
    for tree in range(n_trees):  # tree by tree (its nodes stay in cache), each row's sum in the trees' order
        start = offset[tree]
        for row in range(X.shape[0]):
            node = start
            while not is_leaf[node]:
                x = X[row, feature_idx[node]]
                if np.isnan(x):
                    go_left = missing_go_to_left[node]
                else:
                    go_left = x <= num_threshold[node]
                node = start + (left[node] if go_left else right[node])
            raw[row] += value[node]
    return 1.0 / (1.0 + np.exp(-raw))
