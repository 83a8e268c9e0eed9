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
P(class 1) is its logistic function.

The rows of a batch walk a tree in lockstep, one level at a time for as
many levels as the tree's deepest leaf, each leaf being its own child: the
rows' steps are independent of each other, so the processor overlaps them
instead of waiting on one row's chain of loads and mispredicted branches.  A batch without NaN, the usual case,
walks with one comparison per step.  Classifiers that this walk does not
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
    feature : ndarray of uint32
        Feature of each split node (0 for a leaf).
    threshold : ndarray of float64
        Its threshold: values above it go right, the others left (+inf for a leaf).
    missing_go_right : ndarray of bool
        Where NaN goes (False for a leaf).
    children : ndarray of uint32, shape (n_nodes, 2)
        Left and right child, as rows (a leaf is both its children).
    value : ndarray of float64
        Leaf values (raw score, log-odds).
    offset : ndarray of int64, shape (n_trees + 1,)
        First row of each tree, then the number of rows.
    depth : ndarray of int64, shape (n_trees,)
        Depth of each tree's deepest leaf.
    baseline : float
        Raw score before the first tree.
    n_features : int
        Columns the classifier was fitted on.
    """

    feature: np.ndarray
    threshold: np.ndarray
    missing_go_right: np.ndarray
    children: np.ndarray
    value: np.ndarray
    offset: np.ndarray
    depth: np.ndarray
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
    if any(size == 0 for size in sizes) or sum(sizes) >= np.iinfo(np.int32).max:
        return None  # (the walk numbers the nodes in 32 bits)

    def column(field, dtype):
        if not trees:
            return np.zeros(0, dtype=dtype)
        return np.concatenate([nodes[field] for nodes in trees]).astype(dtype)

    leaf, left, right, feature = (
        column("is_leaf", np.bool_),
        column("left", np.int64),
        column("right", np.int64),
        column("feature_idx", np.int64),
    )
    offset = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    size = np.repeat(np.diff(offset), np.diff(offset))
    if np.any(~leaf & ((feature < 0) | (feature >= n_features))):
        return None
    if np.any(~leaf & ((left < 0) | (left >= size) | (right < 0) | (right >= size))):
        return None  # the walk could leave the arrays
    first, row = np.repeat(offset[:-1], np.diff(offset)), np.arange(len(leaf))
    children = np.column_stack([np.where(leaf, row, first + left), np.where(leaf, row, first + right)])
    depth = _depths(children, leaf, offset)
    if depth is None:
        return None
    return CompiledBoosting(
        feature=np.where(leaf, 0, feature).astype(np.uint32),
        threshold=np.where(leaf, np.inf, column("num_threshold", np.float64)),
        missing_go_right=~leaf & ~column("missing_go_to_left", np.bool_),
        children=np.ascontiguousarray(children, dtype=np.uint32),
        value=column("value", np.float64),
        offset=offset,
        depth=depth,
        baseline=float(baseline.ravel()[0]),
        n_features=n_features,
    )


def _depths(children, leaf, offset):
    """Depth of each tree's deepest leaf; None unless every tree is a tree (each node reached once from its root)."""
    depth = np.zeros(len(offset) - 1, dtype=np.int64)
    for tree in range(len(depth)):
        level, seen, d = [offset[tree]], 0, 0
        while level:
            seen += len(level)
            if seen > offset[tree + 1] - offset[tree]:
                return None  # a cycle
            depth[tree] = d
            level = [int(c) for k in level if not leaf[k] for c in children[k]]
            d += 1
    return depth


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
        compiled.feature,
        compiled.threshold,
        compiled.missing_go_right,
        compiled.children,
        compiled.value,
        compiled.offset,
        compiled.depth,
        compiled.baseline,
    )


@numba.njit(cache=True, nogil=True)
def _walk(X, feature, threshold, missing_go_right, children, value, offset, depth, baseline):
    n = X.shape[0]
    raw = np.full(n, baseline)
    # (32-bit unsigned rows and features: fewer bytes loaded per step, and no test of a negative index)
    node = np.empty(n, dtype=np.uint32)
    finite = not _has_nan(X)
    for tree in range(len(depth)):  # tree by tree (its nodes stay in cache), each row's sum in the trees' order
        node[:] = offset[tree]
        if finite:  # (no NaN: one comparison per step; the branch is taken once per tree)
            for _ in range(depth[tree]):  # level by level, the rows in lockstep (a leaf is its own child)
                for row in range(n):
                    k = node[row]
                    node[row] = children[k, np.uint32(X[row, feature[k]] > threshold[k])]
        else:
            for _ in range(depth[tree]):
                for row in range(n):
                    k = node[row]
                    x = X[row, feature[k]]
                    right = (x > threshold[k]) | ((x != x) & missing_go_right[k])
                    node[row] = children[k, np.uint32(right)]
        for row in range(n):
            raw[row] += value[node[row]]
    return 1.0 / (1.0 + np.exp(-raw))


@numba.njit(cache=True, nogil=True)
def _has_nan(X):
    for row in range(X.shape[0]):
        for column in range(X.shape[1]):
            if X[row, column] != X[row, column]:
                return True
    return False
