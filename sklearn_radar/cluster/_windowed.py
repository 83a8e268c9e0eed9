"""The clusterers a user would otherwise pick: scikit-learn's DBSCAN and HDBSCAN per time window or per sequence,
and DBSCAN over a sliding past window (causal)."""

from __future__ import annotations

from numbers import Integral, Real
from typing import ClassVar

import numpy as np
from sklearn.base import BaseEstimator, ClusterMixin, _fit_context
from sklearn.cluster import DBSCAN, HDBSCAN
from sklearn.utils._param_validation import Interval

from .._labels import consecutive_labels
from .._schema import WINDOWED_READS
from .._validation import read_columns, sequence_slices

_SEPARATION = 1e5  # m between windows laid side by side for one DBSCAN call


def _window_ids(c, window):
    """Consecutive id per (sequence, time window of ``window`` s from the sequence start)."""
    t = c["t"]
    sequence = np.zeros(len(t)) if c["sequence"] is None else c["sequence"]
    _, code = np.unique(sequence, return_inverse=True)
    code = code.ravel()
    start = np.full(code.max() + 1 if len(code) else 0, np.inf)
    np.minimum.at(start, code, t)
    bins = np.floor((t - start[code]) / window).astype(np.int64)
    return np.unique(np.c_[code, bins], axis=0, return_inverse=True)[1].ravel()


class _WindowedClusterer(ClusterMixin, BaseEstimator):
    """Shared input handling: columns x, y (m), v_r (m/s), t (s), optional sequence and keep."""

    def _features(self, X, reset):
        X, c = read_columns(self, X, WINDOWED_READS, reset=reset)
        active = np.ones(len(c["x"]), dtype=bool) if c["keep"] is None else c["keep"] != 0
        features = np.c_[c["x"], c["y"], c["v_r"] / self.vr_scale]
        return features, _window_ids(c, self.window), active


class WindowedDBSCAN(_WindowedClusterer):
    """scikit-learn's DBSCAN on (x, y, v_r / vr_scale), each ``window`` of each sequence on its own.

    The baseline a radar engineer would reach for first: a detection's
    neighbourhood is Euclidean in x-y and scaled Doppler, and clusters cannot
    span time windows (there is no sliding window), so an object becomes one
    cluster per window.  Rows with ``keep = False`` are noise.

    Read more in the :ref:`User Guide <user-guide-radar-dbscan>`.

    Parameters
    ----------
    eps : float, default=1.0
        Neighbourhood radius in (m, m, v_r / vr_scale).
    min_samples : int, default=3
        Including the point itself.
    vr_scale : float, default=1.0
        Doppler difference, m/s, that counts like 1 m.
    window : float, default=0.25
        Window length, s.

    Attributes
    ----------
    labels_ : ndarray of shape (n_detections,)
    n_features_in_ : int
    feature_names_in_ : ndarray of str
        When X is a DataFrame.
    """

    _parameter_constraints: ClassVar[dict] = {
        "eps": [Interval(Real, 0, None, closed="neither")],
        "min_samples": [Interval(Integral, 1, None, closed="left")],
        "vr_scale": [Interval(Real, 0, None, closed="neither")],
        "window": [Interval(Real, 0, None, closed="neither")],
    }

    def __init__(self, eps=1.0, min_samples=3, vr_scale=1.0, window=0.25):
        self.eps = eps
        self.min_samples = min_samples
        self.vr_scale = vr_scale
        self.window = window

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y=None):
        """Cluster every window; one scikit-learn call with the windows laid far apart.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections with the columns ``x``, ``y`` (m), ``v_r`` (m/s), ``t`` (s) and
            optionally ``sequence`` and ``keep``.
        y : None
            Ignored.

        Returns
        -------
        self : WindowedDBSCAN
            With ``labels_``.
        """
        features, window_id, active = self._features(X, reset=True)
        labels = np.full(len(features), -1, dtype=np.int64)
        if active.any():
            laid_out = features[active] - features[active].min(axis=0)
            laid_out[:, 0] += _SEPARATION * window_id[active]
            labels[active] = DBSCAN(eps=self.eps, min_samples=self.min_samples).fit_predict(laid_out)
        self.labels_ = consecutive_labels(labels)
        return self


