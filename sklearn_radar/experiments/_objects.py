"""Beyond the paper: the framework's own stages, set up to count objects (panoptic quality).

The object-level ablation (``benchmarks/ablation_object_level.py``, issue #27)
tuned one factor at a time against the paper's best stage 1 (#8) for
per-frame PQ.  What helped: the Eq. 6 velocity merging of stage 2, a fixed
N_min instead of Eq. 2, and a Doppler gate on every detection instead of
Eq. 1's density rule and the core-only ``vr_min``; what did not: tuning
eps_t, and wider ranges (more freedom overfits the search's budget).  The
object experiment takes exactly those choices, within the framework's stages
and parameters:

* ``"frame"``: :class:`~sklearn_radar.FrameTransform` in FCS;
* ``"filter"``: :class:`~sklearn_radar.DopplerDensityFilter` as a pure
  Doppler gate: one rule of Eq. 1, ``|v_r| < vr_threshold`` removes a
  detection whatever its neighbour count (:data:`GATE_RULE`), and a
  detection without any neighbour goes, as Eq. 1 says;
* stage 1: :class:`~sklearn_radar.RadarDBSCAN` with the joint x-y-v_r
  distance (Eq. 5), a fixed N_min (``alpha_r = 0``), every kept detection
  allowed to be core (``vr_min = -inf``: the gate has judged Doppler), and
  the paper's eps_t of 0.25 s;
* stage 2: :class:`~sklearn_radar.ClusterMerger` merging by the Eq. 6
  velocity estimate, on the tuned stage 1.

It is tuned in two searches, as the paper tunes #12 on #8: stage 1
(:func:`object_search_space` ``(1)``), then stage 2 on it (``(2)``).  With
``causal=True`` every stage decides from the past only (the filter's and
stage 1's ``causal`` rules; stage 2 is causal by construction), which is what
a car can run.
"""

from __future__ import annotations

from numbers import Integral

import numpy as np
from sklearn.pipeline import Pipeline
from sklearn.utils._param_validation import HasMethods, Options, validate_params

from .._skopt import Integer, Real
from ._paper import EPS_T

__all__ = ["GATE_RULE", "OBJECT_EXPERIMENT", "object_pipeline", "object_search_space"]

#: The step key and name of the object experiment in ``reproduce``.
OBJECT_EXPERIMENT = "objects"

#: Eq. 1 reduced to a Doppler gate: ``threshold_ratios=(1,)`` and a neighbour count that no detection reaches,
#: so every detection with ``|v_r| < vr_threshold`` is removed, dense or not.
GATE_RULE = {"threshold_ratios": (1,), "min_neighbors": (1_000_000,)}

#: Stage 1's fixed part: Eq. 5, fixed N_min, no core-only gate, the paper's eps_t (s).
_STAGE1_FIXED = {"metric": "xyv", "alpha_r": 0.0, "vr_min": -np.inf, "eps_t": EPS_T}


