"""Numba kernels of RadarDBSCAN: neighbourhood criteria (Eqs. 3-5), core points, causal updates.

All kernels work on the points of one sequence sorted by (grid cell, time)
as produced by :func:`sklearn_radar._neighbors.build_grid`.  Neighbours are
visited on the fly, cell by cell, so memory stays linear in the number of
points however dense the clutter is.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .._neighbors import neighbor_cells, point_cells, time_range
from .._union_find import find, union_keep_smaller

BOX, XY, XYV, BOX_UNROTATED = 0, 1, 2, 3
METRIC_CODES = {"box": BOX, "xy": XY, "xyv": XYV}


@numba.njit(cache=True, nogil=True, inline="always")
def _spatial_neighbor(i, j, x, y, v, t, cos_h, sin_h, metric, eps_xy, eps_vr, vr_scale, eps_xyv):
    """Eqs. 3-5 without the time criterion (strict inequalities, as printed in the paper)."""
    dx = x[j] - x[i]
    dy = y[j] - y[i]
    dv = v[j] - v[i]
    if metric == BOX_UNROTATED:  # every heading is 0: the box axes are the x-y axes
        return abs(dx) < eps_xy and abs(dy) < eps_xy and abs(dv) < eps_vr
    if metric == BOX:
        # Box axes: the car frame of the later detection of the pair (the newest scan of a sliding window).
        k = i if t[i] >= t[j] else j
        along = cos_h[k] * dx + sin_h[k] * dy
        across = cos_h[k] * dy - sin_h[k] * dx
        return abs(along) < eps_xy and abs(across) < eps_xy and abs(dv) < eps_vr
    if metric == XY:
        return dx * dx + dy * dy < eps_xy * eps_xy and abs(dv) < eps_vr
    return dx * dx + dy * dy + dv * dv / (vr_scale * vr_scale) < eps_xyv * eps_xyv


@numba.njit(cache=True, nogil=True, inline="always")
def _pair_distance(i, j, x, y, v, t, cos_h, sin_h, metric, eps_xy, eps_vr, vr_scale, eps_xyv):
    """The criterion as a normalised distance (< 1 for neighbours); ranks border candidates."""
    dx = x[j] - x[i]
    dy = y[j] - y[i]
    dv = abs(v[j] - v[i])
    if metric == BOX_UNROTATED:
        return max(abs(dx) / eps_xy, abs(dy) / eps_xy, dv / eps_vr)
    if metric == BOX:
        k = i if t[i] >= t[j] else j
        along = abs(cos_h[k] * dx + sin_h[k] * dy)
        across = abs(cos_h[k] * dy - sin_h[k] * dx)
        return max(along / eps_xy, across / eps_xy, dv / eps_vr)
    if metric == XY:
        return max(math.sqrt(dx * dx + dy * dy) / eps_xy, dv / eps_vr)
    return math.sqrt(dx * dx + dy * dy + dv * dv / (vr_scale * vr_scale)) / eps_xyv


@numba.njit(cache=True, nogil=True)
def dbscan_sorted(x, y, v, t, cos_h, sin_h, min_points, can_be_core, cell_x, cell_y, cell_keys, cell_start, cell_end,
                  metric, eps_xy, eps_vr, vr_scale, eps_xyv, eps_t):  # fmt: skip
    """DBSCAN on grid-sorted points; returns (root per point or -1, core flags).

    A point is core when it may be (``can_be_core``) and it has at least
    ``min_points - 1`` neighbours: like scikit-learn, the point counts
    itself toward its (real-valued) minimum.  Core neighbours are joined;
    a non-core point joins the cluster of its closest core neighbour.
    Passes 2 and 3 visit core points only, so static clutter that cannot be
    core costs one capped count, however dense it is.
    """
    n = len(x)
    n_cells = len(cell_keys)
    cells = neighbor_cells(cell_keys, cell_start, cell_x, cell_y)
    point_cell = point_cells(cell_start, cell_end, n)

    # Pass 1: core points, counting neighbours up to the number needed.
    core = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        if not can_be_core[i]:
            continue
        need = max(math.ceil(min_points[i]) - 1, 0)
        count = 0
        for k in range(9):
            c = cells[point_cell[i], k]
            if c < 0 or count >= need:
                continue
            lo, hi = time_range(t, cell_start[c], cell_end[c], t[i] - eps_t, t[i] + eps_t)
            for j in range(lo, hi):
                if j == i:
                    continue
                if _spatial_neighbor(i, j, x, y, v, t, cos_h, sin_h, metric, eps_xy, eps_vr, vr_scale, eps_xyv):
                    count += 1
                    if count >= need:
                        break
        core[i] = count >= need

    # The core points keep the (cell, time) order: per cell, a contiguous run.
    core_position = np.flatnonzero(core)
    core_t = t[core_position]
    core_start = np.zeros(n_cells, dtype=np.int64)
    core_end = np.zeros(n_cells, dtype=np.int64)
    for k in range(len(core_position)):
        c = point_cell[core_position[k]]
        if k == 0 or point_cell[core_position[k - 1]] != c:
            core_start[c] = k
        core_end[c] = k + 1

    # Pass 2: join neighbouring core points; each pair is visited once, from its lower cell.
    parent = np.arange(n)
    for i in core_position:
        own = point_cell[i]
        for k in range(9):
            c = cells[own, k]
            if c < own or core_end[c] == core_start[c]:
                continue
            lo, hi = time_range(core_t, core_start[c], core_end[c], t[i] - eps_t, t[i] + eps_t)
            for m in range(lo, hi):
                j = core_position[m]
                if c == own and j <= i:
                    continue
                if _spatial_neighbor(i, j, x, y, v, t, cos_h, sin_h, metric, eps_xy, eps_vr, vr_scale, eps_xyv):
                    union_keep_smaller(parent, i, j)

    # Pass 3: roots; a non-core point takes its closest core neighbour's.
    roots = np.full(n, -1, dtype=np.int64)
    for i in range(n):
        if core[i]:
            roots[i] = find(parent, i)
            continue
        closest, closest_distance = -1, np.inf
        for k in range(9):
            c = cells[point_cell[i], k]
            if c < 0 or core_end[c] == core_start[c]:
                continue
            lo, hi = time_range(core_t, core_start[c], core_end[c], t[i] - eps_t, t[i] + eps_t)
            for m in range(lo, hi):
                j = core_position[m]
                if _spatial_neighbor(i, j, x, y, v, t, cos_h, sin_h, metric, eps_xy, eps_vr, vr_scale, eps_xyv):
                    d = _pair_distance(i, j, x, y, v, t, cos_h, sin_h, metric, eps_xy, eps_vr, vr_scale, eps_xyv)
                    if d < closest_distance:
                        closest, closest_distance = j, d
        if closest >= 0:
            roots[i] = find(parent, closest)
    return roots, core


@numba.njit(cache=True, nogil=True, inline="always")
def _past_neighbor(i, j, x, y, v, t, cos_h, sin_h, metric, eps_xy, eps_vr, vr_scale, eps_xyv, eps_t):
    """j is a neighbour of i at or before i's time (the causal neighbourhood)."""
    # Plain ifs: the same test as one chained boolean expression compiled 8x slower.
    if j == i:
        return False
    lag = t[i] - t[j]
    if lag < 0.0 or lag > eps_t:
        return False
    return _spatial_neighbor(i, j, x, y, v, t, cos_h, sin_h, metric, eps_xy, eps_vr, vr_scale, eps_xyv)


