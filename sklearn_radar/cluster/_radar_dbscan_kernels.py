"""Numba kernels of RadarDBSCAN: neighbourhood criteria (Eqs. 3-5), core points, causal updates.

All kernels work on the points of one sequence: sorted by (grid cell, time)
as produced by :func:`sklearn_radar._neighbors.build_grid` for the offline
pass, sorted by time for the causal ones.  Neighbours are visited on the
fly, so memory stays linear in the number of points however dense the
clutter is.  The kernels read two typed records, :class:`Points` (the
coordinates of each point) and :class:`Criterion` (the thresholds, built
only by :func:`criterion_of`); the estimator calls the Python wrappers at
the bottom of this module with keyword arguments, never a kernel.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np

from .._neighbors import neighbor_cells, point_cells, time_range
from .._union_find import find, union_keep_smaller

BOX, XY, XYV, BOX_UNROTATED = 0, 1, 2, 3
METRIC_CODES = {"box": BOX, "xy": XY, "xyv": XYV}


class Criterion(NamedTuple):
    """The neighbourhood criterion of RadarDBSCAN (Eqs. 3-5 plus the time window), as the kernels read it.

    Build it with :func:`criterion_of`.  Two points i, j are neighbours when
    ``|t_i - t_j| <= eps_t`` and the spatial-Doppler test of ``metric`` holds.

    Attributes
    ----------
    metric : int
        ``BOX`` (Eq. 3, in the car axes of the later point of the pair; of both at equal times),
        ``XY`` (Eq. 4), ``XYV`` (Eq. 5) or ``BOX_UNROTATED`` (Eq. 3 when every
        heading is 0, so the car axes are the x-y axes).
    eps_xy : float
        Spatial threshold of Eqs. 3 and 4, m.
    eps_vr : float
        Doppler threshold of Eqs. 3 and 4, m/s.
    vr_scale : float
        eps'_vr of Eq. 5: the Doppler difference, m/s, that counts like 1 m.
    eps_xyv : float
        Threshold of the joint distance of Eq. 5, m (Doppler scaled by ``vr_scale``).
    eps_t : float
        Time threshold, s; ``inf`` for none.
    """

    metric: int
    eps_xy: float
    eps_vr: float
    vr_scale: float
    eps_xyv: float
    eps_t: float


class Points(NamedTuple):
    """The coordinates of the points of one sequence, float64 arrays of equal length.

    Attributes
    ----------
    x, y : ndarray of float64
        Working coordinates, m.
    v : ndarray of float64
        Ego-motion-compensated radial velocity, m/s.
    t : ndarray of float64
        Time, s.
    cos_h, sin_h : ndarray of float64
        Cosine and sine of the car heading, rad, at each point (the box axes of Eq. 3).
    """

    x: np.ndarray
    y: np.ndarray
    v: np.ndarray
    t: np.ndarray
    cos_h: np.ndarray
    sin_h: np.ndarray


@numba.njit(cache=True, nogil=True, inline="always")
def _box_offset(dx, dy, t_i, t_j, cos_i, sin_i, cos_j, sin_j):
    """The rotated box of Eq. 3: the larger of |along| and |across|, m, of the offset (dx, dy) in the box axes.

    Box axes: the car frame of the later detection of the pair (the newest
    scan of a sliding window); at equal times, the larger over both
    detections' frames (symmetric in i and j; one heading per scan makes
    them equal).
    """
    if t_i < t_j:
        cos_i, sin_i, cos_j, sin_j = cos_j, sin_j, cos_i, sin_i
    offset = _offset_in_car_axes(cos_i, sin_i, dx, dy)
    if t_i == t_j and (cos_i != cos_j or sin_i != sin_j):
        offset = max(offset, _offset_in_car_axes(cos_j, sin_j, dx, dy))
    return offset


@numba.njit(cache=True, nogil=True, inline="always")
def _offset_in_car_axes(cos_h, sin_h, dx, dy):
    """The larger of |along| and |across|, m, of the offset (dx, dy) in the car axes of heading (cos_h, sin_h)."""
    return max(abs(cos_h * dx + sin_h * dy), abs(cos_h * dy - sin_h * dx))


@numba.njit(cache=True, nogil=True, inline="always")
def _spatial_neighbor(i, j, points, crit):
    """Eqs. 3-5 without the time criterion (strict inequalities, as printed in the paper)."""
    dx = points.x[j] - points.x[i]
    dy = points.y[j] - points.y[i]
    dv = points.v[j] - points.v[i]
    eps_xy, eps_vr = crit.eps_xy, crit.eps_vr
    if crit.metric == BOX_UNROTATED:  # every heading is 0: the box axes are the x-y axes
        return abs(dx) < eps_xy and abs(dy) < eps_xy and abs(dv) < eps_vr
    if crit.metric == BOX:
        return (
            abs(dv) < eps_vr
            and _box_offset(
                dx, dy, points.t[i], points.t[j], points.cos_h[i], points.sin_h[i], points.cos_h[j], points.sin_h[j]
            )
            < eps_xy
        )
    # Eqs. 4 and 5 first reject |dx| >= eps, which decides as the full test would (dx^2 alone rounds to at
    # least eps^2, and adding non-negative terms does not round below it) and spares most pairs the rest.
    if crit.metric == XY:
        if abs(dx) >= eps_xy:
            return False
        return dx * dx + dy * dy < eps_xy * eps_xy and abs(dv) < eps_vr
    if abs(dx) >= crit.eps_xyv:
        return False
    return dx * dx + dy * dy + dv * dv / (crit.vr_scale * crit.vr_scale) < crit.eps_xyv * crit.eps_xyv


@numba.njit(cache=True, nogil=True, inline="always")
def _pair_distance(i, j, points, crit):
    """The criterion as a normalised distance (< 1 for neighbours); ranks border candidates."""
    dx = points.x[j] - points.x[i]
    dy = points.y[j] - points.y[i]
    dv = abs(points.v[j] - points.v[i])
    eps_xy, eps_vr = crit.eps_xy, crit.eps_vr
    if crit.metric == BOX_UNROTATED:
        return max(abs(dx) / eps_xy, abs(dy) / eps_xy, dv / eps_vr)
    if crit.metric == BOX:
        return max(
            _box_offset(
                dx, dy, points.t[i], points.t[j], points.cos_h[i], points.sin_h[i], points.cos_h[j], points.sin_h[j]
            )
            / eps_xy,
            dv / eps_vr,
        )
    if crit.metric == XY:
        return max(math.sqrt(dx * dx + dy * dy) / eps_xy, dv / eps_vr)
    return math.sqrt(dx * dx + dy * dy + dv * dv / (crit.vr_scale * crit.vr_scale)) / crit.eps_xyv


@numba.njit(cache=True, nogil=True, inline="always")
def _advance(times, position, end, bound, inclusive):
    """First position from ``position`` on whose time exceeds ``bound`` (``>=`` it unless ``inclusive``).

    Walks a few steps (the usual case: the window moved by one scan), then
    falls back to a binary search over the rest of the run.
    """
    for _ in range(8):
        if position >= end:
            return position
        if times[position] > bound or (not inclusive and times[position] == bound):
            return position
        position += 1
    side_right = inclusive
    if side_right:
        return position + np.searchsorted(times[position:end], bound, side="right")
    return position + np.searchsorted(times[position:end], bound, side="left")


@numba.njit(cache=True, nogil=True)  # not inlined (3 call sites): its callees are, inside it
def _window(times, start, end, lo, hi, owner, own, t_low, t_high):
    """Positions [lo, hi) of a time-sorted run within [t_low, t_high], and the cell they are found for.

    The one window walk of :func:`_dbscan_sorted`'s passes.  ``lo``, ``hi``
    are the slot's previous answer, found for the points of cell ``owner``.
    For the first point of a new cell ``own`` they are found afresh (two
    binary searches); for the next points of the cell, visited in time
    order, they only move forward (a few steps).
    """
    if owner != own:
        lo, hi = time_range(times, start, end, t_low, t_high)
        return lo, hi, own
    lo = _advance(times, lo, end, t_low, False)
    hi = _advance(times, max(hi, lo), end, t_high, True)
    return lo, hi, own


#: Order in which pass 1 visits the 3 x 3 neighbour cells: its own cell (slot 4) first, where neighbours are likeliest.
_OWN_FIRST = np.array([4, 0, 1, 2, 3, 5, 6, 7, 8], dtype=np.int64)


@numba.njit(cache=True, nogil=True)
def _dbscan_sorted(points, min_points, can_be_core, cell_x, cell_y, cell_keys, cell_start, cell_end, crit):
    """DBSCAN on grid-sorted points; returns (root per point or -1, core flags).

    A point is core when it may be (``can_be_core``) and it has at least
    ``min_points - 1`` neighbours: like scikit-learn, the point counts
    itself toward its (real-valued) minimum.  Core neighbours are joined;
    a non-core point joins the cluster of its closest core neighbour.
    Passes 2 and 3 visit core points only, so static clutter that cannot be
    core costs one capped count, however dense it is.

    Each pass visits the points cell by cell in time order, so the time
    window within each neighbour cell only moves forward: it is found by a
    binary search at the first point of a cell and then by a few steps.
    """
    t, eps_t = points.t, crit.eps_t
    n = len(t)
    n_cells = len(cell_keys)
    cells = neighbor_cells(cell_keys, cell_start, cell_x, cell_y)
    point_cell = point_cells(cell_start, cell_end, n)
    lo = np.zeros(9, dtype=np.int64)
    hi = np.zeros(9, dtype=np.int64)
    owner = np.full(9, -1, dtype=np.int64)  # the cell whose points the window of each slot was last found for

    # Pass 1: core points, counting neighbours up to the number needed (own cell first).
    core = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        if not can_be_core[i]:
            continue
        need = max(math.ceil(min_points[i]) - 1, 0)
        count = 0
        own = point_cell[i]
        for kk in range(9):
            if count >= need:
                break
            k = _OWN_FIRST[kk]
            c = cells[own, k]
            if c < 0:
                continue
            lo[k], hi[k], owner[k] = _window(
                t, cell_start[c], cell_end[c], lo[k], hi[k], owner[k], own, t[i] - eps_t, t[i] + eps_t
            )
            for j in range(lo[k], hi[k]):
                if j == i:
                    continue
                if _spatial_neighbor(i, j, points, crit):
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

    # Pass 2: join neighbouring core points; each pair is visited once, from its lower cell.  The core
    # points' coordinates are gathered first, so that the pass reads them in order.
    core_points = Points(
        points.x[core_position],
        points.y[core_position],
        points.v[core_position],
        core_t,
        points.cos_h[core_position],
        points.sin_h[core_position],
    )
    parent = np.arange(n)
    owner[:] = -1
    for position in range(len(core_position)):
        i = core_position[position]
        own = point_cell[i]
        root_i = find(parent, i)  # stays i's root: only unions with i happen until the next i
        for k in range(9):
            c = cells[own, k]
            if c < own or core_end[c] == core_start[c]:
                continue
            lo[k], hi[k], owner[k] = _window(
                core_t, core_start[c], core_end[c], lo[k], hi[k], owner[k], own, t[i] - eps_t, t[i] + eps_t
            )
            # In its own cell, i meets only the core points after it (the earlier ones met i).
            for m in range(max(lo[k], position + 1) if c == own else lo[k], hi[k]):
                if _spatial_neighbor(position, m, core_points, crit):
                    root_j = find(parent, core_position[m])  # union_keep_smaller(parent, i, j) with i's root known
                    if root_j < root_i:
                        parent[root_i] = root_j
                        root_i = root_j
                    elif root_i < root_j:
                        parent[root_j] = root_i

    # Pass 3: roots; a non-core point takes its closest core neighbour's.
    roots = np.full(n, -1, dtype=np.int64)
    owner[:] = -1
    for i in range(n):
        if core[i]:
            roots[i] = find(parent, i)
            continue
        own = point_cell[i]
        # np.int64, not the literal -1: numba would also compile find() for the argument type Literal[int](-1).
        closest, closest_distance = np.int64(-1), np.inf
        for k in range(9):
            c = cells[own, k]
            if c < 0 or core_end[c] == core_start[c]:
                continue
            lo[k], hi[k], owner[k] = _window(
                core_t, core_start[c], core_end[c], lo[k], hi[k], owner[k], own, t[i] - eps_t, t[i] + eps_t
            )
            for m in range(lo[k], hi[k]):
                j = core_position[m]
                if _spatial_neighbor(i, j, points, crit):
                    d = _pair_distance(i, j, points, crit)
                    if d < closest_distance:
                        closest, closest_distance = j, d
        if closest >= 0:
            roots[i] = find(parent, closest)
    return roots, core


@numba.njit(cache=True, nogil=True, inline="always")
def _past_neighbor(i, j, points, crit):
    """j is a neighbour of i at or before i's time (the causal neighbourhood)."""
    # Plain ifs: the same test as one chained boolean expression compiled 8x slower.
    if j == i:
        return False
    lag = points.t[i] - points.t[j]
    if lag < 0.0 or lag > crit.eps_t:
        return False
    return _spatial_neighbor(i, j, points, crit)


