"""ClusterMerger: stage 2, merging stage-1 clusters of the same road user (Eq. 6 and continuation)."""

from __future__ import annotations

from numbers import Integral, Real
from typing import ClassVar

import numpy as np
import pandas as pd
from sklearn.base import BaseEstimator, ClusterMixin, _fit_context, clone
from sklearn.utils._param_validation import HasMethods, Interval, StrOptions
from sklearn.utils.validation import check_memory

from .._labels import consecutive_labels, drop_small_clusters
from .._schema import MERGER_READS, STAGE1_READS
from .._validation import read_columns, sequence_slices
from ._merge_kernels import (
    candidate_pairs,
    cluster_runs,
    continuation_edges,
    merge_components,
    velocity_agreement,
    velocity_window_rows,
    velocity_windows,
)
from ._radar_dbscan import RadarDBSCAN, _gate_static_clusters
from ._velocity import _VELOCITY_DEFAULTS, _estimate, _estimate_velocities


def _stage1_labels(stage1, columns):
    """Stage-1 labels of the working columns (a separate function so that joblib.Memory can cache it)."""
    table = pd.DataFrame({name: values for name, values in columns.items() if values is not None})
    return stage1.fit(table).labels_


class ClusterMerger(ClusterMixin, BaseEstimator):
    """Merge stage-1 clusters that belong to the same road user (Scheiner et al. 2019, Sec. "Cluster Merging").

    Runs ``stage1`` (a :class:`RadarDBSCAN`), then a second DBSCAN over its
    clusters (``min_samples = 1`` in the paper: connected components) with
    one of two neighbourhood criteria between an older cluster A and a
    cluster B that starts at ``s_B``:

    * ``mode="velocity"`` (Eq. 6): ``d_min < eps_d`` and ``dphi < eps_phi``
      and ``dv < eps_v`` and ``dt < eps_t2``.  d_min is the smallest distance
      between detections of A and of B within the ``eps_t2`` window, dphi and
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
      window ``[s_B, s_B + eps_t2]``, the minimum counts; dv is the norm of the
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

    Read more in the :ref:`User Guide <user-guide-merging>`.

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
        Time window, s.
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
    cluster_vr_min : float >= 0 or None, default=None
        Cluster-level Doppler gate on the final, merged clusters, m/s: a
        merged cluster whose median ``|v_r|`` is at most ``cluster_vr_min``
        becomes noise and the remaining ids are renumbered consecutively.
        It is applied after merging, so a merged cluster whose median passes
        is kept even if one of its stage-1 parts alone would fail.  None
        (the default) turns it off, as in the paper.  The reason is that of
        ``RadarDBSCAN.cluster_vr_min``: the paper's V-measure does not
        penalise clusters of static background, so tuned settings cluster
        guard rails; the gate removes them without changing which
        detections may be core.  ``stage1_labels_`` and ``merges_`` are
        not gated.
    min_cluster_size : int, default=1
        Smallest merged cluster kept, in detections (HDBSCAN's
        ``min_cluster_size``); the detections of a smaller one become noise.
        1 (the default) keeps every cluster, as in the paper; beyond it, see
        the user guide's "Counting objects".
    causal_min_size : bool, default=False
        How ``min_cluster_size`` counts.  False: a merged cluster's whole
        size.  True: a detection counts the detections of its cluster up to
        its own time (those of the same time included), so a cluster's first
        detections stay noise until it has ``min_cluster_size`` (a track
        confirmation rule).  The merging is causal either way.

    Attributes
    ----------
    labels_ : ndarray of shape (n_detections,)
        Merged cluster per row, -1 for noise (including clusters removed by ``cluster_vr_min`` and
        ``min_cluster_size``); consecutive ids.
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
    sensor_yaw]`` (:data:`~sklearn_radar._schema.WORK_LAYOUT`); the velocity
    mode raises when the line-of-sight columns are missing, rather than
    assume a boresight view.

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

    _parameter_constraints: ClassVar[dict] = {
        "mode": [StrOptions({"continuation", "velocity"})],
        "eps_d": [Interval(Real, 0, None, closed="neither")],
        "eps_phi": [Interval(Real, 0, None, closed="neither")],
        "eps_v": [Interval(Real, 0, None, closed="neither")],
        "eps_t2": [Interval(Real, 0, None, closed="left")],
        "min_samples": [Interval(Integral, 1, None, closed="left")],
        "unknown_velocity": [StrOptions({"reject", "accept"})],
        "stage1": [HasMethods(["fit"]), None],
        "memory": [None, str, HasMethods(["cache"])],
        "cluster_vr_min": [Interval(Real, 0, None, closed="left"), None],
        "min_cluster_size": [Interval(Integral, 1, None, closed="left")],
        "causal_min_size": ["boolean"],
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
        cluster_vr_min=None,
        min_cluster_size=1,
        causal_min_size=False,
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
        self.cluster_vr_min = cluster_vr_min
        self.min_cluster_size = min_cluster_size
        self.causal_min_size = causal_min_size

    @_fit_context(prefer_skip_nested_validation=False)
    def fit(self, X, y=None):
        """Cluster with stage 1, then merge the clusters.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections (the output of :class:`FrameTransform`, optionally filtered by
            :class:`DopplerDensityFilter`), or an array in the order of
            :data:`~sklearn_radar._schema.WORK_LAYOUT`.
        y : None
            Ignored.

        Returns
        -------
        self : ClusterMerger
        """
        X, c = read_columns(self, X, MERGER_READS, reset=True)
        if self.mode == "velocity" and (c["azimuth_sc"] is None or c["sensor_yaw"] is None):
            raise ValueError("ClusterMerger: mode='velocity' needs the columns 'azimuth_sc' and 'sensor_yaw' (rad)")
        stage1 = clone(self.stage1) if self.stage1 is not None else RadarDBSCAN()
        stage1_labels = check_memory(self.memory).cache(_stage1_labels)(
            stage1, {name: c[name] for name in STAGE1_READS.names}
        )
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
        roots = _gate_static_clusters(roots, c["v_r"], self.cluster_vr_min)
        roots = drop_small_clusters(roots, self.min_cluster_size, c["t"] if self.causal_min_size else None)
        self.labels_ = consecutive_labels(roots)
        self.merges_ = np.array(merges, dtype=np.float64).reshape(-1, 3)
        return self

    def _merge_sequence(self, rows, c, stage1_labels, los):
        """Root row (global row number of a cluster's representative) per row of one sequence."""
        extra = (c["v_r"][rows],) if los is None else (c["v_r"][rows], los[rows])  # ties of (t, x, y): by value
        runs = cluster_runs(stage1_labels[rows], c["x"][rows], c["y"][rows], c["t"][rows], extra)
        roots = np.full(len(rows), -1, dtype=np.int64)
        if len(runs.ids) == 0:
            return roots, []
        pair_a, pair_b = candidate_pairs(runs, self.eps_t2, self.eps_d, self.mode)
        if self.mode == "velocity":
            merge = self._velocity_merges(runs, pair_a, pair_b, c["v_r"][rows], los[rows])
        else:
            merge = continuation_edges(
                runs, pair_a, pair_b, self.eps_d, self.eps_v, self.eps_t2, self.unknown_velocity == "accept"
            )
        edges = list(zip(pair_a[merge].tolist(), pair_b[merge].tolist(), strict=True))
        component = merge_components(len(runs.ids), edges, self.min_samples)
        cluster_of_position = np.repeat(np.arange(len(runs.ids)), runs.run_end - runs.run_start)
        representative = runs.order[runs.run_start]  # earliest detection of each cluster
        roots[runs.order] = rows[representative[component[cluster_of_position]]]
        return roots, [(int(runs.ids[a]), int(runs.ids[b])) for a, b in edges]

    def _velocity_merges(self, runs, pair_a, pair_b, v_r, los):
        """Eq. 6 for every pair; the velocities of all windows close enough in space are estimated in one batch."""
        merge = np.zeros(len(pair_a), dtype=bool)
        windows = velocity_windows(runs, pair_a, pair_b, self.eps_d, self.eps_t2)
        if len(windows) == 0:
            return merge
        # Rows of A's window (group 2i) and of B's (group 2i + 1), in time order, for every kept pair i.
        rows, group = velocity_window_rows(windows, runs.order)
        window_v_r, window_los = v_r[rows], los[rows]
        if np.isfinite(window_v_r.sum() + window_los.sum()):  # groups 0, 1, ... sorted, none empty: no regrouping
            vx, vy, _ = _estimate(window_v_r, window_los, group, 2 * len(windows), *_VELOCITY_DEFAULTS)
        else:  # non-finite rows are left out, as estimate_velocities leaves them out
            known_x, known_y, _, groups = _estimate_velocities(window_v_r, window_los, group)
            vx, vy = np.full(2 * len(windows), np.nan), np.full(2 * len(windows), np.nan)
            vx[groups.astype(np.int64)], vy[groups.astype(np.int64)] = known_x, known_y
        merge[windows[:, 0]] = velocity_agreement(vx, vy, self.eps_phi, self.eps_v, self.unknown_velocity == "accept")
        return merge