@validate_params(
    {
        "stage": [Options(Integral, {1, 2})],
        "params": [dict, None],
        "stage1_params": [dict, None],
        "causal": ["boolean"],
        "memory": [None, str, HasMethods(["cache"])],
    },
    prefer_skip_nested_validation=True,
)
def object_pipeline(stage=2, *, params=None, stage1_params=None, causal=False, memory=None):
    """The object experiment's pipeline: frame transform, Doppler gate, stage 1, and (``stage=2``) velocity merging.

    Parameters
    ----------
    stage : {1, 2}, default=2
        1: ``frame``, ``filter``, ``cluster`` (:class:`~sklearn_radar.RadarDBSCAN`);
        2: ``frame``, ``filter``, ``merge`` (:class:`~sklearn_radar.ClusterMerger` on stage 1).
    params : dict, default=None
        Pipeline parameters set after construction (a search's ``best_params_``).
    stage1_params : dict, default=None
        Stage 2 only: the tuned stage 1, as the stage-1 pipeline's ``filter__`` and ``cluster__`` parameters
        (the first search's ``best_params_``).
    causal : bool, default=False
        Every stage decides from the past only.
    memory : str, joblib.Memory or None, default=None
        The pipeline's (and the merger's) cache.

    Returns
    -------
    pipeline : sklearn.pipeline.Pipeline

    Examples
    --------
    >>> from sklearn_radar.experiments import object_pipeline
    >>> [name for name, _ in object_pipeline().steps]
    ['frame', 'filter', 'merge']
    >>> object_pipeline().get_params()["merge__mode"]
    'velocity'
    """
    from ..cluster import ClusterMerger, RadarDBSCAN
    from ..preprocessing import DopplerDensityFilter, FrameTransform

    if stage == 1 and stage1_params is not None:
        raise ValueError("stage1_params applies to stage=2, not to stage 1")
    stage1_params = stage1_params or {}
    gate = {key.removeprefix("filter__"): v for key, v in stage1_params.items() if key.startswith("filter__")}
    cluster = {key.removeprefix("cluster__"): v for key, v in stage1_params.items() if key.startswith("cluster__")}
    unknown = set(stage1_params) - {f"filter__{k}" for k in gate} - {f"cluster__{k}" for k in cluster}
    if unknown:
        raise ValueError(f"stage1_params takes filter__ and cluster__ parameters, got {sorted(unknown)}")
    stage1 = RadarDBSCAN(**{**_STAGE1_FIXED, **cluster, "causal": causal})
    steps = [
        ("frame", FrameTransform(frame="frame")),
        ("filter", DopplerDensityFilter(**{**GATE_RULE, **gate, "causal": causal})),
        ("cluster", stage1) if stage == 1 else ("merge", ClusterMerger(mode="velocity", stage1=stage1, memory=memory)),
    ]
    pipeline = Pipeline(steps, memory=memory)
    if params:
        pipeline.set_params(**params)
    return pipeline


@validate_params({"stage": [Options(Integral, {1, 2})]}, prefer_skip_nested_validation=True)
def object_search_space(stage):
    """The object experiment's search space of ``stage`` (skopt dimensions, keys of :func:`object_pipeline`).

    ==========================  ============  ========  ===========  =====
    key                         range         unit      prior        stage
    ==========================  ============  ========  ===========  =====
    ``filter__vr_threshold``    [0, 1.5]      m/s       uniform      1
    ``cluster__eps_xyv``        [0.2, 3.0]    m         uniform      1
    ``cluster__vr_scale``       [0.3, 20]     m/s       log-uniform  1
    ``cluster__min_samples``    {2, ..., 8}   points    integer      1
    ``merge__eps_d``            [0.2, 3.0]    m         uniform      2
    ``merge__eps_phi``          [0.05, 1.5]   rad       uniform      2
    ``merge__eps_v``            [0.2, 6.0]    m/s       uniform      2
    ``merge__eps_t2``           [0.1, 1.0]    s         uniform      2
    ``merge__min_samples``      {1, 2, 3}     clusters  integer      2
    ==========================  ============  ========  ===========  =====

    The ranges are #8's and #12's (:func:`search_space`), so the experiment gets no wider freedom than the
    paper's; the gate's range is ``vr_min``'s.

    Parameters
    ----------
    stage : {1, 2}

    Returns
    -------
    space : dict
    """
    if stage == 1:
        return {
            "filter__vr_threshold": Real(0.0, 1.5, name="filter__vr_threshold"),
            "cluster__eps_xyv": Real(0.2, 3.0, name="cluster__eps_xyv"),
            "cluster__vr_scale": Real(0.3, 20.0, prior="log-uniform", name="cluster__vr_scale"),
            "cluster__min_samples": Integer(2, 8, name="cluster__min_samples"),
        }
    return {
        "merge__eps_d": Real(0.2, 3.0, name="merge__eps_d"),
        "merge__eps_phi": Real(0.05, 1.5, name="merge__eps_phi"),
        "merge__eps_v": Real(0.2, 6.0, name="merge__eps_v"),
        "merge__eps_t2": Real(0.1, 1.0, name="merge__eps_t2"),
        "merge__min_samples": Integer(1, 3, name="merge__min_samples"),
    }
