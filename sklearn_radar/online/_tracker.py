"""Tracker: constant-velocity Kalman tracks over the clusters of each radar scan, with lasting track ids."""

from __future__ import annotations

import math
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
#: Tracks and links a new Tracker has room for before its arrays grow.
_ROOM = 8


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
        # Tracks in slots 0 .. _n - 1 of arrays with room to spare (ids increasing with the slot)
        self._n = 0
        self._state = np.zeros((_ROOM, 4))
        self._cov = np.zeros((_ROOM, 4, 4))
        self._ids = np.zeros(_ROOM, dtype=np.int64)
        self._hits = np.zeros(_ROOM, dtype=np.int64)
        self._last = np.zeros(_ROOM)  # time of the last cluster, s
        self._confirmed = np.zeros(_ROOM, dtype=bool)
        # Links cluster id -> track id and time last seen (s), in 0 .. _n_links - 1, cluster ids increasing
        self._n_links = 0
        self._link_code = np.zeros(_ROOM, dtype=np.int64)
        self._link_track = np.zeros(_ROOM, dtype=np.int64)
        self._link_time = np.zeros(_ROOM)
        self._next_id = 0
        self._now = None

    @property
    def n_tracks(self):
        """int: Live tracks (tentative and confirmed)."""
        return self._n

    def tracks(self):
        """The live tracks: id, state and confirmation, as arrays.

        Returns
        -------
        tracks : dict
            ``track_id`` (int64), ``x``, ``y`` (m), ``vx``, ``vy`` (m/s) predicted to the last scan's time,
            ``hits``, ``confirmed`` and ``last_update`` (s), one entry per track.
        """
        n = self._n
        return {
            "track_id": self._ids[:n].copy(),
            "x": self._state[:n, 0].copy(),
            "y": self._state[:n, 1].copy(),
            "vx": self._state[:n, 2].copy(),
            "vy": self._state[:n, 3].copy(),
            "hits": self._hits[:n].copy(),
            "confirmed": self._confirmed[:n].copy(),
            "last_update": self._last[:n].copy(),
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
        if not math.isfinite(t):
            raise ValueError(f"Tracker.update: t must be finite, got {t}")
        if self._now is not None and t <= self._now:
            raise ValueError(f"Tracker.update: the scan at t={t} s is not later than the previous one ({self._now} s)")
        if self._now is not None:
            self._end_tracks(t)
        self._now = t
        # The rows in one order of their values: the sums (centroids, Doppler updates) and so the ids do not depend
        # on the order the rows came in (rows equal in every column are interchangeable).
        order = np.lexsort((los, v_r, y, x, clusters))
        x, y, v_r, los, clusters = x[order], y[order], v_r[order], los[order], clusters[order]
        member, of_cluster = self._associate(x, y, v_r, los, t, clusters)
        noise_radius = -1.0 if self.noise_radius is None else float(self.noise_radius)
        params = (self.position_noise**2, self.doppler_noise**2, DOPPLER_SIGMAS, self.min_hits, self.doppler_gate)
        arrays = (self._state, self._cov, self._ids, self._hits, self._last, self._confirmed)
        found = kernels.finish(*arrays, self._n, member, of_cluster, x, y, v_r, los, t, noise_radius, params)
        track_id = np.empty_like(found)
        track_id[order] = found
        return track_id

    def _end_tracks(self, t):
        """Predict the tracks to ``t``; drop those without a cluster for over ``max_age``, and the links to them."""
        arrays = (self._state, self._cov, self._ids, self._hits, self._last, self._confirmed)
        n = kernels.advance(*arrays, self._n, t - self._now, self.acceleration**2, t, self.max_age)
        if n < self._n:
            links = (self._link_code, self._link_track, self._link_time)
            self._n_links = kernels.drop_links(*links, self._n_links, t - self.max_age)
        self._n = n

    def _associate(self, x, y, v_r, los, t, clusters):
        """Cluster of every detection (-1 for noise) and track slot of every cluster (new tracks added)."""
        links = (self._link_code, self._link_track, self._n_links)
        codes, member, cx, cy, of_cluster, n_free = kernels.group(clusters, x, y, *links, self._ids, self._n)
        n_codes = len(codes)
        if n_codes == 0:
            return member, of_cluster
        n = self._n
        if n and n_free:
            free, cost, inside, open_cost = kernels.gate(
                cx, cy, of_cluster, member, v_r, los, self._state, self._cov, self._confirmed, n,
                self.position_noise**2, self.gate**2, self.doppler_gate, _UNGATED,
            )  # fmt: skip
            rows, cols = linear_sum_assignment(open_cost)
            n_free = kernels.assign(rows, cols, open_cost, cost, inside, self._confirmed, free, of_cluster, _UNGATED)
        if n_free:
            self._reserve_tracks(n + n_free)
            arrays = (self._state, self._cov, self._ids, self._hits, self._last, self._confirmed)
            speed_var = INITIAL_SPEED**2
            self._n = kernels.start_tracks(
                *arrays, n, of_cluster, cx, cy, self._next_id, self.position_noise**2, speed_var
            )
            self._next_id += n_free
        self._reserve_links(self._n_links + n_codes)
        links = (self._link_code, self._link_track, self._link_time)
        self._n_links = kernels.store_links(*links, self._n_links, codes, self._ids[of_cluster], t)
        return member, of_cluster

    def _reserve_tracks(self, size):
        """Room for ``size`` tracks (twice as much when growing, the live ones kept)."""
        if size <= len(self._ids):
            return
        room = max(size, 2 * len(self._ids))
        for name in ("_state", "_cov", "_ids", "_hits", "_last", "_confirmed"):
            old = getattr(self, name)
            new = np.zeros((room, *old.shape[1:]), dtype=old.dtype)
            new[: self._n] = old[: self._n]
            setattr(self, name, new)

    def _reserve_links(self, size):
        """Room for ``size`` links (twice as much when growing, the current ones kept)."""
        if size <= len(self._link_code):
            return
        room = max(size, 2 * len(self._link_code))
        for name in ("_link_code", "_link_track", "_link_time"):
            old = getattr(self, name)
            new = np.zeros(room, dtype=old.dtype)
            new[: self._n_links] = old[: self._n_links]
            setattr(self, name, new)


def followed_ids(object_ids, confirmed, learned):
    """The object ids a pipeline's Tracker follows at a scan, -1 for none.

    Every object id; with the learned grouping the confirmed ones only (clusters with ``min_cluster_size``
    detections, those its offline ``predict`` keeps: the others are often a few detections of static clutter).
    """
    return np.where(confirmed, object_ids, -1) if learned else object_ids


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
    if not len(columns[1]) == len(columns[2]) == len(columns[3]) == len(clusters) == n:
        for name, values in zip((*names, "clusters"), (*columns, clusters), strict=True):
            if len(values) != n:
                raise ValueError(f"Tracker.update: {name!r} has {len(values)} values, 'x' has {n}")
    bad = kernels.first_not_finite(*columns)
    if bad >= 0:
        raise ValueError(f"Tracker.update: {names[bad]!r} holds values that are not finite")
    if clusters.dtype.kind not in "iu":
        if not (np.isfinite(clusters).all() and (clusters == np.round(clusters)).all()):
            raise ValueError("Tracker.update: 'clusters' must hold integer ids (-1 for noise)")
    return (*columns, np.ascontiguousarray(clusters, dtype=np.int64))
