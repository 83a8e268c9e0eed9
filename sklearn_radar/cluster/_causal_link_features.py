"""Causal features of LinkClustering: neighbourhoods from the past only, and candidate pairs in arrival order (numba).

The detections of one sequence are sorted by time (the estimator's order).
A detection's causal neighbourhood is every other detection within the same
radius and window as :func:`~._link_features.detection_features` whose time
is at or before its own: detections of the same time count as each other's
past, as :class:`~sklearn_radar.cluster.ScanStream` counts them.  So the
features of a detection are those that
:func:`~._link_features.detection_features` gives it on the data truncated
at its time, and they never change once computed.

The kernels work on the sorted arrays from a ``start`` index: offline,
``start = 0`` (every detection); online, the window of the recent past is
the head of the arrays and the new scan the tail.  Each detection's
neighbours are visited in index order, so a detection's features are the
same floating-point numbers whichever way they are computed.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ._link_features import (
    LOCAL_RADIUS,
    LOCAL_WINDOW,
    MAX_IMPLIED_SPEED,
    NEAR_RADIUS,
    NEAR_WINDOW,
    PAIR_FEATURES,
    RIDGE,
    V_MOVING,
    V_SIMILAR,
    Detections,
    LocalMotion,
)


def causal_detection_features(d: Detections, start=0):
    """Per-detection features (:data:`~._link_features.DETECTION_FEATURES`) from each detection's past.

    Parameters
    ----------
    d : Detections
        Detections of one sequence sorted by time (``t`` non-decreasing), s.
    start : int, default=0
        The first detection whose features are computed; the earlier ones serve as the past only.

    Returns
    -------
    features : ndarray of float64, shape (n - start, len(DETECTION_FEATURES))
    local : LocalMotion
        Of the detections from ``start`` on.
    """
    v, los = d.v[start:], d.los[start:]
    count, near, similar, n_moving, mean_abs, spread, vx, vy, residual = _neighbourhoods(
        *(np.ascontiguousarray(a, dtype=np.float64) for a in (d.x, d.y, d.t, d.v, d.los)), np.int64(start)
    )
    c, s = np.cos(los), np.sin(los)
    columns = (np.abs(v), v, d.rcs[start:], d.range[start:], np.abs(d.ego[start:]), count, near, similar, n_moving)
    columns += (mean_abs, spread, np.hypot(vx, vy), -vx * s + vy * c, residual, d.sensor[start:])
    features = np.empty((len(v), len(columns)))
    for k, column in enumerate(columns):  # (np.column_stack's values, without its per-call overhead)
        features[:, k] = column
    return features, LocalMotion(vx=vx, vy=vy, count=count, spread=spread)


@numba.njit(cache=True, nogil=True)
def _neighbourhoods(x, y, t, v, los, start):
    n = len(x)
    m = max(n - start, 0)
    count, near, similar = np.zeros(m), np.zeros(m), np.zeros(m)
    n_moving, mean_abs, spread = np.zeros(m), np.zeros(m), np.zeros(m)
    vx, vy, residual = np.zeros(m), np.zeros(m), np.zeros(m)
    lo, hi = 0, start
    while start > lo and t[start] - t[lo] > LOCAL_WINDOW:
        lo += 1
    cos_los, sin_los = np.empty(n), np.empty(n)  # (of the detections that a neighbourhood can hold)
    for j in range(lo, n):
        cos_los[j], sin_los[j] = math.cos(los[j]), math.sin(los[j])
    box = np.empty(n, dtype=np.int64)
    for k in range(start, n):
        tk = t[k]
        while tk - t[lo] > LOCAL_WINDOW:
            lo += 1
        while hi < n and t[hi] <= tk:
            hi += 1
        total_v = total_sq = total_abs = 0.0
        a11 = a12 = a22 = b1 = b2 = vv = 0.0
        n_local = n_near = n_similar = moving = 0.0
        found = _in_box(x, y, lo, hi, x[k], y[k], LOCAL_RADIUS, box)
        for q in range(found):
            j = box[q]
            if j == k:
                continue
            dt = tk - t[j]
            dx, dy = x[k] - x[j], y[k] - y[j]
            if dt > LOCAL_WINDOW or abs(dx) > LOCAL_RADIUS or abs(dy) > LOCAL_RADIUS:
                continue  # (the box test is exact: a distance within the radius has both sides within it)
            if not _within(dx, dy, LOCAL_RADIUS):
                continue
            vj = v[j]
            n_local += 1.0
            if dt <= NEAR_WINDOW and _within(dx, dy, NEAR_RADIUS):
                n_near += 1.0
            if abs(v[k] - vj) < V_SIMILAR:
                n_similar += 1.0
            total_v += vj
            total_sq += vj * vj
            total_abs += abs(vj)
            if abs(vj) > V_MOVING:
                moving += 1.0
                cj, sj = cos_los[j], sin_los[j]
                a11 += cj * cj
                a12 += cj * sj
                a22 += sj * sj
                b1 += vj * cj
                b2 += vj * sj
                vv += vj * vj
        r = k - start
        per = max(n_local, 1.0)
        mean_v = total_v / per
        count[r], near[r], similar[r], n_moving[r] = n_local, n_near, n_similar, moving
        mean_abs[r] = total_abs / per
        spread[r] = math.sqrt(max(total_sq / per - mean_v * mean_v, 0.0))
        # Eq. 6's rigid velocity of the moving neighbours and the detection itself, ridge towards v u.
        ck, sk, vk = cos_los[k], sin_los[k], v[k]
        a11 += ck * ck
        a12 += ck * sk
        a22 += sk * sk
        b1 += vk * ck
        b2 += vk * sk
        vv += vk * vk
        r1, r2 = b1 + RIDGE * vk * ck, b2 + RIDGE * vk * sk
        m11, m22 = a11 + RIDGE, a22 + RIDGE
        det = m11 * m22 - a12 * a12
        fx, fy = (m22 * r1 - a12 * r2) / det, (m11 * r2 - a12 * r1) / det
        squares = vv - 2 * (fx * b1 + fy * b2) + fx * fx * a11 + 2 * fx * fy * a12 + fy * fy * a22
        vx[r], vy[r] = fx, fy
        residual[r] = math.sqrt(max(squares, 0.0) / (moving + 1))
    return count, near, similar, n_moving, mean_abs, spread, vx, vy, residual


@numba.njit(cache=True, nogil=True, inline="always")
def _within(dx, dy, radius):
    """``math.hypot(dx, dy) <= radius``, the same answer: from the squares where they decide beyond any rounding,
    from ``hypot`` (slower) near the circle."""
    squares, limit = dx * dx + dy * dy, radius * radius
    if 1e-200 < limit < 1e200:  # (no square of the radius lost to underflow or overflow)
        if squares < limit * (1.0 - 1e-9):
            return True
        if squares > limit * (1.0 + 1e-9):
            return False
    return math.hypot(dx, dy) <= radius


@numba.njit(cache=True, nogil=True)
def _in_box(x, y, lo, hi, x0, y0, radius, out):
    """Into ``out``, in index order: the indices in ``lo:hi`` whose x and y are both within ``radius`` of
    ``(x0, y0)``; returns how many.  (Without a branch per index: a box holds few of a window's detections, and
    a mispredicted branch costs more than the test.)"""
    found = 0
    for j in range(lo, hi):
        out[found] = j
        found += (abs(x0 - x[j]) <= radius) & (abs(y0 - y[j]) <= radius)
    return found


def causal_pairs(x, y, t, node, start, radius, window, max_links=None):
    """Candidate pairs ``i < j`` with ``j >= start``, in the order of ``j``, then ``i``.

    The pairs of :func:`~._link_features.pairs_within` (planar distance
    <= ``radius``, time difference <= ``window``, both detections in
    ``node``) whose later detection is ``start`` or after: each pair is
    found once, when its later detection arrives.  With ``max_links``, a
    detection keeps only its ``max_links`` nearest earlier candidates in the
    scaled distance ``(dx^2 + dy^2) / radius^2 + (dt / window)^2`` (ties to
    the earlier one): a choice made from the detection and its past only, so
    a stream that starts at ``start`` keeps the same pairs.

    Parameters
    ----------
    x, y : ndarray of float64, shape (n,)
        Positions, m.
    t : ndarray of float64, shape (n,)
        Times, s, non-decreasing.
    node : ndarray of bool, shape (n,)
        The detections that take part.
    start : int
        The first detection that may be the later one of a pair.
    radius : float
        m.
    window : float
        s.
    max_links : int or None, default=None
        Most pairs kept per later detection; None keeps them all.

    Returns
    -------
    i, j : ndarray of int64
    """
    return _pairs(
        np.ascontiguousarray(x, dtype=np.float64),
        np.ascontiguousarray(y, dtype=np.float64),
        np.ascontiguousarray(t, dtype=np.float64),
        np.ascontiguousarray(node, dtype=np.bool_),
        np.int64(start),
        np.float64(radius),
        np.float64(window),
        np.int64(-1 if max_links is None else max_links),
    )


@numba.njit(cache=True, nogil=True)
def _pairs(x, y, t, node, start, radius, window, max_links):
    found_i = np.empty(16, dtype=np.int64)
    found_j = np.empty(16, dtype=np.int64)
    near = np.empty(16, dtype=np.float64)  # scaled squared distance of each pair found
    used = 0
    nodes = np.flatnonzero(node)  # only nodes take part: the loops visit them alone, in index order
    node_x, node_y = x[nodes], y[nodes]
    box = np.empty(len(nodes), dtype=np.int64)
    lo = 0
    for b in range(np.searchsorted(nodes, start), len(nodes)):
        j = nodes[b]
        while t[j] - t[nodes[lo]] > window:
            lo += 1
        first = used
        for q in range(_in_box(node_x, node_y, lo, b, x[j], y[j], radius, box)):
            i = nodes[box[q]]
            if _within(x[i] - x[j], y[i] - y[j], radius):
                if used == len(found_i):
                    found_i = np.concatenate((found_i, np.empty(used, dtype=np.int64)))
                    found_j = np.concatenate((found_j, np.empty(used, dtype=np.int64)))
                    near = np.concatenate((near, np.empty(used, dtype=np.float64)))
                found_i[used] = i
                found_j[used] = j
                dt = (t[j] - t[i]) / window if window > 0 else 0.0
                near[used] = ((x[i] - x[j]) ** 2 + (y[i] - y[j]) ** 2) / (radius * radius) + dt * dt
                used += 1
        if max_links >= 0 and used - first > max_links:  # the nearest, back in the order of i
            used = _keep_nearest(found_i, near, first, used, max_links)
    return found_i[:used].copy(), found_j[:used].copy()


@numba.njit(cache=True, nogil=True)
def _keep_nearest(found_i, near, first, used, max_links):
    """Keep, in place and in their order, the ``max_links`` candidates of ``first:used`` nearest in ``near``.

    The first ``max_links`` of a stable sort by ``near`` (of equal ones, the earlier): a sorted buffer of the
    best so far, then its positions back in ascending order.  Returns the new ``used``.
    """
    best_near = np.empty(max_links)
    best_at = np.empty(max_links, dtype=np.int64)
    size = 0
    for a in range(first, used):
        if size == max_links and not near[a] < best_near[size - 1]:
            continue  # (a later candidate of equal distance loses to the earlier ones)
        k = size if size < max_links else size - 1
        while k > 0 and near[a] < best_near[k - 1]:
            best_near[k], best_at[k] = best_near[k - 1], best_at[k - 1]
            k -= 1
        best_near[k], best_at[k] = near[a], a
        size = min(size + 1, max_links)
    for k in range(1, size):  # (few: by insertion)
        at, q = best_at[k], k
        while q > 0 and best_at[q - 1] > at:
            best_at[q] = best_at[q - 1]
            q -= 1
        best_at[q] = at
    for k in range(size):
        found_i[first + k] = found_i[best_at[k]]
    return first + size


#: The columns of :func:`causal_pair_features`.
N_PAIR_FEATURES = len(PAIR_FEATURES)


def causal_pair_features(d: Detections, local: LocalMotion, objectness, i, j):
    """:func:`~._link_features.pair_features` in one compiled loop (the causal estimator's and the stream's).

    The same features by the same formulas, in one loop over the pairs.  Offline (``causal=True``) and online
    use this one, so that both compute the same floating-point numbers.

    Parameters
    ----------
    d : Detections
        The detections (of a sequence, or a stream's window).
    local : LocalMotion
        Their local motion.
    objectness : ndarray of float64
        Their P(road user).
    i, j : ndarray of int64
        The pairs.

    Returns
    -------
    features : ndarray of float64, shape (n_pairs, len(PAIR_FEATURES))
    """
    columns = (d.x, d.y, d.t, d.v, d.los, d.range, d.sensor, d.rcs, local.count, local.spread, objectness, local.vx)
    return _pair_features(
        *(np.ascontiguousarray(a, dtype=np.float64) for a in (*columns, local.vy)),
        np.ascontiguousarray(i, dtype=np.int64),
        np.ascontiguousarray(j, dtype=np.int64),
    )


@numba.njit(cache=True, nogil=True, inline="always")
def _lo(a, b):
    """numpy's minimum: NaN when either is."""
    if a != a or b != b:
        return np.nan
    return a if a < b else b


@numba.njit(cache=True, nogil=True, inline="always")
def _hi(a, b):
    if a != a or b != b:
        return np.nan
    return a if a > b else b


@numba.njit(cache=True, nogil=True)
def _pair_features(x, y, t, v, los, ranges, sensor, rcs, count, spread, objectness, vx, vy, i, j):
    n = len(i)
    out = np.empty((n, N_PAIR_FEATURES))
    cos_los, sin_los = np.full(len(x), np.nan), np.empty(len(x))  # (each detection's once: NaN until then)
    for e in range(n):
        for k in (i[e], j[e]):
            if cos_los[k] != cos_los[k]:
                cos_los[k], sin_los[k] = math.cos(los[k]), math.sin(los[k])
    for e in range(n):
        a, b = i[e], j[e]
        dx, dy, dt = x[b] - x[a], y[b] - y[a], t[b] - t[a]
        ca, sa, cb, sb = cos_los[a], sin_los[a], cos_los[b], sin_los[b]
        res_ab = abs(v[b] - (cb * vx[a] + sb * vy[a]))
        res_ba = abs(v[a] - (ca * vx[b] + sa * vy[b]))
        det = ca * sb - sa * cb
        safe = det
        if abs(det) < 1e-3:
            safe = math.copysign(1e-3, det + 1e-12)
        implied = math.hypot((v[a] * sb - v[b] * sa) / safe, (ca * v[b] - cb * v[a]) / safe)
        if not implied <= MAX_IMPLIED_SPEED and implied == implied:
            implied = MAX_IMPLIED_SPEED
        out[e, 0] = math.hypot(dx, dy)
        out[e, 1] = abs(dt)
        out[e, 2] = abs(v[a] - v[b])
        out[e, 3] = _lo(res_ab, res_ba)
        out[e, 4] = _hi(res_ab, res_ba)
        out[e, 5] = implied
        out[e, 6] = abs(det)
        out[e, 7] = math.hypot(vx[a] - vx[b], vy[a] - vy[b])
        out[e, 8] = math.hypot(dx - (vx[a] + vx[b]) / 2 * dt, dy - (vy[a] + vy[b]) / 2 * dt)
        out[e, 9] = (ranges[a] + ranges[b]) / 2
        same = sensor[a] + sensor[b]
        out[e, 10] = np.nan if same != same else (1.0 if sensor[a] == sensor[b] else 0.0)
        k = 11
        for values in (rcs, count, spread, objectness):
            out[e, k] = _lo(values[a], values[b])
            out[e, k + 1] = _hi(values[a], values[b])
            k += 2
        out[e, 19] = _lo(abs(v[a]), abs(v[b]))
        out[e, 20] = _hi(abs(v[a]), abs(v[b]))
    return out
