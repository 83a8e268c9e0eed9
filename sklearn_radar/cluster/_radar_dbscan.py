"""RadarDBSCAN: spatio-temporal DBSCAN for radar detections (Eqs. 2-5)."""

from __future__ import annotations

from numbers import Integral, Real
from typing import ClassVar

import numpy as np
from joblib import Parallel, delayed, effective_n_jobs
from sklearn.base import BaseEstimator, ClusterMixin, _fit_context
from sklearn.utils._param_validation import Interval, StrOptions, validate_params

from .._labels import consecutive_labels, roots_to_rows
from .._neighbors import build_grid
from .._schema import STAGE1_READS
from .._validation import read_columns, sequence_slices
from ._radar_dbscan_kernels import (
    METRIC_CODES,
    cluster_causal,
    cluster_sorted,
    criterion_of,
    points_of,
)
from ._radar_dbscan_stream import STREAM_GATE_ERROR, ScanStream


@validate_params(
    {
        "range_m": ["array-like"],
        "min_samples": [Interval(Real, 1, None, closed="left")],
        "alpha_r": [Interval(Real, 0, 1, closed="both")],
        "range_scaling": [StrOptions({"reciprocal", "linear"})],
    },
    prefer_skip_nested_validation=True,
)
def min_points_at_range(range_m, min_samples, alpha_r, range_scaling="reciprocal"):
    """Eq. 2: the range-adaptive minimum number of points N_min(r).

    ``linear`` is the formula as printed in the paper,
    ``N_min,50 * (1 + alpha_r * (clip(r, 25, 125) / 50 - 1))``, which grows
    with range.  ``reciprocal`` is the relation the paper's text describes
    (remote objects have fewer reflections, so they need fewer points),
    ``N_min,50 * (1 + alpha_r * (50 / clip(r, 25, 125) - 1))``.

    Read more in the :ref:`User Guide <user-guide-radar-dbscan>`.

    Parameters
    ----------
    range_m : array-like
        Range of each detection to its sensor, m.
    min_samples : float >= 1
        N_min,50, the minimum at 50 m (real-valued).
    alpha_r : float in [0, 1]
        Slope; 0 gives the fixed ``min_samples``.
    range_scaling : {"reciprocal", "linear"}, default="reciprocal"
        Any other value raises ``InvalidParameterError`` (a ``ValueError``) naming the parameter.

    Returns
    -------
    ndarray of float
    """
    return _min_points_at_range(range_m, min_samples, alpha_r, range_scaling)


def _min_points_at_range(range_m, min_samples, alpha_r, range_scaling):
    """Eq. 2 without parameter validation, for callers that validated them (the stream calls it per scan)."""
    r = np.clip(np.asarray(range_m, dtype=np.float64), 25.0, 125.0)
    relative = r / 50.0 - 1.0 if range_scaling == "linear" else 50.0 / r - 1.0
    return min_samples * (1.0 + alpha_r * relative)


