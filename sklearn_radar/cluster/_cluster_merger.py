"""ClusterMerger: stage 2, merging stage-1 clusters of the same road user (Eq. 6 and continuation)."""

from __future__ import annotations

from numbers import Integral, Real

import numpy as np
import pandas as pd
from sklearn.base import BaseEstimator, ClusterMixin, _fit_context, clone
from sklearn.utils._param_validation import HasMethods, Interval, StrOptions
from sklearn.utils.validation import check_memory

from .._validation import ARRAY_LAYOUT, read_columns, sequence_slices
from ._merge_kernels import (
    candidate_pairs,
    cluster_rows,
    continuation,
    merge_components,
    min_distance,
    predict,
    scan_centres,
)
from ._radar_dbscan import RadarDBSCAN, _consecutive_labels
from ._velocity import estimate_velocities

#: Array layout of ClusterMerger: RadarDBSCAN's, then the line-of-sight columns.
MERGER_LAYOUT = {**ARRAY_LAYOUT, "azimuth_sc": 0.0, "sensor_yaw": 0.0}
_STAGE1_COLUMNS = ("x", "y", "v_r", "t", "sequence", "keep", "range_sc", "heading")
#: m/s: no road user is assumed faster; bounds the pairs the continuation criterion examines.
MAX_SPEED = 40.0


def _stage1_labels(stage1, columns):
    """Stage-1 labels of the working columns (a separate function so that joblib.Memory can cache it)."""
    frame = pd.DataFrame({name: values for name, values in columns.items() if values is not None})
    return stage1.fit(frame).labels_


