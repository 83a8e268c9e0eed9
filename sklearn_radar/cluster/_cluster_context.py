"""Cluster context of the causal links: features of the cluster a pair's earlier detection already belongs to (numba).

When the later detection ``j`` of a candidate pair ``(i, j)`` arrives, the
causal agglomeration has already put ``i`` in a cluster.  The features of
:data:`CONTEXT_FEATURES` describe that cluster over its nodes of the last
``cluster_window`` s (``i`` itself among them when the window reaches it; a
node of ``j``'s own time is a cluster of its own; a cluster without a node in
the window has ``cluster_nodes`` 0 and the other features NaN) and ``j``
against it: how well the cluster's rigid
velocity (Eq. 6, fitted to its nodes' compensated Doppler and lines of
sight) predicts ``j``'s Doppler, how far ``j`` lies from where that
velocity moves the cluster, and how long the cluster would grow.

Since the features depend on the merges decided before, the links are
computed time by time: :func:`context_merges` runs a sequence through the
causal agglomeration (:func:`~._causal_agglomeration.step`), asking at each
time for the links of that time's pairs with their context.  The stream
(:class:`~sklearn_radar.online._learned_stream.LearnedStream`) calls
:func:`context_features` on its window with the same numbers, so both give
the same features.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .._compiled import entry_point
from ._causal_agglomeration import new_state, step
from ._link_features import RIDGE
from ._link_training import positive_proba

#: The features of the cluster context: name -> (unit, meaning, measurements needed).
CONTEXT_FEATURES = {
    "cluster_nodes": ("", "nodes of the earlier detection's cluster in the cluster window", ()),
    "cluster_doppler_residual": (
        "m/s",
        "the later detection's Doppler minus what the cluster's rigid velocity (Eq. 6) predicts, absolute",
        ("los",),
    ),
    "cluster_fit_residual": ("m/s", "RMS residual of the cluster's rigid velocity over its nodes", ("los",)),
    "cluster_predicted_distance": (
        "m",
        "distance of the later detection from the cluster's mean position moved by its rigid velocity",
        ("los",),
    ),
    "cluster_extent_with": ("m", "bounding-box diagonal of the cluster with the later detection", ()),
    "cluster_extent": ("m", "bounding-box diagonal of the cluster", ()),
    "cluster_speed": ("m/s", "speed of the cluster's rigid velocity", ("los",)),
    "cluster_span": ("s", "time from the cluster's oldest node in the window to the later detection", ()),
}
N_CONTEXT_FEATURES = len(CONTEXT_FEATURES)
# The sums of one cluster's nodes: count, x, y, t, the normal equations of Eq. 6 (cc, cs, ss, vc, vs, vv), the
# sums of cos, sin and v, then the bounding box and the oldest time.
_N, _X, _Y, _T, _CC, _CS, _SS, _VC, _VS, _VV, _C, _S, _V, _LOW_X, _HIGH_X, _LOW_Y, _HIGH_Y, _FIRST = range(18)


def context_features(x, y, t, v, los, cluster, node, lo, first, window, i, j, now):
    """Features (:data:`CONTEXT_FEATURES`) of each pair's earlier end's cluster and its later end.

    Parameters
    ----------
    x, y : ndarray of float64
        Positions, m.
    t : ndarray of float64
        Times, s, non-decreasing.
    v : ndarray of float64
        Compensated Doppler, m/s.
    los : ndarray of float64
        Line of sight, rad.
    cluster : ndarray of int64
        The current cluster of each node before ``first`` (any number).
    node : ndarray of bool
        The detections that are nodes.
    lo : int
        No detection before ``lo`` is in the window (the search for the recent nodes starts there).
    first : int
        The first detection of the current time; an earlier end at or after it is a cluster of its own.
    window : float
        The cluster window, s: a cluster is described by its nodes ``r`` with ``lo <= r < first`` and
        ``now - t[r] <= window``.
    i, j : ndarray of int64
        The pairs, ``j`` of the current time.
    now : float
        The current time, s.

    Returns
    -------
    features : ndarray of float64, shape (n_pairs, N_CONTEXT_FEATURES)
    """
    args = (
        *(np.ascontiguousarray(a, dtype=np.float64) for a in (x, y, t, v, los)),
        np.ascontiguousarray(cluster, dtype=np.int64),
        np.ascontiguousarray(node, dtype=np.bool_),
        np.int64(lo),
        np.int64(first),
        np.float64(window),
        np.ascontiguousarray(i, dtype=np.int64),
        np.ascontiguousarray(j, dtype=np.int64),
        np.float64(now),
    )
    return entry_point(_context_features, args)(*args)


@numba.njit(cache=True, nogil=True)
def _context_features(x, y, t, v, los, cluster, node, lo, first, window, i, j, now):
    keys = np.empty(len(i), dtype=np.int64)
    for e in range(len(i)):
        keys[e] = _key(cluster, first, i[e])
    unique = np.unique(keys)  # the clusters met, sorted: a cluster's slot is its place here
    sums = np.zeros((len(unique), 18))
    for q in range(len(unique)):
        sums[q, _LOW_X] = sums[q, _LOW_Y] = sums[q, _FIRST] = np.inf
        sums[q, _HIGH_X] = sums[q, _HIGH_Y] = -np.inf
    for r in range(lo, first):
        if node[r] and now - t[r] <= window:
            q = np.searchsorted(unique, cluster[r])
            if q < len(unique) and unique[q] == cluster[r]:
                _add(sums[q], x[r], y[r], t[r], v[r], los[r])
    for q in range(len(unique)):
        if unique[q] < 0:  # a node of the current time: itself
            a = -1 - unique[q]
            _add(sums[q], x[a], y[a], t[a], v[a], los[a])
    velocity = np.full((len(unique), 3), np.nan)  # vx, vy, RMS residual
    for q in range(len(unique)):
        if sums[q, _N] > 0:
            velocity[q] = _rigid_velocity(sums[q])
    out = np.empty((len(i), 8))
    last, cb, sb = -1, 0.0, 0.0
    for e in range(len(i)):
        b = j[e]
        if b != last:  # (the pairs come in blocks of one later end)
            last, cb, sb = b, math.cos(los[b]), math.sin(los[b])
        q = np.searchsorted(unique, keys[e])
        s = sums[q]
        n = s[_N]
        if n == 0:  # no node of the cluster in the window (one shorter than the pair window): nothing to describe
            out[e, 0] = 0.0
            out[e, 1:] = np.nan
            continue
        vx, vy = velocity[q, 0], velocity[q, 1]
        lead = now - s[_T] / n
        dx, dy = x[b] - (s[_X] / n + vx * lead), y[b] - (s[_Y] / n + vy * lead)
        width, height = max(s[_HIGH_X], x[b]) - min(s[_LOW_X], x[b]), max(s[_HIGH_Y], y[b]) - min(s[_LOW_Y], y[b])
        own_width, own_height = s[_HIGH_X] - s[_LOW_X], s[_HIGH_Y] - s[_LOW_Y]
        out[e, 0] = n  # (lengths as sqrt of squares: math.hypot's care for overflow costs more than the rest)
        out[e, 1] = abs(v[b] - (cb * vx + sb * vy))
        out[e, 2] = velocity[q, 2]
        out[e, 3] = math.sqrt(dx * dx + dy * dy)
        out[e, 4] = math.sqrt(width * width + height * height)
        out[e, 5] = math.sqrt(own_width * own_width + own_height * own_height)
        out[e, 6] = math.sqrt(vx * vx + vy * vy)
        out[e, 7] = now - s[_FIRST]
    return out


@numba.njit(cache=True, nogil=True, inline="always")
def _key(cluster, first, a):
    """The cluster of node ``a`` as a key: its number, or ``-1 - a`` for a node of the current time."""
    return cluster[a] if a < first else -1 - a


@numba.njit(cache=True, nogil=True, inline="always")
def _add(s, x, y, t, v, los):
    c, n = math.cos(los), math.sin(los)
    s[_N] += 1.0
    s[_X] += x
    s[_Y] += y
    s[_T] += t
    s[_CC] += c * c
    s[_CS] += c * n
    s[_SS] += n * n
    s[_VC] += v * c
    s[_VS] += v * n
    s[_VV] += v * v
    s[_C] += c
    s[_S] += n
    s[_V] += v
    s[_LOW_X] = min(s[_LOW_X], x)
    s[_HIGH_X] = max(s[_HIGH_X], x)
    s[_LOW_Y] = min(s[_LOW_Y], y)
    s[_HIGH_Y] = max(s[_HIGH_Y], y)
    s[_FIRST] = min(s[_FIRST], t)


@numba.njit(cache=True, nogil=True)
def _rigid_velocity(s):
    """Eq. 6's velocity of a cluster from its sums, ridge ``RIDGE`` towards the radial velocity of its mean (its
    mean Doppler along its mean line of sight), and the RMS residual of its nodes' Doppler."""
    n = s[_N]
    mean_c, mean_s, mean_v = s[_C] / n, s[_S] / n, s[_V] / n
    norm = math.hypot(mean_c, mean_s)
    if norm > 0:
        mean_c, mean_s = mean_c / norm, mean_s / norm
    r1, r2 = s[_VC] + RIDGE * mean_v * mean_c, s[_VS] + RIDGE * mean_v * mean_s
    m11, m22 = s[_CC] + RIDGE, s[_SS] + RIDGE
    det = m11 * m22 - s[_CS] * s[_CS]
    vx, vy = (m22 * r1 - s[_CS] * r2) / det, (m11 * r2 - s[_CS] * r1) / det
    squares = s[_VV] - 2 * (vx * s[_VC] + vy * s[_VS]) + vx * vx * s[_CC] + 2 * vx * vy * s[_CS] + vy * vy * s[_SS]
    out = np.empty(3)
    out[0], out[1], out[2] = vx, vy, math.sqrt(max(squares, 0.0) / n)
    return out


