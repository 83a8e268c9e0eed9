"""Tracker: constant-velocity Kalman tracks over the clusters of each radar scan, with lasting track ids."""

from __future__ import annotations

from numbers import Integral, Real
from typing import ClassVar

import numpy as np
from scipy.optimize import linear_sum_assignment
from sklearn.utils._param_validation import Interval, validate_parameter_constraints

from . import _tracker_kernels as kernels

#: Standard deviation of a new track's velocity on each axis before its first Doppler update, m/s.
INITIAL_SPEED = 15.0
#: A detection's Doppler is left out of an update when its residual exceeds this many standard deviations.
DOPPLER_SIGMAS = 3.0
_UNGATED = 1e18


class Tracker:
    """Constant-velocity Kalman tracks over the clusters of each scan: lasting track ids for the detections.

    Fed one scan at a time (the detections of one time of one sequence, in
    the fixed frame, with a cluster id each, -1 for noise), it returns a
    track id per detection.  Each cluster of the scan (its detections with
    one id) is a measurement: its centroid (x, y) and each detection's
    Doppler, ``v_r = vx cos(los) + vy sin(los)`` (the linear model of
    Eq. 6), which a constant-velocity Kalman filter folds into the track's
    state ``(x, y, vx, vy)`` predicted to the scan's time.  Association:

    1. a cluster whose id was given to a live track at an earlier scan stays
       with it (the clustering's own continuity);
    2. the other clusters are assigned to the tracks not yet updated by the
       Hungarian method (:func:`scipy.optimize.linear_sum_assignment`) on
       the squared Mahalanobis distance of the centroid to the predicted
       position, within ``gate`` standard deviations (and, for a confirmed
       track, a mean Doppler residual within ``doppler_gate``);
    3. a cluster left over that is within the gate of a confirmed track
       joins it (a cluster split for a scan); any other starts a tentative
       track.

    A track is confirmed after ``min_hits`` scans with a cluster, and ended
    when it has had none for ``max_age`` seconds.  Detections get the id
    of a confirmed track, -1 otherwise; ids are never reused.  With
    ``noise_radius`` a noise detection within that distance of a confirmed
    track's predicted position whose Doppler its velocity explains (within
    ``doppler_gate``) takes the track's id too (it does not update it).

    Not a scikit-learn estimator: the state of one stream (as
    :class:`OnlinePipeline`), updated scan by scan; pass one to
    ``OnlinePipeline(tracker=...)``, which keeps a fresh one per sequence.

    Read more in the :ref:`User Guide <online-tracking>`.

    Parameters
    ----------
    gate : float, default=3.0
        Association gate: Mahalanobis distance of a cluster's centroid to a
        track's predicted position, in standard deviations (of the
        prediction and ``position_noise`` together).
    min_hits : int, default=3
        Scans with a cluster before a track is confirmed (and its id given).
    max_age : float, default=0.5
        s without a cluster after which a track ends.
    position_noise : float, default=1.0
        Standard deviation of a cluster's centroid about the object's
        position, m (a cluster often holds part of an object).
    doppler_noise : float, default=0.3
        Standard deviation of a detection's Doppler about the object's
        radial velocity, m/s.
    acceleration : float, default=2.0
        Standard deviation of the object's acceleration, m/s², over one
        second (the white-noise acceleration's density is its square,
        m²/s³).
    doppler_gate : float, default=1.0
        Doppler agreement, m/s: the mean absolute residual
        ``|v_r - vx cos(los) - vy sin(los)|`` of a cluster for a confirmed
        track (association), and of a noise detection (``noise_radius``).
    noise_radius : float or None, default=None
        Distance, m, from a confirmed track's predicted position within
        which a noise detection whose Doppler agrees takes its id; None:
        noise stays -1.

    Attributes
    ----------
    n_tracks : int
        Live tracks, tentative and confirmed.

    See Also
    --------
    OnlinePipeline : gives the clusters; ``tracker=`` runs a Tracker on them.

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_radar.online import Tracker
    >>> tracker = Tracker(min_hits=2)
    >>> for k in range(3):  # an object 10 m ahead moving at 5 m/s along x, seen every 0.1 s
    ...     x = np.array([10.0, 10.4]) + 0.5 * k
    ...     ids = tracker.update(x, np.zeros(2), np.full(2, 5.0), np.zeros(2), 0.1 * k, np.array([7, 7]))
    >>> ids
    array([0, 0])
    """

    _parameter_constraints: ClassVar[dict] = {
        "gate": [Interval(Real, 0, None, closed="neither")],
        "min_hits": [Interval(Integral, 1, None, closed="left")],
        "max_age": [Interval(Real, 0, None, closed="neither")],
        "position_noise": [Interval(Real, 0, None, closed="neither")],
        "doppler_noise": [Interval(Real, 0, None, closed="neither")],
        "acceleration": [Interval(Real, 0, None, closed="left")],
        "doppler_gate": [Interval(Real, 0, None, closed="left")],
        "noise_radius": [Interval(Real, 0, None, closed="left"), None],
    }

    def __init__(
        self,
        gate=3.0,
        min_hits=3,
        max_age=0.5,
        position_noise=1.0,
        doppler_noise=0.3,
        acceleration=2.0,
        doppler_gate=1.0,
        noise_radius=None,
    ):
        self.gate = gate
        self.min_hits = min_hits
        self.max_age = max_age
        self.position_noise = position_noise
        self.doppler_noise = doppler_noise
        self.acceleration = acceleration
        self.doppler_gate = doppler_gate
        self.noise_radius = noise_radius
        validate_parameter_constraints(self._parameter_constraints, self.get_params(), type(self).__name__)
        for name in self._parameter_constraints:
            value = getattr(self, name)
            if value is not None and not np.isfinite(value):
                raise ValueError(f"Tracker: the {name!r} parameter must be finite, got {value!r}")
        self._reset()

    def get_params(self):
        """The parameters, as given.

        Returns
        -------
        params : dict
        """
        return {name: getattr(self, name) for name in self._parameter_constraints}

    def fresh(self):
        """A new Tracker with the same parameters and no tracks (the state of another stream).

        Returns
        -------
        tracker : Tracker
        """
        return type(self)(**self.get_params())

    def __repr__(self):
        """``Tracker(...)`` with the parameters that differ from the defaults."""
        defaults = type(self)().get_params() if type(self) is Tracker else {}
        shown = [f"{k}={v!r}" for k, v in self.get_params().items() if defaults.get(k, object()) != v]
        return f"{type(self).__name__}({', '.join(shown)})"

    def _reset(self):
        self._state = np.zeros((0, 4))
        self._cov = np.zeros((0, 4, 4))
        self._ids = np.zeros(0, dtype=np.int64)  # track id per slot, increasing
        self._hits = np.zeros(0, dtype=np.int64)
        self._last = np.zeros(0)  # time of the last cluster, s
        self._confirmed = np.zeros(0, dtype=bool)
        self._links = {}  # cluster id -> (track id, time last seen, s)
        self._next_id = 0
        self._now = None

    @property
    def n_tracks(self):
        """int: Live tracks (tentative and confirmed)."""
        return len(self._ids)

    def tracks(self):
        """The live tracks: id, state and confirmation, as arrays.

        Returns
        -------
        tracks : dict
            ``track_id`` (int64), ``x``, ``y`` (m), ``vx``, ``vy`` (m/s) predicted to the last scan's time,
            ``hits``, ``confirmed`` and ``last_update`` (s), one entry per track.
        """
        return {
            "track_id": self._ids.copy(),
            "x": self._state[:, 0].copy(),
            "y": self._state[:, 1].copy(),
            "vx": self._state[:, 2].copy(),
            "vy": self._state[:, 3].copy(),
            "hits": self._hits.copy(),
            "confirmed": self._confirmed.copy(),
            "last_update": self._last.copy(),
        }

    def update(self, x, y, v_r, los, t, clusters):
        """Track one scan: predict the tracks to time ``t``, associate the scan's clusters, update.

        Parameters
        ----------
        x, y : array-like of shape (n_detections,)
            Positions in the fixed frame (the sequence frame), m.
        v_r : array-like of shape (n_detections,)
            Ego-motion compensated Doppler, m/s.
        los : array-like of shape (n_detections,)
            Direction of each detection's line of sight in the fixed frame, rad.
        t : float
            The scan's time, s; later than the previous scan's.
        clusters : array-like of int of shape (n_detections,)
            Cluster (object) id of each detection, -1 for noise; an id kept
            from scan to scan is one object (e.g. the object ids of
            :class:`OnlinePipeline`).

        Returns
        -------
        track_id : ndarray of int64, shape (n_detections,)
            Id of the confirmed track of each detection, -1 for none.

        Raises
        ------
        ValueError
            If the arrays differ in length or hold values that are not
            finite, or ``t`` is not later than the previous scan's.
        """
        x, y, v_r, los, clusters = _read(x, y, v_r, los, clusters)
        t = float(t)
        if not np.isfinite(t):
            raise ValueError(f"Tracker.update: t must be finite, got {t}")
        if self._now is not None and t <= self._now:
            raise ValueError(f"Tracker.update: the scan at t={t} s is not later than the previous one ({self._now} s)")
        if self._now is not None:
            kernels.predict(self._state, self._cov, len(self._ids), t - self._now, self.acceleration**2)
            self._end_tracks(t)
        self._now = t
        slot = self._associate(x, y, v_r, los, t, clusters)
        r_pos, r_vr = self.position_noise**2, self.doppler_noise**2
        count = kernels.update(self._state, self._cov, slot, x, y, v_r, los, r_pos, r_vr, DOPPLER_SIGMAS)
        updated = count > 0
        self._hits[updated] += 1
        self._last[updated] = t
        self._confirmed |= self._hits >= self.min_hits
        if self.noise_radius is not None and self._confirmed.any():
            noise = np.flatnonzero(clusters < 0)
            if len(noise):
                slot[noise] = kernels.nearest_agreeing(
                    x, y, v_r, los, noise, self._state, self._confirmed, self.noise_radius, self.doppler_gate
                )
        track_id = np.full(len(x), -1, dtype=np.int64)
        shown = slot >= 0
        shown[shown] = self._confirmed[slot[shown]]
        track_id[shown] = self._ids[slot[shown]]
        return track_id

    def _end_tracks(self, t):
        """Drop the tracks without a cluster for more than ``max_age``, and the links to them."""
        alive = t - self._last <= self.max_age
        if alive.all():
            return
        for name in ("_state", "_cov", "_ids", "_hits", "_last", "_confirmed"):
            setattr(self, name, getattr(self, name)[alive])
        oldest = t - self.max_age
        self._links = {c: link for c, link in self._links.items() if link[1] >= oldest}

    def _slots(self, track_ids):
        """Slot of each live track id (-1 for an ended one, or for -1)."""
        if len(self._ids) == 0:
            return np.full(len(track_ids), -1, dtype=np.int64)
        at = np.minimum(np.searchsorted(self._ids, track_ids), len(self._ids) - 1)
        return np.where(self._ids[at] == track_ids, at, -1)

    def _associate(self, x, y, v_r, los, t, clusters):
        """Track slot of every clustered detection (new tracks added), -1 for noise."""
        slot = np.full(len(x), -1, dtype=np.int64)
        clustered = np.flatnonzero(clusters >= 0)
        if len(clustered) == 0:
            return slot
        codes, member = np.unique(clusters[clustered], return_inverse=True)
        member = member.ravel()
        n = len(codes)
        links = self._links
        linked = np.array([links[c][0] if c in links else -1 for c in codes.tolist()], dtype=np.int64)
        of_cluster = self._slots(linked)
        free = np.flatnonzero(of_cluster < 0)
        if len(free) and len(self._ids):
            count = np.bincount(member, minlength=n).astype(np.float64)
            cx = np.bincount(member, x[clustered], minlength=n)[free] / count[free]
            cy = np.bincount(member, y[clustered], minlength=n)[free] / count[free]
            cost = kernels.centroid_distances(cx, cy, self._state, self._cov, self.position_noise**2)
            inside = cost <= self.gate**2
            if self._confirmed.any():
                local = np.full(n, -1, dtype=np.int64)
                local[free] = np.arange(len(free))
                misfit = kernels.doppler_misfit(v_r[clustered], los[clustered], local[member], len(free), self._state)
                inside &= ~self._confirmed | (misfit <= self.doppler_gate)
            taken = np.zeros(len(self._ids), dtype=bool)
            taken[of_cluster[of_cluster >= 0]] = True
            open_cost = np.where(inside & ~taken, cost, _UNGATED)
            rows, cols = linear_sum_assignment(open_cost)
            hit = open_cost[rows, cols] < _UNGATED
            of_cluster[free[rows[hit]]] = cols[hit]
            left = np.flatnonzero(of_cluster[free] < 0)
            if len(left):  # a split cluster joins the confirmed track it is gated to
                joinable = np.where(inside[left] & self._confirmed, cost[left], np.inf)
                best = np.argmin(joinable, axis=1)
                ok = np.isfinite(joinable[np.arange(len(left)), best])
                of_cluster[free[left[ok]]] = best[ok]
        new = np.flatnonzero(of_cluster < 0)
        if len(new):
            of_cluster[new] = self._new_tracks(x[clustered], y[clustered], member, new, n)
        for code, k in zip(codes.tolist(), of_cluster.tolist(), strict=True):
            links[code] = (int(self._ids[k]), t)
        slot[clustered] = of_cluster[member]
        return slot

    def _new_tracks(self, x, y, member, new, n):
        """Start a tentative track at the centroid of each cluster in ``new``; their slots."""
        count = np.bincount(member, minlength=n).astype(np.float64)
        cx = np.bincount(member, x, minlength=n)[new] / count[new]
        cy = np.bincount(member, y, minlength=n)[new] / count[new]
        k = len(new)
        state = np.zeros((k, 4))
        state[:, 0], state[:, 1] = cx, cy
        cov = np.zeros((k, 4, 4))
        cov[:, 0, 0] = cov[:, 1, 1] = self.position_noise**2
        cov[:, 2, 2] = cov[:, 3, 3] = INITIAL_SPEED**2
        first = len(self._ids)
        self._state = np.concatenate([self._state, state])
        self._cov = np.concatenate([self._cov, cov])
        self._ids = np.concatenate([self._ids, np.arange(self._next_id, self._next_id + k)])
        self._next_id += k
        self._hits = np.concatenate([self._hits, np.zeros(k, dtype=np.int64)])
        self._last = np.concatenate([self._last, np.full(k, np.nan)])
        self._confirmed = np.concatenate([self._confirmed, np.zeros(k, dtype=bool)])
        return np.arange(first, first + k)


