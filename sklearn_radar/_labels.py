"""Label bookkeeping shared by every estimator and the schema: one implementation each.

* :func:`rank_by_first_appearance` numbers distinct keys 0, 1, ... in the
  order of their first row (the numbering of ``labels_`` and of
  :func:`~sklearn_radar.instance_target`);
* :func:`consecutive_labels` applies it to cluster roots, keeping -1 (noise);
* :func:`roots_to_rows` turns per-subset roots (positions within a subset of
  rows) into global row numbers, the step that joins per-sequence results;
* :func:`drop_small_clusters` makes the rows of small clusters noise, by
  their whole size or by their size so far (a track confirmation rule).
"""

from __future__ import annotations

import numba
import numpy as np


def rank_by_first_appearance(keys) -> np.ndarray:
    """For each element of ``keys``, the rank of its value by first appearance.

    Parameters
    ----------
    keys : array-like of shape (n,)
        Any sortable values (ints, strings).

    Returns
    -------
    rank : ndarray of int64, shape (n,)
        0 for every element equal to ``keys[0]``, 1 for the next distinct
        value met, and so on.
    """
    keys = np.asarray(keys)
    if keys.size == 0:
        return np.zeros(0, dtype=np.int64)
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    rank = np.empty(len(first), dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(len(first))
    return rank[inverse.ravel()]


def consecutive_labels(roots) -> np.ndarray:
    """Cluster ids 0, 1, ... in order of each cluster's first row; negative roots become -1.

    Parameters
    ----------
    roots : array-like of int, shape (n,)
        Any cluster key per row (a root row, a stage-1 id), -1 for noise.

    Returns
    -------
    labels : ndarray of int64, shape (n,)
    """
    roots = np.asarray(roots)
    if roots.dtype.kind in "iu" and len(roots) and roots.max() < 4 * len(roots) + 1024:
        return _number_by_first_row(roots.astype(np.int64, copy=False))  # row-number roots: linear time
    labels = np.full(len(roots), -1, dtype=np.int64)
    clustered = roots >= 0
    labels[clustered] = rank_by_first_appearance(roots[clustered])
    return labels


@numba.njit(cache=True, nogil=True)
def _number_by_first_row(roots):
    """:func:`consecutive_labels` of small non-negative integer keys (-1 or any negative: noise), in one pass."""
    number = np.full(max(roots.max(), 0) + 1, -1, dtype=np.int64)
    labels = np.full(len(roots), -1, dtype=np.int64)
    next_label = 0
    for i in range(len(roots)):
        key = roots[i]
        if key < 0:
            continue
        if number[key] < 0:
            number[key] = next_label
            next_label += 1
        labels[i] = number[key]
    return labels


def roots_to_rows(rows, local_roots, out) -> None:
    """Write ``rows[local_roots]`` into ``out[rows]`` where a local root exists (>= 0).

    Parameters
    ----------
    rows : ndarray of int, shape (m,)
        Global row numbers of one subset (e.g. one sequence).
    local_roots : ndarray of int, shape (m,)
        Root of each row of the subset as a position within ``rows``, -1 for none.
    out : ndarray of int64
        Global roots, updated in place; rows without a root are left as they are.
    """
    found = local_roots >= 0
    out[rows[found]] = rows[local_roots[found]]


def drop_small_clusters(roots, min_size, t=None) -> np.ndarray:
    """``roots`` with every row of a cluster of fewer than ``min_size`` rows made -1 (noise).

    Parameters
    ----------
    roots : ndarray of int, shape (n,)
        Any cluster key per row, negative for noise.
    min_size : int
        The smallest cluster kept, in rows; 1 keeps every cluster.
    t : ndarray of float, shape (n,), default=None
        Time of each row, s.  None: a cluster's size is its whole number of rows.  Given: a row counts the rows
        of its cluster up to its own time (rows of the same time count whole), so a cluster's first rows are
        noise until it has ``min_size`` (a track confirmation rule, causal).

    Returns
    -------
    roots : ndarray of int64, shape (n,)
        A copy.
    """
    roots = np.array(roots, dtype=np.int64)
    clustered = np.flatnonzero(roots >= 0)
    if min_size <= 1 or len(clustered) == 0:
        return roots
    if t is None:
        _, inverse, counts = np.unique(roots[clustered], return_inverse=True, return_counts=True)
        roots[clustered[counts[inverse.ravel()] < min_size]] = -1
        return roots
    t = np.asarray(t, dtype=np.float64)
    order = clustered[np.lexsort((t[clustered], roots[clustered]))]  # by cluster, then time
    keys, times = roots[order], t[order]
    new_cluster = np.r_[True, keys[1:] != keys[:-1]]
    new_time = new_cluster | np.r_[False, times[1:] != times[:-1]]
    position = np.arange(len(order))
    cluster_start = np.maximum.accumulate(np.where(new_cluster, position, 0))
    last_of_time = np.r_[np.flatnonzero(new_time)[1:] - 1, len(order) - 1][np.cumsum(new_time) - 1]
    roots[order[last_of_time - cluster_start + 1 < min_size]] = -1
    return roots
