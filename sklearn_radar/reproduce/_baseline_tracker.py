"""The baseline tracker of the tracking step: each scan's clusters to the tracks' last centroids, Hungarian method.

What a user would write without a motion model: the comparison point of :class:`~sklearn_radar.online.Tracker`
(:ref:`online-tracking-measured`), not a tracker to recommend, so it lives with the runner, not in the library.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

_UNGATED = 1e9


class NearestCentroidTracker:
    """Each scan's clusters assigned to the tracks' last centroids (Hungarian method), no motion model, no Doppler.

    A track is where its last cluster was.  A cluster within ``gate`` metres of a track's last centroid may be
    assigned to it (one cluster per track, the assignment of least total distance); any other cluster starts a
    tentative track.  The confirmation and deletion rule are :class:`~sklearn_radar.online.Tracker`'s: confirmed
    after ``min_hits`` scans with a cluster, ended after ``max_age`` s without one; detections get the id of a
    confirmed track, -1 otherwise.

    Parameters
    ----------
    gate : float, default=2.0
        Largest distance of a cluster's centroid to a track's last centroid, m.
    min_hits : int, default=3
        Scans with a cluster before a track is confirmed.
    max_age : float, default=0.5
        s without a cluster after which a track ends.
    """

    def __init__(self, gate=2.0, min_hits=3, max_age=0.5):
        self.gate, self.min_hits, self.max_age = gate, min_hits, max_age
        self._xy = np.zeros((0, 2))
        self._ids = np.zeros(0, dtype=np.int64)
        self._hits = np.zeros(0, dtype=np.int64)
        self._last = np.zeros(0)
        self._next_id = 0

    def update(self, x, y, t, clusters):
        """Track one scan: positions ``x``, ``y`` (m, fixed frame), its time ``t`` (s), cluster ids (-1 noise).

        Returns
        -------
        track_id : ndarray of int64
            The confirmed track of each detection, -1 for none.
        """
        alive = t - self._last <= self.max_age
        self._xy, self._ids, self._hits, self._last = (
            self._xy[alive],
            self._ids[alive],
            self._hits[alive],
            self._last[alive],
        )
        out = np.full(len(x), -1, dtype=np.int64)
        rows = np.flatnonzero(clusters >= 0)
        if len(rows) == 0:
            return out
        codes, member = np.unique(clusters[rows], return_inverse=True)
        member = member.ravel()
        count = np.bincount(member)
        centroid = np.c_[np.bincount(member, x[rows]), np.bincount(member, y[rows])] / count[:, None]
        slot = np.full(len(codes), -1)
        if len(self._ids):
            distance = np.linalg.norm(centroid[:, None, :] - self._xy[None, :, :], axis=2)
            cost = np.where(distance <= self.gate, distance, _UNGATED)
            r, c = linear_sum_assignment(cost)
            ok = cost[r, c] < _UNGATED
            slot[r[ok]] = c[ok]
        new = np.flatnonzero(slot < 0)
        if len(new):
            slot[new] = len(self._ids) + np.arange(len(new))
            self._xy = np.r_[self._xy, centroid[new]]
            self._ids = np.r_[self._ids, self._next_id + np.arange(len(new))]
            self._next_id += len(new)
            self._hits = np.r_[self._hits, np.zeros(len(new), dtype=np.int64)]
            self._last = np.r_[self._last, np.zeros(len(new))]
        self._xy[slot] = centroid
        self._hits[slot] += 1
        self._last[slot] = t
        shown = np.where(self._hits[slot] >= self.min_hits, self._ids[slot], -1)
        out[rows] = shown[member]
        return out
