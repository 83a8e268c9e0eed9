"""The Doppler-density filter (Eq. 1) on a live stream: each scan counted against the past ``dt`` only."""

from __future__ import annotations

import numpy as np

from ..preprocessing._doppler_density_kernels import keep_new, speed_limits
from ._merger import TimeColumns


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
        self.speed_limits = speed_limits(self.vr_threshold, ratios)
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
        return keep_new(w["x"], w["y"], w["t"], v_r, first_new, radius2, self.dt, self.speed_limits, self.min_neighbors)