@numba.njit(cache=True, nogil=True)
def _local_id(ids, n_ids, cluster_id):
    """Position of ``cluster_id`` among the first ``n_ids`` entries of ``ids`` (-1 if absent)."""
    for k in range(n_ids):
        if ids[k] == cluster_id:
            return k
    return -1


@numba.njit(cache=True, nogil=True)
def _causal_update(points, min_points, can_be_core, core, cluster, first_new, next_id, crit):
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
    n = len(points.t)
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
            if _past_neighbor(i, j, points, crit):
                count += 1
        core[i] = count >= need

    # Phase A: components of the new core points among themselves.
    parent = np.arange(n_new)
    for i in range(first_new, n):
        if core[i]:
            for j in range(i + 1, n):
                if not core[j]:
                    continue
                if _spatial_neighbor(i, j, points, crit):
                    union_keep_smaller(parent, i - first_new, j - first_new)
    # Phase B: old clusters touched by a component merge into the oldest (smallest) id.
    ids = np.empty(first_new, dtype=np.int64)  # distinct old cluster ids met
    id_parent = np.empty(first_new, dtype=np.int64)
    n_ids = np.int64(0)  # not a literal 0 (one compiled _local_id, see _dbscan_sorted's closest)
    best = np.full(n_new, -1, dtype=np.int64)  # per component: local index of an id it touches
    for i in range(first_new, n):
        if not core[i]:
            continue
        root = find(parent, i - first_new)
        for j in range(first_new):
            if not core[j]:
                continue
            if not _past_neighbor(i, j, points, crit):
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
            if not _past_neighbor(i, j, points, crit):
                continue
            d = _pair_distance(i, j, points, crit)
            if d < closest_distance:
                closest, closest_distance = j, d
        cluster[i] = cluster[closest] if closest >= 0 else -1
    return next_id


