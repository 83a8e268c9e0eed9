"""Training of LinkClustering: its classifiers, their out-of-fold probabilities, and the threshold search."""

from __future__ import annotations

import weakref

import numpy as np

from .._labels import drop_small_clusters, roots_to_rows
from ._agglomeration import mean_link_merges, roots_at
from ._causal_agglomeration import confirmed_roots, sequence_merges
from ._tree_walk import boosting_proba, compile_boosting

#: Rows from which the classifiers stop early (as scikit-learn's ``early_stopping="auto"``), and the fewest rows of
#: the smaller class that allow it (its stratified hold-out of 10 % needs some of each class).
EARLY_STOPPING_ROWS = 10_000
EARLY_STOPPING_CLASS_ROWS = 50
#: Batches of at most this many rows go through the compiled tree walk (equal to ``predict_proba`` to the bit, without
#: its fixed cost of about a millisecond per call); larger ones through ``predict_proba`` (its OpenMP threads).
WALK_ROWS = 4096

#: The compiled trees of each classifier met, as ``(its list of predictors, compiled or None)``: a refit classifier
#: has a new list, so an entry is valid only while the list is the same object.
_COMPILED = weakref.WeakKeyDictionary()


def binary_classifier(max_iter, seed, early_stopping, max_leaf_nodes=31, max_depth=None):
    """The classifier of objectness and links: histogram gradient boosting.

    Parameters
    ----------
    max_iter : int
        The most boosting iterations.
    seed : int
        Its random state.
    early_stopping : bool
        Stop when the loss on a 10 % hold-out has not improved for 10 iterations.
    max_leaf_nodes : int, default=31
        The most leaves of each tree.
    max_depth : int or None, default=None
        The most splits from a tree's root to a leaf (None: as many as the leaves allow).

    Returns
    -------
    classifier : HistGradientBoostingClassifier
    """
    from sklearn.ensemble import (
        HistGradientBoostingClassifier,
    )  # on first use: importing the cluster package stays light

    return HistGradientBoostingClassifier(
        max_iter=max_iter,
        learning_rate=0.1,
        max_leaf_nodes=max_leaf_nodes,
        max_depth=max_depth,
        early_stopping=early_stopping,
        random_state=seed,
    )


def _fit(X, y, max_iter, seed, tree):
    """A fitted classifier of the boolean ``y``; the constant P(True) when ``y`` holds one class or none."""
    n_true = int(np.count_nonzero(y))
    if n_true in (0, len(y)):
        return float(y[0]) if len(y) else 0.0
    early = len(y) > EARLY_STOPPING_ROWS and min(n_true, len(y) - n_true) >= EARLY_STOPPING_CLASS_ROWS
    return binary_classifier(max_iter, seed, early, **tree).fit(X, y)


def positive_proba(model, X):
    """P(True) of each row of ``X`` by a model of :func:`_fit`.

    Batches of at most :data:`WALK_ROWS` rows go through the compiled tree
    walk of :mod:`._tree_walk` (the same probabilities as ``predict_proba``),
    larger ones through ``predict_proba``.

    Parameters
    ----------
    model : HistGradientBoostingClassifier or float
        A classifier of a boolean target, or a constant probability.
    X : ndarray of shape (n, n_features)

    Returns
    -------
    proba : ndarray of float64, shape (n,)
    """
    if isinstance(model, float):
        return np.full(len(X), model)
    if len(X) == 0:
        return np.zeros(0)
    if len(X) <= WALK_ROWS:
        compiled = _compiled(model)
        if compiled is not None:
            return boosting_proba(compiled, X)
    return model.predict_proba(X)[:, 1]


def _compiled(model):
    """The compiled trees of ``model`` (None when the walk does not cover it), compiled on first use."""
    predictors = getattr(model, "_predictors", None)
    try:
        entry = _COMPILED.get(model)
    except TypeError:  # not weakly referable
        return compile_boosting(model)
    if entry is None or entry[0] is not predictors:
        entry = (predictors, compile_boosting(model))
        _COMPILED[model] = entry
    return entry[1]


