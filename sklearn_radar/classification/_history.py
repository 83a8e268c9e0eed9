"""A cluster's history: causal aggregates over the time windows a cluster id has been seen in so far.

A cluster id that persists over time (the clusters of the object setting, which span windows; the persistent
object ids of :class:`~sklearn_radar.online.OnlinePipeline`) is one road user seen in several windows.  Its
segments (one per window) are the rows of the feature table of one ``(sequence, cluster)``, in window order
(:func:`~sklearn_radar.classification._features.segment_keys` sorts them so).  Everything here but
:func:`cluster_weighted_mean` is causal: a segment's aggregate reads only the segments of its cluster at or before
its own window.  No Python loop runs over segments: the running sums are one cumulative sum minus its value at each
cluster's start.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

#: The options of ``ClusterClassifier(history=...)`` besides None (each window classified alone).
HISTORY_OPTIONS = ("mean_proba", "features", "cluster_mean_proba")

#: The per-window features whose running maximum over the cluster's windows so far is a history feature.
RUNNING_MAX = ("n_detections", "extent_along", "extent_across", "vr_range", "rcs_max", "speed")

#: ``{feature: (unit, meaning)}`` of the history features of ``history="features"`` (besides the running means
#: ``mean_<feature>`` of every per-window feature and the running maxima ``max_<feature>`` of :data:`RUNNING_MAX`,
#: in the unit of the feature).
HISTORY_FEATURES = {
    "history_windows": ("1", "number of windows the cluster has been seen in, this one included"),
    "history_age": ("s", "time from the start of the cluster's first window to the start of this one"),
}


def cluster_starts(table):
    """Whether each row of the feature table is its cluster's first segment (rows sorted by sequence, cluster)."""
    sequence, cluster = table["sequence"].to_numpy(), table["cluster"].to_numpy()
    first = np.ones(len(table), dtype=bool)
    first[1:] = (sequence[1:] != sequence[:-1]) | (cluster[1:] != cluster[:-1])
    return first


def running_mean(values, first):
    """The mean of each row's cluster's rows up to it, NaN left out (NaN when all are); rows in cluster order.

    Parameters
    ----------
    values : ndarray of float64, shape (n_segments,) or (n_segments, k)
    first : ndarray of bool, shape (n_segments,)
        Whether a row starts its cluster.

    Returns
    -------
    means : ndarray of float64, the shape of ``values``
    """
    known = ~np.isnan(values)
    sums = _running_sum(np.where(known, values, 0.0), first)
    counts = _running_sum(known.astype(np.float64), first)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(counts > 0, sums / np.maximum(counts, 1.0), np.nan)


def running_weighted_mean(values, weights, first):
    """The mean of each row's cluster's rows up to it, weighted (``values`` without NaN, ``weights`` > 0).

    Parameters
    ----------
    values : ndarray of float64, shape (n_segments, k)
    weights : ndarray of float64, shape (n_segments,)
    first : ndarray of bool, shape (n_segments,)
        Whether a row starts its cluster.

    Returns
    -------
    means : ndarray of float64, shape (n_segments, k)
    """
    weights = weights[:, None]
    return _running_sum(values * weights, first) / _running_sum(weights, first)


def cluster_weighted_mean(values, weights, first):
    """The mean of all the rows of each row's cluster, weighted: later rows included (not causal).

    Parameters
    ----------
    values : ndarray of float64, shape (n_segments, k)
    weights : ndarray of float64, shape (n_segments,)
        Each > 0.
    first : ndarray of bool, shape (n_segments,)
        Whether a row starts its cluster.

    Returns
    -------
    means : ndarray of float64, shape (n_segments, k)
        Equal for the rows of one cluster.
    """
    start = np.flatnonzero(first)
    if not len(start):
        return np.empty_like(values)
    weights = weights[:, None]
    means = np.add.reduceat(values * weights, start, axis=0) / np.add.reduceat(weights, start, axis=0)
    return means[np.cumsum(first) - 1]


def _running_sum(values, first):
    """Cumulative sum of each cluster's rows, restarted at each cluster's first row."""
    total = np.cumsum(values, axis=0)
    start = np.flatnonzero(first)
    before = np.concatenate([np.zeros_like(total[:1]), total[:-1]], axis=0)[start]  # the sum before each cluster
    counts = np.diff(np.append(start, len(values)))
    return total - np.repeat(before, counts, axis=0)


def with_history(table, window):
    """The feature table with the history features appended (:data:`HISTORY_FEATURES`, running means and maxima).

    Parameters
    ----------
    table : DataFrame
        The feature table of :func:`~sklearn_radar.classification._features.segment_features`: ``sequence``,
        ``cluster``, ``window``, then the per-window features.
    window : float or None
        Window length, s (None: one segment per cluster, whose history is itself).

    Returns
    -------
    table : DataFrame
        A new table: the same rows, the history features after the per-window ones.
    """
    first = cluster_starts(table)
    features = list(table.columns[3:])
    group = np.cumsum(first) - 1
    windows = table["window"].to_numpy(dtype=np.float64)
    found = {
        "history_windows": _running_sum(np.ones(len(table)), first),
        "history_age": (windows - windows[first][group]) * (0.0 if window is None else window),
    }
    means = running_mean(table[features].to_numpy(dtype=np.float64), first)
    found.update({f"mean_{name}": means[:, i] for i, name in enumerate(features)})
    for name in RUNNING_MAX:
        if name in table.columns:
            values = table[name].to_numpy(dtype=np.float64)
            peak = pd.Series(np.where(np.isnan(values), -np.inf, values)).groupby(group).cummax().to_numpy()
            found[f"max_{name}"] = np.where(np.isinf(peak), np.nan, peak)
    return pd.concat([table, pd.DataFrame(found, index=table.index)], axis=1)
