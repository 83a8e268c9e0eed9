"""The Doppler-density filter (Eq. 1) on a live stream: each scan counted against the past ``dt`` only."""

from __future__ import annotations

import numba
import numpy as np

from ..preprocessing._doppler_density_filter import _doppler_density_keep


@numba.njit(cache=True, nogil=True)
def _count_past(x, y, t, first_new, radius2, before):
    """Neighbours of the points ``[first_new, n)`` (one scan, one time) among the points before them.

    ``t`` is sorted; a point j counts for i when ``t_i - before <= t_j <= t_i``,
    ``(x_j - x_i)^2 + (y_j - y_i)^2 <= radius2`` (m^2) and ``j != i``: the
    offline causal count (its cap changes no decision of Eq. 1).  A compiled
    loop: twice as fast as the numpy comparison block on a 0.25 s window.
    """
    low = np.searchsorted(t, t[first_new] - before)
    counts = np.full(len(t) - first_new, -1, dtype=np.int64)  # each point is within 0 m of itself
    for k in range(len(counts)):
        xi, yi = x[first_new + k], y[first_new + k]
        for j in range(low, len(t)):
            counts[k] += (x[j] - xi) ** 2 + (y[j] - yi) ** 2 <= radius2
    return counts


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
        self.ratios, self.min_neighbors = filter_._rule()
        self.origin = None
        self.x, self.y, self.t = np.zeros(0), np.zeros(0), np.zeros(0)  # m, m, s relative to the origin

    def keep(self, x, y, t, v_r):
        """Eq. 1 for a new scan (``t``: its times, s); the scan joins the window."""
        if self.origin is None:
            self.origin = float(t[0]) if len(t) else None
        if len(t) == 0:
            return np.zeros(0, dtype=bool)
        relative = t - self.origin
        first_kept = int(np.searchsorted(self.t, relative[0] - self.dt, side="left"))
        self.x = np.concatenate([self.x[first_kept:], x])
        self.y = np.concatenate([self.y[first_kept:], y])
        self.t = np.concatenate([self.t[first_kept:], relative])
        first_new = len(self.t) - len(t)
        counts = _count_past(self.x, self.y, self.t, first_new, self.d_xy**2, self.dt)
        return _doppler_density_keep(v_r, counts, self.vr_threshold, self.ratios, self.min_neighbors)