def _fewest_hdbscan_rows(min_cluster_size, min_samples):
    """Fewest rows a part needs for HDBSCAN to find a cluster (with fewer, scikit-learn raises or finds none)."""
    return max(min_cluster_size, min_samples or 0, 2)


class WindowedHDBSCAN(_WindowedClusterer):
    """scikit-learn's HDBSCAN on (x, y, v_r / vr_scale), each ``window`` of each sequence on its own.

    Read more in the :ref:`User Guide <user-guide-radar-dbscan>`.

    Parameters
    ----------
    min_cluster_size : int, default=3
        Smallest cluster, in detections.
    min_samples : int, default=None
        None: equal to ``min_cluster_size``.
    cluster_selection_epsilon : float, default=0.0
        Clusters closer than this (m, in the scaled space) are merged.
    vr_scale : float, default=1.0
        Doppler difference, m/s, that counts like 1 m.
    window : float, default=0.25
        Window length, s.

    Attributes
    ----------
    labels_ : ndarray of shape (n_detections,)
    n_features_in_ : int
    feature_names_in_ : ndarray of str
        When X is a DataFrame.
    """

    _parameter_constraints: ClassVar[dict] = {
        "min_cluster_size": [Interval(Integral, 2, None, closed="left")],
        "min_samples": [Interval(Integral, 1, None, closed="left"), None],
        "cluster_selection_epsilon": [Interval(Real, 0, None, closed="left")],
        "vr_scale": [Interval(Real, 0, None, closed="neither")],
        "window": [Interval(Real, 0, None, closed="neither")],
    }

    def __init__(self, min_cluster_size=3, min_samples=None, cluster_selection_epsilon=0.0, vr_scale=1.0, window=0.25):
        self.min_cluster_size = min_cluster_size
        self.min_samples = min_samples
        self.cluster_selection_epsilon = cluster_selection_epsilon
        self.vr_scale = vr_scale
        self.window = window

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y=None):
        """Cluster every window with its own HDBSCAN.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections with the columns ``x``, ``y`` (m), ``v_r`` (m/s), ``t`` (s) and
            optionally ``sequence`` and ``keep``.
        y : None
            Ignored.

        Returns
        -------
        self : WindowedHDBSCAN
            With ``labels_``.
        """
        features, window_id, active = self._features(X, reset=True)
        labels = np.full(len(features), -1, dtype=np.int64)
        rows = np.flatnonzero(active)
        order = rows[np.argsort(window_id[rows], kind="stable")]
        offset = 0
        for part in np.split(order, np.flatnonzero(np.diff(window_id[order])) + 1):
            if len(part) < _fewest_hdbscan_rows(self.min_cluster_size, self.min_samples):
                continue
            found = HDBSCAN(
                min_cluster_size=self.min_cluster_size,
                min_samples=self.min_samples,
                cluster_selection_epsilon=float(self.cluster_selection_epsilon),
                copy=True,
            ).fit_predict(features[part])
            labels[part] = np.where(found >= 0, found + offset, -1)
            offset += max(found.max() + 1, 0)
        self.labels_ = consecutive_labels(labels)
        return self


class _SequenceClusterer(ClusterMixin, BaseEstimator):
    """Shared input handling of the per-sequence baselines: scaled (x, y, v_r, t) and the Doppler gate."""

    def _features(self, X, reset):
        """Features (x, y, v_r / vr_scale, t * t_scale), rows taking part, the row indices of each sequence, t (s)."""
        X, c = read_columns(self, X, WINDOWED_READS, reset=reset)
        active = np.abs(c["v_r"]) > self.vr_min
        if c["keep"] is not None:
            active &= c["keep"] != 0
        features = np.c_[c["x"], c["y"], c["v_r"] / self.vr_scale, c["t"] * self.t_scale]
        sequences = [np.arange(len(features))[rows] for rows in sequence_slices(c["sequence"])]
        return features, active, sequences, c["t"]


