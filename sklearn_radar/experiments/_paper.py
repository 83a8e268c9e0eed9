"""The paper's experiments #1-#13 as data: settings, scores, pipelines and search spaces.

Scheiner et al. 2019, Tables III (stage 1, #1-#11) and IV (stage 2, #12 and
#13).  Parameter names are those of :class:`~sklearn_radar.RadarDBSCAN` and
:class:`~sklearn_radar.ClusterMerger`; values are the tables' values,
verbatim, in SI units (the paper omits units: m, m/s, s), except that the
paper's eps_phi in degrees is stored in radians as well.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from numbers import Integral

import pandas as pd
from sklearn.pipeline import Pipeline
from sklearn.utils._param_validation import HasMethods, Interval, validate_params

from .._schema import FRAME_TRANSFORM_READS
from .._skopt import Integer, Real
from ..cluster import ClusterMerger, RadarDBSCAN
from ..preprocessing import DopplerDensityFilter, FrameTransform

__all__ = [
    "PAPER_EXPERIMENTS",
    "PIPELINE_COLUMNS",
    "PaperExperiment",
    "derived_params",
    "experiment_pipeline",
    "get_experiment",
    "paper_experiments",
    "paper_params",
    "search_space",
]

#: eps_t of every stage-1 experiment (Table III caption), s.
EPS_T = 0.25

#: The detection-table columns that the experiment pipelines read: those that
#: :class:`~sklearn_radar.FrameTransform` reads, as the schema lists them
#: (``azimuth_sc`` and ``sensor_yaw`` also serve the velocity estimate of
#: stage 2).  With ``memory=``, pass ``X[list(PIPELINE_COLUMNS)]``: joblib
#: hashes the whole input on every call, and the string columns ``uuid`` and
#: ``track_id`` make hashing 250,000 detections take about 1 s (0.03 s for
#: these columns), more than the frame transform and the filter take (about
#: 0.2 s), measured.
PIPELINE_COLUMNS = FRAME_TRANSFORM_READS.names


@dataclass(frozen=True)
class PaperExperiment:
    """One row of Table III or IV of Scheiner et al. 2019.

    Each parameter is kept as the attribute of the same name (a frozen
    dataclass).

    Parameters
    ----------
    number : int
        Experiment number (#1-#13).
    method : str
        The paper's method name.
    frame : {"car", "frame"}
        Coordinate system: "car" (CCS) or "frame" (FCS); the
        ``FrameTransform(frame=...)`` value.
    filtered : bool
        Whether the Doppler-density filter (Eq. 1) runs before clustering.
    stage : {1, 2}
        Clustering stage the experiment tunes.
    v1_percent : float
        The paper's V-measure on its test set, %.
    params : dict
        The paper's setting of the tuned estimator (``RadarDBSCAN`` for stage
        1, ``ClusterMerger`` for stage 2) as keyword arguments in SI units:
        eps_xy, eps_xyv, eps_d (m), eps_vr, vr_scale, vr_min, eps_v (m/s),
        eps_t, eps_t2 (s), eps_phi (rad), min_samples and alpha_r (1).
    equations : tuple of int
        Equations of the paper used (1 = filter, 2 = N_min(r), 3-5 = criteria, 6 = velocity merging).
    tuned : bool
        False for the fixed settings #1 (expert), #10 and #11 (transferred from #8).
    derived_from : int or None
        Experiment whose setting a fixed experiment reuses (#10, #11: #8);
        for stage 2, the experiment whose stage-1 setting is the base (#8).
    eps_phi_deg : float or None
        eps_phi as printed in the paper, degrees (#12 only).
    """

    number: int
    method: str
    frame: str
    filtered: bool
    stage: int
    v1_percent: float
    params: dict = field(default_factory=dict)
    equations: tuple = ()
    tuned: bool = True
    derived_from: int | None = None
    eps_phi_deg: float | None = None


def _box(eps_xy, eps_vr, min_samples, vr_min, alpha_r=0.0, metric="box"):
    return {
        "metric": metric,
        "eps_xy": eps_xy,
        "eps_vr": eps_vr,
        "min_samples": min_samples,
        "vr_min": vr_min,
        "alpha_r": alpha_r,
        "eps_t": EPS_T,
    }


def _xyv(eps_xyv, vr_scale, min_samples, vr_min, alpha_r=0.0):
    return {
        "metric": "xyv",
        "eps_xyv": eps_xyv,
        "vr_scale": vr_scale,
        "min_samples": min_samples,
        "vr_min": vr_min,
        "alpha_r": alpha_r,
        "eps_t": EPS_T,
    }


_EPS_PHI_12_DEG = 23.11

#: Table III (#1-#11) and Table IV (#12, #13), verbatim.
PAPER_EXPERIMENTS = (
    PaperExperiment(1, "Expert Setting", "car", True, 1, 67.57, _box(1.00, 5.00, 3, 0.40), (1, 3), tuned=False),
    PaperExperiment(2, "Baseline", "car", True, 1, 68.87, _box(0.62, 11.2, 3, 0.23), (1, 3)),
    PaperExperiment(3, "Baseline", "frame", True, 1, 69.19, _box(0.60, 12.3, 3, 0.25), (1, 3)),
    PaperExperiment(4, "Baseline -- unfiltered", "frame", False, 1, 69.19, _box(0.60, 12.3, 3, 0.25), (3,)),
    PaperExperiment(
        5, "Euclidean xy-distance", "frame", True, 1, 69.33, _box(0.76, 14.1, 3, 0.31, metric="xy"), (1, 4)
    ),
    PaperExperiment(6, "Euclidean xyv_r-distance", "frame", True, 1, 69.47, _xyv(0.72, 13.5, 3, 0.48), (1, 5)),
    PaperExperiment(7, "Adaptive N_min(r)", "frame", True, 1, 70.56, _box(0.76, 8.63, 3.02, 0.46, 0.99), (1, 2, 3)),
    PaperExperiment(
        8, "Combined N_min(r) & eps_xyv_r", "frame", True, 1, 71.55, _xyv(1.04, 1.03, 3.87, 1.00, 0.99), (1, 2, 5)
    ),
    PaperExperiment(9, "Combined -- unfiltered", "frame", False, 1, 69.91, _xyv(1.18, 1.01, 3.81, 0.98, 0.99), (2, 5)),
    PaperExperiment(
        10,
        "Best setting -- unfiltered",
        "frame",
        False,
        1,
        69.86,
        _xyv(1.04, 1.03, 3.87, 1.00, 0.99),
        (2, 5),
        tuned=False,
        derived_from=8,
    ),
    PaperExperiment(
        11,
        "Best setting on baseline",
        "frame",
        True,
        1,
        67.73,
        _box(1.04, 1.03, 4, 1.00),
        (1, 3),
        tuned=False,
        derived_from=8,
    ),
    PaperExperiment(
        12,
        "Step 2 -- real velocity estimate",
        "frame",
        True,
        2,
        70.36,
        {
            "mode": "velocity",
            "eps_d": 1.00,
            "eps_phi": math.radians(_EPS_PHI_12_DEG),
            "eps_v": 1.04,
            "min_samples": 1,
            "eps_t2": 0.35,
        },
        (1, 2, 5, 6),
        derived_from=8,
        eps_phi_deg=_EPS_PHI_12_DEG,
    ),
    PaperExperiment(
        13,
        "Step 2 -- cluster continuation",
        "frame",
        True,
        2,
        71.79,
        {"mode": "continuation", "eps_d": 0.94, "eps_v": 2.72, "min_samples": 1, "eps_t2": 0.35},
        (1, 2, 5),
        derived_from=8,
    ),
)


#: Constraint of an experiment number: one of the paper's experiments, 1-13.
_NUMBER = [Interval(Integral, 1, len(PAPER_EXPERIMENTS), closed="both")]


@validate_params({"number": _NUMBER}, prefer_skip_nested_validation=True)
def get_experiment(number):
    """The :class:`PaperExperiment` numbered ``number`` (1-13).

    Parameters
    ----------
    number : int
        Experiment, 1-13.

    Returns
    -------
    experiment : PaperExperiment
        Its row of Table III or IV.

    Examples
    --------
    >>> from sklearn_radar.experiments import get_experiment
    >>> get_experiment(8).method
    'Combined N_min(r) & eps_xyv_r'
    """
    return _get_experiment(number)


def _get_experiment(number):
    """:func:`get_experiment` without its parameter validation, for callers inside the package."""
    for experiment in PAPER_EXPERIMENTS:
        if experiment.number == number:
            return experiment
    raise ValueError(f"number must be one of the paper's experiments 1-13, got {number!r}")


@validate_params({}, prefer_skip_nested_validation=True)
def paper_experiments():
    """Tables III and IV as one DataFrame, one row per experiment, indexed by number.

    Read more in the :ref:`User Guide <user-guide-radar-dbscan>`.

    Returns
    -------
    table : DataFrame
        Columns ``method``, ``frame``, ``filtered``, ``stage``, ``v1_percent``,
        ``tuned``, ``derived_from``, ``equations``, ``eps_phi_deg``, and one
        column per pipeline parameter of :func:`experiment_pipeline`
        (``cluster__eps_xy``, ..., ``merge__eps_d``, ...; NaN where an
        experiment does not set it).
    """
    rows = []
    for e in PAPER_EXPERIMENTS:
        row = {
            "number": e.number,
            "method": e.method,
            "frame": e.frame,
            "filtered": e.filtered,
            "stage": e.stage,
            "v1_percent": e.v1_percent,
            "tuned": e.tuned,
            "derived_from": e.derived_from,
            "equations": e.equations,
            "eps_phi_deg": e.eps_phi_deg,
        }
        row.update(_paper_params(e.number))
        rows.append(row)
    table = pd.DataFrame(rows).set_index("number")
    table["derived_from"] = table["derived_from"].astype("Int64")
    return table


@validate_params({"number": _NUMBER}, prefer_skip_nested_validation=True)
def paper_params(number):
    """The paper's setting of experiment ``number`` as :func:`experiment_pipeline` parameters.

    Parameters
    ----------
    number : int
        Experiment, 1-13.

    Returns
    -------
    params : dict
        ``{"cluster__eps_xy": 0.60, ...}`` (stage 1) or ``{"merge__eps_d": 0.94, ...}`` (stage 2).

    Examples
    --------
    >>> from sklearn_radar.experiments import paper_params
    >>> paper_params(13)["merge__eps_d"]
    0.94
    """
    return _paper_params(number)


def _paper_params(number):
    """:func:`paper_params` without its parameter validation, for callers inside the package."""
    experiment = _get_experiment(number)
    step = "cluster" if experiment.stage == 1 else "merge"
    return {f"{step}__{key}": value for key, value in experiment.params.items()}


@validate_params({"number": _NUMBER, "best_params": [dict, None]}, prefer_skip_nested_validation=True)
def derived_params(number, best_params=None):
    """Setting of a control experiment derived from experiment #8 (#10 and #11).

    * #10: #8's setting itself, to be applied to unfiltered data;
    * #11: #8's eps values transferred to the box criterion (Eq. 3):
      ``eps_xy = eps_xyv``, ``eps_vr = vr_scale``,
      ``min_samples = round(N_min,50)``, ``vr_min`` as #8, ``alpha_r = 0``.

    Read more in the :ref:`User Guide <user-guide-tuning>`.

    Parameters
    ----------
    number : {10, 11}
        The control experiment.
    best_params : dict, default=None
        #8's setting as pipeline parameters (e.g. a search's
        ``best_params_``); None means #8's Table III values, which gives the
        table's #10 and #11 settings.

    Returns
    -------
    params : dict
        Pipeline parameters for ``experiment_pipeline(number, params=...)``.

    Raises
    ------
    ValueError
        If ``number`` is an experiment other than 10 and 11.
    """
    if number not in (10, 11):
        raise ValueError(f"only experiments 10 and 11 are derived from #8, got {number!r}")
    best = _paper_params(8)
    best.update(best_params or {})
    if number == 10:
        return best
    return {
        "cluster__metric": "box",
        "cluster__eps_xy": best["cluster__eps_xyv"],
        "cluster__eps_vr": best["cluster__vr_scale"],
        "cluster__min_samples": round(float(best["cluster__min_samples"])),
        "cluster__vr_min": best["cluster__vr_min"],
        "cluster__alpha_r": 0.0,
        "cluster__eps_t": best.get("cluster__eps_t", EPS_T),
    }


def _stage1_setting(stage1_params):
    """RadarDBSCAN keyword arguments: #8's setting, or ``stage1_params`` (``cluster__`` prefix stripped)."""
    if stage1_params is None:
        return dict(_get_experiment(8).params)
    setting = {"eps_t": EPS_T}
    for key, value in stage1_params.items():
        setting[key.removeprefix("cluster__")] = value
    return setting


@validate_params(
    {
        "number": _NUMBER,
        "memory": [None, str, HasMethods(["cache"])],
        "params": [dict, None],
        "n_jobs": [Integral, None],
        "stage1_params": [dict, None],
    },
    prefer_skip_nested_validation=True,
)
def experiment_pipeline(number, *, memory=None, params=None, n_jobs=None, stage1_params=None):
    """The pipeline of experiment ``number`` at the paper's setting.

    Steps:

    * ``"frame"``: :class:`~sklearn_radar.FrameTransform` in the experiment's
      coordinate system (CCS for #1 and #2, FCS otherwise);
    * ``"filter"``: :class:`~sklearn_radar.DopplerDensityFilter` with the
      paper's chosen setting (0.10 m/s, 1.4 m) for filtered experiments,
      ``"passthrough"`` for the unfiltered ones (#4, #9, #10);
    * ``"cluster"``: :class:`~sklearn_radar.RadarDBSCAN` with the Table III
      setting (stage-1 experiments #1-#11), **or**
    * ``"merge"``: :class:`~sklearn_radar.ClusterMerger` with the Table IV
      setting and ``stage1=RadarDBSCAN(**stage1_params)`` (#12, #13).

    Read more in the :ref:`User Guide <user-guide-tuning>`.

    Parameters
    ----------
    number : int
        Experiment, 1-13.
    memory : str, joblib.Memory or None, default=None
        Cache directory.  Passed to the Pipeline, so that the frame transform
        and the filter are computed once per data subset when only the
        clusterer's parameters change, and for stage 2 also to the
        ``ClusterMerger``, so that stage 1 is computed once.  Feed such a
        pipeline ``X[list(PIPELINE_COLUMNS)]`` (see :data:`PIPELINE_COLUMNS`),
        or hashing the input costs more than the cache saves.
    params : dict, default=None
        Pipeline parameters set after construction, e.g.
        ``{"cluster__eps_xy": 0.7}`` or a search's ``best_params_``.
    n_jobs : int or None, default=None
        Sequences processed in parallel (threads) by the filter and the clusterers.
    stage1_params : dict, default=None
        Stage 2 only: the fixed stage-1 setting, as ``RadarDBSCAN`` keyword
        arguments (a ``cluster__`` prefix, as in a stage-1 search's
        ``best_params_``, is stripped; parameters not given take
        ``RadarDBSCAN``'s defaults, with eps_t = 0.25 s).  None means
        experiment #8's Table III setting, the paper's base for #12 and #13.

    Returns
    -------
    pipeline : sklearn.pipeline.Pipeline
        Takes the detection table; ``fit_predict`` returns a cluster per row.

    Examples
    --------
    >>> from sklearn_radar.experiments import experiment_pipeline
    >>> pipe = experiment_pipeline(8)
    >>> [name for name, _ in pipe.steps]
    ['frame', 'filter', 'cluster']
    >>> pipe.get_params()["cluster__eps_xyv"]
    1.04
    """
    experiment = _get_experiment(number)
    if experiment.stage == 1 and stage1_params is not None:
        raise ValueError(f"stage1_params applies to the stage-2 experiments 12 and 13, not to #{number}")
    steps = [
        ("frame", FrameTransform(frame=experiment.frame)),
        ("filter", DopplerDensityFilter(n_jobs=n_jobs) if experiment.filtered else "passthrough"),
    ]
    if experiment.stage == 1:
        steps.append(("cluster", RadarDBSCAN(**experiment.params, n_jobs=n_jobs)))
    else:
        stage1 = RadarDBSCAN(**_stage1_setting(stage1_params), n_jobs=n_jobs)
        steps.append(("merge", ClusterMerger(**experiment.params, stage1=stage1, memory=memory)))
    pipeline = Pipeline(steps, memory=memory)
    if params:
        pipeline.set_params(**params)
    return pipeline


@validate_params({"number": _NUMBER}, prefer_skip_nested_validation=True)
def search_space(number):
    """Bayesian-optimisation search space of experiment ``number`` (skopt dimensions).

    Keys are parameters of :func:`experiment_pipeline` (``number``).  Every
    range contains the paper's optimum of Tables III/IV.  ``eps_vr`` and
    ``vr_scale`` span two orders of magnitude (the paper finds 1.03 and 13.5
    for the same parameter), so they are searched log-uniformly.

    ==========================  ==================  ========  =====================  ==========
    key                         range               unit      prior                  experiments
    ==========================  ==================  ========  =====================  ==========
    ``cluster__eps_xy``         [0.2, 3.0]          m         uniform                2-5, 7
    ``cluster__eps_vr``         [0.5, 20]           m/s       log-uniform            2-5, 7
    ``cluster__eps_xyv``        [0.2, 3.0]          m         uniform                6, 8, 9
    ``cluster__vr_scale``       [0.3, 20]           m/s       log-uniform            6, 8, 9
    ``cluster__min_samples``    {2, ..., 8}         points    integer                2-6 (fixed N_min)
    ``cluster__min_samples``    [1.5, 8.0]          points    uniform (N_min,50)     7-9
    ``cluster__alpha_r``        [0, 1]              1         uniform                7-9
    ``cluster__vr_min``         [0, 1.5]            m/s       uniform                2-9
    ``merge__eps_d``            [0.2, 3.0]          m         uniform                12, 13
    ``merge__eps_phi``          [0.05, 1.5]         rad       uniform                12
    ``merge__eps_v``            [0.2, 6.0]          m/s       uniform                12, 13
    ``merge__eps_t2``           [0.1, 1.0]          s         uniform                12, 13
    ``merge__min_samples``      {1, 2, 3}           clusters  integer                12, 13
    ==========================  ==================  ========  =====================  ==========

    eps_t is fixed at 0.25 s, as in the paper.  The experiments without
    optimisation return ``{}`` (``BayesSearchCV`` rejects an empty space;
    evaluate ``experiment_pipeline(number)`` directly):

    * #1, the expert setting (CCS, box criterion);
    * #10, #8's tuned setting applied to unfiltered data
      (``experiment_pipeline(10, params=...)`` with #8's ``best_params_``);
    * #11, #8's eps values transferred to the box criterion (Eq. 3):
      ``eps_xy = eps_xyv``, ``eps_vr = vr_scale``,
      ``min_samples = round(N_min,50)``, ``vr_min`` as #8, ``alpha_r = 0``.

    For the stage-2 experiments (#12, #13) only ``merge__*`` parameters are
    searched; stage 1 stays at the ``stage1_params`` of
    :func:`experiment_pipeline`.

    Read more in the :ref:`User Guide <user-guide-tuning>`.

    Parameters
    ----------
    number : int
        Experiment, 1-13.

    Returns
    -------
    space : dict
        ``{pipeline parameter: skopt.space.Dimension}``.
    """
    experiment = _get_experiment(number)
    if not experiment.tuned:
        return {}
    if experiment.stage == 2:
        space = {
            "merge__eps_d": Real(0.2, 3.0, name="merge__eps_d"),
            "merge__eps_v": Real(0.2, 6.0, name="merge__eps_v"),
            "merge__eps_t2": Real(0.1, 1.0, name="merge__eps_t2"),
            "merge__min_samples": Integer(1, 3, name="merge__min_samples"),
        }
        if experiment.params["mode"] == "velocity":
            space["merge__eps_phi"] = Real(0.05, 1.5, name="merge__eps_phi")
        return space
    params = experiment.params
    if params["metric"] == "xyv":
        space = {
            "cluster__eps_xyv": Real(0.2, 3.0, name="cluster__eps_xyv"),
            "cluster__vr_scale": Real(0.3, 20.0, prior="log-uniform", name="cluster__vr_scale"),
        }
    else:
        space = {
            "cluster__eps_xy": Real(0.2, 3.0, name="cluster__eps_xy"),
            "cluster__eps_vr": Real(0.5, 20.0, prior="log-uniform", name="cluster__eps_vr"),
        }
    if params["alpha_r"] > 0:
        space["cluster__min_samples"] = Real(1.5, 8.0, name="cluster__min_samples")
        space["cluster__alpha_r"] = Real(0.0, 1.0, name="cluster__alpha_r")
    else:
        space["cluster__min_samples"] = Integer(2, 8, name="cluster__min_samples")
    space["cluster__vr_min"] = Real(0.0, 1.5, name="cluster__vr_min")
    return space
