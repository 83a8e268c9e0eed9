"""The paper's experiments as data: Tables III/IV, pipelines and search spaces."""

import math
from numbers import Integral

import numpy as np
import pytest
from sklearn.base import clone

from sklearn_radar import ClusterMerger, DopplerDensityFilter, FrameTransform, RadarDBSCAN
from sklearn_radar._skopt import Integer
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import (
    PAPER_EXPERIMENTS,
    derived_params,
    experiment_pipeline,
    get_experiment,
    paper_experiments,
    paper_params,
    search_space,
)

TUNED = [2, 3, 4, 5, 6, 7, 8, 9, 12, 13]
FIXED = [1, 10, 11]

#: The "Optimized Parameter Sets" columns printed in Tables III and IV, per experiment.
OPTIMISED = {
    **{n: ("eps_xy", "eps_vr", "min_samples", "vr_min") for n in (2, 3, 4, 5)},
    6: ("eps_xyv", "vr_scale", "min_samples", "vr_min"),
    7: ("eps_xy", "eps_vr", "min_samples", "vr_min", "alpha_r"),
    8: ("eps_xyv", "vr_scale", "min_samples", "vr_min", "alpha_r"),
    9: ("eps_xyv", "vr_scale", "min_samples", "vr_min", "alpha_r"),
    12: ("eps_d", "eps_phi", "eps_v", "min_samples", "eps_t2"),
    13: ("eps_d", "eps_v", "min_samples", "eps_t2"),
}


@pytest.fixture(scope="module")
def tiny():
    return make_scenes(n_sequences=1, duration=3.0, random_state=1).data


def test_tables_are_transcribed():
    table = paper_experiments()
    assert list(table.index) == list(range(1, 14)) == [e.number for e in PAPER_EXPERIMENTS]
    assert table.loc[8, "v1_percent"] == 71.55 and table.loc[13, "v1_percent"] == 71.79
    assert table.loc[1, "v1_percent"] == 67.57
    assert list(table.index[table["frame"] == "car"]) == [1, 2]
    assert list(table.index[~table["filtered"]]) == [4, 9, 10]
    assert list(table.index[table["stage"] == 2]) == [12, 13]
    assert list(table.index[~table["tuned"]]) == FIXED
    assert table.loc[3, ["cluster__eps_xy", "cluster__eps_vr", "cluster__min_samples", "cluster__vr_min"]].tolist() == [
        0.60, 12.3, 3, 0.25
    ]
    assert table.loc[8, ["cluster__eps_xyv", "cluster__vr_scale", "cluster__min_samples", "cluster__vr_min",
                         "cluster__alpha_r"]].tolist() == [1.04, 1.03, 3.87, 1.00, 0.99]
    assert table.loc[13, ["merge__eps_d", "merge__eps_v", "merge__min_samples", "merge__eps_t2"]].tolist() == [
        0.94, 2.72, 1, 0.35
    ]
    assert get_experiment(12).eps_phi_deg == 23.11
    assert get_experiment(12).params["eps_phi"] == pytest.approx(math.radians(23.11))
    assert all(e.params.get("eps_t", 0.25) == 0.25 for e in PAPER_EXPERIMENTS if e.stage == 1)


def test_expert_setting_is_radar_dbscans_default():
    expert = experiment_pipeline(1).named_steps["cluster"].get_params()
    assert expert == RadarDBSCAN().get_params()


def test_fixed_experiments_derive_from_8():
    assert search_space(1) == search_space(10) == search_space(11) == {}
    assert derived_params(10) == paper_params(10) == paper_params(8)
    assert derived_params(11) == paper_params(11)
    tuned = {"cluster__eps_xyv": 1.3, "cluster__vr_scale": 2.5, "cluster__min_samples": 3.4, "cluster__vr_min": 0.7}
    transferred = derived_params(11, tuned)
    assert (transferred["cluster__eps_xy"], transferred["cluster__eps_vr"], transferred["cluster__min_samples"]) == (
        1.3, 2.5, 3
    )
    assert transferred["cluster__metric"] == "box" and transferred["cluster__alpha_r"] == 0.0
    experiment_pipeline(11, params=transferred)  # valid pipeline parameters
    with pytest.raises(ValueError, match="10 and 11"):
        derived_params(8)


