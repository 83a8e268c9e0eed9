"""The scans of a detection table in arrival order: what ``sklearn-radar stream`` replays, one scan at a time."""

from __future__ import annotations

import numpy as np
import pandas as pd
from sklearn.utils._param_validation import validate_params

__all__ = ["iter_scans", "scan_order"]


def scan_order(data):
    """Row positions of each scan (one timestamp of one sequence, its sensors together), in timestamp order.

    ``data`` holds ``timestamp`` and optionally ``sequence`` (one sequence
    without it); ties of timestamp across sequences go by sequence, and the
    rows of a scan keep their order in ``data``.
    """
    timestamp = np.asarray(data["timestamp"])
    sequence = np.asarray(data["sequence"]) if "sequence" in data else np.zeros(len(timestamp), dtype=np.int64)
    order = np.lexsort((sequence, timestamp))
    cut = np.flatnonzero((np.diff(timestamp[order]) != 0) | (np.diff(sequence[order]) != 0)) + 1
    return np.split(order, cut)


@validate_params({"data": [pd.DataFrame]}, prefer_skip_nested_validation=True)
def iter_scans(data):
    """The scans of a detection table in arrival order, for :meth:`OnlinePipeline.update`.

    A scan is the detections of one ``timestamp`` (µs) of one ``sequence``,
    the sensors that measured at that time together (the causal stages
    count them as each other's past, so they go in one update).  The scans
    come in timestamp order, the sequences and sensors interleaved as they
    were recorded (ties of timestamp across sequences by sequence number),
    the order in which ``sklearn-radar stream`` replays a recording.

    Read more in the :ref:`User Guide <user-guide-online>`.

    Parameters
    ----------
    data : DataFrame
        Detections with a ``timestamp`` column (µs) and, when they come from
        more than one recording, ``sequence``; for example
        :func:`~sklearn_radar.datasets.load_radarscenes`'s or
        :func:`~sklearn_radar.datasets.make_scenes`'s ``data``.

    Returns
    -------
    scans : iterator of DataFrame
        The rows of each scan, in the order they have in ``data`` and with
        its index (so results can be put back with ``.loc[scan.index]``).

    Raises
    ------
    ValueError
        If ``data`` has no ``timestamp`` column, or ``timestamp`` or
        ``sequence`` holds values that are not finite numbers.

    See Also
    --------
    OnlinePipeline.update : label one scan.

    Examples
    --------
    >>> from sklearn_radar.datasets import make_scenes
    >>> from sklearn_radar.experiments import experiment_pipeline
    >>> from sklearn_radar.online import OnlinePipeline, iter_scans
    >>> scenes = make_scenes(n_sequences=1, duration=2.0, random_state=0)
    >>> online = OnlinePipeline(experiment_pipeline(13))
    >>> for scan in iter_scans(scenes.data):
    ...     result = online.update(scan)
    >>> result.labels.shape == (len(scan),)
    True
    """
    for name in ("timestamp", "sequence"):
        if name not in data.columns:
            if name == "timestamp":
                raise ValueError("iter_scans: data has no 'timestamp' column (the time of each detection, µs)")
            continue
        values = data[name].to_numpy()
        if values.dtype.kind not in "iuf":
            raise ValueError(f"iter_scans: column {name!r} must hold numbers, got dtype {values.dtype}")
        if not np.isfinite(values).all():
            raise ValueError(f"iter_scans: column {name!r} holds values that are not finite")
    if not len(data):
        return iter(())
    return (data.iloc[rows] for rows in scan_order(data))