@numba.njit(cache=True, nogil=True)
def _local_id(ids, n_ids, cluster_id):
    """Position of ``cluster_id`` among the first ``n_ids`` entries of ``ids`` (-1 if absent)."""
    for k in range(n_ids):
        if ids[k] == cluster_id:
            return k
    return -1


@numba.njit(cache=True, nogil=True)
def causal_update(x, y, v, t, cos_h, sin_h, min_points, can_be_core, core, cluster, first_new, next_id,
                  metric, eps_xy, eps_vr, vr_scale, eps_xyv, eps_t):  # fmt: skip
    """Label one new scan against the sliding window before it, using only the past.

    The arrays hold the window: points ``[0, first_new)`` are earlier
    detections still within ``eps_t`` (their ``core`` flags and ``cluster``
    ids are final), points ``[first_new, n)`` the new scan.  A new point is
    core when it may be and has at least ``min_points - 1`` neighbours at or
    before its time (itself counted, like the offline rule).  New core points
    join their core neighbours; clusters that meet keep the oldest (smallest)
    id and the window is relabelled.  A new non-core point joins its closest
    core neighbour.  ``core`` and ``cluster`` are updated in place; returns
    the next free cluster id.
    """
    n = len(x)
    n_new = n - first_new
    if n_new <= 0:
        return next_id
    for i in range(first_new, n):
        if not can_be_core[i]:
            continue
        need = max(math.ceil(min_points[i]) - 1, 0)
        count = 0
        for j in range(n):
            if count >= need:
                break
            if _past_neighbor(i, j, x, y, v, t, cos_h, sin_h, metric, eps_xy, eps_vr, vr_scale, eps_xyv, eps_t):
                count += 1
        core[i] = count >= need

    # Phase A: components of the new core points among themselves.
    parent = np.arange(n_new)
    for i in range(first_new, n):
        if core[i]:
            for j in range(i + 1, n):
                if not core[j]:
                    continue
                if _spatial_neighbor(i, j, x, y, v, t, cos_h, sin_h, metric, eps_xy, eps_vr, vr_scale, eps_xyv):
                    union_keep_smaller(parent, i - first_new, j - first_new)
    # Phase B: old clusters touched by a component merge into the oldest (smallest) id.
    ids = np.empty(first_new, dtype=np.int64)  # distinct old cluster ids met
    id_parent = np.empty(first_new, dtype=np.int64)
    n_ids = 0
    best = np.full(n_new, -1, dtype=np.int64)  # per component: local index of an id it touches
    for i in range(first_new, n):
        if not core[i]:
            continue
        root = find(parent, i - first_new)
        for j in range(first_new):
            if not core[j]:
                continue
            if not _past_neighbor(i, j, x, y, v, t, cos_h, sin_h, metric, eps_xy, eps_vr, vr_scale, eps_xyv, eps_t):
                continue
            k = _local_id(ids, n_ids, cluster[j])
            if k < 0:
                k = n_ids
                ids[k] = cluster[j]
                id_parent[k] = k
                n_ids += 1
            if best[root] < 0:
                best[root] = k
            else:
                a, b = find(id_parent, k), find(id_parent, best[root])
                if ids[a] < ids[b]:
                    id_parent[b] = a
                elif ids[b] < ids[a]:
                    id_parent[a] = b
    for j in range(first_new):
        if cluster[j] >= 0:
            k = _local_id(ids, n_ids, cluster[j])
            if k >= 0:
                cluster[j] = ids[find(id_parent, k)]
    final = np.full(n_new, -1, dtype=np.int64)
    for i in range(first_new, n):
        if not core[i]:
            continue
        root = find(parent, i - first_new)
        if final[root] < 0:
            if best[root] >= 0:
                final[root] = ids[find(id_parent, best[root])]
            else:
                final[root] = next_id
                next_id += 1
        cluster[i] = final[root]

    for i in range(first_new, n):
        if core[i]:
            continue
        closest, closest_distance = -1, np.inf
        for j in range(n):
            if not core[j]:
                continue
            if not _past_neighbor(i, j, x, y, v, t, cos_h, sin_h, metric, eps_xy, eps_vr, vr_scale, eps_xyv, eps_t):
                continue
            d = _pair_distance(i, j, x, y, v, t, cos_h, sin_h, metric, eps_xy, eps_vr, vr_scale, eps_xyv)
            if d < closest_distance:
                closest, closest_distance = j, d
        cluster[i] = cluster[closest] if closest >= 0 else -1
    return next_id