@numba.njit(cache=True, nogil=True)
def _causal_sequence(points, min_points, can_be_core, crit):
    """Offline-causal labels of one time-sorted sequence: each scan as the stream would see it.

    Returns the label each detection receives when its scan arrives (cluster
    ids never reused, oldest id kept on merges) and the core flags.
    """
    t = points.t
    n = len(t)
    core = np.zeros(n, dtype=np.bool_)
    cluster = np.full(n, -1, dtype=np.int64)
    emitted = np.full(n, -1, dtype=np.int64)
    next_id = np.int64(0)  # not a literal 0: numba would compile the large _causal_update twice
    start = 0
    scan_start = 0
    while scan_start < n:
        scan_end = scan_start + 1
        while scan_end < n and t[scan_end] == t[scan_start]:
            scan_end += 1
        while t[start] < t[scan_start] - crit.eps_t:
            start += 1
        window = Points(
            points.x[start:scan_end],
            points.y[start:scan_end],
            points.v[start:scan_end],
            t[start:scan_end],
            points.cos_h[start:scan_end],
            points.sin_h[start:scan_end],
        )
        next_id = _causal_update(
            window,
            min_points[start:scan_end],
            can_be_core[start:scan_end],
            core[start:scan_end],
            cluster[start:scan_end],
            scan_start - start,
            next_id,
            crit,
        )
        emitted[scan_start:scan_end] = cluster[scan_start:scan_end]
        scan_start = scan_end
    return emitted, core