class ClusterMerger(ClusterMixin, BaseEstimator):
    """Merge stage-1 clusters that belong to the same road user (Scheiner et al. 2019, Sec. "Cluster Merging").

    Runs ``stage1`` (a :class:`RadarDBSCAN`), then a second DBSCAN over its
    clusters (``min_samples = 1`` in the paper: connected components) with
    one of two neighbourhood criteria between an older cluster A and a
    cluster B that starts at ``s_B``:

    * ``mode="velocity"`` (Eq. 6): ``d_min < eps_d`` and ``dphi < eps_phi``
      and ``dv < eps_v`` and ``dt < eps_t2``.  d_min is the smallest distance
      between detections of A and of B within the ``eps_t2`` frame, dphi and
      dv the differences of direction and magnitude of the clusters' full
      velocities, estimated from Doppler and line of sight
      (:func:`estimate_velocity`, Kellner et al. 2013).
    * ``mode="continuation"``: ``d_pred,min < eps_d`` and ``dv < eps_v`` and
      ``dt < eps_t2``.  Each cluster's per-scan centres are smoothed by a
      moving average; the derivative at the last centre of the cubic
      through the last four smoothed centres (the end piece of a cubic
      spline; a line below four scans) is the velocity, which continues the
      centre forward.  d_pred is the distance
      of the two continued centres at the beginning, middle and end of the
      frame ``[s_B, s_B + eps_t2]``, the minimum counts; dv is the norm of the
      velocity difference.

    ``dt`` is the gap from A's last detection before ``s_B`` to ``s_B`` (0
    when A is still alive).  **Causal**: the pair is decided at
    ``tau = min(end of B, s_B + eps_t2)`` with detections at or before tau
    only (A within ``[s_B - eps_t2, tau]`` for Eq. 6, A's whole past for
    continuation), as real time demands; the decision then labels both
    clusters as one.  A velocity is unknown when the geometry cannot give
    one (too few detections, too little spread of the lines of sight, a
    single scan for continuation); ``unknown_velocity`` decides whether such
    a pair can merge on distance and time alone.

    Only detections with a stage-1 cluster take part; noise stays noise.

    Parameters
    ----------
    mode : {"continuation", "velocity"}, default="continuation"
    eps_d : float, default=0.94
        Distance threshold (d_min or d_pred,min), m.
    eps_phi : float, default=0.403
        Direction threshold of Eq. 6, rad (the paper's #12: 23.11 deg).
    eps_v : float, default=2.72
        Velocity threshold, m/s (the paper: 2.72 for continuation #13, 1.04 for Eq. 6 #12).
    eps_t2 : float, default=0.35
        Time frame, s.
    min_samples : int, default=1
        N_min of the second DBSCAN, counted in clusters (itself included).
    unknown_velocity : {"reject", "accept"}, default="reject"
        "reject": a pair with an unknown velocity never merges (wrong merges
        cost more than missed ones, the paper's finding for Eq. 6);
        "accept": such a pair is judged on distance and time alone.
    stage1 : RadarDBSCAN, default=None
        The point clusterer; None means ``RadarDBSCAN()``.  It is cloned.
    memory : str, joblib.Memory or None, default=None
        Caches the stage-1 labels, so that tuning the stage-2 parameters
        runs stage 1 once per data set (like ``Pipeline(memory=...)``).

    Attributes
    ----------
    labels_ : ndarray of shape (n_detections,)
        Merged cluster per row, -1 for noise; consecutive ids.
    stage1_labels_ : ndarray of shape (n_detections,)
        The stage-1 clusters.
    merges_ : ndarray of shape (n_merges, 3)
        (sequence, stage-1 label A, stage-1 label B) of every pair that met the criterion.
    n_features_in_ : int
    feature_names_in_ : ndarray of str
        When X is a DataFrame.

    Notes
    -----
    Reads the columns of :class:`RadarDBSCAN` plus, for ``mode="velocity"``,
    ``azimuth_sc`` and ``sensor_yaw`` (rad): a detection's line of sight is
    ``azimuth_sc + sensor_yaw + heading``.  A plain array is read by
    position ``[x, y, v_r, t, sequence, keep, range_sc, heading, azimuth_sc,
    sensor_yaw]``.

    Examples
    --------
    >>> from sklearn.pipeline import make_pipeline
    >>> from sklearn_radar import ClusterMerger, DopplerDensityFilter, FrameTransform, RadarDBSCAN
    >>> from sklearn_radar.datasets import make_scenes
    >>> scenes = make_scenes(n_sequences=1, duration=4.0, random_state=0)
    >>> model = make_pipeline(FrameTransform(), DopplerDensityFilter(), ClusterMerger(stage1=RadarDBSCAN()))
    >>> labels = model.fit_predict(scenes.data)
    >>> labels.shape == scenes.target.shape
    True
    """

    _parameter_constraints: dict = {
        "mode": [StrOptions({"continuation", "velocity"})],
        "eps_d": [Interval(Real, 0, None, closed="neither")],
        "eps_phi": [Interval(Real, 0, None, closed="neither")],
        "eps_v": [Interval(Real, 0, None, closed="neither")],
        "eps_t2": [Interval(Real, 0, None, closed="left")],
        "min_samples": [Interval(Integral, 1, None, closed="left")],
        "unknown_velocity": [StrOptions({"reject", "accept"})],
        "stage1": [HasMethods(["fit"]), None],
        "memory": [None, str, HasMethods(["cache"])],
    }

    def __init__(
        self,
        mode="continuation",
        eps_d=0.94,
        eps_phi=0.403,
        eps_v=2.72,
        eps_t2=0.35,
        min_samples=1,
        unknown_velocity="reject",
        stage1=None,
        memory=None,
    ):
        self.mode = mode
        self.eps_d = eps_d
        self.eps_phi = eps_phi
        self.eps_v = eps_v
        self.eps_t2 = eps_t2
        self.min_samples = min_samples
        self.unknown_velocity = unknown_velocity
        self.stage1 = stage1
        self.memory = memory

    @_fit_context(prefer_skip_nested_validation=False)
    def fit(self, X, y=None):
        """Cluster with stage 1, then merge the clusters.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
        y : None
            Ignored.

        Returns
        -------
        self : ClusterMerger
        """
        optional = _STAGE1_COLUMNS[4:] + (("azimuth_sc", "sensor_yaw") if self.mode == "velocity" else ())
        X, c = read_columns(self, X, _STAGE1_COLUMNS[:4], optional, reset=True, layout=MERGER_LAYOUT)
        if self.mode == "velocity" and (c["azimuth_sc"] is None or c["sensor_yaw"] is None):
            raise ValueError("ClusterMerger: mode='velocity' needs the columns 'azimuth_sc' and 'sensor_yaw' (rad)")
        stage1 = clone(self.stage1) if self.stage1 is not None else RadarDBSCAN()
        stage1_labels = check_memory(self.memory).cache(_stage1_labels)(stage1, {name: c[name] for name in _STAGE1_COLUMNS})
        stage1_labels = np.asarray(stage1_labels)
        sequence = np.zeros(len(stage1_labels)) if c["sequence"] is None else c["sequence"]
        los = None
        if self.mode == "velocity":
            heading = 0.0 if c["heading"] is None else c["heading"]
            los = c["azimuth_sc"] + c["sensor_yaw"] + heading
        roots = np.full(len(stage1_labels), -1, dtype=np.int64)
        merges = []
        for rows in sequence_slices(c["sequence"]):
            rows = np.arange(len(stage1_labels))[rows]
            sequence_roots, sequence_merges = self._merge_sequence(rows, c, stage1_labels, los)
            roots[rows] = sequence_roots
            merges += [(sequence[rows[0]], a, b) for a, b in sequence_merges]
        self.stage1_labels_ = stage1_labels
        self.labels_ = _consecutive_labels(roots)
        self.merges_ = np.array(merges, dtype=np.float64).reshape(-1, 3)
        return self

    def _merge_sequence(self, rows, c, stage1_labels, los):
        """Root row (global row number of a cluster's representative) per row of one sequence."""
        x, y, t, v_r = c["x"][rows], c["y"][rows], c["t"][rows], c["v_r"][rows]
        clusters = cluster_rows(stage1_labels[rows], t)
        roots = np.full(len(rows), -1, dtype=np.int64)
        if len(clusters.ids) == 0:
            return roots, []
        # Continued centres may drift apart from the detections around s_B by up to
        # MAX_SPEED * eps_t2 each; Eq. 6 compares detections directly.
        reach = self.eps_d + (2 * MAX_SPEED * self.eps_t2 if self.mode == "continuation" else 0.0)
        frames = [self._pair_frames(a, b, clusters, t) for a, b in candidate_pairs(clusters, x, y, t, self.eps_t2, reach)]
        frames = [f for f in frames if f is not None]
        if self.mode == "velocity":
            edges = self._velocity_edges(frames, clusters, x, y, t, v_r, los[rows])
        else:
            edges = self._continuation_edges(frames, clusters, x, y, t)
        component = merge_components(len(clusters.ids), edges, self.min_samples)
        representative = np.array([member_rows[0] for member_rows in clusters.rows])
        for k, member_rows in enumerate(clusters.rows):
            roots[member_rows] = rows[representative[component[k]]]
        return roots, [(int(clusters.ids[a]), int(clusters.ids[b])) for a, b in edges]

    def _pair_frames(self, a, b, clusters, t):
        """Decision time tau of the pair and the rows each criterion may use; None if dt >= eps_t2.

        B (starting at s_B) is judged at ``tau = min(end of B, s_B + eps_t2)``:
        only detections at or before tau are used.
        """
        start_b = clusters.start[b]
        tau = min(clusters.end[b], start_b + self.eps_t2)
        rows_a = clusters.rows[a]
        past_a = rows_a[t[rows_a] <= tau]
        before_b = past_a[t[past_a] <= start_b]
        alive = len(past_a) > len(before_b)
        gap = 0.0 if alive else start_b - t[before_b[-1]]
        if gap >= self.eps_t2:
            return None
        rows_b = clusters.rows[b]
        return a, b, tau, past_a, rows_b[t[rows_b] <= tau]

    def _velocity_edges(self, frames, clusters, x, y, t, v_r, los):
        """Eq. 6 for every candidate pair; all velocities are estimated in one batch."""
        windows = []  # (pair index, rows of A within the eps_t2 frame, rows of B)
        for k, (a, b, tau, past_a, rows_b) in enumerate(frames):
            frame_a = past_a[t[past_a] >= clusters.start[b] - self.eps_t2]
            if len(frame_a) and min_distance(x[frame_a], y[frame_a], x[rows_b], y[rows_b]) < self.eps_d:
                windows.append((k, frame_a, rows_b))
        if not windows:
            return []
        rows = np.concatenate([np.concatenate([frame_a, rows_b]) for _, frame_a, rows_b in windows])
        group = np.concatenate([np.r_[np.full(len(fa), 2 * i), np.full(len(rb), 2 * i + 1)] for i, (_, fa, rb) in enumerate(windows)])
        vx, vy, _, groups = estimate_velocities(v_r[rows], los[rows], group)
        velocity = np.full((2 * len(windows), 2), np.nan)
        velocity[groups.astype(np.int64)] = np.c_[vx, vy]
        edges = []
        for i, (k, _, _) in enumerate(windows):
            va, vb = velocity[2 * i], velocity[2 * i + 1]
            if not (np.all(np.isfinite(va)) and np.all(np.isfinite(vb))):
                merge = self.unknown_velocity == "accept"
            else:
                dphi = abs((np.arctan2(va[1], va[0]) - np.arctan2(vb[1], vb[0]) + np.pi) % (2 * np.pi) - np.pi)
                merge = dphi < self.eps_phi and abs(np.hypot(*va) - np.hypot(*vb)) < self.eps_v
            if merge:
                edges.append(frames[k][:2])
        return edges

    def _continuation_edges(self, frames, clusters, x, y, t):
        """The continuation criterion for every candidate pair; tracks are fitted once per (cluster, cut)."""
        centres, fitted = {}, {}

        def track(cluster, rows):
            """Continuation from the first len(rows) detections of a cluster (a time-sorted prefix)."""
            if cluster not in centres:
                centres[cluster] = scan_centres(clusters.rows[cluster], x, y, t)
            times, cx, cy = centres[cluster]
            n_scans = int(np.searchsorted(times, t[rows[-1]], side="right"))
            if (cluster, n_scans) not in fitted:
                fitted[cluster, n_scans] = continuation(times[:n_scans], cx[:n_scans], cy[:n_scans])
            return fitted[cluster, n_scans]

        edges = []
        for a, b, tau, past_a, rows_b in frames:
            end_a, position_a, velocity_a = track(a, past_a)
            end_b, position_b, velocity_b = track(b, rows_b)
            at = clusters.start[b] + np.array([0.0, 0.5, 1.0]) * self.eps_t2
            gap = predict(end_a, position_a, velocity_a, at) - predict(end_b, position_b, velocity_b, at)
            if np.min(np.hypot(gap[:, 0], gap[:, 1])) >= self.eps_d:
                continue
            if not (np.all(np.isfinite(velocity_a)) and np.all(np.isfinite(velocity_b))):
                merge = self.unknown_velocity == "accept"
            else:
                merge = np.hypot(*(velocity_a - velocity_b)) < self.eps_v
            if merge:
                edges.append((a, b))
        return edges