def sequence_frame(c, x, y, frame):
    """x, y (m) and the line of sight (rad) in the sequence frame, from raw columns ``c`` and the working x, y.

    ``frame``: FrameTransform's ``frame``, the frame of ``x`` and ``y`` (``"car"``: moved to the sequence frame
    with the scan's odometry, as ``frame="frame"`` does).
    """
    if frame != "frame":
        cos_e, sin_e = np.cos(c["ego_yaw_seq"]), np.sin(c["ego_yaw_seq"])
        x, y = c["ego_x_seq"] + cos_e * x - sin_e * y, c["ego_y_seq"] + sin_e * x + cos_e * y
    return x, y, c["azimuth_sc"] + c["sensor_yaw"] + c["ego_yaw_seq"]


def _read(x, y, v_r, los, clusters):
    """The columns as contiguous float64 arrays (clusters int64), checked for length and finiteness."""
    names = ("x", "y", "v_r", "los")
    columns = [np.ascontiguousarray(np.ravel(value), dtype=np.float64) for value in (x, y, v_r, los)]
    clusters = np.ravel(clusters)
    n = len(columns[0])
    for name, values in zip((*names, "clusters"), (*columns, clusters), strict=True):
        if len(values) != n:
            raise ValueError(f"Tracker.update: {name!r} has {len(values)} values, 'x' has {n}")
    for name, values in zip(names, columns, strict=True):
        if not np.isfinite(values).all():
            raise ValueError(f"Tracker.update: {name!r} holds values that are not finite")
    if clusters.dtype.kind not in "iu":
        if not (np.isfinite(clusters).all() and (clusters == np.round(clusters)).all()):
            raise ValueError("Tracker.update: 'clusters' must hold integer ids (-1 for noise)")
    return (*columns, np.ascontiguousarray(clusters, dtype=np.int64))
