"""Eq. 1, written once: the rule of the Doppler-density filter, for the batch filter and the online window.

:func:`removed_by_eq1` is the rule.  The batch filter
(:class:`~sklearn_radar.preprocessing.DopplerDensityFilter`) applies it to
whole columns with numpy; :func:`keep_new` (the online filter's compiled
loop) counts each new detection's neighbours in the window and applies the
same function, compiled, to that detection.  Read more in the
:ref:`User Guide <user-guide-filter>`.
"""

from __future__ import annotations

import numba
import numpy as np


def speed_limits(vr_threshold, threshold_ratios):
    """The Doppler thresholds ``eta_i = vr_threshold / threshold_ratios[i]`` of Eq. 1, m/s, as float64."""
    return np.array([vr_threshold / ratio for ratio in threshold_ratios], dtype=np.float64)


def removed_by_eq1(speed, n_neighbors, limits, min_neighbors):
    """Eq. 1: True where a detection is removed.

    Removed when ``n_neighbors < 1``, or when ``speed < limits[i]`` and
    ``n_neighbors < min_neighbors[i]`` for some i.  ``speed`` is the absolute
    compensated radial velocity (m/s), ``limits`` the thresholds of
    :func:`speed_limits`.  Element-wise on numpy arrays (the batch filter),
    or on one detection's numbers inside a compiled loop.
    """
    remove = n_neighbors < 1
    for rule in range(len(limits)):
        remove = remove | ((speed < limits[rule]) & (n_neighbors < min_neighbors[rule]))
    return remove


_removed_by_eq1 = numba.njit(cache=True, nogil=True)(removed_by_eq1)


@numba.njit(cache=True, nogil=True)
def keep_new(x, y, t, v_r, first_new, radius2, before, limits, min_neighbors):
    """Eq. 1 for the points ``[first_new, n)`` (one scan, one time), counted among the points before them.

    ``t`` is sorted (s); ``v_r`` (m/s) holds the new points' velocities only.
    A point j counts for i when ``t_i - before <= t_j <= t_i``,
    ``(x_j - x_i)^2 + (y_j - y_i)^2 <= radius2`` (m^2) and ``j != i``: the
    offline causal count (its cap changes no decision of Eq. 1); the count
    of a point stops once it reaches the number past which no rule of Eq. 1
    removes it.  The decision is :func:`removed_by_eq1` (its cost:
    :ref:`online-speed`).
    """
    low = np.searchsorted(t, t[first_new] - before)
    keep = np.empty(len(t) - first_new, dtype=np.bool_)
    for k in range(len(keep)):
        xi, yi, speed = x[first_new + k], y[first_new + k], abs(v_r[k])
        enough = 1  # neighbours past which no rule of Eq. 1 removes this point
        for rule in range(len(limits)):
            if speed < limits[rule] and min_neighbors[rule] > enough:
                enough = min_neighbors[rule]
        count = -1  # each point is within 0 m of itself
        for j in range(low, len(t)):
            count += (x[j] - xi) ** 2 + (y[j] - yi) ** 2 <= radius2
            if count >= enough:
                break  # (before the point itself is met, count is one short: the decision stands all the more)
        keep[k] = not _removed_by_eq1(speed, count, limits, min_neighbors)
    return keep
