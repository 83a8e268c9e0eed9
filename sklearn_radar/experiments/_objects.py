"""Beyond the paper: the framework's own stages, set up to count objects (panoptic quality).

The object experiment is the paper's own #12 on #8 with a minimum cluster
size, tuned for per-window panoptic quality (PQ).  Why these stages and not
others (an ablation of one factor at a time against #8): read more in the
:ref:`User Guide <objects-measured>`.

* ``"frame"``: :class:`~sklearn_radar.FrameTransform` in FCS;
* ``"filter"``: :class:`~sklearn_radar.DopplerDensityFilter` at the paper's
  chosen setting (0.10 m/s, 1.4 m);
* stage 1: :class:`~sklearn_radar.RadarDBSCAN` with the joint x-y-v_r
  distance (Eq. 5), N_min(r) (Eq. 2), the core-only Doppler gate ``vr_min``
  and the paper's eps_t of 0.25 s (#8);
* stage 2: :class:`~sklearn_radar.ClusterMerger` merging by the Eq. 6
  velocity estimate, on the tuned stage 1 (#12), with a tuned
  ``min_cluster_size``.

It is tuned in two searches, as the paper tunes #12 on #8: stage 1
(:func:`object_search_space` ``(1)``), then stage 2 on it (``(2)``), always for
PQ.  With ``causal=True`` every stage decides from the past only (the
filter's and stage 1's ``causal`` rules; stage 2 merges causally by
construction and its ``causal`` rule confirms a cluster once it has
``min_cluster_size`` detections), which is what a car can run.
"""

from __future__ import annotations

from numbers import Integral

from sklearn.utils._param_validation import HasMethods, Options, validate_params

from .._skopt import Integer
from ._paper import experiment_pipeline, paper_params, search_space

__all__ = ["OBJECT_EXPERIMENT", "object_pipeline", "object_search_space"]

#: The step key and name of the object experiment in ``reproduce``.
OBJECT_EXPERIMENT = "objects"


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
    """The object experiment's pipeline: #8's stage 1 (``stage=1``) or #12's velocity merging on it (``stage=2``).

    Read more in the :ref:`User Guide <user-guide-objects>`.

    Parameters
    ----------
    stage : {1, 2}, default=2
        1: ``frame``, ``filter``, ``cluster`` (:class:`~sklearn_radar.RadarDBSCAN`);
        2: ``frame``, ``filter``, ``merge`` (:class:`~sklearn_radar.ClusterMerger` on stage 1).
    params : dict, default=None
        Pipeline parameters set after construction (a search's ``best_params_``).
    stage1_params : dict, default=None
        Stage 2 only: the tuned stage 1, as the stage-1 pipeline's ``cluster__`` parameters (the first search's
        ``best_params_``); parameters not given keep #8's setting.
    causal : bool, default=False
        Every stage decides from the past only.
    memory : str, joblib.Memory or None, default=None
        The pipeline's (and the merger's) cache.

    Returns
    -------
    pipeline : sklearn.pipeline.Pipeline
        Without ``params`` and ``stage1_params``, offline, the pipeline of experiment #8 (``stage=1``) or #12
        (``stage=2``, ``min_cluster_size`` 1) at the paper's setting.

    Examples
    --------
    >>> from sklearn_radar.experiments import object_pipeline
    >>> [name for name, _ in object_pipeline().steps]
    ['frame', 'filter', 'merge']
    >>> object_pipeline().get_params()["merge__mode"]
    'velocity'
    """
    if stage == 1 and stage1_params is not None:
        raise ValueError("stage1_params applies to stage=2, not to stage 1")
    stage1_params = stage1_params or {}
    unknown = sorted(key for key in stage1_params if not key.startswith("cluster__"))
    if unknown:
        raise ValueError(f"stage1_params takes the stage-1 search's cluster__ parameters, got {unknown}")
    if stage == 1:
        pipeline = experiment_pipeline(8, memory=memory)
        pipeline.set_params(cluster__causal=causal)
    else:
        setting = {**paper_params(8), **stage1_params, "cluster__causal": causal}
        pipeline = experiment_pipeline(12, memory=memory, stage1_params=setting)
        pipeline.set_params(merge__causal_min_size=causal)
    pipeline.set_params(filter__causal=causal)
    if params:
        pipeline.set_params(**params)
    return pipeline


@validate_params({"stage": [Options(Integral, {1, 2})]}, prefer_skip_nested_validation=True)
def object_search_space(stage):
    """The object experiment's search space of ``stage``: #8's (stage 1), #12's and a minimum cluster size (stage 2).

    ===========================  ===========  ========  =====================  =====
    key                          range        unit      prior                  stage
    ===========================  ===========  ========  =====================  =====
    ``cluster__eps_xyv``         [0.2, 3.0]   m         uniform                1
    ``cluster__vr_scale``        [0.3, 20]    m/s       log-uniform            1
    ``cluster__min_samples``     [1.5, 8.0]   points    uniform (N_min,50)     1
    ``cluster__alpha_r``         [0, 1]       -         uniform                1
    ``cluster__vr_min``          [0, 1.5]     m/s       uniform                1
    ``merge__eps_d``             [0.2, 3.0]   m         uniform                2
    ``merge__eps_phi``           [0.05, 1.5]  rad       uniform                2
    ``merge__eps_v``             [0.2, 6.0]   m/s       uniform                2
    ``merge__eps_t2``            [0.1, 1.0]   s         uniform                2
    ``merge__min_samples``       {1, 2, 3}    clusters  integer                2
    ``merge__min_cluster_size``  [1, 300]     points    log-uniform (integer)  2
    ===========================  ===========  ========  =====================  =====

    The paper's ranges (:func:`search_space` of 8 and 12): wider ones overfit the search's budget.  The minimum
    cluster size reaches from off (1) to a few seconds of one road user's detections.

    Read more in the :ref:`User Guide <user-guide-objects>`.

    Parameters
    ----------
    stage : {1, 2}

    Returns
    -------
    space : dict
    """
    if stage == 1:
        return search_space(8)
    size = Integer(1, 300, prior="log-uniform", name="merge__min_cluster_size")
    return {**search_space(12), "merge__min_cluster_size": size}