@pytest.mark.parametrize("number", TUNED)
def test_search_space_contains_the_papers_optimum(number):
    space = search_space(number)
    step = "cluster" if number < 12 else "merge"
    assert set(space) == {f"{step}__{name}" for name in OPTIMISED[number]}
    optimum = paper_params(number)
    for key, dimension in space.items():
        low, high = dimension.bounds
        value = optimum[key]
        assert low <= value <= high, (key, value, dimension)
        assert value in dimension
        if isinstance(dimension, Integer):
            assert isinstance(value, Integral)
        assert dimension.name == key


def test_min_samples_is_integer_for_fixed_and_real_for_range_adaptive_n_min():
    for number in (2, 3, 4, 5, 6):
        assert isinstance(search_space(number)["cluster__min_samples"], Integer)
    for number in (7, 8, 9):
        assert search_space(number)["cluster__min_samples"].bounds == (1.5, 8.0)
        assert not isinstance(search_space(number)["cluster__min_samples"], Integer)


@pytest.mark.parametrize("number", TUNED)
def test_sampled_points_are_valid_pipeline_parameters(number, tiny):
    space = search_space(number)
    rng = np.random.RandomState(number)
    for _ in range(2):
        point = {key: dimension.rvs(random_state=rng)[0] for key, dimension in space.items()}
        pipeline = experiment_pipeline(number).set_params(**point)
        labels = clone(pipeline).fit_predict(tiny)
        assert labels.shape == (len(tiny),) and labels.min() >= -1


@pytest.mark.parametrize("number", range(1, 14))
def test_pipeline_steps(number, tiny):
    experiment = get_experiment(number)
    pipeline = experiment_pipeline(number, n_jobs=2)
    assert [name for name, _ in pipeline.steps] == ["frame", "filter", "cluster" if number < 12 else "merge"]
    assert isinstance(pipeline.named_steps["frame"], FrameTransform)
    assert pipeline.named_steps["frame"].frame == experiment.frame
    filter_step = pipeline.named_steps["filter"]
    if experiment.filtered:
        assert isinstance(filter_step, DopplerDensityFilter) and filter_step.n_jobs == 2
        assert (filter_step.vr_threshold, filter_step.d_xy) == (0.10, 1.4)
    else:
        assert filter_step == "passthrough"
    last = pipeline.steps[-1][1]
    if number < 12:
        assert isinstance(last, RadarDBSCAN) and last.n_jobs == 2
        assert {k: last.get_params()[k] for k in experiment.params} == experiment.params
    else:
        assert isinstance(last, ClusterMerger) and isinstance(last.stage1, RadarDBSCAN)
        assert {k: last.get_params()[k] for k in experiment.params} == experiment.params
        assert {k: last.stage1.get_params()[k] for k in get_experiment(8).params} == get_experiment(8).params
    labels = pipeline.fit_predict(tiny)
    assert labels.shape == (len(tiny),)


def test_memory_reaches_pipeline_and_cluster_merger(tmp_path):
    assert experiment_pipeline(3, memory=str(tmp_path)).memory == str(tmp_path)
    stage2 = experiment_pipeline(13, memory=str(tmp_path))
    assert stage2.memory == stage2.named_steps["merge"].memory == str(tmp_path)


def test_params_and_stage1_params():
    pipeline = experiment_pipeline(5, params={"cluster__eps_xy": 0.9, "filter__d_xy": 1.2})
    assert pipeline.named_steps["cluster"].eps_xy == 0.9 and pipeline.named_steps["filter"].d_xy == 1.2
    stage1 = {"cluster__metric": "box", "cluster__eps_xy": 0.6, "cluster__eps_vr": 12.3, "vr_min": 0.25}
    merger = experiment_pipeline(13, stage1_params=stage1).named_steps["merge"]
    assert merger.stage1.get_params() == RadarDBSCAN(metric="box", eps_xy=0.6, eps_vr=12.3, vr_min=0.25).get_params()
    with pytest.raises(ValueError, match="stage1_params"):
        experiment_pipeline(8, stage1_params=stage1)


@pytest.mark.parametrize("number", [0, 14, "8"])
def test_unknown_experiment_raises(number):
    with pytest.raises(ValueError, match="number"):
        experiment_pipeline(number)
    with pytest.raises(ValueError, match="number"):
        search_space(number)
