"""Compiled kernels of the Tracker: constant-velocity Kalman prediction, scalar updates, gating distances.

A track's state is ``(x, y, vx, vy)`` (m, m/s) in the fixed frame with a 4 x 4 covariance.  Measurements are
scalar and independent, so an update is a sequence of scalar Kalman updates (no matrix inverse): the centroid's
``x`` and ``y`` (variance ``r_pos``), and each detection's Doppler ``v_r = cos(los) vx + sin(los) vy`` (variance
``r_vr``), the linear model of Eq. 6.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def predict(state, cov, n, dt, q):
    """Predict the first ``n`` tracks ``dt`` s ahead in place: constant velocity, white acceleration of density q.

    ``q`` is the spectral density of the acceleration, m^2/s^3, on each axis: the process noise is
    ``q [[dt^3/3, dt^2/2], [dt^2/2, dt]]`` per axis.
    """
    q11, q12, q22 = q * dt**3 / 3.0, q * dt**2 / 2.0, q * dt
    for k in range(n):
        s = state[k]
        s[0] += dt * s[2]
        s[1] += dt * s[3]
        p = cov[k]
        # P <- F P F^T with F = [[I, dt I], [0, I]]: rows then columns
        for j in range(4):
            p[0, j] += dt * p[2, j]
            p[1, j] += dt * p[3, j]
        for i in range(4):
            p[i, 0] += dt * p[i, 2]
            p[i, 1] += dt * p[i, 3]
        for a in range(2):
            p[a, a] += q11
            p[a, a + 2] += q12
            p[a + 2, a] += q12
            p[a + 2, a + 2] += q22


@numba.njit(cache=True, nogil=True, inline="always")
def _scalar_update(s, p, h, z, r):
    """One scalar Kalman update of state ``s`` and covariance ``p`` with measurement row ``h``, value z, variance r."""
    ph = np.zeros(4)
    for i in range(4):
        acc = 0.0
        for j in range(4):
            acc += p[i, j] * h[j]
        ph[i] = acc
    innovation_var = r
    predicted = 0.0
    for i in range(4):
        innovation_var += h[i] * ph[i]
        predicted += h[i] * s[i]
    gain = ph / innovation_var
    residual = z - predicted
    for i in range(4):
        s[i] += gain[i] * residual
    for i in range(4):
        for j in range(4):
            p[i, j] -= gain[i] * ph[j]


@numba.njit(cache=True, nogil=True)
def update(state, cov, track, x, y, v_r, los, r_pos, r_vr, doppler_sigmas):
    """Update every track given detections (``track[i]``: the track slot of detection i, -1 none) in place.

    Each track with detections gets its centroid (two scalar updates, variance ``r_pos``) and then the Doppler of
    each of its detections (variance ``r_vr``) whose residual is within ``doppler_sigmas`` standard deviations
    of the predicted one (micro-Doppler, clutter).  Returns the number of detections of each slot.
    """
    n_tracks = state.shape[0]
    count = np.zeros(n_tracks, dtype=np.int64)
    sum_x = np.zeros(n_tracks)
    sum_y = np.zeros(n_tracks)
    for i in range(track.shape[0]):
        k = track[i]
        if k >= 0:
            count[k] += 1
            sum_x[k] += x[i]
            sum_y[k] += y[i]
    h = np.zeros(4)
    for k in range(n_tracks):
        if count[k] == 0:
            continue
        h[:] = 0.0
        h[0] = 1.0
        _scalar_update(state[k], cov[k], h, sum_x[k] / count[k], r_pos)
        h[0] = 0.0
        h[1] = 1.0
        _scalar_update(state[k], cov[k], h, sum_y[k] / count[k], r_pos)
    for i in range(track.shape[0]):
        k = track[i]
        if k < 0:
            continue
        c, s = np.cos(los[i]), np.sin(los[i])
        p = cov[k]
        spread = r_vr + c * c * p[2, 2] + 2.0 * c * s * p[2, 3] + s * s * p[3, 3]
        residual = v_r[i] - c * state[k, 2] - s * state[k, 3]
        if residual * residual > doppler_sigmas * doppler_sigmas * spread:
            continue
        h[:] = 0.0
        h[2] = c
        h[3] = s
        _scalar_update(state[k], cov[k], h, v_r[i], r_vr)
    return count


@numba.njit(cache=True, nogil=True)
def centroid_distances(cx, cy, state, cov, r_pos):
    """Squared Mahalanobis distance of each centroid (rows) to each track's predicted position (columns)."""
    out = np.empty((cx.shape[0], state.shape[0]))
    for k in range(state.shape[0]):
        a = cov[k, 0, 0] + r_pos
        b = cov[k, 0, 1]
        d = cov[k, 1, 1] + r_pos
        det = a * d - b * b
        for m in range(cx.shape[0]):
            dx = cx[m] - state[k, 0]
            dy = cy[m] - state[k, 1]
            out[m, k] = (d * dx * dx - 2.0 * b * dx * dy + a * dy * dy) / det
    return out


@numba.njit(cache=True, nogil=True)
def doppler_misfit(v_r, los, cluster, n_clusters, state):
    """Per (cluster, track): the mean absolute Doppler residual |v_r - u . v| of the cluster's detections, m/s."""
    out = np.zeros((n_clusters, state.shape[0]))
    count = np.zeros(n_clusters)
    for i in range(v_r.shape[0]):
        m = cluster[i]
        if m < 0:
            continue
        count[m] += 1.0
        c, s = np.cos(los[i]), np.sin(los[i])
        for k in range(state.shape[0]):
            out[m, k] += abs(v_r[i] - c * state[k, 2] - s * state[k, 3])
    for m in range(n_clusters):
        if count[m] > 0:
            out[m] /= count[m]
    return out


@numba.njit(cache=True, nogil=True)
def nearest_agreeing(x, y, v_r, los, rows, state, eligible, radius, doppler_gate):
    """For each detection in ``rows``: the nearest eligible track within ``radius`` m whose velocity explains its
    Doppler within ``doppler_gate`` m/s (-1: none)."""
    out = np.full(rows.shape[0], -1, dtype=np.int64)
    r2 = radius * radius
    for j in range(rows.shape[0]):
        i = rows[j]
        c, s = np.cos(los[i]), np.sin(los[i])
        best = r2
        for k in range(state.shape[0]):
            if not eligible[k]:
                continue
            dx = x[i] - state[k, 0]
            dy = y[i] - state[k, 1]
            d2 = dx * dx + dy * dy
            if d2 <= best and abs(v_r[i] - c * state[k, 2] - s * state[k, 3]) <= doppler_gate:
                best = d2
                out[j] = k
    return out
