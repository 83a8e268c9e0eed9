"""Cluster-level kernels for stage 2: per-cluster tracks, the pair criteria, merging.

Everything here works on one sequence and uses, for a decision at time tau,
only detections at or before tau.  The detections of every stage-1 cluster
form one run of a flat array sorted by (cluster, time); the pair loops are
numba kernels, because a tuned stage 1 can leave thousands of small clusters
and tens of thousands of pairs per sequence (the cost of a Python loop over
them: :ref:`performance`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from .._neighbors import CELL_COORDINATE_BOUND, cell_key, cell_runs, time_range
from .._union_find import find, union_keep_smaller


@dataclass
class ClusterRuns:
    """The detections of each stage-1 cluster of one sequence, as runs of a flat, (cluster, time)-sorted array."""

    ids: np.ndarray  # cluster labels, ascending
    order: np.ndarray  # flat position -> row, sorted by (cluster, time, x, y, extra keys, row)
    run_start: np.ndarray  # first flat position of each cluster
    run_end: np.ndarray  # one past the last
    t: np.ndarray  # s, time of each flat position
    x: np.ndarray  # m
    y: np.ndarray  # m
    scan_t: np.ndarray  # s, per (cluster, scan time): the scan's time ...
    scan_x: np.ndarray  # m, ... and the mean position of the cluster's detections in it
    scan_y: np.ndarray
    scan_start: np.ndarray  # first scan of each cluster
    scan_end: np.ndarray
    by_start: np.ndarray  # the clusters by (first detection (t, x, y, extra keys), size): A before B in a pair

    @property
    def start(self):
        """s, first detection time of each cluster."""
        return self.t[self.run_start]

    @property
    def end(self):
        """s, last detection time of each cluster."""
        return self.t[self.run_end - 1]


def cluster_runs(labels, x, y, t, extra=()):
    """Sort the non-noise rows by (label, time, x, y, *extra) and summarise every cluster's scans.

    The sort keys make everything that follows independent of the row
    order: the detections of a scan are taken in the order of their values
    (``extra``: further per-row arrays, e.g. Doppler, that break ties of
    x and y), and clusters starting in the same scan are ordered by their
    first detection's values, then size (``by_start``), not by their
    label ids, which follow the rows.
    """
    clustered = np.flatnonzero(labels >= 0)
    keys = [np.asarray(column)[clustered] for column in (*extra[::-1], y, x, t)]
    order = clustered[np.lexsort((*keys, labels[clustered]))]
    sorted_labels, sorted_t = labels[order], t[order]
    ids, run_start = np.unique(sorted_labels, return_index=True)
    run_end = np.r_[run_start[1:], len(order)].astype(np.int64)
    new_scan = np.ones(len(order), dtype=bool)  # a scan of a cluster: a run of equal (label, time)
    new_scan[1:] = (sorted_labels[1:] != sorted_labels[:-1]) | (sorted_t[1:] != sorted_t[:-1])
    scan_of_row = np.cumsum(new_scan) - 1
    count = np.bincount(scan_of_row)
    scan_first = np.flatnonzero(new_scan)
    scan_cluster = np.searchsorted(ids, sorted_labels[scan_first])
    scan_start = np.searchsorted(scan_cluster, np.arange(len(ids)), side="left")
    scan_end = np.searchsorted(scan_cluster, np.arange(len(ids)), side="right")
    first = order[run_start]
    size = run_end - run_start
    by_start = np.lexsort((size, *[np.asarray(column)[first] for column in (*extra[::-1], y, x, t)]))
    return ClusterRuns(
        ids=ids,
        order=order,
        run_start=run_start.astype(np.int64),
        run_end=run_end,
        t=np.ascontiguousarray(sorted_t, dtype=np.float64),
        x=np.ascontiguousarray(x[order], dtype=np.float64),
        y=np.ascontiguousarray(y[order], dtype=np.float64),
        scan_t=np.ascontiguousarray(sorted_t[scan_first], dtype=np.float64),
        scan_x=np.bincount(scan_of_row, x[order]) / count,
        scan_y=np.bincount(scan_of_row, y[order]) / count,
        scan_start=scan_start.astype(np.int64),
        scan_end=scan_end.astype(np.int64),
        by_start=by_start.astype(np.int64),
    )


@numba.njit(cache=True, nogil=True)
def _time_compatible_pairs(by_start, start, end, eps_t2):
    """Pairs (a, b): a comes before b in ``by_start`` and has a detection after s_b - eps_t2.

    The unpruned enumeration, quadratic in the clusters alive at once: the
    reference of :func:`_candidate_pairs` in the tests.
    """
    first_a, second_b = [], []
    for position in range(len(by_start)):
        b = by_start[position]
        for earlier in range(position):
            a = by_start[earlier]
            if end[a] > start[b] - eps_t2:
                first_a.append(a)
                second_b.append(b)
    return np.array(first_a, dtype=np.int64), np.array(second_b, dtype=np.int64)


_MAX_CLUSTER_CELLS = 64  # a cluster whose reach covers more grid cells is compared with every other one


@numba.njit(cache=True, nogil=True)
def _boxes_close(a, b, lo_x, hi_x, lo_y, hi_y, half):
    """False only when the boxes of a and b are ``half[a] + half[b]`` or more apart along x or along y."""
    reach = half[a] + half[b]
    if not reach < np.inf:  # unbounded (or nan): never prune
        return True
    gap_x = max(lo_x[b] - hi_x[a], lo_x[a] - hi_x[b])
    gap_y = max(lo_y[b] - hi_y[a], lo_y[a] - hi_y[b])
    return not (gap_x >= reach or gap_y >= reach)


@numba.njit(cache=True, nogil=True)
def _reach_cells(by_start, lo_x, hi_x, lo_y, hi_y, half, side):
    """The grid cells each cluster reaches, and the entries of the grid of :func:`_candidate_pairs`.

    Cells have ``side`` m.  A cluster's reach is its box ``[lo_x, hi_x] x
    [lo_y, hi_y]`` (m) expanded by ``half`` (m); ``reach`` holds its cells
    ``[x0, x1] x [y0, y1]`` with one spare cell each side (rounding cannot
    hide a pair), and ``large`` flags the clusters whose reach covers more
    than ``_MAX_CLUSTER_CELLS`` cells or lies beyond the cell keys' range.
    Each other cluster is entered in the cells of its reach (without the
    spare ring), in the order of ``by_start``.

    Returns
    -------
    reach : ndarray of int64, shape (n, 4)
        (x0, x1, y0, y1) per cluster; 0 for a large one.
    large : ndarray of bool, shape (n,)
    entry_x, entry_y, entry_cluster, entry_rank : ndarray of int64
        The cell, the cluster and its position in ``by_start`` of every entry.
    """
    n = len(by_start)
    reach = np.zeros((n, 4), dtype=np.int64)
    large = np.zeros(n, dtype=np.bool_)
    n_entries = 0
    for c in range(n):
        fx0 = np.floor((lo_x[c] - half[c]) / side) - 1.0
        fx1 = np.floor((hi_x[c] + half[c]) / side) + 1.0
        fy0 = np.floor((lo_y[c] - half[c]) / side) - 1.0
        fy1 = np.floor((hi_y[c] + half[c]) / side) + 1.0
        in_range = fx0 >= -CELL_COORDINATE_BOUND and fx1 < CELL_COORDINATE_BOUND  # False for nan and inf
        if not (in_range and fy0 >= -CELL_COORDINATE_BOUND and fy1 < CELL_COORDINATE_BOUND):
            large[c] = True
            continue
        if (fx1 - fx0 + 1.0) * (fy1 - fy0 + 1.0) > _MAX_CLUSTER_CELLS:
            large[c] = True
            continue
        reach[c, 0], reach[c, 1], reach[c, 2], reach[c, 3] = int(fx0), int(fx1), int(fy0), int(fy1)
        n_entries += (reach[c, 1] - reach[c, 0] - 1) * (reach[c, 3] - reach[c, 2] - 1)
    entry_x = np.empty(n_entries, dtype=np.int64)
    entry_y = np.empty(n_entries, dtype=np.int64)
    entry_cluster = np.empty(n_entries, dtype=np.int64)
    entry_rank = np.empty(n_entries, dtype=np.int64)
    k = 0
    for position in range(n):
        c = by_start[position]
        if large[c]:
            continue
        for cx in range(reach[c, 0] + 1, reach[c, 1]):
            for cy in range(reach[c, 2] + 1, reach[c, 3]):
                entry_x[k], entry_y[k], entry_cluster[k], entry_rank[k] = cx, cy, c, position
                k += 1
    return reach, large, entry_x, entry_y, entry_cluster, entry_rank


@numba.njit(cache=True, nogil=True)
def _candidate_pairs(by_start, start, end, eps_t2, lo_x, hi_x, lo_y, hi_y, half, reach, large, grid):
    """The pairs of :func:`_time_compatible_pairs` (same order) whose boxes are less than ``half[a] + half[b]`` apart.

    ``by_start`` orders the clusters (a pair's a comes first); the boxes
    ``[lo_x, hi_x] x [lo_y, hi_y]`` (m) bound each cluster, ``half`` is the
    reach of each cluster (m, inf for unbounded).  ``reach`` and ``large``
    are those of :func:`_reach_cells`; ``grid`` = (cell keys, cell start,
    cell end, cluster of each sorted entry) is the cell table
    (:func:`sklearn_radar._neighbors.cell_runs`) of its entries, so a
    cluster finds its spatial neighbours in the cells of its reach; a large
    one is compared with all.  Memory is linear in the clusters plus the
    pairs returned.
    """
    cell_keys, cell_start, cell_end, members = grid
    n = len(by_start)
    rank = np.empty(n, dtype=np.int64)
    for position in range(n):
        rank[by_start[position]] = position
    large_by_rank = [by_start[position] for position in range(n) if large[by_start[position]]]
    first_a, second_b = [], []
    seen = np.full(n, -1, dtype=np.int64)
    found = np.empty(n, dtype=np.int64)
    for position in range(n):
        b = by_start[position]
        n_found = 0
        if large[b]:
            for earlier in range(position):
                a = by_start[earlier]
                if end[a] > start[b] - eps_t2 and _boxes_close(a, b, lo_x, hi_x, lo_y, hi_y, half):
                    found[n_found] = a
                    n_found += 1
        else:
            for cx in range(reach[b, 0], reach[b, 1] + 1):
                # The cells (cx, y0..y1) are the keys in [key(cx, y0), key(cx, y1)]: one search per column.
                q = np.searchsorted(cell_keys, cell_key(cx, reach[b, 2]))
                last = cell_key(cx, reach[b, 3])
                while q < len(cell_keys) and cell_keys[q] <= last:
                    for m in range(cell_start[q], cell_end[q]):
                        a = members[m]
                        if rank[a] >= position:  # a cell's entries are in rank order
                            break
                        if seen[a] == b:
                            continue
                        seen[a] = b
                        if end[a] > start[b] - eps_t2 and _boxes_close(a, b, lo_x, hi_x, lo_y, hi_y, half):
                            found[n_found] = a
                            n_found += 1
                    q += 1
            for a in large_by_rank:
                if rank[a] >= position:
                    break
                if end[a] > start[b] - eps_t2 and _boxes_close(a, b, lo_x, hi_x, lo_y, hi_y, half):
                    found[n_found] = a
                    n_found += 1
            if n_found > 1:
                ranks = np.empty(n_found, dtype=np.int64)
                for i in range(n_found):
                    ranks[i] = rank[found[i]]
                # The ranks are distinct, so any sort gives this order: mergesort, compiled for the keys already
                # (quicksort would be compiled too), copied by a loop (a slice assignment compiles its error text).
                by_rank = found[:n_found][np.argsort(ranks, kind="mergesort")]
                for i in range(n_found):
                    found[i] = by_rank[i]
        for i in range(n_found):
            first_a.append(found[i])
            second_b.append(b)
    return np.array(first_a, dtype=np.int64), np.array(second_b, dtype=np.int64)


@numba.njit(cache=True, nogil=True)
def _max_speeds(scan_t, scan_x, scan_y, scan_start, scan_end):
    """Per cluster, the largest finite speed (m/s) :func:`_continuation` gives for any prefix of its track (0 if none).

    inf when a finite velocity's norm overflows.
    """
    n = len(scan_start)
    speed = np.zeros(n)
    for c in range(n):
        for length in range(2, scan_end[c] - scan_start[c] + 1):
            _end_t, _x, _y, vx, vy = _continuation(scan_t, scan_x, scan_y, scan_start[c], length)
            if np.isfinite(vx) and np.isfinite(vy):
                speed[c] = max(speed[c], np.hypot(vx, vy))
    return speed


def _cell_side(lo_x, hi_x, lo_y, hi_y, half):
    """Grid cell side of :func:`_reach_cells`, m: the median finite expanded extent of the clusters (else 1).

    At least one grid cell per typical cluster.  The extent of a cluster is
    the larger side of its box (numba's ``max``: the first unless the second
    is larger) plus twice its reach.
    """
    with np.errstate(over="ignore", invalid="ignore"):
        width, height = hi_x - lo_x, hi_y - lo_y
        extent = np.where(height > width, height, width) + 2.0 * half
    finite = extent[np.isfinite(extent)]
    side = float(np.median(finite)) if len(finite) > 0 else 1.0
    return side if 0.0 < side < np.inf else 1.0


def _cluster_boxes(runs):
    """Per cluster (lo_x, hi_x, lo_y, hi_y), m: the bounding box of its detections (and of its scan centres)."""
    lo_x = np.minimum.reduceat(runs.x, runs.run_start)
    hi_x = np.maximum.reduceat(runs.x, runs.run_start)
    lo_y = np.minimum.reduceat(runs.y, runs.run_start)
    hi_y = np.maximum.reduceat(runs.y, runs.run_start)
    return lo_x, hi_x, lo_y, hi_y


def candidate_pairs(runs, eps_t2, eps_d, mode):
    """Pairs (a, b) of clusters, a before b in ``runs.by_start``, alive within ``eps_t2`` (s) of b's start, and close.

    The same pairs, in the same order, as the plain time test
    (:func:`_time_compatible_pairs`) minus those the merge criterion of
    ``mode`` is certain to reject on distance: a conservative spatial
    prefilter, so that the pairs (and memory) grow with the clusters that
    are near each other in space and time rather than with the square of
    the clusters alive at once.

    * ``"velocity"``: d_min (m) is a distance between detections of A and
      B, at least the gap between their bounding boxes along x or y.
    * ``"continuation"``: a continued centre is the raw mean of a scan (in
      the box) plus ``lag * v``, with ``|lag| <= 2 eps_t2`` (the window
      ``[s_B, s_B + eps_t2]`` against an end time in ``(s_B - eps_t2, tau]``)
      and ``|v|`` at most the largest speed of any prefix of the track
      (:func:`_max_speeds`), so the two centres are at least the box gap
      minus ``2 eps_t2 (|v_A|max + |v_B|max)`` apart.  The bound uses the
      velocities actually estimated (not a guessed top speed); a track with
      an unbounded one is compared with every cluster.

    Relative margins of 1e-6 (and 1e-9 of the coordinates' and times'
    magnitudes) absorb rounding, so a pair at the threshold is kept.
    """
    n = len(runs.ids)
    if n < 2:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    start, end = np.ascontiguousarray(runs.start), np.ascontiguousarray(runs.end)
    by_start = runs.by_start
    lo_x, hi_x, lo_y, hi_y = _cluster_boxes(runs)
    scale = np.maximum.reduce([np.abs(lo_x), np.abs(hi_x), np.abs(lo_y), np.abs(hi_y)])
    with np.errstate(over="ignore", invalid="ignore"):
        reach = np.zeros(n)
        if mode == "continuation":
            t_scale = float(np.max(np.abs(runs.t)))
            lag = (2.0 * float(eps_t2) + 1e-9 * t_scale) * (1.0 + 1e-6)
            speed = _max_speeds(runs.scan_t, runs.scan_x, runs.scan_y, runs.scan_start, runs.scan_end)
            reach = lag * speed
        half = (0.5 * float(eps_d) + reach) * (1.0 + 1e-6) + 1e-9 * scale
    half = np.ascontiguousarray(np.where(np.isnan(half), np.inf, half))
    side = _cell_side(lo_x, hi_x, lo_y, hi_y, half)  # in numpy: numba's median would compile for about 1 s
    reach, large, entry_x, entry_y, entry_cluster, entry_rank = _reach_cells(
        by_start, lo_x, hi_x, lo_y, hi_y, half, side
    )
    order, cell_keys, cell_start, cell_end = cell_runs(entry_x, entry_y, entry_rank)
    grid = (cell_keys, cell_start, cell_end, entry_cluster[order])
    return _candidate_pairs(by_start, start, end, float(eps_t2), lo_x, hi_x, lo_y, hi_y, half, reach, large, grid)


def time_compatible_pairs(runs, eps_t2):
    """Pairs (a, b) of clusters, a before b in ``runs.by_start``, alive within ``eps_t2`` (s) of b's start."""
    if len(runs.ids) < 2:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    return _time_compatible_pairs(
        runs.by_start, np.ascontiguousarray(runs.start), np.ascontiguousarray(runs.end), float(eps_t2)
    )


@numba.njit(cache=True, nogil=True)
def _pair_window(a, b, t, run_start, run_end, eps_t2):
    """Decision time tau of pair (a, b) and its row ranges; ``ok`` is False when A ended eps_t2 or more before s_B.

    Returns (ok, tau, end of A's rows up to tau, end of B's rows up to tau):
    A's past is ``[run_start[a], past_a_end)``, B's part ``[run_start[b], b_end)``.
    """
    start_b = t[run_start[b]]
    tau = min(t[run_end[b] - 1], start_b + eps_t2)
    _, past_a_end = time_range(t, run_start[a], run_end[a], -np.inf, tau)
    _, before_b_end = time_range(t, run_start[a], past_a_end, -np.inf, start_b)
    alive = past_a_end > before_b_end
    gap = 0.0 if alive else start_b - t[before_b_end - 1]
    _, b_end = time_range(t, run_start[b], run_end[b], -np.inf, tau)
    return gap < eps_t2, tau, past_a_end, b_end


@numba.njit(cache=True, nogil=True)
def _velocity_windows(pair_a, pair_b, t, x, y, run_start, run_end, eps_d, eps_t2):
    """Eq. 6's windows: A's rows in [s_B - eps_t2, tau], B's rows up to tau, kept when d_min < eps_d (m).

    Returns a (n_kept, 5) array of (pair index, A's first, A's end, B's first, B's end) flat positions.
    """
    kept = np.empty((len(pair_a), 5), dtype=np.int64)
    n_kept = 0
    eps_d2 = eps_d * eps_d
    for k in range(len(pair_a)):
        a, b = pair_a[k], pair_b[k]
        ok, _tau, past_a_end, b_end = _pair_window(a, b, t, run_start, run_end, eps_t2)
        if not ok:
            continue
        a_first, a_end = time_range(t, run_start[a], past_a_end, t[run_start[b]] - eps_t2, np.inf)
        if a_first == a_end:
            continue
        close = False
        for i in range(a_first, a_end):
            for j in range(run_start[b], b_end):
                if (x[i] - x[j]) ** 2 + (y[i] - y[j]) ** 2 < eps_d2:
                    close = True
                    break
            if close:
                break
        if close:
            # Element by element: a row assignment compiles numba's text for a shape mismatch (about 1 s).
            kept[n_kept, 0], kept[n_kept, 1], kept[n_kept, 2] = k, a_first, a_end
            kept[n_kept, 3], kept[n_kept, 4] = run_start[b], b_end
            n_kept += 1
    return kept[:n_kept]


def velocity_windows(runs, pair_a, pair_b, eps_d, eps_t2):
    """Candidate pairs of Eq. 6 with their detection windows (see :func:`_velocity_windows`)."""
    return _velocity_windows(
        pair_a, pair_b, runs.t, runs.x, runs.y, runs.run_start, runs.run_end, float(eps_d), float(eps_t2)
    )


@numba.njit(cache=True, nogil=True)
def _smoothed(values, scan, n):
    """Centred 3-scan moving average at ``scan`` of a track of ``n`` scans (the window shrinks at the ends).

    A symmetric window keeps a straight track straight up to its last
    point; padding the ends instead would bend it and bias the end velocity.
    """
    if scan == 0 or scan == n - 1:
        return values[scan]
    return (values[scan - 1] + values[scan] + values[scan + 1]) / 3.0


_TINY = float(np.finfo(np.float64).tiny)  # the smallest normal float64; below, precision is lost


@numba.njit(cache=True, nogil=True)
def _continuation(scan_t, scan_x, scan_y, first, n):
    """End time, end centre and end velocity (m/s; nan if unknown) of the first ``n`` scans of a track.

    The per-scan centres are smoothed by a centred moving average; the
    velocity is the derivative, at the last centre, of the cubic through
    the last four smoothed centres (the end piece of a cubic spline,
    evaluated exactly) or the slope of the line fitted to the last two or
    three.  A single scan has no velocity, nor have scans too close in time
    for the fit (lags whose squares underflow, below about 1e-154 s).
    """
    last = first + n - 1
    end_x, end_y = scan_x[last], scan_y[last]
    if n == 1:
        return scan_t[last], end_x, end_y, np.nan, np.nan
    k = min(4, n)
    lag = np.empty(k)
    sx = np.empty(k)
    sy = np.empty(k)
    for i in range(k):
        scan = n - k + i
        lag[i] = scan_t[first + scan] - scan_t[last]
        sx[i] = _smoothed(scan_x[first : last + 1], scan, n)
        sy[i] = _smoothed(scan_y[first : last + 1], scan, n)
    vx = 0.0
    vy = 0.0
    if k == 4:
        # Derivative at lag 0 (the last node) of the Lagrange interpolant: sum of w_i * value_i.
        for i in range(4):
            for m in range(i):
                if lag[i] - lag[m] == 0.0:  # scans too close for their lags to differ: no velocity
                    return scan_t[last], end_x, end_y, np.nan, np.nan
        for i in range(4):
            if i == 3:
                w = 0.0
                for m in range(3):
                    w += 1.0 / (lag[3] - lag[m])
            else:
                w = 1.0 / (lag[i] - lag[3])
                for m in range(3):
                    if m != i:
                        w *= (lag[3] - lag[m]) / (lag[i] - lag[m])
            vx += w * sx[i]
            vy += w * sy[i]
    else:
        mean_lag, mean_x, mean_y = lag.mean(), sx.mean(), sy.mean()
        spread = 0.0
        for i in range(k):
            spread += (lag[i] - mean_lag) ** 2
            vx += (lag[i] - mean_lag) * (sx[i] - mean_x)
            vy += (lag[i] - mean_lag) * (sy[i] - mean_y)
        if not spread >= _TINY:  # scans closer than ~1e-154 s: the squared lags underflow, no velocity
            return scan_t[last], end_x, end_y, np.nan, np.nan
        vx /= spread
        vy /= spread
    return scan_t[last], end_x, end_y, vx, vy


@numba.njit(cache=True, nogil=True)
def _scans_up_to(scan_t, first, end, tau):
    _lo, hi = time_range(scan_t, first, end, -np.inf, tau)
    return hi - first


@numba.njit(cache=True, nogil=True)
def _continuation_edges(
    pair_a,
    pair_b,
    t,
    run_start,
    run_end,
    scan_t,
    scan_x,
    scan_y,
    scan_start,
    scan_end,
    eps_d,
    eps_v,
    eps_t2,
    accept_unknown,
):
    """The continuation criterion for every pair: continued centres within eps_d (m), velocities within eps_v (m/s)."""
    merge = np.zeros(len(pair_a), dtype=np.bool_)
    for k in range(len(pair_a)):
        a, b = pair_a[k], pair_b[k]
        ok, tau, _past_a_end, _b_end = _pair_window(a, b, t, run_start, run_end, eps_t2)
        if not ok:
            continue
        n_a = _scans_up_to(scan_t, scan_start[a], scan_end[a], tau)
        n_b = _scans_up_to(scan_t, scan_start[b], scan_end[b], tau)
        end_a, xa, ya, vxa, vya = _continuation(scan_t, scan_x, scan_y, scan_start[a], n_a)
        end_b, xb, yb, vxb, vyb = _continuation(scan_t, scan_x, scan_y, scan_start[b], n_b)
        known_a = np.isfinite(vxa) and np.isfinite(vya)
        known_b = np.isfinite(vxb) and np.isfinite(vyb)
        pa_x, pa_y = (vxa, vya) if known_a else (0.0, 0.0)  # an unknown velocity continues standing still
        pb_x, pb_y = (vxb, vyb) if known_b else (0.0, 0.0)
        start_b = t[run_start[b]]
        d_pred = np.inf
        for fraction in (0.0, 0.5, 1.0):
            at = start_b + fraction * eps_t2
            dx = (xa + (at - end_a) * pa_x) - (xb + (at - end_b) * pb_x)
            dy = (ya + (at - end_a) * pa_y) - (yb + (at - end_b) * pb_y)
            d_pred = min(d_pred, np.sqrt(dx * dx + dy * dy))
        if d_pred >= eps_d:
            continue
        if known_a and known_b:
            merge[k] = np.sqrt((vxa - vxb) ** 2 + (vya - vyb) ** 2) < eps_v
        else:
            merge[k] = accept_unknown
    return merge


def continuation_edges(runs, pair_a, pair_b, eps_d, eps_v, eps_t2, accept_unknown):
    """Boolean per pair: does the continuation criterion merge it? (see :func:`_continuation_edges`)."""
    return _continuation_edges(
        pair_a,
        pair_b,
        runs.t,
        runs.run_start,
        runs.run_end,
        runs.scan_t,
        runs.scan_x,
        runs.scan_y,
        runs.scan_start,
        runs.scan_end,
        float(eps_d),
        float(eps_v),
        float(eps_t2),
        bool(accept_unknown),
    )


def track_continuation(runs, cluster, tau):
    """(end time s, end centre m, end velocity m/s) of ``cluster``'s track from its scans up to ``tau`` (s)."""
    first, end = runs.scan_start[cluster], runs.scan_end[cluster]
    n = int(np.searchsorted(runs.scan_t[first:end], tau, side="right"))
    end_t, x, y, vx, vy = _continuation(runs.scan_t, runs.scan_x, runs.scan_y, first, n)
    return end_t, np.array([x, y]), np.array([vx, vy])


@numba.njit(cache=True, nogil=True)
def _merge_components(n_clusters, edges, min_samples):
    """Kernel of :func:`merge_components`; ``edges`` is an (n_edges, 2) int64 array of cluster indices."""
    degree = np.zeros(n_clusters, dtype=np.int64)
    for k in range(len(edges)):
        degree[edges[k, 0]] += 1
        degree[edges[k, 1]] += 1
    core = degree + 1 >= min_samples
    parent = np.arange(n_clusters)
    for k in range(len(edges)):
        if core[edges[k, 0]] and core[edges[k, 1]]:
            union_keep_smaller(parent, edges[k, 0], edges[k, 1])
    root = np.empty(n_clusters, dtype=np.int64)
    for i in range(n_clusters):
        root[i] = find(parent, i)
    for k in range(len(edges)):  # a non-core cluster joins a core partner
        a, b = edges[k, 0], edges[k, 1]
        if core[a] and not core[b] and root[b] == b:
            root[b] = root[a]
        elif core[b] and not core[a] and root[a] == a:
            root[a] = root[b]
    return root


def merge_components(n_clusters, edges, min_samples):
    """DBSCAN over clusters: cores have >= min_samples - 1 merge partners; returns a root per cluster.

    Core clusters joined by an edge share the smallest cluster index as
    their root (the union-find of :mod:`sklearn_radar._union_find`); a
    non-core cluster takes the root of its first core partner.

    Parameters
    ----------
    n_clusters : int
        Number of stage-1 clusters of the sequence.
    edges : sequence of (int, int)
        Pairs of cluster indices that the merge criterion accepts.
    min_samples : int
        Minimum number of clusters in a core cluster's neighbourhood, itself included.

    Returns
    -------
    root : ndarray of int64, shape (n_clusters,)
    """
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    return _merge_components(int(n_clusters), edges, int(min_samples))


@numba.njit(cache=True, nogil=True)
def _velocity_window_rows(windows, order):
    """Rows of every window of :func:`velocity_windows`: A's of pair i as group 2i, B's as 2i + 1, in time order."""
    total = 0
    for k in range(len(windows)):
        total += (windows[k, 2] - windows[k, 1]) + (windows[k, 4] - windows[k, 3])
    rows = np.empty(total, dtype=np.int64)
    group = np.empty(total, dtype=np.int64)
    m = 0
    for k in range(len(windows)):
        for side in range(2):
            for position in range(windows[k, 1 + 2 * side], windows[k, 2 + 2 * side]):
                rows[m], group[m] = order[position], 2 * k + side
                m += 1
    return rows, group


def velocity_window_rows(windows, order):
    """(rows, group) of the windows: the detection rows (``order`` of :class:`ClusterRuns`) and each row's window."""
    return _velocity_window_rows(
        np.ascontiguousarray(windows, dtype=np.int64), np.ascontiguousarray(order, dtype=np.int64)
    )


@numba.njit(cache=True, nogil=True)
def _velocity_agreement(vx, vy, eps_phi, eps_v, accept_unknown):
    merge = np.empty(len(vx) // 2, dtype=np.bool_)
    for k in range(len(merge)):
        xa, ya, xb, yb = vx[2 * k], vy[2 * k], vx[2 * k + 1], vy[2 * k + 1]
        if not (np.isfinite(xa) and np.isfinite(ya) and np.isfinite(xb) and np.isfinite(yb)):
            merge[k] = accept_unknown
            continue
        dphi = abs(np.remainder(np.arctan2(ya, xa) - np.arctan2(yb, xb) + np.pi, 2 * np.pi) - np.pi)
        merge[k] = dphi < eps_phi and abs(np.hypot(xa, ya) - np.hypot(xb, yb)) < eps_v
    return merge


def velocity_agreement(vx, vy, eps_phi, eps_v, accept_unknown):
    """Eq. 6's velocity test per window pair (A's velocity at 2i, B's at 2i + 1, m/s; NaN unknown).

    True when the directions differ by less than ``eps_phi`` (rad) and the
    speeds by less than ``eps_v`` (m/s); a pair with an unknown velocity
    merges when ``accept_unknown``.
    """
    return _velocity_agreement(
        np.ascontiguousarray(vx, dtype=np.float64),
        np.ascontiguousarray(vy, dtype=np.float64),
        float(eps_phi),
        float(eps_v),
        bool(accept_unknown),
    )
