"""Beyond the paper: the scikit-learn clusterers a user would otherwise pick, on the input of experiment #3.

Each baseline replaces the clustering step of the FCS box pipeline (#3:
frame transform and Doppler-density filter) and is tuned on the same
budget and split as the experiments.
"""

from __future__ import annotations

from sklearn.utils._param_validation import HasMethods, StrOptions, validate_params

from .._skopt import Integer, Real
from ..cluster import SequenceDBSCAN, SequenceHDBSCAN, SlidingDBSCAN, WindowedDBSCAN, WindowedHDBSCAN
from ._paper import experiment_pipeline

__all__ = ["BASELINE_INPUT", "SKLEARN_BASELINES", "SLIDING_BASELINE", "baseline_pipeline"]

#: The experiment whose stage 0 (FCS, filtered) the baselines cluster: #3, the FCS box baseline.
BASELINE_INPUT = 3


def _scales(*, t_scale=None, vr_min=None):
    space = {"cluster__vr_scale": Real(0.01, 50.0, prior="log-uniform", name="cluster__vr_scale")}
    if t_scale is not None:
        # t_scale, m/s: how many metres one second counts (4 m/s puts 0.25 s, the paper's eps_t, at 1 m).
        space["cluster__t_scale"] = Real(t_scale, 100.0, prior="log-uniform", name="cluster__t_scale")
    if vr_min is not None:
        space["cluster__vr_min"] = Real(vr_min, 6.0, name="cluster__vr_min")
    return space


def _dbscan_space():
    return {
        "cluster__eps": Real(0.2, 10.0, prior="log-uniform", name="cluster__eps"),
        # 1 point: every detection is a core point and clusters are the eps-connected components.
        "cluster__min_samples": Integer(1, 40, prior="log-uniform", name="cluster__min_samples"),
    }


def _hdbscan_space(largest_cluster):
    # cluster_selection_epsilon stays 0: scikit-learn 1.9.1's epsilon search crashed on this data.
    return {
        "cluster__min_cluster_size": Integer(2, largest_cluster, prior="log-uniform", name="cluster__min_cluster_size"),
        "cluster__min_samples": Integer(1, 40, prior="log-uniform", name="cluster__min_samples"),
    }


#: The baseline that decides from the past only (its input is filtered causally too).
SLIDING_BASELINE = "sklearn DBSCAN over a sliding past window (x, y, v_r, t) with Doppler gate, causal"

#: Name -> (clusterer class, search space), in run order.  The ranges were widened where a tuned setting of the
#: object-level ablation (``benchmarks/ablation_object_level.py``, 5 seeds x 3 presets) stopped at an end:
#: min_samples down to 1, vr_min up to 6 m/s, vr_scale down to 0.01, the sliding window's t_scale down to 0.01 m/s
#: (its window bounds time anyway); the report names any setting that still does
#: (``model_selection._bounds.bounds_reached``).
SKLEARN_BASELINES = {
    "sklearn DBSCAN per 0.25 s window": (WindowedDBSCAN, {**_dbscan_space(), **_scales()}),
    "sklearn HDBSCAN per 0.25 s window": (WindowedHDBSCAN, {**_hdbscan_space(40), **_scales()}),
    "sklearn DBSCAN per sequence (x, y, v_r, t) with Doppler gate": (
        SequenceDBSCAN,
        {**_dbscan_space(), **_scales(t_scale=0.1, vr_min=0.0)},
    ),
    # vr_min from 0.1 m/s: below it static clutter makes one fit take 6 s.
    "sklearn HDBSCAN per sequence (x, y, v_r, t) with Doppler gate": (
        SequenceHDBSCAN,
        {**_hdbscan_space(400), **_scales(t_scale=0.1, vr_min=0.1)},
    ),
    # vr_min from 0.1 m/s and windows up to 1 s: one DBSCAN per scan over a long window of static clutter made
    # one fit of a 10 s sequence take 20 s.
    SLIDING_BASELINE: (
        SlidingDBSCAN,
        {
            **_dbscan_space(),
            **_scales(t_scale=0.01, vr_min=0.1),
            "cluster__window": Real(0.1, 1.0, prior="log-uniform", name="cluster__window"),
        },
    ),
}


@validate_params(
    {"name": [StrOptions(set(SKLEARN_BASELINES))], "memory": [None, str, HasMethods(["cache"])]},
    prefer_skip_nested_validation=True,
)
def baseline_pipeline(name, memory=None):
    """The pipeline of baseline ``name``: #3's stage 0, then the baseline's clusterer (default parameters).

    The sliding-window baseline's filter counts neighbours in the past only (``causal=True``), as its clusterer.

    Parameters
    ----------
    name : str
        A key of :data:`SKLEARN_BASELINES`.
    memory : str, joblib.Memory or None, default=None
        The pipeline's cache.

    Returns
    -------
    pipeline : Pipeline
    """
    clusterer, _ = SKLEARN_BASELINES[name]
    pipeline = experiment_pipeline(BASELINE_INPUT, memory=memory)
    pipeline.steps[-1] = ("cluster", clusterer())
    if name == SLIDING_BASELINE:
        pipeline.set_params(filter__causal=True)
    return pipeline
