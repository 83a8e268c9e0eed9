"""The neighbourhood of each detection: counts, Doppler and RCS statistics within a radius and a time window.

The features of the point-wise baseline with ``radius`` set (:class:`PointClassifier`): what a point-wise
learner that sees each detection's surroundings (PointNet++ and its successors group the points within a
radius) can know without any clustering.  The neighbours of detection ``i`` are the detections ``j`` of
its sequence (itself included) with ``(x_j - x_i)^2 + (y_j - y_i)^2 <= radius^2`` and
``|t_j - t_i| <= time_window`` (offline), or ``t_i - time_window <= t_j <= t_i`` (``causal``: the past
only).  The pairs are found with a k-d tree on ``(x, y, t * radius / time_window)`` under the maximum norm
(a box that holds every neighbour) and then checked exactly; the statistics are sums over the pairs
(``bincount``), so no Python loop runs over detections.
"""

from __future__ import annotations

import itertools

import numpy as np
from scipy.spatial import cKDTree

#: ``{feature: (unit, meaning)}`` of the neighbourhood, in the order of the feature rows.
NEIGHBOURHOOD_FEATURES = {
    "nb_count": ("detections", "neighbours, the detection itself included"),
    "nb_spread": ("m", "RMS x-y distance of the neighbours to their centroid"),
    "nb_vr_mean": ("m/s", "mean compensated Doppler of the neighbours"),
    "nb_vr_std": ("m/s", "standard deviation of the neighbours' compensated Doppler (the Doppler spread)"),
    "nb_rcs_mean": ("dBsm", "mean RCS of the neighbours"),
    "nb_rcs_std": ("dB", "standard deviation of the neighbours' RCS"),
    "nb_rcs_max": ("dBsm", "largest RCS among the neighbours"),
}


def _directed_pairs(x, y, t, radius, time_window, causal):
    """Every (centre, neighbour) pair of one sequence's detections, the detection itself included."""
    n = len(x)
    points = np.column_stack([x, y, t * (radius / time_window)])
    pairs = cKDTree(points).query_pairs(radius * (1 + 1e-9), p=np.inf, output_type="ndarray")
    i, j = pairs[:, 0].astype(np.int64), pairs[:, 1].astype(np.int64)
    close = (x[i] - x[j]) ** 2 + (y[i] - y[j]) ** 2 <= radius**2
    close &= np.abs(t[i] - t[j]) <= time_window
    i, j = i[close], j[close]
    centre = np.concatenate([np.arange(n), i, j])
    other = np.concatenate([np.arange(n), j, i])
    if causal:
        past = t[other] <= t[centre]
        centre, other = centre[past], other[past]
    return centre, other


def neighbourhood_features(c, rows, radius, time_window, causal):
    """The :data:`NEIGHBOURHOOD_FEATURES` of the detections ``rows`` among themselves, per sequence.

    Parameters
    ----------
    c : dict of str to ndarray or None
        The columns (``x``, ``y`` in m, ``t`` in s, ``v_r`` in m/s, ``rcs`` in dBsm or None, ``sequence`` or
        None).
    rows : ndarray of int64
        The detections that take part (those the filter kept), as centres and as neighbours.
    radius : float
        x-y radius, m, > 0.
    time_window : float
        Half-width of the time window (offline) or its length into the past (causal), s, > 0.
    causal : bool
        Neighbours from the past (and the same instant) only.

    Returns
    -------
    features : dict of str to ndarray
        One value per row of ``rows``; the RCS features only when ``rcs`` is present.
    """
    n = len(rows)
    sequence = np.zeros(len(c["x"])) if c["sequence"] is None else c["sequence"]
    local = {name: c[name][rows] for name in ("x", "y", "t", "v_r")}
    rcs = None if c["rcs"] is None else c["rcs"][rows]
    centres, others = [], []
    for members in _positions_by_value(sequence[rows]):
        centre, other = _directed_pairs(
            local["x"][members], local["y"][members], local["t"][members], radius, time_window, causal
        )
        centres.append(members[centre])
        others.append(members[other])
    centre = np.concatenate(centres) if centres else np.zeros(0, dtype=np.int64)
    other = np.concatenate(others) if others else np.zeros(0, dtype=np.int64)

    count = np.bincount(centre, minlength=n).astype(np.float64)

    def mean_and_std(values):
        mean = np.bincount(centre, weights=values[other], minlength=n) / np.maximum(count, 1)
        square = np.bincount(centre, weights=(values[other] - mean[centre]) ** 2, minlength=n)
        return mean, np.sqrt(square / np.maximum(count, 1))

    x_std = mean_and_std(local["x"])[1]
    y_std = mean_and_std(local["y"])[1]
    features = {"nb_count": count, "nb_spread": np.hypot(x_std, y_std)}
    features["nb_vr_mean"], features["nb_vr_std"] = mean_and_std(local["v_r"])
    if rcs is not None:
        features["nb_rcs_mean"], features["nb_rcs_std"] = mean_and_std(rcs)
        rcs_max = np.full(n, -np.inf)
        np.maximum.at(rcs_max, centre, rcs[other])
        features["nb_rcs_max"] = rcs_max
    return features


def _positions_by_value(values):
    """The positions of each distinct value of ``values``, as arrays (stable order)."""
    if not len(values):
        return []
    order = np.argsort(values, kind="stable")
    bounds = np.flatnonzero(np.r_[True, values[order][1:] != values[order][:-1], True])
    return [order[start:end] for start, end in itertools.pairwise(bounds)]