# Python wrappers: the estimator's only entry points, called with keyword arguments.


def criterion_of(*, metric, eps_xy, eps_vr, vr_scale, eps_xyv, eps_t, heading=None) -> Criterion:
    """The neighbourhood criterion (Eqs. 3-5 and the time window) as the kernels' :class:`Criterion`.

    The one place where thresholds become a :class:`Criterion`.

    Parameters
    ----------
    metric : {"box", "xy", "xyv"}
        Eq. 3, 4 or 5.
    eps_xy : float
        Spatial threshold of Eqs. 3 and 4, m.
    eps_vr : float
        Doppler threshold of Eqs. 3 and 4, m/s.
    vr_scale : float
        eps'_vr of Eq. 5, m/s.
    eps_xyv : float
        Threshold of Eq. 5, m.
    eps_t : float or None
        Time threshold, s; None for no time limit.
    heading : array-like of float, default=None
        Car heading, rad, of every point the criterion will be applied to.
        When given and all 0, the box of Eq. 3 is ``BOX_UNROTATED`` (the same
        test without the rotation).  None, as for a stream whose future
        headings are unknown, keeps the rotated box.

    Returns
    -------
    criterion : Criterion
    """
    code = METRIC_CODES[metric]
    if code == BOX and heading is not None and not np.any(heading):
        code = BOX_UNROTATED
    return Criterion(
        metric=code,
        eps_xy=float(eps_xy),
        eps_vr=float(eps_vr),
        vr_scale=float(vr_scale),
        eps_xyv=float(eps_xyv),
        eps_t=np.inf if eps_t is None else float(eps_t),
    )


