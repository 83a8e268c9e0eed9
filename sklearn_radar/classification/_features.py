"""Cluster features: one row per cluster (and time window) of clustered radar detections.

The features are the established ones of feature-based radar road-user
classification (Scheiner et al., "Radar-based feature design and multiclass
classification for road user recognition", IV 2018; Schumann et al.,
"Comparison of random forest and long short-term memory network performances
in classification tasks using radar", SDF 2017), computed from the
detections of one *segment*: one cluster of one sequence, or its part inside
one time window (:data:`CLUSTER_FEATURES` lists them with their units).

Implementation: the clustered rows are sorted once by segment (sequence,
cluster, window); sums are ``np.add.reduceat``, extremes
``np.maximum.reduceat`` / ``np.minimum.reduceat`` over the sorted rows, the
sensor count a (segment, sensor) presence table, and the velocity of Eq. 6
is the batched estimate of :mod:`sklearn_radar.cluster._velocity` (one
compiled call for all segments).  No Python loop runs over segments; apart
from the sort, work is linear in the number of detections.
"""

from __future__ import annotations

from numbers import Real

import numpy as np
import pandas as pd
from sklearn.utils._param_validation import Interval, validate_params

from .._schema import CLUSTER_FEATURE_READS
from .._validation import _numeric_column, check_plausible
from ..cluster._velocity import _velocities_and_residuals

__all__ = ["CLUSTER_FEATURES", "cluster_features"]

#: ``{feature: (unit, meaning, columns it needs besides x, y, v_r, t)}``, in the order of the feature table.
CLUSTER_FEATURES = {
    "n_detections": ("1", "number of detections", ()),
    "duration": ("s", "time from the first to the last detection", ()),
    "extent_along": ("m", "extent (max - min) of the x-y positions along the first principal axis", ()),
    "extent_across": ("m", "extent of the x-y positions along the second principal axis", ()),
    "vr_mean": ("m/s", "mean compensated Doppler velocity v_r", ()),
    "vr_std": ("m/s", "standard deviation of v_r (population, ddof=0)", ()),
    "vr_range": ("m/s", "max - min of v_r", ()),
    "rcs_mean": ("dBsm", "mean radar cross section (of the dB values)", ("rcs",)),
    "rcs_std": ("dB", "standard deviation of the RCS", ("rcs",)),
    "rcs_max": ("dBsm", "largest RCS", ("rcs",)),
    "range_mean": ("m", "mean range to the measuring sensor", ("range_sc",)),
    "azimuth_spread": (
        "rad",
        "circular standard deviation of the line of sight azimuth_sc + sensor_yaw in the car frame",
        ("azimuth_sc", "sensor_yaw"),
    ),
    "speed": (
        "m/s",
        "magnitude of the Eq. 6 velocity estimate (Kellner et al. 2013; NaN when unknown)",
        ("azimuth_sc", "sensor_yaw"),
    ),
    "speed_residual": (
        "m/s",
        "RMS of v_r minus the Doppler the Eq. 6 velocity predicts, all detections (NaN when unknown)",
        ("azimuth_sc", "sensor_yaw"),
    ),
    "length": (
        "m",
        "extent along the first principal axis of the positions moved to the segment's mean time with the Eq. 6 "
        "velocity (NaN when unknown)",
        ("azimuth_sc", "sensor_yaw"),
    ),
    "width": ("m", "the same along the second principal axis (NaN when unknown)", ("azimuth_sc", "sensor_yaw")),
    "n_sensors": ("1", "number of distinct sensors that saw the segment", ("sensor_id",)),
}

#: The columns of the feature table that say which segment a row describes.
KEY_COLUMNS = ("sequence", "cluster", "window")


