"""The Doppler-density filter (Eq. 1) on a live stream: each scan counted against the past ``dt`` only."""

from __future__ import annotations

import numba
import numpy as np

from ._merger import TimeColumns


@numba.njit(cache=True, nogil=True)
def _keep_new(x, y, t, v_r, first_new, radius2, before, speed_limits, min_neighbors):
    """Eq. 1 for the points ``[first_new, n)`` (one scan, one time), counted among the points before them.

    ``t`` is sorted; a point j counts for i when ``t_i - before <= t_j <= t_i``,
    ``(x_j - x_i)^2 + (y_j - y_i)^2 <= radius2`` (m^2) and ``j != i``: the
    offline causal count (its cap changes no decision of Eq. 1).  Point i
    is removed when it has no neighbour, or when ``|v_r| < speed_limits[k]``
    (m/s: ``vr_threshold / threshold_ratios[k]``) and fewer than
    ``min_neighbors[k]`` for some k: the rule of
    :func:`~sklearn_radar.preprocessing.doppler_density_keep`, with the
    same comparisons, as one compiled loop (its cost: :ref:`online-speed`).
    """
    low = np.searchsorted(t, t[first_new] - before)
    keep = np.empty(len(t) - first_new, dtype=np.bool_)
    for k in range(len(keep)):
        xi, yi = x[first_new + k], y[first_new + k]
        count = -1  # each point is within 0 m of itself
        for j in range(low, len(t)):
            count += (x[j] - xi) ** 2 + (y[j] - yi) ** 2 <= radius2
        remove = count < 1
        speed = abs(v_r[k])
        for rule in range(len(speed_limits)):
            remove |= speed < speed_limits[rule] and count < min_neighbors[rule]
        keep[k] = not remove
    return keep


class FilterWindow:
    """The detections of one sequence within the last ``dt`` (s), and Eq. 1 for each new scan.

    Times are kept relative to the sequence's first scan, the origin the
    offline filter uses (``t - t.min()`` over the sequence, equal for a
    stream in time order), so that the window edges round alike.
    """

    def __init__(self, filter_):
        self.d_xy = float(filter_.d_xy)
        self.dt = float(filter_.dt)
        self.vr_threshold = filter_.vr_threshold
        ratios, min_neighbors = filter_._rule()
        # vr_threshold / ratio as the numpy rule computes it (a scalar per ratio), compared in the compiled loop.
        self.speed_limits = np.array([self.vr_threshold / ratio for ratio in ratios], dtype=np.float64)
        self.min_neighbors = np.ascontiguousarray(min_neighbors, dtype=np.int64)
        self.origin = None
        self.window = TimeColumns(("t", "x", "y"))  # s relative to the origin, m, m

    def keep(self, x, y, t, v_r):
        """Eq. 1 for a new scan (``t``: its times, s); the scan joins the window."""
        if self.origin is None:
            self.origin = float(t[0]) if len(t) else None
        if len(t) == 0:
            return np.zeros(0, dtype=bool)
        relative = t - self.origin
        self.window.drop_before(relative[0] - self.dt)
        self.window.append({"t": relative, "x": x, "y": y})
        w = self.window
        first_new = len(w) - len(t)
        v_r = np.ascontiguousarray(v_r, dtype=np.float64)
        radius2 = self.d_xy**2
        return _keep_new(
            w["x"], w["y"], w["t"], v_r, first_new, radius2, self.dt, self.speed_limits, self.min_neighbors
        )