class SequenceDBSCAN(_SequenceClusterer):
    """scikit-learn's DBSCAN on (x, y, v_r / vr_scale, t * t_scale) over each whole sequence, with a Doppler gate.

    The baseline a user would pick who knows that radar clusters need time
    and that static detections are background: one Euclidean DBSCAN in
    space, scaled Doppler and scaled time, so an object can form one
    cluster for as long as it is seen (no windows), and detections with
    ``|v_r| <= vr_min`` are noise before clustering (the gate removes the
    static background; unlike :class:`RadarDBSCAN`'s ``vr_min`` they are
    not even border points).  Rows with ``keep = False`` are noise.
    Sequences never share a cluster: they are clustered in one scikit-learn
    call, laid far apart along x.

    Read more in the :ref:`User Guide <user-guide-objects>`.

    Parameters
    ----------
    eps : float, default=1.0
        Neighbourhood radius in the scaled space (m, m, v_r / vr_scale, t * t_scale).
    min_samples : int, default=3
        Including the point itself.
    vr_scale : float, default=1.0
        Doppler difference, m/s, that counts like 1 m.
    t_scale : float, default=4.0
        How many metres one second counts, m/s: with ``eps = 1`` m the
        default reaches 0.25 s, the paper's ``eps_t``.
    vr_min : float, default=0.4
        Doppler gate, m/s: detections with ``|v_r| <= vr_min`` are noise
        (the paper's expert setting uses 0.4 m/s for its core points);
        ``-inf`` keeps every detection.

    Attributes
    ----------
    labels_ : ndarray of shape (n_detections,)
        Cluster id per row, -1 for noise; consecutive ids, unique across sequences.
    n_features_in_ : int
    feature_names_in_ : ndarray of str
        When X is a DataFrame.
    """

    _parameter_constraints: ClassVar[dict] = {
        "eps": [Interval(Real, 0, None, closed="neither")],
        "min_samples": [Interval(Integral, 1, None, closed="left")],
        "vr_scale": [Interval(Real, 0, None, closed="neither")],
        "t_scale": [Interval(Real, 0, None, closed="left")],
        "vr_min": [Real],
    }

    def __init__(self, eps=1.0, min_samples=3, vr_scale=1.0, t_scale=4.0, vr_min=0.4):
        self.eps = eps
        self.min_samples = min_samples
        self.vr_scale = vr_scale
        self.t_scale = t_scale
        self.vr_min = vr_min

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y=None):
        """Cluster every sequence; one scikit-learn call with the sequences laid far apart.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections with the columns ``x``, ``y`` (m), ``v_r`` (m/s), ``t`` (s) and
            optionally ``sequence`` and ``keep``.
        y : None
            Ignored.

        Returns
        -------
        self : SequenceDBSCAN
            With ``labels_``.
        """
        features, active, sequences, _ = self._features(X, reset=True)
        labels = np.full(len(features), -1, dtype=np.int64)
        laid_out = np.zeros_like(features)
        offset = 0.0
        for rows in sequences:
            rows = rows[active[rows]]
            if len(rows) == 0:
                continue
            part = features[rows] - features[rows].min(axis=0)  # each sequence starts at the origin
            part[:, 0] += offset
            laid_out[rows] = part
            offset += float(np.ptp(part[:, 0])) + 2.0 * self.eps + 1.0  # farther than eps from the next sequence
        rows = np.flatnonzero(active)
        if len(rows):
            labels[rows] = DBSCAN(eps=self.eps, min_samples=self.min_samples).fit_predict(laid_out[rows])
        self.labels_ = consecutive_labels(labels)
        return self


