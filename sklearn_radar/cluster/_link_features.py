"""Features of LinkClustering: per-detection neighbourhoods and symmetric features of candidate pairs (numpy).

Everything here works on the kept detections of one sequence, in a fixed
order (the estimator sorts them by time, position and Doppler first), so
that the features do not depend on the row order of the input.  A
neighbourhood is every other detection within a radius in x-y (m) and a
window in time (s), past and future; pairs are enumerated with a k-d tree
(:class:`scipy.spatial.cKDTree`) on ``(x, y, t * radius / window)`` and
filtered exactly.  The local rigid velocity is the model of Eq. 6 (each
detection's Doppler is the projection of one velocity on its line of
sight) fitted to the moving neighbours.

A measurement that X lacks (``rcs``, ``range_sc``, ``sensor_id``,
``ego_vx``, the line of sight ``azimuth_sc`` + ``sensor_yaw``) is NaN here; the features that
need it are NaN and the estimator leaves them out.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.spatial import cKDTree

#: m, s: the neighbourhood of the per-detection features.
LOCAL_RADIUS, LOCAL_WINDOW = 2.5, 0.15
#: m, s: the small neighbourhood (its count is a feature of its own).
NEAR_RADIUS, NEAR_WINDOW = 1.0, 0.1
#: m/s: neighbours faster than this enter the local rigid-velocity fit.
V_MOVING = 0.2
#: m/s: two Doppler values closer than this count as similar.
V_SIMILAR = 0.5
#: Ridge weight (in detections) pulling the local velocity towards the detection's own radial velocity.
RIDGE = 0.3
#: m/s: the largest speed a pair's two Doppler values may imply (beyond it the lines of sight are near parallel).
MAX_IMPLIED_SPEED = 60.0

#: ``{feature: (unit, meaning, measurements it needs)}`` of one detection, in the order of the feature columns.
DETECTION_FEATURES = {
    "abs_v_r": ("m/s", "|compensated Doppler|", ()),
    "v_r": ("m/s", "compensated Doppler", ()),
    "rcs": ("dBsm", "radar cross section", ("rcs",)),
    "range": ("m", "range to the sensor", ("range",)),
    "ego_speed": ("m/s", "|ego speed|", ("ego",)),
    "n_local": ("", "neighbours within 2.5 m and 0.15 s", ()),
    "n_near": ("", "neighbours within 1 m and 0.1 s", ()),
    "n_similar": ("", "local neighbours whose Doppler differs by less than 0.5 m/s", ()),
    "n_moving": ("", "local neighbours faster than 0.2 m/s", ()),
    "mean_abs_v_r": ("m/s", "mean |Doppler| of the local neighbours", ()),
    "spread_v_r": ("m/s", "standard deviation of the local neighbours' Doppler", ()),
    "speed": ("m/s", "speed of the local rigid velocity (Eq. 6)", ("los",)),
    "tangential": ("m/s", "local velocity across the line of sight", ("los",)),
    "residual": ("m/s", "RMS Doppler residual of the local velocity fit", ("los",)),
    "sensor": ("", "sensor id", ("sensor",)),
}

#: ``{feature: (unit, meaning, measurements it needs)}`` of a pair, in the order of the feature columns; every
#: feature is symmetric in the two detections (``lo_``/``hi_``: the smaller and larger of their two values).
PAIR_FEATURES = {
    "distance": ("m", "distance in x-y", ()),
    "abs_dt": ("s", "time difference", ()),
    "abs_dv_r": ("m/s", "Doppler difference", ()),
    "min_cross_residual": (
        "m/s",
        "the smaller error of one side's local velocity predicting the other's Doppler",
        ("los",),
    ),
    "max_cross_residual": ("m/s", "the larger one", ("los",)),
    "implied_speed": ("m/s", "speed of the velocity that both Doppler values imply (capped)", ("los",)),
    "los_sine": ("", "|sine of the angle between the two lines of sight|", ("los",)),
    "velocity_difference": ("m/s", "difference of the two local velocities", ("los",)),
    "motion_offset": ("m", "offset left after moving one detection by the mean local velocity", ("los",)),
    "mean_range": ("m", "mean range to the sensors", ("range",)),
    "same_sensor": ("", "1 when both come from one sensor", ("sensor",)),
    "lo_rcs": ("dBsm", "smaller RCS", ("rcs",)),
    "hi_rcs": ("dBsm", "larger RCS", ("rcs",)),
    "lo_n_local": ("", "smaller neighbour count", ()),
    "hi_n_local": ("", "larger neighbour count", ()),
    "lo_spread_v_r": ("m/s", "smaller local Doppler spread", ()),
    "hi_spread_v_r": ("m/s", "larger local Doppler spread", ()),
    "lo_objectness": ("", "smaller P(road user)", ()),
    "hi_objectness": ("", "larger P(road user)", ()),
    "lo_abs_v_r": ("m/s", "smaller |Doppler|", ()),
    "hi_abs_v_r": ("m/s", "larger |Doppler|", ()),
}


class Detections(NamedTuple):
    """The kept detections of one sequence, float64 arrays of equal length (NaN: not measured).

    Attributes
    ----------
    x, y : ndarray
        Working coordinates, m.
    t : ndarray
        Time, s.
    v : ndarray
        Ego-motion-compensated radial velocity, m/s.
    los : ndarray
        Line of sight in the working frame, rad (``azimuth_sc + sensor_yaw + heading``).
    rcs : ndarray
        Radar cross section, dBsm.
    range : ndarray
        Range to the sensor, m.
    sensor : ndarray
        Sensor id.
    ego : ndarray
        Ego speed, m/s.
    """

    x: np.ndarray
    y: np.ndarray
    t: np.ndarray
    v: np.ndarray
    los: np.ndarray
    rcs: np.ndarray
    range: np.ndarray
    sensor: np.ndarray
    ego: np.ndarray


class LocalMotion(NamedTuple):
    """What the pair features reuse of the per-detection features, arrays of shape (n,).

    Attributes
    ----------
    vx, vy : ndarray
        Local rigid velocity, m/s (NaN without lines of sight).
    count : ndarray
        Neighbours within ``LOCAL_RADIUS`` and ``LOCAL_WINDOW``.
    spread : ndarray
        Standard deviation of their Doppler, m/s.
    """

    vx: np.ndarray
    vy: np.ndarray
    count: np.ndarray
    spread: np.ndarray


def pairs_within(x, y, t, radius, window, subset=None):
    """Pairs ``i < j`` with planar distance <= ``radius`` (m) and ``|t_i - t_j| <= window`` (s).

    Parameters
    ----------
    x, y, t : ndarray of float64, shape (n,)
        Positions, m, and times, s.
    radius : float
        m, > 0.
    window : float
        s, >= 0.
    subset : ndarray of bool, shape (n,), default=None
        Only these detections take part; None: all.

    Returns
    -------
    i, j : ndarray of int64
        Indices into the arrays, ``i < j``, sorted by ``(i, j)``.
    """
    idx = np.arange(len(x)) if subset is None else np.flatnonzero(subset)
    if len(idx) < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    # Time scaled so that the window spans the radius: the box of (radius, window) lies in a ball of radius * sqrt 2.
    scale = radius / window if window > 0 else 0.0
    points = np.column_stack([x[idx], y[idx], (t[idx] - t[idx].min()) * scale])
    found = cKDTree(points).query_pairs(radius * np.sqrt(2.0) * (1 + 1e-9), output_type="ndarray")
    i, j = idx[found[:, 0]], idx[found[:, 1]]
    i, j = np.minimum(i, j), np.maximum(i, j)
    ok = (np.hypot(x[i] - x[j], y[i] - y[j]) <= radius) & (np.abs(t[i] - t[j]) <= window)
    i, j = i[ok], j[ok]
    order = np.lexsort((j, i))
    return i[order].astype(np.int64), j[order].astype(np.int64)


def _both(i, j):
    return np.concatenate([i, j]), np.concatenate([j, i])


def detection_features(d: Detections):
    """Per-detection features (:data:`DETECTION_FEATURES`) and the local motion the pair features reuse.

    Parameters
    ----------
    d : Detections
        The kept detections of one sequence.

    Returns
    -------
    features : ndarray of float64, shape (n, len(DETECTION_FEATURES))
    local : LocalMotion
    """
    x, y, t, v = d.x, d.y, d.t, d.v
    n = len(x)
    src, dst = _both(*pairs_within(x, y, t, LOCAL_RADIUS, LOCAL_WINDOW))
    count = np.bincount(src, minlength=n).astype(np.float64)
    per = np.maximum(count, 1.0)
    similar = np.bincount(src, weights=np.abs(v[src] - v[dst]) < V_SIMILAR, minlength=n)
    moving = (np.abs(v[dst]) > V_MOVING).astype(np.float64)
    n_moving = np.bincount(src, weights=moving, minlength=n)
    mean_v = np.bincount(src, weights=v[dst], minlength=n) / per
    mean_sq = np.bincount(src, weights=v[dst] ** 2, minlength=n) / per
    spread = np.sqrt(np.maximum(mean_sq - mean_v**2, 0.0))
    mean_abs = np.bincount(src, weights=np.abs(v[dst]), minlength=n) / per
    near = np.bincount(_both(*pairs_within(x, y, t, NEAR_RADIUS, NEAR_WINDOW))[0], minlength=n).astype(np.float64)
    vx, vy, residual = _local_velocity(d, src, dst, moving, n_moving)
    c, s = np.cos(d.los), np.sin(d.los)
    features = np.column_stack(
        [
            np.abs(v),
            v,
            d.rcs,
            d.range,
            np.abs(d.ego),
            count,
            near,
            similar,
            n_moving,
            mean_abs,
            spread,
            np.hypot(vx, vy),
            -vx * s + vy * c,
            residual,
            d.sensor,
        ]
    )
    return features, LocalMotion(vx=vx, vy=vy, count=count, spread=spread)


def _local_velocity(d, src, dst, moving, n_moving):
    """Eq. 6's rigid velocity ``V`` (``v_r = u . V``) of each detection's moving neighbours and itself.

    A least-squares fit, ridge-regularised towards the radial-only solution
    ``v u`` (weight :data:`RIDGE`), and the RMS Doppler residual of the fit.
    """
    n = len(d.x)
    v = d.v
    c, s = np.cos(d.los), np.sin(d.los)
    cd, sd, vd = c[dst], s[dst], v[dst]

    def total(weights, own):
        return np.bincount(src, weights=moving * weights, minlength=n) + own

    a11, a12, a22 = total(cd**2, c**2), total(cd * sd, c * s), total(sd**2, s**2)
    b1, b2, vv = total(vd * cd, v * c), total(vd * sd, v * s), total(vd**2, v**2)
    r1, r2 = b1 + RIDGE * v * c, b2 + RIDGE * v * s
    m11, m22 = a11 + RIDGE, a22 + RIDGE
    det = m11 * m22 - a12**2  # >= RIDGE**2 > 0: the ridge keeps the system regular
    vx, vy = (m22 * r1 - a12 * r2) / det, (m11 * r2 - a12 * r1) / det
    squares = vv - 2 * (vx * b1 + vy * b2) + vx**2 * a11 + 2 * vx * vy * a12 + vy**2 * a22
    return vx, vy, np.sqrt(np.maximum(squares, 0.0) / (n_moving + 1))


def pair_features(d: Detections, local: LocalMotion, objectness, i, j):
    """Symmetric features (:data:`PAIR_FEATURES`) of the candidate pairs ``(i, j)`` of one sequence.

    Parameters
    ----------
    d : Detections
        The kept detections of the sequence.
    local : LocalMotion
        Of :func:`detection_features`.
    objectness : ndarray of float64, shape (n,)
        P(road user) of each detection.
    i, j : ndarray of int64, shape (n_pairs,)
        The pairs.

    Returns
    -------
    features : ndarray of float64, shape (n_pairs, len(PAIR_FEATURES))
    """
    x, y, t, v = d.x, d.y, d.t, d.v
    dx, dy, dt = x[j] - x[i], y[j] - y[i], t[j] - t[i]
    c, s = np.cos(d.los), np.sin(d.los)
    vx, vy = local.vx, local.vy
    # Consistency of both Doppler values with one rigid velocity: each side's local velocity predicts the other's
    # Doppler; and the velocity that the two Doppler values alone imply (a 2 x 2 solve, large when inconsistent).
    res_ij = np.abs(v[j] - (c[j] * vx[i] + s[j] * vy[i]))
    res_ji = np.abs(v[i] - (c[i] * vx[j] + s[i] * vy[j]))
    det = c[i] * s[j] - s[i] * c[j]
    safe = np.where(np.abs(det) < 1e-3, np.copysign(1e-3, det + 1e-12), det)
    implied = np.minimum(
        np.hypot((v[i] * s[j] - v[j] * s[i]) / safe, (c[i] * v[j] - c[j] * v[i]) / safe), MAX_IMPLIED_SPEED
    )
    motion = np.hypot(dx - (vx[i] + vx[j]) / 2 * dt, dy - (vy[i] + vy[j]) / 2 * dt)
    columns = [
        np.hypot(dx, dy),
        np.abs(dt),
        np.abs(v[i] - v[j]),
        np.minimum(res_ij, res_ji),
        np.maximum(res_ij, res_ji),
        implied,
        np.abs(det),
        np.hypot(vx[i] - vx[j], vy[i] - vy[j]),
        motion,
        (d.range[i] + d.range[j]) / 2,
        np.where(np.isnan(d.sensor[i] + d.sensor[j]), np.nan, d.sensor[i] == d.sensor[j]),
    ]
    for values in (d.rcs, local.count, local.spread, objectness, np.abs(v)):
        columns += [np.minimum(values[i], values[j]), np.maximum(values[i], values[j])]
    return np.column_stack(columns).reshape(len(i), len(PAIR_FEATURES))


def usable(table, present):
    """Mask of the features of ``table`` whose measurements are all in ``present`` (a set of names)."""
    return np.array([set(needs) <= present for _, _, needs in table.values()], dtype=bool)
