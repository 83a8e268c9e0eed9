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

The state of one sequence is a tuple of arrays (see :func:`new_state`);
:func:`step` advances it by one time.  Each live cluster holds a *slot*: the
evidence between clusters is a matrix over slots (sum and count; a count of
0 is no evidence), so that a merge adds one row to another instead of
updating a hash map per neighbour.  The matrices double when the live
clusters outgrow them and never shrink: 16 bytes times the square of the
most clusters live at once (those of one pair window).  The offline
estimator runs :func:`sequence_merges` (every time of a sequence in one
call), the online pipeline :func:`step` once per scan with new nodes: the
same code, so both give the same floating-point means and the same merges.
"""

from __future__ import annotations

import heapq

import numba
import numpy as np
from numba import types
from numba.typed import List

from .._compiled import entry_point

#: The state's arrays, by name: per slot (a live cluster's place in the evidence matrices), per recent node (in time
#: order from the head on), and the stack of free slots; then its counters.
_CLUSTER, _SIZE, _FREE, _NUMBER, _SLOT = range(5)  # int arrays
_LAST, _TIME, _X, _Y = range(4)  # float arrays
_N_FREE, _HEAD, _TAIL = range(3)  # counters


@numba.njit(cache=True, nogil=True)
def _new_state():
    ints = List.empty_list(types.int64[::1])
    ints.append(np.full(16, -1, dtype=np.int64))  # slot -> its cluster (its oldest node's number), -1 when free
    ints.append(np.zeros(16, dtype=np.int64))  # slot -> the cluster's nodes so far
    ints.append(np.arange(15, -1, -1).astype(np.int64))  # the free slots, the next one last
    ints.append(np.zeros(64, dtype=np.int64))  # recent node -> its number
    ints.append(np.zeros(64, dtype=np.int64))  # recent node -> its cluster's slot
    floats = List.empty_list(types.float64[::1])
    floats.append(np.zeros(16))  # slot -> time of the cluster's last node, s
    floats.append(np.zeros(64))  # recent node -> its time, s
    floats.append(np.zeros(64))  # ... and its position, m
    floats.append(np.zeros(64))
    sums = List.empty_list(types.float64[:, ::1])
    sums.append(np.zeros((16, 16)))  # slot x slot -> sum of P(link) between the two clusters
    counts = List.empty_list(types.int64[:, ::1])
    counts.append(np.zeros((16, 16), dtype=np.int64))  # ... and the number of pairs (0: no evidence)
    counters = np.array([16, 0, 0], dtype=np.int64)  # free slots, head and tail of the recent nodes
    return ints, floats, sums, counts, counters


def new_state():
    """The empty state of one sequence.

    Returns
    -------
    state : tuple
        Arrays in numba typed lists: per live cluster, its evidence (sum and count of link probabilities) to
        each other live cluster, its size and the time of its last node; per recent node, its number, cluster,
        time and position.
    """
    return _new_state()


def live_clusters(state):
    """The live clusters of a state and the evidence between them (for inspection and tests).

    Parameters
    ----------
    state : tuple
        Of :func:`new_state`.

    Returns
    -------
    sizes : dict
        Live cluster -> its nodes so far.
    evidence : dict
        ``(a, b)`` with ``a < b`` -> (sum of P(link), number of pairs) between clusters ``a`` and ``b``.
    """
    ints, _, sums, counts, _ = state
    cluster, size = ints[_CLUSTER], ints[_SIZE]
    live = np.flatnonzero(cluster >= 0)
    sizes = {int(cluster[s]): int(size[s]) for s in live}
    evidence = {}
    for s in live:
        for o in live:
            if counts[0][s, o] > 0 and cluster[s] < cluster[o]:
                evidence[int(cluster[s]), int(cluster[o])] = (float(sums[0][s, o]), int(counts[0][s, o]))
    return sizes, evidence


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
    ints, floats, sums, counts, counters = state
    _retire(state, now, window)
    _make_room(state, len(new_nodes))
    cluster, size, free, number, slot = ints[_CLUSTER], ints[_SIZE], ints[_FREE], ints[_NUMBER], ints[_SLOT]
    last, times, xs, ys = floats[_LAST], floats[_TIME], floats[_X], floats[_Y]
    total, count = sums[0], counts[0]
    head, first_new = counters[_HEAD], counters[_TAIL]
    for q in range(len(new_nodes)):  # each new node a cluster of its own, in a free slot (its rows hold zeros)
        counters[_N_FREE] -= 1
        s = free[counters[_N_FREE]]
        cluster[s], size[s], last[s] = new_nodes[q], 1, now
        k = first_new + q
        number[k], slot[k], times[k], xs[k], ys[k] = new_nodes[q], s, now, x[q], y[q]
    tail = counters[_TAIL] = first_new + len(new_nodes)
    # The evidence of the new pairs: each new node b is still a cluster of its own, and its pairs (a block of j)
    # sum up per cluster a of their earlier end, in the pairs' order; no pair of clusters (a, b) had evidence before.
    at = np.searchsorted(number[head:tail], i) + head
    heap = [(0.0, np.int64(0), np.int64(0), np.int64(0), np.int64(0))]
    heap.pop()
    distinct = np.empty(len(i), dtype=np.int64)
    found_sums = np.empty(len(i), dtype=np.float64)
    found_counts = np.empty(len(i), dtype=np.int64)
    e = 0
    while e < len(i):
        later = j[e]
        b = slot[first_new + np.searchsorted(new_nodes, later)]
        found = 0
        while e < len(i) and j[e] == later:
            a = slot[at[e]]
            place = -1
            for q in range(found):
                if distinct[q] == a:
                    place = q
                    break
            if place < 0:
                distinct[found], found_sums[found], found_counts[found] = a, links[e], 1
                found += 1
            else:
                found_sums[place] += links[e]
                found_counts[place] += 1
            e += 1
        for q in range(found):
            a = distinct[q]
            total[a, b] = total[b, a] = found_sums[q]
            count[a, b] = count[b, a] = found_counts[q]
            mean = found_sums[q] / found_counts[q]
            if mean > threshold:
                heap.append(_candidate(mean, cluster, a, b))
    heapq.heapify(heap)
    child = List.empty_list(types.int64)
    survivor = List.empty_list(types.int64)
    while len(heap):
        negative, older, younger, a, b = heapq.heappop(heap)
        if cluster[a] != older or cluster[b] != younger or count[a, b] == 0:
            continue  # one side merged or retired since (its slot free, or another cluster's)
        if total[a, b] / count[a, b] != -negative:
            continue  # stale: the link changed since
        if max_extent < np.inf and _extent(slot, xs, ys, head, tail, a, b) > max_extent:
            continue  # too long a cluster: refused (the evidence stays)
        # b (the younger) joins a.
        child.append(younger)
        survivor.append(older)
        total[a, b] = total[b, a] = 0.0
        count[a, b] = count[b, a] = 0
        for c in range(len(cluster)):
            if count[b, c] == 0:
                continue
            s, k = total[b, c], count[b, c]
            total[b, c] = total[c, b] = 0.0
            count[b, c] = count[c, b] = 0
            if count[a, c] > 0:
                s, k = total[a, c] + s, count[a, c] + k
            total[a, c] = total[c, a] = s
            count[a, c] = count[c, a] = k
            mean = s / k
            if mean > threshold:
                heapq.heappush(heap, _candidate(mean, cluster, a, c))
        for k in range(head, tail):
            if slot[k] == b:
                slot[k] = a
        size[a] += size[b]
        last[a] = max(last[a], last[b])
        _free(state, b)
    out = np.empty(len(new_nodes), dtype=np.int64)
    sizes = np.empty(len(new_nodes), dtype=np.int64)
    for q in range(len(new_nodes)):
        out[q] = cluster[slot[first_new + q]]
        sizes[q] = size[slot[first_new + q]]
    n_merges = len(child)
    child_out = np.empty(n_merges, dtype=np.int64)
    survivor_out = np.empty(n_merges, dtype=np.int64)
    for k in range(n_merges):
        child_out[k] = child[k]
        survivor_out[k] = survivor[k]
    return out, sizes, child_out, survivor_out


@numba.njit(cache=True, nogil=True)
def _candidate(mean, cluster, a, b):
    """The heap entry of a mean link between the clusters of slots ``a`` and ``b``: largest mean first, ties to
    the smaller pair of cluster numbers; the older (smaller) cluster first."""
    if cluster[a] < cluster[b]:
        return (-mean, cluster[a], cluster[b], a, b)
    return (-mean, cluster[b], cluster[a], b, a)


@numba.njit(cache=True, nogil=True)
def _free(state, s):
    """Forget the cluster of slot ``s``: its evidence (row and column) to zero, the slot back on the stack."""
    ints, _, sums, counts, counters = state
    total, count = sums[0], counts[0]
    for o in range(len(ints[_CLUSTER])):
        if count[s, o] > 0:
            total[s, o] = total[o, s] = 0.0
            count[s, o] = count[o, s] = 0
    ints[_CLUSTER][s] = -1
    ints[_FREE][counters[_N_FREE]] = s
    counters[_N_FREE] += 1


@numba.njit(cache=True, nogil=True)
def _retire(state, now, window):
    """Retire the clusters that no new pair can reach, and forget the nodes that no new pair can end at."""
    ints, floats, _, _, counters = state
    cluster, last, times = ints[_CLUSTER], floats[_LAST], floats[_TIME]
    for s in range(len(cluster)):
        if cluster[s] >= 0 and not now - last[s] <= window:
            _free(state, s)
    head = counters[_HEAD]
    while head < counters[_TAIL] and not now - times[head] <= window:
        head += 1
    counters[_HEAD] = head


@numba.njit(cache=True, nogil=True)
def _make_room(state, n):
    """Room for ``n`` new nodes: as many free slots and places after the tail (moved to the front, or grown)."""
    ints, floats, sums, counts, counters = state
    slots = len(ints[_CLUSTER])
    if counters[_N_FREE] < n:  # more slots: the matrices grown, the new slots free
        grown = max(2 * slots, slots - counters[_N_FREE] + n)
        total, count = np.zeros((grown, grown)), np.zeros((grown, grown), dtype=np.int64)
        total[:slots, :slots], count[:slots, :slots] = sums[0], counts[0]
        sums[0], counts[0] = total, count
        cluster, size, last = np.full(grown, -1, dtype=np.int64), np.zeros(grown, dtype=np.int64), np.zeros(grown)
        cluster[:slots], size[:slots], last[:slots] = ints[_CLUSTER], ints[_SIZE], floats[_LAST]
        ints[_CLUSTER], ints[_SIZE], floats[_LAST] = cluster, size, last
        free = np.empty(grown, dtype=np.int64)
        added = grown - slots
        free[:added] = np.arange(grown - 1, slots - 1, -1)
        free[added : added + counters[_N_FREE]] = ints[_FREE][: counters[_N_FREE]]
        ints[_FREE] = free
        counters[_N_FREE] += added
    head, tail, places = counters[_HEAD], counters[_TAIL], len(ints[_NUMBER])
    if tail + n > places:  # the recent nodes moved to the front, into larger arrays if they still do not fit
        kept = tail - head
        size = max(places, 2 * (kept + n))
        for k in (_NUMBER, _SLOT):
            moved = np.zeros(size, dtype=np.int64)
            moved[:kept] = ints[k][head:tail]
            ints[k] = moved
        for k in (_TIME, _X, _Y):
            moved = np.zeros(size)
            moved[:kept] = floats[k][head:tail]
            floats[k] = moved
        counters[_HEAD], counters[_TAIL] = 0, kept


@numba.njit(cache=True, nogil=True)
def _extent(slot, xs, ys, head, tail, a, b):
    """Diagonal of the x-y bounding box of the recent nodes (``head:tail``) of the clusters of slots ``a`` and
    ``b``, m."""
    low_x, high_x, low_y, high_y = np.inf, -np.inf, np.inf, -np.inf
    for k in range(head, tail):
        if slot[k] == a or slot[k] == b:
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