def fold_of_groups(groups, cv):
    """``GroupKFold`` fold of each detection, per sequence, with at most ``cv`` folds.

    Parameters
    ----------
    groups : list of ndarray of int
        The group of each detection of each sequence (at least two distinct groups in all).
    cv : int
        The most folds.

    Returns
    -------
    folds : list of ndarray of int64
        Shaped as ``groups``.
    """
    from sklearn.model_selection import GroupKFold  # on first use, as the classifier

    every = np.concatenate(groups)
    n_splits = min(cv, len(np.unique(every)))
    fold = np.empty(len(every), dtype=np.int64)
    for k, (_, test) in enumerate(GroupKFold(n_splits=n_splits).split(every, groups=every)):
        fold[test] = k
    return np.split(fold, np.cumsum([len(g) for g in groups])[:-1])


def cross_fit(features, targets, folds, max_iter, seed, max_rows, rng, *, out_of_fold, tree=None):
    """A classifier fitted on every sequence's rows, and its out-of-fold probabilities of them.

    Parameters
    ----------
    features : list of ndarray of shape (n_k, n_features)
        The rows of each sequence.
    targets : list of ndarray of bool
        Their targets.
    folds : list of ndarray of int
        Their folds.
    max_iter : int
        Boosting iterations.
    seed : int
        Seed of every classifier.
    max_rows : int or None
        Rows per fit; more are subsampled at random (``rng``).
    rng : RandomState
        For the subsampling.
    out_of_fold : bool
        True: the probabilities of each fold come from a classifier fitted on the other folds.  False: from the
        final classifier (in-sample).
    tree : dict, default=None
        The trees' size, as keyword arguments of :func:`binary_classifier` (``max_leaf_nodes``, ``max_depth``);
        None: its defaults.

    Returns
    -------
    model : HistGradientBoostingClassifier or float
        Fitted on every row (or a subsample of ``max_rows``).
    proba : list of ndarray of float64
        P(True) of each sequence's rows.
    """
    X = np.concatenate(features) if features else np.zeros((0, 0))
    y = np.concatenate(targets) if targets else np.zeros(0, dtype=bool)
    fold = np.concatenate(folds) if folds else np.zeros(0, dtype=np.int64)

    proba = np.empty(len(y))
    if out_of_fold:
        for k, model in _per_fold(X, y, fold, max_iter, seed, max_rows, rng, tree).items():
            held = fold == k
            proba[held] = positive_proba(model, X[held])
    model = _subsampled_fit(X, y, np.arange(len(y)), max_iter, seed, max_rows, rng, tree)
    if not out_of_fold:
        proba = positive_proba(model, X)
    return model, np.split(proba, np.cumsum([len(t) for t in targets])[:-1]) if targets else []


def fold_classifiers(features, targets, folds, max_iter, seed, max_rows, rng, tree=None):
    """The classifier of each fold, fitted on the other folds' rows (those :func:`cross_fit` gives out-of-fold
    probabilities with).

    Parameters
    ----------
    features, targets, folds, max_iter, seed, max_rows, rng, tree
        As for :func:`cross_fit`.

    Returns
    -------
    models : dict
        Fold -> its classifier (HistGradientBoostingClassifier or a constant probability).
    """
    X = np.concatenate(features) if features else np.zeros((0, 0))
    y = np.concatenate(targets) if targets else np.zeros(0, dtype=bool)
    fold = np.concatenate(folds) if folds else np.zeros(0, dtype=np.int64)
    return _per_fold(X, y, fold, max_iter, seed, max_rows, rng, tree)


def _per_fold(X, y, fold, max_iter, seed, max_rows, rng, tree):
    return {
        k: _subsampled_fit(X, y, np.flatnonzero(fold != k), max_iter, seed, max_rows, rng, tree)
        for k in np.unique(fold).tolist()
    }


