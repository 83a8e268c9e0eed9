"""Greedy mean-link agglomeration over a sparse graph of link probabilities (numba), for LinkClustering.

Every node starts as a cluster of its own.  Two clusters are joined by the
candidate pairs between them (the edges of the graph, each with a link
probability); the *link* of two clusters is the mean probability over
those pairs.  Pairs that are not edges carry no evidence either way: a
cluster's link to another is never diluted by the pairs that were never
candidates (as average linkage's distance 1 would), and one strong pair
cannot chain two clusters whose other pairs disagree (as single linkage
would).  Repeatedly, the two clusters with the largest link are merged,
while it exceeds a floor.

The merge order does not depend on the floor (a floor only stops the
merging), so one run at the lowest floor gives the clusters of every higher
threshold: :func:`roots_at` replays the merges up to the first whose link
is not above it.  Ties of the link are broken by the smaller node number,
then the larger one; a merged cluster keeps the number of the side with
more neighbouring clusters (of the smaller number at equal counts).  So
the result depends only on the numbering of the nodes, which the caller
makes independent of the row order.
"""

from __future__ import annotations

import heapq

import numba
import numpy as np


def mean_link_merges(n_nodes, i, j, probability, floor):
    """The merges of the greedy mean-link agglomeration, in order.

    Parameters
    ----------
    n_nodes : int
        Number of nodes, numbered 0 to ``n_nodes - 1``.
    i, j : ndarray of int, shape (n_edges,)
        The edges, ``i != j``, each pair of nodes at most once.
    probability : ndarray of float, shape (n_edges,)
        Link probability of each edge, in [0, 1].
    floor : float
        Merging stops when no two clusters have a link above it.

    Returns
    -------
    child : ndarray of int64, shape (n_merges,)
        The cluster (by its node number) that is merged away.
    survivor : ndarray of int64, shape (n_merges,)
        The cluster it joins, which keeps its number.
    link : ndarray of float64, shape (n_merges,)
        The mean link probability at the merge, > ``floor``.

    Raises
    ------
    ValueError
        If the edges are not of equal length, a node number is out of range, an edge joins a node to itself or is
        given twice, or a probability is not finite.
    """
    i = np.asarray(i, dtype=np.int64)
    j = np.asarray(j, dtype=np.int64)
    probability = np.asarray(probability, dtype=np.float64)
    if not len(i) == len(j) == len(probability):
        raise ValueError(
            f"i, j and probability must have one value per edge, got {len(i)}, {len(j)}, {len(probability)}"
        )
    if len(i):
        if min(i.min(), j.min()) < 0 or max(i.max(), j.max()) >= n_nodes:
            raise ValueError(f"edges must join nodes 0 to {n_nodes - 1}")
        if np.any(i == j):
            raise ValueError("an edge joins a node to itself")
        if not np.all(np.isfinite(probability)):
            raise ValueError("probability must be finite")
        low, high = np.minimum(i, j), np.maximum(i, j)
        keys = low * np.int64(n_nodes) + high
        if len(np.unique(keys)) < len(keys):
            raise ValueError("an edge is given twice")
        i, j = low, high
    return _merges(np.int64(n_nodes), i, j, probability, np.float64(floor))


@numba.njit(cache=True, nogil=True)
def _merges(n_nodes, i, j, probability, floor):
    n_edges = len(i)
    # The link of two live clusters a < b: its sum and count of edge probabilities, in the slot that the table
    # gives for the key a * n + b.
    table = _new_table(n_edges)
    total = np.empty(n_edges, dtype=np.float64)
    count = np.empty(n_edges, dtype=np.int64)
    # Each cluster's neighbours as a linked list of entries (target, next); entries may be stale (a target merged
    # away, or the pair moved on): the table is the truth.
    capacity = 2 * n_edges + 16
    target = np.empty(capacity, dtype=np.int64)
    following = np.empty(capacity, dtype=np.int64)
    head = np.full(n_nodes, -1, dtype=np.int64)
    tail = np.full(n_nodes, -1, dtype=np.int64)
    degree = np.zeros(n_nodes, dtype=np.int64)
    alive = np.ones(n_nodes, dtype=np.bool_)
    used = 0
    heap = [(0.0, np.int64(0), np.int64(0))]
    heap.pop()
    for e in range(n_edges):
        a, b = i[e], j[e]
        table = _insert(table, a * n_nodes + b, e)
        total[e] = probability[e]
        count[e] = 1
        for u, w in ((a, b), (b, a)):
            if used == capacity:
                target, following, capacity = _grown(target, following, capacity)
            target[used] = w
            following[used] = -1
            if tail[u] >= 0:
                following[tail[u]] = used
            else:
                head[u] = used
            tail[u] = used
            used += 1
            degree[u] += 1
        if probability[e] > floor:
            heap.append((-probability[e], a, b))
    heapq.heapify(heap)
    child = np.empty(max(n_nodes - 1, 0), dtype=np.int64)
    survivor = np.empty(max(n_nodes - 1, 0), dtype=np.int64)
    link = np.empty(max(n_nodes - 1, 0), dtype=np.float64)
    n_merges = 0
    while len(heap):
        negative, a, b = heapq.heappop(heap)
        if not (alive[a] and alive[b]):
            continue
        s = _find(table, a * n_nodes + b)
        if s < 0 or -negative != total[s] / count[s]:
            continue  # stale: the pair has moved on or its link changed since
        if degree[a] < degree[b]:
            a, b = b, a
        # b joins a.
        alive[b] = False
        child[n_merges], survivor[n_merges], link[n_merges] = b, a, -negative
        n_merges += 1
        _remove(table, min(a, b) * n_nodes + max(a, b))
        degree[a] -= 1
        k = head[b]
        while k >= 0:
            c = target[k]
            k = following[k]
            if c == a or not alive[c]:
                continue
            old_key = min(b, c) * n_nodes + max(b, c)
            s = _find(table, old_key)
            if s < 0:
                continue  # a stale entry
            _remove(table, old_key)
            new_key = min(a, c) * n_nodes + max(a, c)
            t = _find(table, new_key)
            if t >= 0:  # c was a neighbour of both: the links add up, c loses a neighbour
                total[t] += total[s]
                count[t] += count[s]
                degree[c] -= 1
            else:  # c was b's alone: the pair moves to a (c's neighbour b becomes a)
                t = s
                table = _insert(table, new_key, t)
                degree[a] += 1
                for u, w in ((a, c), (c, a)):
                    if used == capacity:
                        target, following, capacity = _grown(target, following, capacity)
                    target[used] = w
                    following[used] = -1
                    following[tail[u]] = used
                    tail[u] = used
                    used += 1
            value = total[t] / count[t]
            if value > floor:
                heapq.heappush(heap, (-value, min(a, c), max(a, c)))
        degree[b] = 0
    return child[:n_merges].copy(), survivor[:n_merges].copy(), link[:n_merges].copy()