class RadarDBSCAN(ClusterMixin, BaseEstimator):
    """DBSCAN over x, y, Doppler and time for radar detections (Scheiner et al. 2019, Eqs. 2-5).

    Two detections are neighbours when they belong to the same sequence, lie
    at most ``eps_t`` apart in time (``|dt| <= eps_t``) and satisfy the
    neighbourhood criterion ``metric``:

    * ``"box"`` (Eq. 3): ``|dx| < eps_xy`` and ``|dy| < eps_xy`` and
      ``|dv_r| < eps_vr``, with dx, dy in the car axes of the later detection
      of the pair (column ``heading``; the sequence axes when it is absent).
      Two detections of the same time with different headings (which a real
      scan, one heading per time, cannot have) must pass the box in the
      axes of each: neither is the later one, and the test stays symmetric,
      so the labels do not depend on the row order;
    * ``"xy"`` (Eq. 4): ``sqrt(dx^2 + dy^2) < eps_xy`` and ``|dv_r| < eps_vr``;
    * ``"xyv"`` (Eq. 5): ``sqrt(dx^2 + dy^2 + dv_r^2 / vr_scale^2) < eps_xyv``.

    The spatial and Doppler comparisons are strict, as Eqs. 3-5 print them;
    the time comparison is inclusive, as the paper's text says ("smaller or
    equal"), although its equations print ``<``.  A detection is a core point when
    ``|v_r| > vr_min`` and it has at least ``N_min(r)`` neighbours counting
    itself (as scikit-learn does), with ``N_min(r)`` from Eq. 2 (see
    :func:`~sklearn_radar.cluster.min_points_at_range`; fixed ``min_samples`` when ``alpha_r = 0``).
    Clusters are the connected core points plus their border points; a
    border point joins its closest core neighbour.  Because neighbours must be
    close in time, an object seen for 20 s forms one cluster, and detections
    of different sequences never connect.  Rows with ``keep = False`` (see
    :class:`DopplerDensityFilter`) are noise and take part in nothing.

    Parameters
    ----------
    metric : {"box", "xy", "xyv"}, default="box"
        Neighbourhood criterion: Eq. 3, 4 or 5.
    eps_xy : float, default=1.0
        Spatial threshold of "box" and "xy", m.
    eps_vr : float, default=5.0
        Doppler threshold of "box" and "xy", m/s.
    eps_xyv : float, default=1.0
        Threshold of the joint distance of "xyv" (m, with Doppler scaled).
    vr_scale : float, default=1.0
        eps'_vr of Eq. 5: the Doppler difference, m/s, that counts like 1 m.
    eps_t : float or None, default=0.25
        Time threshold, s; None means no time limit.
    min_samples : float, default=3
        N_min (N_min,50 when ``alpha_r > 0``), real-valued; includes the point itself.
    alpha_r : float, default=0.0
        Slope of the range-adaptive minimum (Eq. 2); 0 fixes it at ``min_samples``.
    range_scaling : {"reciprocal", "linear"}, default="reciprocal"
        Form of Eq. 2, see :func:`~sklearn_radar.cluster.min_points_at_range`.  The paper prints
        the linear form (N_min grows with range) but describes the
        reciprocal one (remote objects give fewer reflections, so need fewer
        points); why the reciprocal form is the default is in the
        :ref:`User Guide <radar-dbscan-range-scaling>`.
    vr_min : float, default=0.4
        Only detections with ``|v_r| > vr_min`` (m/s) can be core points;
        ``-inf`` lets every detection be one.
    causal : bool, default=False
        If True, :meth:`fit` labels each scan as the real-time stream of
        :meth:`partial_fit` would: a detection's neighbours are only the
        detections at or before its time, its core status and label are
        decided when its scan arrives and never revised, and clusters that
        meet keep the older id.  If False, the whole time window around each
        detection (``|dt| <= eps_t``, past and future) is used.
    cluster_vr_min : float >= 0 or None, default=None
        Cluster-level Doppler gate, m/s: after clustering, a cluster whose
        median ``|v_r|`` (ego-motion-compensated radial speed) is at most
        ``cluster_vr_min`` becomes noise, and the remaining ids are
        renumbered consecutively.  None (the default) turns the gate off, so
        the paper's experiments stay as printed.  The gate needs the whole
        cluster, so :meth:`partial_fit` and :class:`ScanStream` raise when it
        is set; with ``causal=True`` :meth:`fit` applies it in hindsight, to
        the whole cluster.  Why it exists: :ref:`User Guide <radar-dbscan-cluster-gate>`.
    n_jobs : int, default=None
        Sequences clustered in parallel (joblib threads).

    Attributes
    ----------
    labels_ : ndarray of shape (n_detections,)
        Cluster id per row, -1 for noise.  Ids are consecutive, numbered in
        order of each cluster's first row, and unique across sequences.
    core_sample_indices_ : ndarray of shape (n_core,)
        Row positions of the core points.  The core points of clusters
        removed by ``cluster_vr_min`` are not listed (they are noise).
    n_features_in_ : int
    feature_names_in_ : ndarray of str
        When X is a DataFrame.

    Notes
    -----
    The defaults are the paper's expert setting (experiment #1).  Reads the
    columns ``x``, ``y`` (m), ``v_r`` (m/s), ``t`` (s) and, when present,
    ``sequence``, ``keep``, ``range_sc`` (m, needed when ``alpha_r > 0``) and
    ``heading`` (rad).  A plain array is read by position
    ``[x, y, v_r, t, sequence, keep, range_sc, heading]``
    (:data:`~sklearn_radar._schema.WORK_LAYOUT`); ``alpha_r > 0`` raises when
    ``range_sc`` is missing rather than assume a range.  With one
    sequence, ``eps_t=None``, ``alpha_r=0`` and ``vr_min=-inf`` the result is
    scikit-learn's DBSCAN on (x, y) with ``metric="xy"`` and a huge
    ``eps_vr``, on (x, y, v_r / vr_scale) with ``metric="xyv"``, and the
    Chebyshev DBSCAN on (x, y, v_r * eps_xy / eps_vr) with ``metric="box"``
    (up to ties at exactly eps).

    Read more in the :ref:`User Guide <user-guide-radar-dbscan>`.

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_radar import RadarDBSCAN
    >>> X = np.array([[0.0, 0.0], [0.5, 0.0], [1.0, 0.0], [9.0, 9.0]])
    >>> RadarDBSCAN(metric="xy", eps_xy=0.6, min_samples=2, vr_min=-np.inf).fit_predict(X)
    array([ 0,  0,  0, -1])
    """

    _parameter_constraints: ClassVar[dict] = {
        "metric": [StrOptions(set(METRIC_CODES))],
        "eps_xy": [Interval(Real, 0, None, closed="neither")],
        "eps_vr": [Interval(Real, 0, None, closed="neither")],
        "eps_xyv": [Interval(Real, 0, None, closed="neither")],
        "vr_scale": [Interval(Real, 0, None, closed="neither")],
        "eps_t": [Interval(Real, 0, None, closed="left"), None],
        "min_samples": [Interval(Real, 1, None, closed="left")],
        "alpha_r": [Interval(Real, 0, 1, closed="both")],
        "range_scaling": [StrOptions({"reciprocal", "linear"})],
        "vr_min": [Real],
        "causal": ["boolean"],
        "cluster_vr_min": [Interval(Real, 0, None, closed="left"), None],
        "n_jobs": [None, Integral],
    }

    def __init__(
        self,
        metric="box",
        eps_xy=1.0,
        eps_vr=5.0,
        eps_xyv=1.0,
        vr_scale=1.0,
        eps_t=0.25,
        min_samples=3,
        alpha_r=0.0,
        range_scaling="reciprocal",
        vr_min=0.4,
        causal=False,
        cluster_vr_min=None,
        n_jobs=None,
    ):
        self.metric = metric
        self.eps_xy = eps_xy
        self.eps_vr = eps_vr
        self.eps_xyv = eps_xyv
        self.vr_scale = vr_scale
        self.eps_t = eps_t
        self.min_samples = min_samples
        self.alpha_r = alpha_r
        self.range_scaling = range_scaling
        self.vr_min = vr_min
        self.causal = causal
        self.cluster_vr_min = cluster_vr_min
        self.n_jobs = n_jobs

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y=None):
        """Cluster the detections.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Detections with the working columns of :class:`FrameTransform`.
        y : None
            Ignored.

        Returns
        -------
        self : RadarDBSCAN
        """
        X, c = read_columns(self, X, STAGE1_READS, reset=True)
        self.__dict__.pop("_stream", None)  # a batch fit ends any stream
        n = len(c["x"])
        active, min_points, can_be_core = self._point_rules(c)
        roots = np.full(n, -1, dtype=np.int64)
        core = np.zeros(n, dtype=bool)
        active_rows = np.flatnonzero(active)
        sequence = None if c["sequence"] is None else c["sequence"][active_rows]
        slices = [active_rows[part] for part in sequence_slices(sequence)]
        cluster = self._cluster_sequence_causal if self.causal else self._cluster_sequence
        if len(slices) > 1 and effective_n_jobs(self.n_jobs) > 1:
            results = Parallel(n_jobs=self.n_jobs, prefer="threads")(
                delayed(cluster)(rows, c, min_points, can_be_core) for rows in slices
            )
        else:  # one thread: no pool to set up (a tenth of a 10,000-detection fit)
            results = [cluster(rows, c, min_points, can_be_core) for rows in slices]
        for rows, sequence_roots, sequence_core in results:
            roots_to_rows(rows, sequence_roots, roots)  # roots as global row numbers
            core[rows] = sequence_core
        roots = _gate_static_clusters(roots, c["v_r"], self.cluster_vr_min)
        self.labels_ = consecutive_labels(roots)
        self.core_sample_indices_ = np.flatnonzero(core & (roots >= 0))
        return self

    @_fit_context(prefer_skip_nested_validation=True)
    def partial_fit(self, X, y=None):
        """Label the next scan(s) of a live stream, using only the past.

        Keeps, per sequence, the detections of the last ``eps_t`` seconds
        and labels the new ones against them exactly as ``causal=True`` does
        offline.  A cluster that continues keeps its id from call to call;
        when two clusters meet, the older (smaller) id wins.  Ids are never
        reused.  The first call starts the stream; :meth:`fit` ends it.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            One or more complete scans, not older than anything already
            passed for their sequence.
        y : None
            Ignored.

        Returns
        -------
        self : RadarDBSCAN
            ``labels_`` holds the labels of the rows of X (-1 for noise).

        Raises
        ------
        ValueError
            When ``cluster_vr_min`` is set: the gate needs whole clusters, which a stream never has.
        """
        first_call = not hasattr(self, "_stream")
        if self.cluster_vr_min is not None:
            raise ValueError(STREAM_GATE_ERROR)
        X, c = read_columns(self, X, STAGE1_READS, reset=first_call)
        if first_call:
            self._stream = ScanStream(self)
        self.labels_ = self._stream._label(c)
        return self

    def _point_rules(self, c):
        """Per detection: taking part (keep), N_min (Eq. 2) and whether it may be core."""
        n = len(c["x"])
        if self.alpha_r > 0 and c["range_sc"] is None:
            raise ValueError("RadarDBSCAN: alpha_r > 0 needs the column 'range_sc' (range to the sensor, m)")
        active = np.ones(n, dtype=bool) if c["keep"] is None else c["keep"] != 0
        if self.alpha_r == 0:
            min_points = np.full(n, float(self.min_samples))
        else:
            min_points = _min_points_at_range(c["range_sc"], self.min_samples, self.alpha_r, self.range_scaling)
        return active, min_points, active & (np.abs(c["v_r"]) > self.vr_min)

    def _cluster_sequence_causal(self, rows, c, min_points, can_be_core):
        """Offline-causal roots (as positions within ``rows``) and core flags of one sequence."""
        order = np.argsort(c["t"][rows], kind="stable")
        rows_sorted = rows[order]
        t = c["t"][rows_sorted]
        heading = np.zeros(len(rows)) if c["heading"] is None else c["heading"][rows_sorted]
        points = points_of(
            x=c["x"][rows_sorted],
            y=c["y"][rows_sorted],
            v=c["v_r"][rows_sorted],
            t=t - t.min() if len(t) else t,
            heading=heading,
        )
        emitted, core_sorted = cluster_causal(
            points=points,
            min_points=min_points[rows_sorted],
            can_be_core=can_be_core[rows_sorted],
            criterion=self._kernel_criterion(heading),
        )
        # Express each emitted id as the (time-sorted) position of the first detection that carried it.
        first_carrier = np.full(len(rows), -1, dtype=np.int64)
        clustered = np.flatnonzero(emitted >= 0)
        _, first, inverse = np.unique(emitted[clustered], return_index=True, return_inverse=True)
        first_carrier[clustered] = clustered[first][inverse.ravel()]
        return (rows, *_unsort(order, first_carrier, core_sorted))

    def _cluster_sequence(self, rows, c, min_points, can_be_core):
        """Roots (positions within ``rows``, or -1) and core flags of one sequence."""
        if len(rows) == 0:
            return rows, np.zeros(0, dtype=np.int64), np.zeros(0, dtype=bool)
        t = c["t"][rows]
        t = t - t.min()  # small numbers: exact time-window edges
        heading = np.zeros(len(rows)) if c["heading"] is None else c["heading"][rows]
        grid = build_grid(c["x"][rows], c["y"][rows], t, self._cell_size(heading))
        order = grid.order
        sorted_roots, sorted_core = cluster_sorted(
            points=points_of(x=grid.x, y=grid.y, v=c["v_r"][rows][order], t=grid.t, heading=heading[order]),
            grid=grid,
            min_points=min_points[rows][order],
            can_be_core=can_be_core[rows][order],
            criterion=self._kernel_criterion(heading),
        )
        return (rows, *_unsort(order, sorted_roots, sorted_core))

    def _kernel_criterion(self, heading=None):
        """The kernels' criterion of these parameters, for points of car heading ``heading`` (rad; None: unknown)."""
        return criterion_of(
            metric=self.metric,
            eps_xy=self.eps_xy,
            eps_vr=self.eps_vr,
            vr_scale=self.vr_scale,
            eps_xyv=self.eps_xyv,
            eps_t=self.eps_t,
            heading=heading,
        )

    def _cell_size(self, heading):
        """Grid cell side, m: the largest spatial reach of the criterion."""
        if self.metric == "box":
            rotated = heading.any() and np.any(np.abs(np.sin(2.0 * heading)) > 1e-12)  # not a multiple of 90 degrees
            return self.eps_xy * np.sqrt(2.0) if rotated else self.eps_xy  # a rotated box reaches its corners
        return self.eps_xy if self.metric == "xy" else self.eps_xyv