def _subsampled_fit(X, y, rows, max_iter, seed, max_rows, rng, tree):
    """A classifier of ``y`` on ``rows`` of ``X``, at most ``max_rows`` of them (drawn with ``rng``)."""
    if max_rows is not None and len(rows) > max_rows:
        rows = rows[np.sort(rng.choice(len(rows), max_rows, replace=False))]
    return _fit(X[rows], y[rows], max_iter, seed, tree or {})


def _panoptic_quality_of(c, y, window):
    """The tuning's objective: labels -> their panoptic quality against ``y`` in frames of ``window`` s."""
    from ..metrics import panoptic_quality  # metrics imports the cluster package: a late import

    groups = np.zeros(len(y)) if c["sequence"] is None else c["sequence"]
    return lambda labels: panoptic_quality(y, labels, times=c["t"], groups=groups, window=window).pq


def tune(sequences, objectness, pairs, links, grids, c, y, window, merges_of=mean_link_merges):
    """The (link, objectness, min size) setting of ``grids`` with the best panoptic quality, and that quality.

    Parameters
    ----------
    sequences, objectness, pairs, links, grids, c, y, window, merges_of
        As for :func:`tune_surface`.

    Returns
    -------
    setting : tuple
        ``(link_threshold, objectness_threshold, min_cluster_size)``; the first of the grids' order among equals.
    score : float
        Its panoptic quality.
    """
    return best_of(tune_surface(sequences, objectness, pairs, links, grids, c, y, window, merges_of), grids)


def best_of(surface, grids):
    """The setting of ``grids`` at the maximum of ``surface`` (the first in the grids' order among equals).

    Parameters
    ----------
    surface : ndarray of shape (n_objectness, n_link, n_size)
        A score per setting, as :func:`tune_surface` gives.
    grids : tuple of three sequences
        The link thresholds, objectness thresholds and minimum sizes.

    Returns
    -------
    setting : tuple
        ``(link_threshold, objectness_threshold, min_cluster_size)``.
    score : float
    """
    link_grid, objectness_grid, size_grid = grids
    gate, threshold, size = np.unravel_index(int(np.argmax(np.nan_to_num(surface, nan=-np.inf))), surface.shape)
    return (link_grid[threshold], objectness_grid[gate], size_grid[size]), float(surface[gate, threshold, size])


def tune_surface(sequences, objectness, pairs, links, grids, c, y, window, merges_of=mean_link_merges):
    """The panoptic quality of every (objectness, link, min size) setting of ``grids``.

    Parameters
    ----------
    sequences : list of _Sequence
        The sequences (training ones when tuning).
    objectness : list of ndarray of float64
        P(road user) of each sequence's detections (out of fold when tuning).
    pairs : list of (ndarray, ndarray)
        Each sequence's candidate pairs.
    links : list of ndarray of float64
        Their P(link) (out of fold when tuning).
    grids : tuple of three sequences
        The link thresholds, objectness thresholds and minimum sizes to try.
    c : dict of ndarray
        The columns read (``t`` in s, ``sequence``).
    y : ndarray of int64
        Ground-truth instance of every row.
    window : float
        Frame of the panoptic quality, s.
    merges_of : callable, default=mean_link_merges
        The agglomeration, in the form of :func:`~._agglomeration.mean_link_merges` (a benchmark swaps it).

    Returns
    -------
    surface : ndarray of float64, shape (n_objectness, n_link, n_size)
        PQ of each setting, indexed in the order of the objectness, link and size grids.
    """
    n_rows, pq = len(y), _panoptic_quality_of(c, y, window)
    link_grid, objectness_grid, size_grid = grids
    surface = np.empty((len(objectness_grid), len(link_grid), len(size_grid)))
    for g, gate in enumerate(objectness_grid):
        merges = []
        for s, p, (i, j), link in zip(sequences, objectness, pairs, links, strict=True):
            node = p > gate
            both = node[i] & node[j]
            merges.append((node, merges_of(len(s.rows), i[both], j[both], link[both], min(link_grid))))
        for t, threshold in enumerate(link_grid):
            roots = np.full(n_rows, -1, dtype=np.int64)
            for s, (node, merged) in zip(sequences, merges, strict=True):
                local = np.where(node, roots_at(len(s.rows), *merged, threshold), -1)
                roots_to_rows(s.rows, local, roots)
            for k, size in enumerate(size_grid):
                surface[g, t, k] = pq(drop_small_clusters(roots, size))
    return surface


