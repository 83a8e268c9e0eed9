"""Cluster-level features for stage 2: per-cluster tracks, centre continuation, pair search.

Everything here works on one sequence and uses, for a decision at time tau,
only detections at or before tau.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SMOOTHING_WINDOW = 3  # scans, moving average of the centres


@dataclass
class ClusterRows:
    """The detections of each stage-1 cluster of one sequence, sorted by time."""

    ids: np.ndarray  # cluster labels, sorted
    rows: list  # per cluster: row positions sorted by time
    start: np.ndarray  # s, first detection time
    end: np.ndarray  # s, last detection time


def cluster_rows(labels, t):
    """Group the rows of each non-noise label, in time order."""
    clustered = np.flatnonzero(labels >= 0)
    if len(clustered) == 0:
        return ClusterRows(np.zeros(0, dtype=np.int64), [], np.zeros(0), np.zeros(0))
    order = clustered[np.lexsort((t[clustered], labels[clustered]))]
    ids, first = np.unique(labels[order], return_index=True)
    last = np.r_[first[1:], len(order)] - 1
    return ClusterRows(ids, np.split(order, first[1:]), t[order[first]], t[order[last]])


def candidate_pairs(clusters, x, y, t, eps_t2, reach):
    """Pairs (a, b) of clusters, a starting no later than b, that may merge.

    b must start less than ``eps_t2`` after a's last detection (or while a
    lives), and the bounding boxes of their detections around b's start
    (a within ``[s_b - eps_t2, s_b + eps_t2]``, b within
    ``[s_b, s_b + eps_t2]``) must come within ``reach`` (m) of each other: a
    coarse bound, the criteria decide.
    """
    order = np.argsort(clusters.start, kind="stable")
    times = [t[rows] for rows in clusters.rows]

    def box(k, low, high):
        rows = clusters.rows[k][np.searchsorted(times[k], low, "left") : np.searchsorted(times[k], high, "right")]
        if len(rows) == 0:
            return None
        return x[rows].min(), x[rows].max(), y[rows].min(), y[rows].max()

    pairs = []
    for position, b in enumerate(order):
        earlier = order[:position]
        start_b = clusters.start[b]
        alive = earlier[(clusters.end[earlier] > start_b - eps_t2) & (clusters.start[earlier] <= start_b)]
        if len(alive) == 0:
            continue
        box_b = box(b, start_b, start_b + eps_t2)
        for a in alive:
            box_a = box(a, start_b - eps_t2, start_b + eps_t2)
            if box_a is None:
                continue
            gap_x = max(box_a[0] - box_b[1], box_b[0] - box_a[1], 0.0)
            gap_y = max(box_a[2] - box_b[3], box_b[2] - box_a[3], 0.0)
            if gap_x * gap_x + gap_y * gap_y <= reach * reach:
                pairs.append((int(a), int(b)))
    return pairs


def scan_centres(rows, x, y, t):
    """Times and mean (x, y) of one cluster's detections per scan, in time order."""
    times, inverse = np.unique(t[rows], return_inverse=True)
    count = np.bincount(inverse)
    return times, np.bincount(inverse, x[rows]) / count, np.bincount(inverse, y[rows]) / count


def moving_average(values, window=SMOOTHING_WINDOW):
    """Centred moving average whose window shrinks symmetrically at the ends.

    A symmetric window keeps a straight track straight up to its last point;
    padding the ends instead would bend it and bias the end velocity.
    """
    n = len(values)
    cumulative = np.concatenate([[0.0], np.cumsum(values)])
    half = np.minimum(np.minimum(np.arange(n), n - 1 - np.arange(n)), window // 2)
    lo, hi = np.arange(n) - half, np.arange(n) + half + 1
    return (cumulative[hi] - cumulative[lo]) / (hi - lo)


def continuation(times, cx, cy):
    """End time, end centre and end velocity of a cluster's smoothed centre track.

    The per-scan centres are smoothed by a moving average; the velocity is
    the derivative, at the last centre, of the cubic through the last four
    smoothed centres -- the end piece of a cubic spline, evaluated exactly
    instead of by fine resampling -- or of the line through the last two or
    three when fewer exist.  With a single scan the velocity is unknown
    (nan).  Only centres up to the track's end are used: nothing later.
    """
    n = len(times)
    if n == 1:
        return times[0], np.array([cx[0], cy[0]]), np.array([np.nan, np.nan])
    tail = slice(max(n - 4 - SMOOTHING_WINDOW, 0), n)  # enough for the last 4 smoothed centres
    t_tail, x_tail, y_tail = times[tail], moving_average(cx[tail]), moving_average(cy[tail])
    k = min(4, len(t_tail))
    lag = t_tail[-k:] - t_tail[-1]
    if k == 4:
        basis = np.vander(lag, 4, increasing=True)  # cubic in time, origin at the last centre
        velocity = np.linalg.solve(basis, np.c_[x_tail[-k:], y_tail[-k:]])[1]
    else:
        velocity = np.polyfit(lag, np.c_[x_tail[-k:], y_tail[-k:]], 1)[0]
    return times[-1], np.array([x_tail[-1], y_tail[-1]]), velocity


def predict(track_end, position, velocity, at):
    """Constant-velocity continuation of a centre to the times ``at`` (s); unknown velocity stays put."""
    v = np.nan_to_num(velocity)
    return position[None, :] + (np.asarray(at)[:, None] - track_end) * v[None, :]


def min_distance(a_x, a_y, b_x, b_y):
    """Smallest distance between two point sets, m."""
    return float(np.sqrt(np.min((a_x[:, None] - b_x[None, :]) ** 2 + (a_y[:, None] - b_y[None, :]) ** 2)))


def merge_components(n_clusters, edges, min_samples):
    """DBSCAN over clusters: cores have >= min_samples - 1 merge partners; returns a root per cluster."""
    degree = np.zeros(n_clusters, dtype=np.int64)
    for a, b in edges:
        degree[a] += 1
        degree[b] += 1
    core = degree + 1 >= min_samples
    parent = np.arange(n_clusters)

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a, b in edges:
        if core[a] and core[b]:
            ra, rb = find(a), find(b)
            parent[max(ra, rb)] = min(ra, rb)
    root = np.array([find(i) for i in range(n_clusters)])
    for a, b in edges:  # a non-core cluster joins a core partner
        if core[a] and not core[b] and root[b] == b:
            root[b] = root[a]
        elif core[b] and not core[a] and root[a] == a:
            root[a] = root[b]
    return root