class SequenceHDBSCAN(_SequenceClusterer):
    """scikit-learn's HDBSCAN on (x, y, v_r / vr_scale, t * t_scale) over each whole sequence, with a Doppler gate.

    As :class:`SequenceDBSCAN`, with one HDBSCAN call per sequence.
    Detections with ``|v_r| <= vr_min`` and rows with ``keep = False`` are
    noise and take part in nothing.

    Read more in the :ref:`User Guide <user-guide-objects>`.

    Parameters
    ----------
    min_cluster_size : int, default=3
        Smallest cluster, in detections.
    min_samples : int, default=None
        None: equal to ``min_cluster_size``.
    cluster_selection_epsilon : float, default=0.0
        Clusters closer than this (m, in the scaled space) are merged.
    vr_scale : float, default=1.0
        Doppler difference, m/s, that counts like 1 m.
    t_scale : float, default=4.0
        How many metres one second counts, m/s.
    vr_min : float, default=0.4
        Doppler gate, m/s: detections with ``|v_r| <= vr_min`` are noise;
        ``-inf`` keeps every detection.

    Attributes
    ----------
    labels_ : ndarray of shape (n_detections,)
        Cluster id per row, -1 for noise; consecutive ids, unique across sequences.
    n_features_in_ : int
    feature_names_in_ : ndarray of str
        When X is a DataFrame.
    """

    _parameter_constraints: ClassVar[dict] = {
        "min_cluster_size": [Interval(Integral, 2, None, closed="left")],
        "min_samples": [Interval(Integral, 1, None, closed="left"), None],
        "cluster_selection_epsilon": [Interval(Real, 0, None, closed="left")],
        "vr_scale": [Interval(Real, 0, None, closed="neither")],
        "t_scale": [Interval(Real, 0, None, closed="left")],
        "vr_min": [Real],
    }

    def __init__(
        self, min_cluster_size=3, min_samples=None, cluster_selection_epsilon=0.0, vr_scale=1.0, t_scale=4.0, vr_min=0.4
    ):
        self.min_cluster_size = min_cluster_size
        self.min_samples = min_samples
        self.cluster_selection_epsilon = cluster_selection_epsilon
        self.vr_scale = vr_scale
        self.t_scale = t_scale
        self.vr_min = vr_min

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y=None):
        """Cluster every sequence with its own HDBSCAN.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections with the columns ``x``, ``y`` (m), ``v_r`` (m/s), ``t`` (s) and
            optionally ``sequence`` and ``keep``.
        y : None
            Ignored.

        Returns
        -------
        self : SequenceHDBSCAN
            With ``labels_``.
        """
        features, active, sequences, _ = self._features(X, reset=True)

        def label(rows):
            if len(rows) < _fewest_hdbscan_rows(self.min_cluster_size, self.min_samples):
                return np.full(len(rows), -1, dtype=np.int64)
            return HDBSCAN(
                min_cluster_size=self.min_cluster_size,
                min_samples=self.min_samples,
                cluster_selection_epsilon=float(self.cluster_selection_epsilon),
                copy=True,
            ).fit_predict(features[rows] - features[rows].min(axis=0))

        self.labels_ = _each_sequence(label, len(features), active, sequences)
        return self


