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


@numba.njit(cache=True, nogil=True)
def all_finite(values):
    """Whether every value of a 1-D array is finite (no NaN, no infinity)."""
    for i in range(values.shape[0]):
        if not np.isfinite(values[i]):
            return False
    return True


@numba.njit(cache=True, nogil=True)
def first_not_finite(x, y, v_r, los):
    """Index of the first of the four columns holding a value that is not finite, -1 if none."""
    if not all_finite(x):
        return 0
    if not all_finite(y):
        return 1
    if not all_finite(v_r):
        return 2
    if not all_finite(los):
        return 3
    return -1


@numba.njit(cache=True, nogil=True)
def advance(state, cov, ids, hits, last, confirmed, n, dt, q, t, max_age):
    """Predict the first ``n`` tracks ``dt`` s ahead, then drop those without a cluster for more than ``max_age`` s.

    The kept tracks move down in place, in their order; returns their number.
    """
    predict(state, cov, n, dt, q)
    kept = 0
    for k in range(n):
        if not (t - last[k] <= max_age):
            continue
        if kept != k:
            state[kept] = state[k]
            cov[kept] = cov[k]
            ids[kept] = ids[k]
            hits[kept] = hits[k]
            last[kept] = last[k]
            confirmed[kept] = confirmed[k]
        kept += 1
    return kept


@numba.njit(cache=True, nogil=True)
def drop_links(code, track, time, n_links, oldest):
    """Keep the first ``n_links`` links seen at ``oldest`` s or later, in place and in order; returns their number."""
    kept = 0
    for j in range(n_links):
        if time[j] >= oldest:
            code[kept], track[kept], time[kept] = code[j], track[j], time[j]
            kept += 1
    return kept


@numba.njit(cache=True, nogil=True)
def group(clusters, x, y, link_code, link_track, n_links, ids, n):
    """The clusters of a scan: their ids (increasing), each detection's cluster (-1: noise), centroids, linked slots.

    ``link_code[:n_links]`` (increasing) are the cluster ids seen before and ``link_track`` their track ids;
    ``ids[:n]`` (increasing) the live tracks' ids.  Returns ``codes``, ``member``, ``cx``, ``cy`` (m, the mean
    of each cluster's detections, summed in row order), ``of_cluster``: the slot of the live track a cluster
    id is linked to, -1 for none, and the number of clusters without one.
    """
    n_rows = clusters.shape[0]
    values = np.empty(n_rows, dtype=np.int64)
    m = 0
    for i in range(n_rows):
        if clusters[i] >= 0:
            values[m] = clusters[i]
            m += 1
    values = np.sort(values[:m])
    codes = np.empty(m, dtype=np.int64)
    n_codes = 0
    for j in range(m):
        if n_codes == 0 or values[j] != codes[n_codes - 1]:
            codes[n_codes] = values[j]
            n_codes += 1
    codes = codes[:n_codes]
    member = np.full(n_rows, -1, dtype=np.int64)
    count = np.zeros(n_codes)
    cx = np.zeros(n_codes)
    cy = np.zeros(n_codes)
    for i in range(n_rows):
        if clusters[i] >= 0:
            j = np.searchsorted(codes, clusters[i])
            member[i] = j
            count[j] += 1.0
            cx[j] += x[i]
            cy[j] += y[i]
    of_cluster = np.full(n_codes, -1, dtype=np.int64)
    n_free = n_codes
    for j in range(n_codes):
        cx[j] /= count[j]
        cy[j] /= count[j]
        at = np.searchsorted(link_code[:n_links], codes[j])
        if at < n_links and link_code[at] == codes[j]:
            slot = np.searchsorted(ids[:n], link_track[at])
            if slot < n and ids[slot] == link_track[at]:
                of_cluster[j] = slot
                n_free -= 1
    return codes, member, cx, cy, of_cluster, n_free


@numba.njit(cache=True, nogil=True)
def gate(cx, cy, of_cluster, member, v_r, los, state, cov, confirmed, n, r_pos, gate2, doppler_gate, ungated):
    """Gating of the clusters without a track (``free``) against the first ``n`` tracks.

    Returns ``free``, the squared Mahalanobis distances ``cost`` (free clusters x tracks), ``inside`` (within
    ``gate2`` and, for a confirmed track, a mean Doppler residual within ``doppler_gate``) and the assignment
    cost: ``cost`` inside the gate of a track no linked cluster took, ``ungated`` elsewhere.
    """
    free = np.flatnonzero(of_cluster < 0)
    cost = centroid_distances(cx[free], cy[free], state[:n], cov[:n], r_pos)
    inside = cost <= gate2
    if confirmed[:n].any():
        local = np.full(of_cluster.shape[0], -1, dtype=np.int64)
        local[free] = np.arange(free.shape[0])
        row_local = np.full(member.shape[0], -1, dtype=np.int64)
        for i in range(member.shape[0]):
            if member[i] >= 0:
                row_local[i] = local[member[i]]
        misfit = doppler_misfit(v_r, los, row_local, free.shape[0], state[:n])
        for a in range(free.shape[0]):
            for k in range(n):
                inside[a, k] = inside[a, k] and ((not confirmed[k]) or misfit[a, k] <= doppler_gate)
    taken = np.zeros(n, dtype=np.bool_)
    for j in range(of_cluster.shape[0]):
        if of_cluster[j] >= 0:
            taken[of_cluster[j]] = True
    open_cost = np.full(cost.shape, ungated)
    for a in range(free.shape[0]):
        for k in range(n):
            if inside[a, k] and not taken[k]:
                open_cost[a, k] = cost[a, k]
    return free, cost, inside, open_cost