def points_of(*, x, y, v, t, heading) -> Points:
    """The :class:`Points` of the kernels from per-point arrays of equal length.

    Parameters
    ----------
    x, y : array-like of float
        Working coordinates, m.
    v : array-like of float
        Ego-motion-compensated radial velocity, m/s.
    t : array-like of float
        Time, s.
    heading : array-like of float
        Car heading, rad (zeros when the box axes are the x-y axes).

    Returns
    -------
    points : Points
        Contiguous float64 arrays, with the cosine and sine of ``heading``.
    """
    heading = np.asarray(heading, dtype=np.float64)
    if not heading.any():  # every heading 0 (no heading column): no trigonometry
        return Points(
            x=np.ascontiguousarray(x, dtype=np.float64),
            y=np.ascontiguousarray(y, dtype=np.float64),
            v=np.ascontiguousarray(v, dtype=np.float64),
            t=np.ascontiguousarray(t, dtype=np.float64),
            cos_h=np.ones(len(heading)),
            sin_h=np.zeros(len(heading)),
        )
    return Points(
        x=np.ascontiguousarray(x, dtype=np.float64),
        y=np.ascontiguousarray(y, dtype=np.float64),
        v=np.ascontiguousarray(v, dtype=np.float64),
        t=np.ascontiguousarray(t, dtype=np.float64),
        cos_h=np.cos(heading),
        sin_h=np.sin(heading),
    )


def cluster_sorted(*, points, grid, min_points, can_be_core, criterion):
    """Offline RadarDBSCAN of one sequence, past and future neighbours alike (Eqs. 2-5).

    Parameters
    ----------
    points : Points
        The points in the order of ``grid`` (sorted by grid cell, then time).
    grid : GridIndex
        The cell table of :func:`sklearn_radar._neighbors.build_grid`; its
        cell side must be the criterion's largest spatial reach, m.
    min_points : ndarray of float, shape (n,)
        N_min per point (Eq. 2), the point itself included.
    can_be_core : ndarray of bool, shape (n,)
        False for points that may not be core (``|v_r| <= vr_min``).
    criterion : Criterion

    Returns
    -------
    roots : ndarray of int64, shape (n,)
        Root of each point's cluster as a (sorted) position, -1 for noise.
    core : ndarray of bool, shape (n,)
    """
    return _dbscan_sorted(
        points,
        np.ascontiguousarray(min_points, dtype=np.float64),
        np.ascontiguousarray(can_be_core, dtype=np.bool_),
        grid.cell_x,
        grid.cell_y,
        grid.cell_keys,
        grid.cell_start,
        grid.cell_end,
        criterion,
    )


def cluster_causal(*, points, min_points, can_be_core, criterion):
    """Offline-causal RadarDBSCAN of one sequence: each scan labelled as the stream labels it.

    Parameters
    ----------
    points : Points
        The points sorted by time, s; a scan is a run of equal times.
    min_points : ndarray of float, shape (n,)
        N_min per point (Eq. 2), the point itself included.
    can_be_core : ndarray of bool, shape (n,)
    criterion : Criterion

    Returns
    -------
    emitted : ndarray of int64, shape (n,)
        The cluster id each point received when its scan arrived, -1 for noise.
    core : ndarray of bool, shape (n,)
    """
    return _causal_sequence(
        points,
        np.ascontiguousarray(min_points, dtype=np.float64),
        np.ascontiguousarray(can_be_core, dtype=np.bool_),
        criterion,
    )


def update_window(*, points, min_points, can_be_core, core, cluster, first_new, next_id, criterion) -> int:
    """Label the newest scan of a sliding window from the past only (see :func:`_causal_update`).

    The arrays must be contiguous, of the dtypes below: ``core`` and
    ``cluster`` are updated in place.

    Parameters
    ----------
    points : Points
        The window sorted by time, s: earlier points within ``criterion.eps_t``, then the new scan.
    min_points : ndarray of float64, shape (n,)
        N_min per point (Eq. 2), the point itself included.
    can_be_core : ndarray of bool, shape (n,)
    core : ndarray of bool, shape (n,)
        Core flags; those of the new scan are written in place.
    cluster : ndarray of int64, shape (n,)
        Cluster ids; the new scan's are written and merged clusters relabelled in place.
    first_new : int
        Position of the first point of the new scan.
    next_id : int
        The next free cluster id.
    criterion : Criterion

    Returns
    -------
    next_id : int
        The next free cluster id after the scan.
    """
    # No conversions: the stream calls this once per scan, with the window's own contiguous arrays.
    return _causal_update(points, min_points, can_be_core, core, cluster, first_new, next_id, criterion)