@validate_params(
    {
        "X": [pd.DataFrame],
        "labels": ["array-like"],
        "window": [Interval(Real, 0, None, closed="neither"), None],
        "return_rows": ["boolean"],
    },
    prefer_skip_nested_validation=True,
)
def cluster_features(X, labels, *, window=None, return_rows=False):
    """One row of features per cluster of each sequence, or per time window of each cluster.

    A *segment* is the set of detections of one cluster (``labels``, -1 =
    noise, which belongs to none) in one sequence; with ``window`` it
    is cut into time windows, detection ``i`` of sequence ``s`` lying in window
    ``floor((t[i] - min(t of s)) / window)`` (the windows of
    :func:`~sklearn_radar.metrics.instance_scores`).  The features of a
    segment, with their units (:data:`CLUSTER_FEATURES`):

    ==================  =====  ==================================================
    feature             unit   meaning
    ==================  =====  ==================================================
    ``n_detections``    1      number of detections
    ``duration``        s      last minus first detection time
    ``extent_along``    m      extent of the x-y positions along the first
                               principal axis (of their 2 x 2 covariance)
    ``extent_across``   m      extent along the second principal axis
    ``vr_mean``         m/s    mean compensated Doppler ``v_r``
    ``vr_std``          m/s    standard deviation of ``v_r``
    ``vr_range``        m/s    max - min of ``v_r``
    ``rcs_mean``        dBsm   mean RCS (of the dB values)
    ``rcs_std``         dB     standard deviation of the RCS
    ``rcs_max``         dBsm   largest RCS
    ``range_mean``      m      mean range to the measuring sensor
    ``azimuth_spread``  rad    circular standard deviation of the car-frame
                               line of sight ``azimuth_sc + sensor_yaw``
    ``speed``           m/s    magnitude of the Eq. 6 velocity estimate
                               (RANSAC and least squares over the segment's
                               Doppler and lines of sight,
                               :func:`~sklearn_radar.cluster.estimate_velocities`
                               at its defaults); NaN when unknown
    ``speed_residual``  m/s    root mean square, over all the segment's
                               detections, of ``v_r`` minus the Doppler that
                               velocity predicts; NaN when unknown
    ``length``          m      extent along the first principal axis of the
                               positions moved to the segment's mean time with
                               that velocity, ``x - vx (t - mean t)`` (likewise
                               y): the body without the distance it travels;
                               NaN when the velocity is unknown
    ``width``           m      the same along the second principal axis
    ``n_sensors``       1      number of distinct ``sensor_id``
    ==================  =====  ==================================================

    Standard deviations are population ones (ddof = 0).  The extents are of
    the positions accumulated over the segment's time span, so a moving
    object's extent along its track includes the distance it travels in that
    time, as in features accumulated over a time window (Scheiner et al.
    2018); ``length`` and ``width`` take the travel out (in the fixed frame,
    ``FrameTransform(frame="frame")``; in the car frame the ego motion stays
    in every position).  A feature whose column X lacks is left out of the
    table, never made up: the RCS features need ``rcs``, ``range_mean`` needs
    ``range_sc``, ``azimuth_spread`` and the velocity features need
    ``azimuth_sc`` and ``sensor_yaw`` (the line of sight of Eq. 6 is
    ``azimuth_sc + sensor_yaw + heading``, ``heading`` 0 when absent), and
    ``n_sensors`` needs ``sensor_id``.

    Read more in the :ref:`User Guide <user-guide-classification>`.

    Parameters
    ----------
    X : DataFrame of shape (n_detections, n_columns)
        Detections with the working columns ``x``, ``y`` (m), ``v_r`` (m/s)
        and ``t`` (s) of :class:`~sklearn_radar.FrameTransform`, and, when
        present, ``sequence``, ``rcs`` (dBsm), ``range_sc`` (m),
        ``azimuth_sc``, ``sensor_yaw``, ``heading`` (rad) and ``sensor_id``.
    labels : array-like of int, shape (n_detections,)
        Cluster of each detection, -1 for noise (e.g. ``RadarDBSCAN().fit(X).labels_``).
        Equal labels in different sequences are different segments.
    window : float or None, default=None
        Length of a time window, s, > 0.  None: one segment per cluster and
        sequence.
    return_rows : bool, default=False
        Also return the row of the feature table of each detection.

    Returns
    -------
    features : DataFrame of shape (n_segments, 3 + n_features)
        ``sequence``, ``cluster`` and ``window`` (0 when ``window`` is
        None) of each segment, sorted by them, then the features in the order
        of the table above.
    rows : ndarray of int64, shape (n_detections,)
        Only with ``return_rows``: the position in ``features`` of each
        detection's segment, -1 for noise.

    Raises
    ------
    ValueError
        If X lacks a working column, a column read is not numeric or not
        finite, or ``labels`` does not have one integer per row of X.

    Examples
    --------
    >>> import pandas as pd
    >>> from sklearn_radar.classification import cluster_features
    >>> X = pd.DataFrame(
    ...     {"x": [0.0, 3.0, 0.0, 9.0], "y": [0.0, 0.0, 1.0, 9.0], "v_r": [1.0, 2.0, 3.0, 0.0], "t": [0.0] * 4}
    ... )
    >>> table = cluster_features(X, [0, 0, 0, -1])
    >>> table[["n_detections", "vr_mean", "vr_range"]].to_dict("records")
    [{'n_detections': 3, 'vr_mean': 2.0, 'vr_range': 2.0}]
    """
    columns = _data_columns(X, CLUSTER_FEATURE_READS, "cluster_features")
    labels = _check_labels(labels, len(X), "cluster_features")
    table, rows = segment_features(columns, labels, window_index(columns["t"], columns["sequence"], window))
    return (table, rows) if return_rows else table


