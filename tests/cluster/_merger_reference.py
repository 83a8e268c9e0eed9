"""A plain per-pair implementation of ClusterMerger's criteria, written for reading, not speed.

It follows the docstring of :class:`ClusterMerger` pair by pair with numpy
(``np.linalg.solve`` on a Vandermonde matrix for the cubic, ``np.polyfit``
for the line) so that the numba kernels can be compared against it.
"""

import numpy as np

from sklearn_radar.cluster._velocity import estimate_velocity


def _per_cluster_rows(labels, t):
    """{label: rows sorted by (time, row)}."""
    clusters = {}
    for label in np.unique(labels[labels >= 0]):
        rows = np.flatnonzero(labels == label)
        clusters[int(label)] = rows[np.argsort(t[rows], kind="stable")]
    return clusters


def _smooth(values):
    """Centred 3-point moving average whose window shrinks symmetrically at the ends."""
    n = len(values)
    out = np.empty(n)
    for i in range(n):
        half = min(i, n - 1 - i, 1)
        out[i] = values[i - half : i + half + 1].mean()
    return out


def reference_continuation(rows, x, y, t):
    """(end time, end centre, end velocity) of the smoothed per-scan centre track of ``rows``."""
    times = np.unique(t[rows])
    cx = np.array([x[rows][t[rows] == s].mean() for s in times])
    cy = np.array([y[rows][t[rows] == s].mean() for s in times])
    if len(times) == 1:
        return times[0], np.array([cx[0], cy[0]]), np.array([np.nan, np.nan])
    sx, sy = _smooth(cx), _smooth(cy)
    k = min(4, len(times))
    lag = times[-k:] - times[-1]
    values = np.c_[sx[-k:], sy[-k:]]
    if k == 4:
        velocity = np.linalg.solve(np.vander(lag, 4, increasing=True), values)[1]
    else:
        velocity = np.polyfit(lag, values, 1)[0]
    return times[-1], np.array([sx[-1], sy[-1]]), velocity


def _start_key(rows, x, y, t, v_r, los):
    """ClusterMerger's documented order of clusters: by the values (t, x, y, v_r, line of sight) of the
    smallest such tuple among their detections, then by size; never by label ids, which follow the rows."""
    first = min((t[r], x[r], y[r], v_r[r], los[r]) for r in rows)
    return (*first, len(rows))


def reference_merges(labels, x, y, t, v_r, los, *, mode, eps_d, eps_phi, eps_v, eps_t2, unknown_velocity):
    """Set of (label A, label B) pairs that meet the criterion, for one sequence."""
    clusters = _per_cluster_rows(labels, t)
    ids = sorted(clusters, key=lambda label: _start_key(clusters[label], x, y, t, v_r, los))
    merges = set()
    for position, b in enumerate(ids):
        rows_b_all = clusters[b]
        start_b = t[rows_b_all[0]]
        tau = min(t[rows_b_all[-1]], start_b + eps_t2)
        rows_b = rows_b_all[t[rows_b_all] <= tau]
        for a in ids[:position]:
            past_a = clusters[a][t[clusters[a]] <= tau]
            before_b = past_a[t[past_a] <= start_b]
            gap = 0.0 if len(past_a) > len(before_b) else start_b - t[before_b[-1]]
            if gap >= eps_t2:
                continue
            if mode == "velocity":
                frame_a = past_a[t[past_a] >= start_b - eps_t2]
                if len(frame_a) == 0:
                    continue
                d_min = np.sqrt(
                    ((x[frame_a, None] - x[None, rows_b]) ** 2 + (y[frame_a, None] - y[None, rows_b]) ** 2).min()
                )
                if d_min >= eps_d:
                    continue
                va = np.array(estimate_velocity(v_r[frame_a], los[frame_a])[:2])
                vb = np.array(estimate_velocity(v_r[rows_b], los[rows_b])[:2])
                if not (np.isfinite(va).all() and np.isfinite(vb).all()):
                    merge = unknown_velocity == "accept"
                else:
                    dphi = abs((np.arctan2(va[1], va[0]) - np.arctan2(vb[1], vb[0]) + np.pi) % (2 * np.pi) - np.pi)
                    merge = dphi < eps_phi and abs(np.hypot(*va) - np.hypot(*vb)) < eps_v
            else:
                end_a, pa, va = reference_continuation(past_a, x, y, t)
                end_b, pb, vb = reference_continuation(rows_b, x, y, t)
                at = start_b + np.array([0.0, 0.5, 1.0]) * eps_t2
                gaps = (pa + (at[:, None] - end_a) * np.nan_to_num(va)) - (
                    pb + (at[:, None] - end_b) * np.nan_to_num(vb)
                )
                if np.hypot(gaps[:, 0], gaps[:, 1]).min() >= eps_d:
                    continue
                if not (np.isfinite(va).all() and np.isfinite(vb).all()):
                    merge = unknown_velocity == "accept"
                else:
                    merge = np.hypot(*(va - vb)) < eps_v
            if merge:
                merges.add((a, b))
    return merges
