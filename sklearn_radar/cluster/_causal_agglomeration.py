"""Causal mean-link agglomeration of LinkClustering: the merges decided time by time, from the past only (numba).

The distinct times of a sequence are processed in order.  At each time the
new nodes (the detections above the objectness threshold) enter as
singletons beside the clusters so far, and the candidate pairs that end at
one of them (:func:`~._causal_link_features.causal_pairs`) add their link
probability to the *evidence* between the two clusters they join: a sum
and a count, accumulated over time (pairs between older clusters were
counted when they arrived).  Then, as in the offline agglomeration
(:mod:`._agglomeration`), the two clusters with the largest mean link merge
while it exceeds the threshold; older clusters may merge with each other
through a new one.  A merged cluster keeps the number of its older side
(the smaller node number: nodes are numbered in time order), so an id once
given is either kept or becomes an alias of an older one.  Ties of the mean
go to the smaller pair of numbers.

A cluster whose last node is more than the pair window older than the
current time can gain no more evidence; and since a merge only averages
means that are at most the threshold, it can never merge again.  It
retires: its evidence is forgotten, so the state holds only the clusters
of the recent past, which bounds the memory of a stream.

With a ``max_extent``, a merge whose cluster would be longer than that is
refused: the diagonal of the x-y bounding box of the two clusters' nodes of
the last pair window (the recent nodes, whose positions the state keeps).
A refused pair keeps its evidence and merges later only if that changes
and the extent then allows it.

The state of one sequence is a tuple of numba typed containers (see
:func:`new_state`); :func:`step` advances it by one time.  The offline
estimator runs :func:`sequence_merges` (every time of a sequence in one
call), the online pipeline :func:`step` once per scan with new nodes: the
same code, so both give the same floating-point means and the same merges.
"""

from __future__ import annotations

import heapq

import numba
import numpy as np
from numba import types
from numba.typed import Dict, List

from .._compiled import entry_point

_EVIDENCE = types.Tuple((types.float64, types.int64))  # (sum of P(link), number of pairs)
_NEIGHBOURS = types.DictType(types.int64, _EVIDENCE)


@numba.njit(cache=True, nogil=True)
def _new_state():
    evidence = Dict.empty(key_type=types.int64, value_type=_NEIGHBOURS)  # cluster -> {cluster: (sum, count)}
    size = Dict.empty(key_type=types.int64, value_type=types.int64)  # live cluster -> its nodes so far
    last = Dict.empty(key_type=types.int64, value_type=types.float64)  # live cluster -> time of its last node, s
    position = Dict.empty(key_type=types.int64, value_type=types.int64)  # recent node -> its place in the lists
    nodes = List.empty_list(types.int64)  # the recent nodes in time order (from head on) ...
    clusters = List.empty_list(types.int64)  # ... their clusters now ...
    times = List.empty_list(types.float64)  # ... and their times, s
    head = np.zeros(1, dtype=np.int64)
    xs = List.empty_list(types.float64)  # ... and their positions, m
    ys = List.empty_list(types.float64)
    return evidence, size, last, position, nodes, clusters, times, head, xs, ys


def new_state():
    """The empty state of one sequence.

    Returns
    -------
    state : tuple
        Numba typed containers: per cluster, the evidence (sum and count of link probabilities) to each
        neighbouring cluster, its size and the time of its last node; per recent node, its cluster, time and
        position.
    """
    return _new_state()


def step(state, now, new_nodes, i, j, links, window, threshold, x=None, y=None, max_extent=None):
    """Advance the state of one sequence by one time: new nodes, their pairs, and the merges they cause.

    Parameters
    ----------
    state : tuple
        Of :func:`new_state`, updated in place.
    now : float
        The time, s, later than every earlier call's.
    new_nodes : ndarray of int64
        The nodes of this time, ascending numbers larger than every earlier node's.
    i, j : ndarray of int64
        The candidate pairs ending at this time (``i < j``, ``j`` a new node, ``i`` a node of the last
        ``window`` s), in the order of ``j``, then ``i``.
    links : ndarray of float64
        P(link) of each pair.
    window : float
        The pair window, s: clusters whose last node is older retire.
    threshold : float
        Clusters merge while their mean link exceeds it.
    x, y : ndarray of float64 or None, default=None
        Position of each new node, m; needed with ``max_extent``.
    max_extent : float or None, default=None
        Longest cluster a merge may make, m: the diagonal of the bounding box of its nodes of the last
        ``window`` s.  None: no limit.

    Returns
    -------
    clusters : ndarray of int64
        The cluster (its oldest node's number) of each new node after the merges.
    sizes : ndarray of int64
        The nodes of that cluster so far.
    child, survivor : ndarray of int64
        The merges, in order: cluster ``child`` joined ``survivor`` (the older).
    """
    new_nodes = np.ascontiguousarray(new_nodes, dtype=np.int64)
    args = (
        state,
        np.float64(now),
        new_nodes,
        np.ascontiguousarray(i, dtype=np.int64),
        np.ascontiguousarray(j, dtype=np.int64),
        np.ascontiguousarray(links, dtype=np.float64),
        np.float64(window),
        np.float64(threshold),
        *_positions(x, y, len(new_nodes), max_extent),
    )
    return entry_point(_step, args)(*args)