def context_merges(d, node, i, j, links_of, pair_window, threshold, cluster_window, max_extent=None):
    """The causal agglomeration of one sequence with each time's links decided from the clusters so far.

    Parameters
    ----------
    d : Detections
        The detections of one sequence sorted by time.
    node : ndarray of bool, shape (n,)
        The detections above the objectness threshold.
    i, j : ndarray of int64
        The candidate pairs among the nodes, in the order of
        :func:`~._causal_link_features.causal_pairs`.
    links_of : callable
        ``links_of(rows, context)``: P(link) of the pairs ``rows`` (indices into ``i`` and ``j``, those ending
        at the current time) given their context features (``(len(rows), N_CONTEXT_FEATURES)``).
    pair_window : float
        The pair window, s.
    threshold : float
        The link threshold.
    cluster_window : float
        The span of a cluster's recent nodes that its features describe, s.
    max_extent : float or None, default=None
        Longest cluster a merge may make, m (see :func:`~._causal_agglomeration.step`).

    Returns
    -------
    roots, sizes : ndarray of int64, shape (n,)
        As :func:`~._causal_agglomeration.sequence_merges` gives them.
    context : ndarray of float64, shape (n_pairs, N_CONTEXT_FEATURES)
        The context features of every pair.
    links : ndarray of float64, shape (n_pairs,)
        The P(link) of every pair that ``links_of`` gave.
    """
    t = d.t
    n = len(t)
    state = new_state()
    parent = np.arange(n)
    at = np.full(n, -1, dtype=np.int64)
    sizes = np.zeros(n, dtype=np.int64)
    cluster = np.full(n, -1, dtype=np.int64)
    context = np.empty((len(i), N_CONTEXT_FEATURES))
    decided = np.zeros(len(i))
    nodes = np.flatnonzero(node)
    starts = np.flatnonzero(np.r_[True, t[1:] != t[:-1]]) if n else np.zeros(0, dtype=np.int64)
    stops = np.r_[starts[1:], n].astype(np.int64)
    pair_stops = np.searchsorted(j, stops)
    pair_starts = np.r_[0, pair_stops[:-1]].astype(np.int64)
    oldest = 0  # the first node still within the longer of the two windows
    low = 0  # the first detection within the cluster window
    for first, stop, e0, e1 in zip(starts, stops, pair_starts, pair_stops, strict=True):
        lo, hi = np.searchsorted(nodes, [first, stop])
        if lo == hi:
            continue
        new = nodes[lo:hi]
        now = t[first]
        while oldest < lo and not now - t[nodes[oldest]] <= max(cluster_window, pair_window):
            oldest += 1
        rows = np.arange(e0, e1)
        links = np.zeros(0)
        while low < first and not now - t[low] <= cluster_window:
            low += 1
        if len(rows):
            context[rows] = context_features(
                d.x, d.y, t, d.v, d.los, cluster, node, low, first, cluster_window, i[rows], j[rows], now
            )
            links = decided[rows] = links_of(rows, context[rows])
        found, counts, child, survivor = step(
            state, now, new, i[rows], j[rows], links, pair_window, threshold, d.x[new], d.y[new], max_extent
        )
        at[new], sizes[new], cluster[new] = found, counts, found
        if len(child):
            parent[child] = survivor
            older = nodes[oldest:lo]
            for c, s in zip(child.tolist(), survivor.tolist(), strict=True):  # in order: chains of merges
                if c < first:  # (a new node's cluster is already the one it ends this time in)
                    cluster[older[cluster[older] == c]] = s
    roots = np.full(n, -1, dtype=np.int64)
    seen = np.flatnonzero(at >= 0)
    found = at[seen]
    while True:
        up = parent[found]
        if np.array_equal(up, found):
            break
        found = up
    roots[seen] = found
    return roots, sizes, context, decided


def links_by_fold(models, x, fold, columns):
    """``links_of`` for :func:`context_merges`: each pair's P(link) by the classifier of its fold.

    Parameters
    ----------
    models : dict
        Fold -> link classifier (fitted on pair features followed by context features), as
        :func:`~._link_training.fold_classifiers` gives; ``{0: model}`` with ``fold`` all 0 for one classifier.
    x : ndarray of float64, shape (n_pairs, n_pair_features)
        The pair features of every pair.
    fold : ndarray of int, shape (n_pairs,)
        The fold of every pair.
    columns : ndarray of int
        The columns of :data:`CONTEXT_FEATURES` the classifiers see.

    Returns
    -------
    links_of : callable
        ``links_of(rows, context) -> P(link)`` of the pairs ``rows``.
    """

    def links_of(rows, context):
        features = np.hstack([x[rows], context[:, columns]])
        folds = fold[rows]
        links = np.empty(len(rows))
        for k in np.unique(folds):
            mine = folds == k
            links[mine] = positive_proba(models[k], features[mine])
        return links

    return links_of