def _data_columns(X, reads, where):
    """The columns of ``reads`` of a DataFrame as float64 arrays (None when an optional one is absent)."""
    missing = [name for name in reads.required if name not in X.columns]
    if missing:
        raise ValueError(f"{where}: X is missing the column(s) {missing} (the working columns of FrameTransform)")
    columns = {name: _numeric_column(X[name], name, where) if name in X.columns else None for name in reads.names}
    check_plausible(columns, where)
    return columns


def _check_labels(labels, n, where):
    """Cluster labels as int64, one per row; a ValueError names the problem."""
    labels = np.asarray(labels)
    if labels.ndim != 1 or labels.shape[0] != n:
        raise ValueError(f"{where}: labels must be 1-D with one label per row of X ({n}), got shape {labels.shape}")
    if labels.dtype.kind == "f" and np.all(np.isfinite(labels)) and np.all(labels == np.round(labels)):
        labels = labels.astype(np.int64)
    if labels.dtype.kind not in "iu":
        raise ValueError(f"{where}: labels must be integers (-1 for noise), got dtype {labels.dtype}")
    return labels.astype(np.int64, copy=False)


def window_index(t, sequence, window, rows=None):
    """Window of each detection, ``floor((t - min(t of its sequence)) / window)``; 0 when window is None.

    Parameters
    ----------
    t : ndarray of float64, shape (n,)
        Time, s.
    sequence : ndarray or None
        Sequence of each detection; None: one sequence.
    window : float or None
        s.
    rows : ndarray of int, default=None
        The detections whose windows are wanted (the starts are those of all
        detections); None: all.

    Returns
    -------
    windows : ndarray of int64, shape (n,) or (len(rows),)
    """
    n = len(t) if rows is None else len(rows)
    if window is None or len(t) == 0:
        return np.zeros(n, dtype=np.int64)
    if sequence is None:
        start = t.min()
    else:
        codes, n_codes = sequence_codes(sequence)
        first = np.full(n_codes, np.inf)
        np.minimum.at(first, codes, t)
        start = first[codes if rows is None else codes[rows]]
    return np.floor(((t if rows is None else t[rows]) - start) / window).astype(np.int64)