# An open-addressing hash table of non-negative int64 keys to int64 values, in one (3, capacity) int64 array:
# row 0 the keys (-1 empty, -2 removed), row 1 the values; row 2, column 0 counts the used cells (keys and removed
# ones), column 1 the live keys.  Linear probing; the capacity is a power of two, at least four times the live keys.
_EMPTY, _REMOVED = -1, -2
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)


@numba.njit(cache=True, nogil=True)
def _new_table(n_keys):
    capacity = 16
    while capacity < 4 * n_keys:
        capacity *= 2
    table = np.full((3, capacity), _EMPTY, dtype=np.int64)
    table[2, 0] = 0
    table[2, 1] = 0
    return table


@numba.njit(cache=True, nogil=True, inline="always")
def _home(key, capacity):
    return np.int64((np.uint64(key) * _GOLDEN) >> np.uint64(32)) & (capacity - 1)


@numba.njit(cache=True, nogil=True)
def _find(table, key):
    """The value of ``key``, -1 when absent."""
    capacity = table.shape[1]
    cell = _home(key, capacity)
    while True:
        found = table[0, cell]
        if found == key:
            return table[1, cell]
        if found == _EMPTY:
            return -1
        cell = (cell + 1) & (capacity - 1)


@numba.njit(cache=True, nogil=True)
def _remove(table, key):
    capacity = table.shape[1]
    cell = _home(key, capacity)
    while table[0, cell] != key:
        cell = (cell + 1) & (capacity - 1)
    table[0, cell] = _REMOVED
    table[2, 1] -= 1


@numba.njit(cache=True, nogil=True)
def _insert(table, key, value):
    """The table with ``key`` (absent) set to ``value``: the same array, or a rebuilt one when it filled up."""
    capacity = table.shape[1]
    if 2 * (table[2, 0] + 1) > capacity:  # half full of keys and removed cells: rebuild with the live keys only
        rebuilt = _new_table(table[2, 1] + 1)
        for cell in range(capacity):
            if table[0, cell] >= 0:
                _place(rebuilt, table[0, cell], table[1, cell])
        table = rebuilt
    _place(table, key, value)
    return table


@numba.njit(cache=True, nogil=True)
def _place(table, key, value):
    """Set the absent ``key`` to ``value`` in the first free cell of its probe sequence (the table has room)."""
    capacity = table.shape[1]
    cell = _home(key, capacity)
    while table[0, cell] >= 0:
        cell = (cell + 1) & (capacity - 1)
    if table[0, cell] == _EMPTY:
        table[2, 0] += 1
    table[0, cell] = key
    table[1, cell] = value
    table[2, 1] += 1


@numba.njit(cache=True, nogil=True)
def _grown(target, following, capacity):
    """The linked-list arrays with twice the room."""
    new_capacity = 2 * capacity
    new_target = np.empty(new_capacity, dtype=np.int64)
    new_following = np.empty(new_capacity, dtype=np.int64)
    new_target[:capacity] = target
    new_following[:capacity] = following
    return new_target, new_following, new_capacity


def roots_at(n_nodes, child, survivor, link, threshold):
    """Cluster of every node after the merges whose link is above ``threshold``.

    The merges are replayed in order up to the first whose link is not
    above ``threshold``: the clusters the agglomeration gives with that
    floor.

    Parameters
    ----------
    n_nodes : int
        Number of nodes.
    child, survivor, link : ndarray
        The merges of :func:`mean_link_merges`.
    threshold : float
        The floor.

    Returns
    -------
    roots : ndarray of int64, shape (n_nodes,)
        The node number that names each node's cluster.
    """
    stop = np.flatnonzero(np.asarray(link) <= threshold)
    n_merges = int(stop[0]) if len(stop) else len(link)
    return _roots(np.int64(n_nodes), np.asarray(child, np.int64), np.asarray(survivor, np.int64), n_merges)


@numba.njit(cache=True, nogil=True)
def _roots(n_nodes, child, survivor, n_merges):
    parent = np.arange(n_nodes)
    for k in range(n_merges):
        parent[child[k]] = survivor[k]
    for start in range(n_nodes):
        root = start
        while parent[root] != root:
            root = parent[root]
        node = start
        while parent[node] != root:  # path compression
            following = parent[node]
            parent[node] = root
            node = following
    return parent
