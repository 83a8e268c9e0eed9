"""RadarDBSCAN: spatio-temporal DBSCAN for radar detections (Eqs. 2-5)."""

from __future__ import annotations

from numbers import Integral, Real

import numpy as np
from joblib import Parallel, delayed
from sklearn.base import BaseEstimator, ClusterMixin, _fit_context
from sklearn.utils._param_validation import Interval, StrOptions

from .._neighbors import build_grid
from .._validation import read_columns, sequence_slices
from ._radar_dbscan_kernels import METRIC_CODES, dbscan_sorted

_REQUIRED = ("x", "y", "v_r", "t")
_OPTIONAL = ("sequence", "keep", "range_sc", "heading")


def min_points_at_range(range_m, min_samples, alpha_r, range_scaling="reciprocal"):
    """Eq. 2: the range-adaptive minimum number of points N_min(r).

    ``linear`` is the formula as printed in the paper,
    ``N_min,50 * (1 + alpha_r * (clip(r, 25, 125) / 50 - 1))``, which grows
    with range.  ``reciprocal`` is the relation the paper's text describes
    (remote objects have fewer reflections, so they need fewer points),
    ``N_min,50 * (1 + alpha_r * (50 / clip(r, 25, 125) - 1))``.

    Parameters
    ----------
    range_m : array-like
        Range of each detection to its sensor, m.
    min_samples : float
        N_min,50, the minimum at 50 m (real-valued).
    alpha_r : float
        Slope; 0 gives the fixed ``min_samples``.
    range_scaling : {"reciprocal", "linear"}, default="reciprocal"

    Returns
    -------
    ndarray of float
    """
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
      of the pair (column ``heading``; the sequence axes when it is absent);
    * ``"xy"`` (Eq. 4): ``sqrt(dx^2 + dy^2) < eps_xy`` and ``|dv_r| < eps_vr``;
    * ``"xyv"`` (Eq. 5): ``sqrt(dx^2 + dy^2 + dv_r^2 / vr_scale^2) < eps_xyv``.

    The spatial and Doppler comparisons are strict and the time comparison
    inclusive, as printed in the paper.  A detection is a core point when
    ``|v_r| > vr_min`` and it has at least ``N_min(r)`` neighbours counting
    itself (as scikit-learn does), with ``N_min(r)`` from Eq. 2 (see
    :func:`min_points_at_range`; fixed ``min_samples`` when ``alpha_r = 0``).
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
        Form of Eq. 2, see :func:`min_points_at_range`.
    vr_min : float, default=0.4
        Only detections with ``|v_r| > vr_min`` (m/s) can be core points;
        ``-inf`` lets every detection be one.
    n_jobs : int, default=None
        Sequences clustered in parallel (joblib threads).

    Attributes
    ----------
    labels_ : ndarray of shape (n_detections,)
        Cluster id per row, -1 for noise.  Ids are consecutive, numbered in
        order of each cluster's first row, and unique across sequences.
    core_sample_indices_ : ndarray of shape (n_core,)
        Row positions of the core points.
    n_features_in_ : int
    feature_names_in_ : ndarray of str
        When X is a DataFrame.

    Notes
    -----
    The defaults are the paper's expert setting (experiment #1).  Reads the
    columns ``x``, ``y`` (m), ``v_r`` (m/s), ``t`` (s) and, when present,
    ``sequence``, ``keep``, ``range_sc`` (m, needed when ``alpha_r > 0``) and
    ``heading`` (rad).  A plain array is read by position
    ``[x, y, v_r, t, sequence, keep, range_sc, heading]``.  With one
    sequence, ``eps_t=None``, ``alpha_r=0`` and ``vr_min=-inf`` the result is
    scikit-learn's DBSCAN on (x, y) with ``metric="xy"`` and a huge
    ``eps_vr``, on (x, y, v_r / vr_scale) with ``metric="xyv"``, and the
    Chebyshev DBSCAN on (x, y, v_r * eps_xy / eps_vr) with ``metric="box"``
    (up to ties at exactly eps).

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_radar import RadarDBSCAN
    >>> X = np.array([[0.0, 0.0], [0.5, 0.0], [1.0, 0.0], [9.0, 9.0]])
    >>> RadarDBSCAN(metric="xy", eps_xy=0.6, min_samples=2, vr_min=-np.inf).fit_predict(X)
    array([ 0,  0,  0, -1])
    """

    _parameter_constraints: dict = {
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
        X, c = read_columns(self, X, _REQUIRED, _OPTIONAL, reset=True)
        if self.alpha_r > 0 and c["range_sc"] is None:
            raise ValueError("RadarDBSCAN: alpha_r > 0 needs the column 'range_sc' (range to the sensor, m)")
        n = len(c["x"])
        active = np.ones(n, dtype=bool) if c["keep"] is None else c["keep"] != 0
        min_points = self._min_points(c["range_sc"], n)
        can_be_core = active & (np.abs(c["v_r"]) > self.vr_min)
        roots = np.full(n, -1, dtype=np.int64)
        core = np.zeros(n, dtype=bool)
        active_rows = np.flatnonzero(active)
        sequence = None if c["sequence"] is None else c["sequence"][active_rows]
        slices = [active_rows[part] for part in sequence_slices(sequence)]
        results = Parallel(n_jobs=self.n_jobs, prefer="threads")(
            delayed(self._cluster_sequence)(rows, c, min_points, can_be_core) for rows in slices
        )
        for rows, sequence_roots, sequence_core in results:
            found = sequence_roots >= 0
            roots[rows[found]] = rows[sequence_roots[found]]  # roots as global row numbers
            core[rows] = sequence_core
        self.labels_ = _consecutive_labels(roots)
        self.core_sample_indices_ = np.flatnonzero(core)
        return self

    def _min_points(self, range_sc, n):
        if self.alpha_r == 0:
            return np.full(n, float(self.min_samples))
        return min_points_at_range(range_sc, self.min_samples, self.alpha_r, self.range_scaling)

    def _cluster_sequence(self, rows, c, min_points, can_be_core):
        """Roots (positions within ``rows``, or -1) and core flags of one sequence."""
        if len(rows) == 0:
            return rows, np.zeros(0, dtype=np.int64), np.zeros(0, dtype=bool)
        t = c["t"][rows]
        t = t - t.min()  # small numbers: exact time-window edges
        eps_t = np.inf if self.eps_t is None else float(self.eps_t)
        grid = build_grid(c["x"][rows], c["y"][rows], t, self._cell_size())
        order = grid.order
        heading = np.zeros(len(rows)) if c["heading"] is None else c["heading"][rows]
        sorted_roots, sorted_core = dbscan_sorted(
            grid.x, grid.y, np.ascontiguousarray(c["v_r"][rows][order]), grid.t,
            np.cos(heading[order]), np.sin(heading[order]),
            np.ascontiguousarray(min_points[rows][order]), np.ascontiguousarray(can_be_core[rows][order]),
            grid.cell_x, grid.cell_y, grid.cell_keys, grid.cell_start, grid.cell_end,
            METRIC_CODES[self.metric], float(self.eps_xy), float(self.eps_vr), float(self.vr_scale),
            float(self.eps_xyv), eps_t,
        )  # fmt: skip
        roots = np.full(len(rows), -1, dtype=np.int64)
        core = np.empty(len(rows), dtype=bool)
        found = sorted_roots >= 0
        roots[order[found]] = order[sorted_roots[found]]
        core[order] = sorted_core
        return rows, roots, core

    def _cell_size(self):
        """Grid cell side, m: the largest spatial reach of the criterion."""
        if self.metric == "box":
            return self.eps_xy * np.sqrt(2.0)  # a rotated box reaches its corners
        return self.eps_xy if self.metric == "xy" else self.eps_xyv


def _consecutive_labels(roots):
    """Cluster ids 0, 1, ... in order of each cluster's first row; -1 stays -1."""
    labels = np.full(len(roots), -1, dtype=np.int64)
    clustered = roots >= 0
    if clustered.any():
        _, first, inverse = np.unique(roots[clustered], return_index=True, return_inverse=True)
        rank = np.empty(len(first), dtype=np.int64)
        rank[np.argsort(first, kind="stable")] = np.arange(len(first))
        labels[clustered] = rank[inverse.ravel()]
    return labels