def _gate_static_clusters(roots, v_r, cluster_vr_min):
    """Turn into noise every cluster whose median ``|v_r|`` is at most ``cluster_vr_min`` (m/s).

    Parameters
    ----------
    roots : ndarray of int, shape (n,)
        Any cluster key per row, negative for noise.
    v_r : ndarray of float, shape (n,)
        Ego-motion-compensated radial velocity, m/s.
    cluster_vr_min : float or None
        The gate, m/s; None returns ``roots`` unchanged.

    Returns
    -------
    roots : ndarray of int64, shape (n,)
        The same keys, -1 for the rows of gated clusters (not renumbered).
    """
    roots = np.asarray(roots, dtype=np.int64)
    if cluster_vr_min is None:
        return roots
    clustered = np.flatnonzero(roots >= 0)
    if len(clustered) == 0:
        return roots
    speed = np.abs(np.asarray(v_r, dtype=np.float64)[clustered])
    key = roots[clustered]
    order = np.lexsort((speed, key))
    key_sorted, speed_sorted = key[order], speed[order]
    start = np.flatnonzero(np.r_[True, key_sorted[1:] != key_sorted[:-1]])
    size = np.diff(np.r_[start, len(key_sorted)])
    median = 0.5 * (speed_sorted[start + (size - 1) // 2] + speed_sorted[start + size // 2])
    static = np.repeat(median <= cluster_vr_min, size)
    out = roots.copy()
    out[clustered[order[static]]] = -1
    return out


def _unsort(order, sorted_roots, sorted_core):
    """Roots and core flags of points processed in ``order``, back in the original order.

    Parameters
    ----------
    order : ndarray of int, shape (n,)
        Sorted position -> original position.
    sorted_roots : ndarray of int, shape (n,)
        Root of each sorted point as a sorted position, -1 for noise.
    sorted_core : ndarray of bool, shape (n,)

    Returns
    -------
    roots : ndarray of int64, shape (n,)
        Root of each point as an original position, -1 for noise.
    core : ndarray of bool, shape (n,)
    """
    roots = np.full(len(order), -1, dtype=np.int64)
    roots_to_rows(order, sorted_roots, roots)
    core = np.empty(len(order), dtype=bool)
    core[order] = sorted_core
    return roots, core