def sequence_codes(sequence):
    """Integer codes ``0 <= code < n_codes`` of the sequences, and ``n_codes`` (unused codes may occur).

    Sequence numbers are small integers (RadarScenes: 1-158): then the code is
    the number minus the smallest, without hashing; other values are
    factorised.
    """
    low, high = sequence.min(), sequence.max()
    if high - low < 4 * len(sequence) + 1024 and np.all(sequence == np.round(sequence)):
        return (sequence - low).astype(np.int64), int(high - low) + 1
    codes, uniques = pd.factorize(sequence)
    return codes.astype(np.int64, copy=False), len(uniques)


def segment_keys(sequence, labels, windows):
    """Sort the clustered rows by segment: ``(order, starts, keys)``.

    Parameters
    ----------
    sequence : ndarray or None
        Sequence of each row (all rows), None: one sequence.
    labels : ndarray of int64, shape (n,)
        Cluster of each row, -1 for noise.
    windows : ndarray of int64, shape (n,)
        Frame of each row.

    Returns
    -------
    order : ndarray of int64, shape (m,)
        The clustered rows (label >= 0), sorted by (sequence, label, window), ties by row.
    starts : ndarray of int64, shape (n_segments,)
        Position in ``order`` of each segment's first row.
    keys : tuple of three ndarrays, shape (n_segments,)
        Sequence (float64, 0 when None), cluster and window of each segment.
    """
    clustered = np.flatnonzero(labels >= 0)
    seq = np.zeros(len(clustered)) if sequence is None else sequence[clustered]
    lab, win = labels[clustered], windows[clustered]
    by = np.lexsort((win, lab, seq))
    order = clustered[by]
    seq, lab, win = seq[by], lab[by], win[by]
    new = np.ones(len(order), dtype=bool)
    if len(order):
        new[1:] = (seq[1:] != seq[:-1]) | (lab[1:] != lab[:-1]) | (win[1:] != win[:-1])
    starts = np.flatnonzero(new)
    return order, starts, (seq[starts], lab[starts], win[starts])


def segment_features(c, labels, windows):
    """The feature table and the table row of each detection, from columns read by name (float64 or None).

    Parameters
    ----------
    c : dict of str to ndarray or None
        The columns of :data:`~sklearn_radar._schema.CLUSTER_FEATURE_READS`.
    labels : ndarray of int64, shape (n,)
        Cluster per row, -1 for noise.
    windows : ndarray of int64, shape (n,)
        Window of each row (:func:`window_index`).

    Returns
    -------
    features : DataFrame
        As :func:`cluster_features`.
    rows : ndarray of int64, shape (n,)
        Row of ``features`` of each detection, -1 for noise.
    """
    n = len(labels)
    order, starts, (seq, lab, win) = segment_keys(c["sequence"], labels, windows)
    n_segments = len(starts)
    counts = np.diff(np.append(starts, len(order)))
    segment = np.repeat(np.arange(n_segments), counts)  # segment of each sorted row
    rows = np.full(n, -1, dtype=np.int64)
    rows[order] = segment

    table = {
        "sequence": seq.astype(np.int64) if np.all(seq == np.round(seq)) else seq,
        "cluster": lab,
        "window": win,
    }
    used = ("x", "y", "v_r", "t", "rcs", "range_sc", "azimuth_sc", "sensor_yaw", "heading", "sensor_id")
    values = {name: None if c[name] is None else c[name][order] for name in used}
    table.update(_features(values, segment, starts, counts, n_segments))
    return pd.DataFrame(table), rows


def _mean(values, starts, counts):
    return np.add.reduceat(values, starts) / counts if len(starts) else np.zeros(0)


def _extent(values, starts):
    if not len(starts):
        return np.zeros(0)
    return np.maximum.reduceat(values, starts) - np.minimum.reduceat(values, starts)


