"""The optimisation target: ground truth pre-clustered per object (Sec. "Point Clustering Results")."""

from __future__ import annotations

from numbers import Real

import numpy as np
import pandas as pd
from sklearn.utils._param_validation import Interval, StrOptions, validate_params

from ..cluster import RadarDBSCAN
from ..preprocessing import FrameTransform


# RadarDBSCAN's constraints for the parameters passed on to it (its own validation is skipped inside).
@validate_params(
    {
        "X": [pd.DataFrame],
        "y": ["array-like"],
        "eps_xy": [Interval(Real, 0, None, closed="neither")],
        "eps_vr": [Interval(Real, 0, None, closed="neither")],
        "eps_t": [Interval(Real, 0, None, closed="left")],
        "vr_min": [Real],
        "min_samples": [Interval(Real, 1, None, closed="left")],
        "frame": [StrOptions({"frame", "car"})],
    },
    prefer_skip_nested_validation=True,
)
def precluster_target(X, y, *, eps_xy=2.0, eps_vr=25.0, eps_t=0.25, vr_min=0.01, min_samples=2, frame="frame"):
    """Split each labelled object into the clusters a liberal DBSCAN finds in it alone.

    The paper does not optimise towards the raw instance labels: an object
    that vanished for a while cannot be one cluster of a 0.25 s sliding
    window.  Each object is therefore clustered *separately* (so objects
    never merge) with very liberal parameters, and its clusters become the
    target instances.  Object detections that this pre-clustering leaves as
    noise (no other detection of the object within 2 m and 0.25 s) become
    background (-1): no stage-1 setting could cluster them either.

    Read more in the :ref:`User Guide <user-guide-scoring>`.

    Parameters
    ----------
    X : DataFrame
        Detections: the detection table, or its :class:`FrameTransform`
        output (columns ``x``, ``y``, ``v_r``, ``t``).
    y : array-like of shape (n_detections,)
        Instance per detection, -1 for background.
    eps_xy : float, default=2.0
        Spatial radius of the box criterion (Eq. 3), m, > 0.
    eps_vr : float, default=25.0
        Radial-velocity radius of the box criterion, m/s, > 0.
    eps_t : float, default=0.25
        Time window, s, >= 0.
    vr_min : float, default=0.01
        Only detections with ``|v_r| > vr_min`` (m/s) can be core points
        (:class:`~sklearn_radar.RadarDBSCAN`'s ``vr_min``).
    min_samples : float, default=2
        Minimum number of detections in a core point's neighbourhood,
        >= 1 (:class:`~sklearn_radar.RadarDBSCAN`'s ``min_samples``).
    frame : {"frame", "car"}, default="frame"
        Coordinates used when X has no working columns yet.

    Returns
    -------
    target : ndarray of int64, shape (n_detections,)
        Target cluster per detection (unique over sequences), -1 for background.

    Raises
    ------
    ValueError
        If ``y`` does not have one label per row of ``X``.
    """
    y = np.asarray(y)
    if len(y) != len(X):
        raise ValueError(f"precluster_target: y has {len(y)} labels for {len(X)} detections")
    if not {"x", "y", "v_r", "t"} <= set(X.columns):
        X = FrameTransform(frame=frame).fit_transform(X)
    target = np.full(len(y), -1, dtype=np.int64)
    objects = np.flatnonzero(y != -1)
    if len(objects) == 0:
        return target
    sequence = X["sequence"].to_numpy()[objects] if "sequence" in X.columns else np.zeros(len(objects))
    # One pseudo-sequence per (sequence, object): objects are clustered separately.
    _, per_object = np.unique(np.c_[sequence, y[objects]], axis=0, return_inverse=True)
    columns = ["x", "y", "v_r", "t"] + [c for c in ("heading",) if c in X.columns]
    objects_only = X.iloc[objects][columns].assign(sequence=per_object.ravel())
    clusterer = RadarDBSCAN(
        metric="box", eps_xy=eps_xy, eps_vr=eps_vr, eps_t=eps_t, vr_min=vr_min, min_samples=min_samples
    )
    target[objects] = clusterer.fit(objects_only).labels_
    return target