@numba.njit(cache=True, nogil=True)
def assign(rows, cols, open_cost, cost, inside, confirmed, free, of_cluster, ungated):
    """Give the free clusters their assigned tracks (pairs within the gate); a cluster left over joins the
    confirmed track within whose gate it is nearest, if any (a split cluster).  In place on ``of_cluster``;
    returns the number of free clusters still without a track."""
    for a in range(rows.shape[0]):
        if open_cost[rows[a], cols[a]] < ungated:
            of_cluster[free[rows[a]]] = cols[a]
    n_left = 0
    for a in range(free.shape[0]):
        if of_cluster[free[a]] >= 0:
            continue
        best, best_cost = -1, np.inf
        for k in range(cost.shape[1]):
            if inside[a, k] and confirmed[k] and cost[a, k] < best_cost:
                best, best_cost = k, cost[a, k]
        if best >= 0:
            of_cluster[free[a]] = best
        else:
            n_left += 1
    return n_left


@numba.njit(cache=True, nogil=True)
def start_tracks(state, cov, ids, hits, last, confirmed, n, of_cluster, cx, cy, next_id, r_pos, speed_var):
    """A tentative track at the centroid of each cluster without one (``of_cluster`` -1), in the slots from
    ``n`` on, with ids from ``next_id`` on, in cluster order; ``of_cluster`` gets their slots.  Returns the new n."""
    for j in range(of_cluster.shape[0]):
        if of_cluster[j] >= 0:
            continue
        state[n] = 0.0
        state[n, 0] = cx[j]
        state[n, 1] = cy[j]
        cov[n] = 0.0
        cov[n, 0, 0] = cov[n, 1, 1] = r_pos
        cov[n, 2, 2] = cov[n, 3, 3] = speed_var
        ids[n] = next_id
        next_id += 1
        hits[n] = 0
        last[n] = np.nan
        confirmed[n] = False
        of_cluster[j] = n
        n += 1
    return n


@numba.njit(cache=True, nogil=True)
def store_links(code, track, time, n_links, codes, track_ids, t):
    """Link each of ``codes`` (increasing) to its track id at time ``t``: the sorted links ``code[:n_links]``
    (room for all of ``codes`` after them) merged in place.  Returns the new number of links."""
    n_new = 0
    for j in range(codes.shape[0]):
        at = np.searchsorted(code[:n_links], codes[j])
        if at == n_links or code[at] != codes[j]:
            n_new += 1
    i, j, write = n_links - 1, codes.shape[0] - 1, n_links + n_new - 1
    while j >= 0:
        if i >= 0 and code[i] > codes[j]:
            code[write], track[write], time[write] = code[i], track[i], time[i]
            i -= 1
        else:
            if i >= 0 and code[i] == codes[j]:
                i -= 1
            code[write], track[write], time[write] = codes[j], track_ids[j], t
            j -= 1
        write -= 1
    return n_links + n_new


@numba.njit(cache=True, nogil=True)
def finish(state, cov, ids, hits, last, confirmed, n, member, of_cluster, x, y, v_r, los, t, noise_radius, params):
    """Kalman update of the tracks with their detections, hits and confirmation, noise ids; the track id per row.

    ``params``: ``r_pos``, ``r_vr``, ``doppler_sigmas``, ``min_hits``, ``doppler_gate``; ``noise_radius`` < 0:
    noise stays -1.
    """
    r_pos, r_vr, doppler_sigmas, min_hits, doppler_gate = params
    n_rows = member.shape[0]
    slot = np.full(n_rows, -1, dtype=np.int64)
    n_noise = 0
    for i in range(n_rows):
        if member[i] >= 0:
            slot[i] = of_cluster[member[i]]
        else:
            n_noise += 1
    count = update(state[:n], cov[:n], slot, x, y, v_r, los, r_pos, r_vr, doppler_sigmas)
    any_confirmed = False
    for k in range(n):
        if count[k] > 0:
            hits[k] += 1
            last[k] = t
        confirmed[k] |= hits[k] >= min_hits
        any_confirmed |= confirmed[k]
    if noise_radius >= 0.0 and any_confirmed and n_noise:
        noise = np.flatnonzero(member < 0)
        slot[noise] = nearest_agreeing(x, y, v_r, los, noise, state[:n], confirmed[:n], noise_radius, doppler_gate)
    track_id = np.full(n_rows, -1, dtype=np.int64)
    for i in range(n_rows):
        if slot[i] >= 0 and confirmed[slot[i]]:
            track_id[i] = ids[slot[i]]
    return track_id