def _principal_extents(dx, dy, segment, starts, counts):
    """Extents of centred positions along their first and second principal axes (of the 2 x 2 covariance)."""
    sxx, syy, sxy = (_mean(product, starts, counts) for product in (dx * dx, dy * dy, dx * dy))
    phi = 0.5 * np.arctan2(2.0 * sxy, sxx - syy)
    cos_phi, sin_phi = np.cos(phi)[segment], np.sin(phi)[segment]
    return _extent(dx * cos_phi + dy * sin_phi, starts), _extent(-dx * sin_phi + dy * cos_phi, starts)


def _std(values, segment, starts, counts):
    """Population standard deviation per segment (two passes: centred first, for large coordinates)."""
    deviation = values - _mean(values, starts, counts)[segment]
    return np.sqrt(_mean(deviation * deviation, starts, counts)), deviation


def _features(v, segment, starts, counts, n_segments):
    """Every feature of :data:`CLUSTER_FEATURES` whose columns are present, from rows sorted by segment."""
    out = {"n_detections": counts.astype(np.int64)}
    out["duration"] = _extent(v["t"], starts)

    dx = v["x"] - _mean(v["x"], starts, counts)[segment]
    dy = v["y"] - _mean(v["y"], starts, counts)[segment]
    out["extent_along"], out["extent_across"] = _principal_extents(dx, dy, segment, starts, counts)

    out["vr_mean"] = _mean(v["v_r"], starts, counts)
    out["vr_std"], _ = _std(v["v_r"], segment, starts, counts)
    out["vr_range"] = _extent(v["v_r"], starts)
    if v["rcs"] is not None:
        out["rcs_mean"] = _mean(v["rcs"], starts, counts)
        out["rcs_std"], _ = _std(v["rcs"], segment, starts, counts)
        out["rcs_max"] = np.maximum.reduceat(v["rcs"], starts) if n_segments else np.zeros(0)
    if v["range_sc"] is not None:
        out["range_mean"] = _mean(v["range_sc"], starts, counts)
    if v["azimuth_sc"] is not None and v["sensor_yaw"] is not None:
        azimuth = v["azimuth_sc"] + v["sensor_yaw"]
        mean = np.arctan2(_mean(np.sin(azimuth), starts, counts), _mean(np.cos(azimuth), starts, counts))
        deviation = np.remainder(azimuth - mean[segment] + np.pi, 2.0 * np.pi) - np.pi
        out["azimuth_spread"] = np.sqrt(_mean(deviation * deviation, starts, counts))
        heading = 0.0 if v["heading"] is None else v["heading"]
        vx, vy, residual = _velocities_and_residuals(v["v_r"], azimuth + heading, segment, n_segments)
        out["speed"] = np.hypot(vx, vy)
        out["speed_residual"] = residual
        # The positions moved to the segment's mean time with its velocity: the body without its travel.
        dt = v["t"] - _mean(v["t"], starts, counts)[segment]
        moved_x, moved_y = dx - vx[segment] * dt, dy - vy[segment] * dt
        out["length"], out["width"] = _principal_extents(moved_x, moved_y, segment, starts, counts)
    if v["sensor_id"] is not None:
        out["n_sensors"] = _distinct_per_segment(v["sensor_id"], segment, n_segments)
    return out


def _distinct_per_segment(values, segment, n_segments):
    """Number of distinct values per segment: a (segment, value) presence table, or a sort when values are many."""
    codes, uniques = pd.factorize(values)
    n_values = len(uniques)
    if n_segments * n_values <= 4 * len(values) + 1024:
        present = np.zeros(n_segments * n_values, dtype=bool)
        present[segment * n_values + codes] = True
        return present.reshape(n_segments, n_values).sum(axis=1).astype(np.int64)
    pairs = np.unique(segment * np.int64(n_values) + codes)
    return np.bincount(pairs // n_values, minlength=n_segments).astype(np.int64)