class SlidingDBSCAN(_SequenceClusterer):
    """scikit-learn's DBSCAN over a sliding past window, scan by scan: the causal form of :class:`SequenceDBSCAN`.

    What a user who needs labels in real time would build from scikit-learn:
    when a scan (the detections of one time) arrives, DBSCAN clusters the
    window of the last ``window`` seconds, ``(t - window, t]``, in the space
    of :class:`SequenceDBSCAN` (x, y, v_r / vr_scale, t * t_scale), and only
    the new scan's detections are labelled.  A new detection's cluster takes
    the oldest id among the already labelled detections of its window
    cluster, or a new id when it has none, so ids persist from scan to scan
    and, where clusters meet, the older one survives.  Labels once given are
    never revised, and nothing after a scan changes its labels.  Detections
    with ``|v_r| <= vr_min`` and rows with ``keep = False`` are noise and
    take part in nothing; sequences never share a cluster.

    Read more in the :ref:`User Guide <user-guide-objects>`.

    Parameters
    ----------
    eps : float, default=1.0
        Neighbourhood radius in the scaled space (m, m, v_r / vr_scale, t * t_scale).
    min_samples : int, default=3
        Including the point itself.
    vr_scale : float, default=1.0
        Doppler difference, m/s, that counts like 1 m.
    t_scale : float, default=4.0
        How many metres one second counts, m/s.
    vr_min : float, default=0.4
        Doppler gate, m/s: detections with ``|v_r| <= vr_min`` are noise;
        ``-inf`` keeps every detection.
    window : float, default=0.5
        Length of the past window, s.

    Attributes
    ----------
    labels_ : ndarray of shape (n_detections,)
        Cluster id per row, -1 for noise; consecutive ids, unique across sequences.
    n_features_in_ : int
    feature_names_in_ : ndarray of str
        When X is a DataFrame.

    See Also
    --------
    SequenceDBSCAN : the same space over the whole sequence, past and future.
    RadarDBSCAN : ``causal=True`` is the framework's causal stage 1.

    Notes
    -----
    One DBSCAN call per scan: the cost grows with the number of scans times
    the detections in a window.
    """

    _parameter_constraints: ClassVar[dict] = {
        **SequenceDBSCAN._parameter_constraints,
        "window": [Interval(Real, 0, None, closed="neither")],
    }

    def __init__(self, eps=1.0, min_samples=3, vr_scale=1.0, t_scale=4.0, vr_min=0.4, window=0.5):
        self.eps = eps
        self.min_samples = min_samples
        self.vr_scale = vr_scale
        self.t_scale = t_scale
        self.vr_min = vr_min
        self.window = window

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y=None):
        """Label every sequence scan by scan, each scan from its past window only.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections with the columns ``x``, ``y`` (m), ``v_r`` (m/s), ``t`` (s) and
            optionally ``sequence`` and ``keep``.
        y : None
            Ignored.

        Returns
        -------
        self : SlidingDBSCAN
            With ``labels_``.
        """
        features, active, sequences, times = self._features(X, reset=True)

        def label(rows):
            return _sliding_window_labels(features[rows], times[rows], self.window, self.eps, self.min_samples)

        self.labels_ = _each_sequence(label, len(features), active, sequences)
        return self


def _each_sequence(label, n_rows, active, sequences):
    """Labels of every row: ``label(rows)`` on each sequence's active rows, ids made unique and consecutive."""
    labels = np.full(n_rows, -1, dtype=np.int64)
    offset = 0
    for rows in sequences:
        rows = rows[active[rows]]
        if len(rows) == 0:
            continue
        found = label(rows)
        labels[rows] = np.where(found >= 0, found + offset, -1)
        offset += max(found.max(initial=-1) + 1, 0)
    return consecutive_labels(labels)


def _sliding_window_labels(features, t, window, eps, min_samples):
    """Scan-by-scan labels of one sequence's rows: DBSCAN on each scan's past window ``(t - window, t]``.

    Ids are local, increasing in order of first use; -1 is noise.
    """
    labels = np.full(len(t), -1, dtype=np.int64)
    if len(t) == 0:
        return labels
    order = np.argsort(t, kind="stable")
    t_sorted = t[order]
    scan_times, scan_start = np.unique(t_sorted, return_index=True)
    scan_end = np.append(scan_start[1:], len(t_sorted))
    window_start = np.searchsorted(t_sorted, scan_times - window, side="right")
    next_id = 0
    dbscan = DBSCAN(eps=eps, min_samples=min_samples)
    for first, start, end in zip(window_start, scan_start, scan_end, strict=True):
        rows = order[first:end]
        if end - first < min_samples:
            continue
        found = dbscan.fit_predict(features[rows] - features[rows].min(axis=0))
        past, new = found[: start - first], found[start - first :]
        past_labels = labels[rows[: start - first]]
        for cluster in np.unique(new[new >= 0]):
            known = past_labels[(past == cluster) & (past_labels >= 0)]
            if len(known):
                cluster_id = known.min()
            else:
                cluster_id, next_id = next_id, next_id + 1
            labels[rows[start - first :][new == cluster]] = cluster_id
    return labels