@numba.njit(cache=True, nogil=True)
def causal_sequence(x, y, v, t, cos_h, sin_h, min_points, can_be_core,
                    metric, eps_xy, eps_vr, vr_scale, eps_xyv, eps_t):  # fmt: skip
    """Offline-causal labels of one time-sorted sequence: each scan as the stream would see it.

    Returns the label each detection receives when its scan arrives (cluster
    ids never reused, oldest id kept on merges) and the core flags.
    """
    n = len(x)
    core = np.zeros(n, dtype=np.bool_)
    cluster = np.full(n, -1, dtype=np.int64)
    emitted = np.full(n, -1, dtype=np.int64)
    next_id = 0
    start = 0
    scan_start = 0
    while scan_start < n:
        scan_end = scan_start + 1
        while scan_end < n and t[scan_end] == t[scan_start]:
            scan_end += 1
        while t[start] < t[scan_start] - eps_t:
            start += 1
        next_id = causal_update(
            x[start:scan_end], y[start:scan_end], v[start:scan_end], t[start:scan_end],
            cos_h[start:scan_end], sin_h[start:scan_end], min_points[start:scan_end],
            can_be_core[start:scan_end], core[start:scan_end], cluster[start:scan_end],
            scan_start - start, next_id, metric, eps_xy, eps_vr, vr_scale, eps_xyv, eps_t,
        )  # fmt: skip
        emitted[scan_start:scan_end] = cluster[scan_start:scan_end]
        scan_start = scan_end
    return emitted, core