def _positions(x, y, n, max_extent):
    """``(x, y, limit)`` for the compiled step: contiguous float64 positions (zeros when not given) and the extent
    limit (infinite for None)."""
    if max_extent is not None and (x is None or y is None):
        raise ValueError("max_extent needs the positions x and y of the nodes")
    x = np.zeros(n) if x is None else np.ascontiguousarray(x, dtype=np.float64)
    y = np.zeros(n) if y is None else np.ascontiguousarray(y, dtype=np.float64)
    if not len(x) == len(y) == n:
        raise ValueError(f"x and y must give one position per node ({n}), got {len(x)} and {len(y)}")
    return x, y, np.float64(np.inf if max_extent is None else max_extent)


@numba.njit(cache=True, nogil=True)
def _step(state, now, new_nodes, i, j, links, window, threshold, x, y, max_extent):
    evidence, size, last, position, nodes, clusters, times, head, xs, ys = state
    # Retire the clusters that no new pair can reach, and forget the nodes that no new pair can end at.
    retired = [c for c in last.keys() if not now - last[c] <= window]
    for c in retired:
        for other in evidence[c].keys():
            del evidence[other][c]
        del evidence[c]
        del size[c]
        del last[c]
    start = head[0]
    while start < len(nodes) and not now - times[start] <= window:
        del position[nodes[start]]
        start += 1
    if start > 64 and 2 * start > len(nodes):  # compact the lists
        for k in range(start, len(nodes)):
            nodes[k - start] = nodes[k]
            clusters[k - start] = clusters[k]
            times[k - start] = times[k]
            xs[k - start] = xs[k]
            ys[k - start] = ys[k]
            position[nodes[k - start]] = k - start
        keep = len(nodes) - start
        while len(nodes) > keep:
            nodes.pop()
            clusters.pop()
            times.pop()
            xs.pop()
            ys.pop()
        start = 0
    head[0] = start
    for q in range(len(new_nodes)):
        node = new_nodes[q]
        evidence[node] = Dict.empty(key_type=types.int64, value_type=_EVIDENCE)
        size[node] = 1
        last[node] = now
        position[node] = len(nodes)
        nodes.append(node)
        clusters.append(node)
        times.append(now)
        xs.append(x[q])
        ys.append(y[q])
    # The evidence of the new pairs: each new node b is still a cluster of its own, and its pairs (a block of j)
    # sum up per cluster a of their earlier end, in the pairs' order; no pair of clusters (a, b) had evidence before.
    heap = [(0.0, np.int64(0), np.int64(0))]
    heap.pop()
    distinct = np.empty(len(i), dtype=np.int64)
    sums = np.empty(len(i), dtype=np.float64)
    counts = np.empty(len(i), dtype=np.int64)
    e = 0
    while e < len(i):
        b = j[e]
        found = 0
        while e < len(i) and j[e] == b:
            a = clusters[position[i[e]]]
            slot = -1
            for q in range(found):
                if distinct[q] == a:
                    slot = q
                    break
            if slot < 0:
                distinct[found], sums[found], counts[found] = a, links[e], 1
                found += 1
            else:
                sums[slot] += links[e]
                counts[slot] += 1
            e += 1
        to_b = evidence[b]
        for q in range(found):
            a = distinct[q]
            to_b[a] = evidence[a][b] = (sums[q], counts[q])
            mean = sums[q] / counts[q]
            if mean > threshold:
                heap.append((-mean, min(a, b), max(a, b)))
    heapq.heapify(heap)
    child = List.empty_list(types.int64)
    survivor = List.empty_list(types.int64)
    while len(heap):
        negative, a, b = heapq.heappop(heap)
        if a not in size or b not in size:
            continue
        of_a = evidence[a]
        if b not in of_a:
            continue
        s, k = of_a[b]
        if s / k != -negative:
            continue  # stale: the link changed since
        if max_extent < np.inf and _extent(clusters, xs, ys, start, a, b) > max_extent:
            continue  # too long a cluster: refused (the evidence stays)
        # b (the younger) joins a.
        child.append(b)
        survivor.append(a)
        of_b = evidence[b]
        del of_a[b]
        del of_b[a]
        for c, (s, k) in of_b.items():
            of_c = evidence[c]
            del of_c[b]
            if c in of_a:
                s_a, k_a = of_a[c]
                s, k = s_a + s, k_a + k
            of_a[c] = of_c[a] = (s, k)
            mean = s / k
            if mean > threshold:
                heapq.heappush(heap, (-mean, min(a, c), max(a, c)))
        del evidence[b]
        if size[b] == 1:  # a cluster of one node is that node (numbered as it), which is still recent
            clusters[position[b]] = a
        else:
            for k in range(start, len(clusters)):
                if clusters[k] == b:
                    clusters[k] = a
        size[a] += size[b]
        last[a] = max(last[a], last[b])
        del size[b]
        del last[b]
    out = np.empty(len(new_nodes), dtype=np.int64)
    sizes = np.empty(len(new_nodes), dtype=np.int64)
    for k in range(len(new_nodes)):
        out[k] = clusters[position[new_nodes[k]]]
        sizes[k] = size[out[k]]
    n_merges = len(child)
    child_out = np.empty(n_merges, dtype=np.int64)
    survivor_out = np.empty(n_merges, dtype=np.int64)
    for k in range(n_merges):
        child_out[k] = child[k]
        survivor_out[k] = survivor[k]
    return out, sizes, child_out, survivor_out