def tune_causal(sequences, objectness, pairs, links, grids, c, y, window, pair_window, max_extent=None):
    """As :func:`tune`, with the causal agglomeration: the best setting of :func:`tune_causal_surface` and its PQ."""
    surface = tune_causal_surface(sequences, objectness, pairs, links, grids, c, y, window, pair_window, max_extent)
    return best_of(surface, grids)


def tune_causal_surface(sequences, objectness, pairs, links, grids, c, y, window, pair_window, max_extent=None):
    """As :func:`tune_surface`, with the causal agglomeration (and ``min_cluster_size`` as its confirmation count).

    Parameters
    ----------
    sequences, objectness, pairs, links, grids, c, y, window
        As for :func:`tune_surface`; the pairs in the order of
        :func:`~._causal_link_features.causal_pairs`.
    pair_window : float
        The pair window, s (when clusters retire).
    max_extent : float or None, default=None
        Longest cluster a merge may make, m (LinkClustering's ``max_extent``).

    Returns
    -------
    surface : ndarray of float64, shape (n_objectness, n_link, n_size)
    """
    n_rows, pq = len(y), _panoptic_quality_of(c, y, window)
    link_grid, objectness_grid, size_grid = grids
    surface = np.empty((len(objectness_grid), len(link_grid), len(size_grid)))
    for g, gate in enumerate(objectness_grid):
        for t, threshold in enumerate(link_grid):
            merged = []
            for s, p, (i, j), link in zip(sequences, objectness, pairs, links, strict=True):
                node = p > gate
                both = node[i] & node[j]
                d = s.detections
                merges = sequence_merges(
                    d.t, node, i[both], j[both], link[both], pair_window, threshold, d.x, d.y, max_extent
                )
                merged.append((s.rows, *merges))
            surface[g, t] = _confirmed_scores(merged, size_grid, n_rows, pq)
    return surface


def _confirmed_scores(merged, sizes, n_rows, pq):
    """The score ``pq`` of the causal merges ``merged`` (``(rows, roots, sizes)`` per sequence) at each confirmation
    count of ``sizes``: labels of all ``n_rows`` rows, -1 where a detection's cluster was not yet confirmed."""
    scores = np.empty(len(sizes))
    for k, size in enumerate(sizes):
        roots = np.full(n_rows, -1, dtype=np.int64)
        for rows, local, counts in merged:
            roots_to_rows(rows, confirmed_roots(local, counts, size), roots)
        scores[k] = pq(roots)
    return scores


def tune_context(merged_at, thresholds, sizes, c, y, window):
    """The (link threshold, confirmation count) with the best panoptic quality for links decided in context.

    Parameters
    ----------
    merged_at : callable
        ``merged_at(threshold)``: for each sequence, ``(rows, roots, sizes)``: its rows of the data and the
        :func:`~._cluster_context.context_merges` at that link threshold.
    thresholds : sequence of float
        The link thresholds to try.
    sizes : sequence of int
        The confirmation counts to try.
    c : dict of ndarray
        The columns read (``t`` in s, ``sequence``).
    y : ndarray of int64
        Ground-truth instance of every row.
    window : float
        Frame of the panoptic quality, s.

    Returns
    -------
    setting : tuple
        ``(link_threshold, min_cluster_size)``; the first in the grids' order among equals.
    score : float
    """
    pq = _panoptic_quality_of(c, y, window)
    surface = np.array([_confirmed_scores(merged_at(threshold), sizes, len(y), pq) for threshold in thresholds])
    g, k = np.unravel_index(int(np.argmax(np.nan_to_num(surface, nan=-np.inf))), surface.shape)
    return (thresholds[g], sizes[k]), float(surface[g, k])