@numba.njit(cache=True, nogil=True)
def _extent(clusters, xs, ys, start, a, b):
    """Diagonal of the x-y bounding box of the recent nodes (from ``start`` on) of clusters ``a`` and ``b``, m."""
    low_x, high_x, low_y, high_y = np.inf, -np.inf, np.inf, -np.inf
    for k in range(start, len(clusters)):
        if clusters[k] == a or clusters[k] == b:
            low_x, high_x = min(low_x, xs[k]), max(high_x, xs[k])
            low_y, high_y = min(low_y, ys[k]), max(high_y, ys[k])
    return np.sqrt((high_x - low_x) ** 2 + (high_y - low_y) ** 2)


def sequence_merges(t, node, i, j, links, window, threshold, x=None, y=None, max_extent=None):
    """The causal agglomeration of one sequence: every time in order, as :func:`step` once per time.

    Parameters
    ----------
    t : ndarray of float64, shape (n,)
        Time of each detection, s, non-decreasing.
    node : ndarray of bool, shape (n,)
        The detections above the objectness threshold.
    i, j : ndarray of int64
        The candidate pairs of :func:`~._causal_link_features.causal_pairs` among the nodes (order of ``j``,
        then ``i``).
    links : ndarray of float64
        Their P(link).
    window : float
        The pair window, s.
    threshold : float
        The link threshold.
    x, y : ndarray of float64 of shape (n,) or None, default=None
        Position of each detection, m; needed with ``max_extent``.
    max_extent : float or None, default=None
        Longest cluster a merge may make, m (see :func:`step`).  None: no limit.

    Returns
    -------
    roots : ndarray of int64, shape (n,)
        The final cluster (its oldest node's number) of each node, -1 for the other detections.
    sizes : ndarray of int64, shape (n,)
        The nodes of each node's cluster at its time (after that time's merges), 0 for the others.
    """
    t = np.ascontiguousarray(t, dtype=np.float64)
    return _sequence_merges(
        t,
        np.ascontiguousarray(node, dtype=np.bool_),
        np.asarray(i, dtype=np.int64),
        np.asarray(j, dtype=np.int64),
        np.asarray(links, dtype=np.float64),
        np.float64(window),
        np.float64(threshold),
        *_positions(x, y, len(t), max_extent),
    )


@numba.njit(cache=True, nogil=True)
def _sequence_merges(t, node, i, j, links, window, threshold, x, y, max_extent):
    n = len(t)
    state = _new_state()
    parent = np.arange(n)
    at = np.full(n, -1, dtype=np.int64)
    sizes = np.zeros(n, dtype=np.int64)
    first = 0
    e = 0
    while first < n:
        stop = first
        while stop < n and t[stop] == t[first]:
            stop += 1
        new = np.flatnonzero(node[first:stop]) + first
        if len(new):
            end = e
            while end < len(j) and j[end] < stop:
                end += 1
            clusters, counts, child, survivor = _step(
                state, t[first], new, i[e:end], j[e:end], links[e:end], window, threshold, x[new], y[new], max_extent
            )
            e = end
            for k in range(len(new)):
                at[new[k]] = clusters[k]
                sizes[new[k]] = counts[k]
            for k in range(len(child)):
                parent[child[k]] = survivor[k]
        first = stop
    roots = np.full(n, -1, dtype=np.int64)
    for k in range(n):
        if at[k] >= 0:
            root = at[k]
            while parent[root] != root:
                root = parent[root]
            roots[k] = root
    return roots, sizes


def confirmed_roots(roots, sizes, min_size):
    """``roots`` where a node's cluster had at least ``min_size`` nodes at its time, -1 elsewhere.

    Parameters
    ----------
    roots, sizes : ndarray of int64, shape (n,)
        Of :func:`sequence_merges`.
    min_size : int
        The confirmation count.

    Returns
    -------
    roots : ndarray of int64, shape (n,)
    """
    return np.where((roots >= 0) & (sizes >= min_size), roots, -1)
