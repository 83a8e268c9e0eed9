"""The object experiment: the framework's stages with a pure Doppler gate, fixed N_min, Eq. 5 and Eq. 6 merging."""

import numpy as np
import pytest
from sklearn.base import clone

from sklearn_radar import ClusterMerger, DopplerDensityFilter, RadarDBSCAN
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import GATE_RULE, object_pipeline, object_search_space, search_space
from sklearn_radar.preprocessing import neighbor_counts


@pytest.fixture(scope="module")
def scenes():
    return make_scenes(n_sequences=2, duration=4.0, random_state=3)


def test_the_gate_removes_every_slow_detection_and_the_isolated_ones(scenes):
    pipe = object_pipeline(1, params={"filter__vr_threshold": 0.6})
    framed = pipe[:1].fit_transform(scenes.data)
    kept = pipe[:2].fit_transform(scenes.data)["keep"].to_numpy(dtype=bool)
    speed = np.abs(framed["v_r"].to_numpy())
    # Eq. 1 by hand: no neighbour within 1.4 m and 0.15 s (the filter's defaults), or |v_r| < 0.6 m/s.
    n = neighbor_counts(
        framed["x"].to_numpy(),
        framed["y"].to_numpy(),
        framed["t"].to_numpy(),
        framed["sequence"].to_numpy(),
        d_xy=DopplerDensityFilter().d_xy,
        dt=DopplerDensityFilter().dt,
        cap=1,
    )
    np.testing.assert_array_equal(kept, (speed >= 0.6) & (n >= 1))
    assert 0 < kept.mean() < 1
    # Dense static clutter is removed too, unlike under the paper's rule.
    assert not kept[speed < 0.6].any()


def test_stage1_and_stage2_steps(scenes):
    stage1 = object_pipeline(1, params={"cluster__eps_xyv": 1.5})
    assert [name for name, _ in stage1.steps] == ["frame", "filter", "cluster"]
    cluster = stage1.named_steps["cluster"]
    assert isinstance(cluster, RadarDBSCAN)
    assert (cluster.metric, cluster.alpha_r, cluster.vr_min, cluster.eps_t) == ("xyv", 0.0, -np.inf, 0.25)
    assert stage1.named_steps["frame"].frame == "frame"
    tuned = {"filter__vr_threshold": 0.3, "cluster__eps_xyv": 1.5, "cluster__min_samples": 4}
    stage2 = object_pipeline(2, stage1_params=tuned, params={"merge__eps_d": 2.0})
    merger = stage2.named_steps["merge"]
    assert isinstance(merger, ClusterMerger) and merger.mode == "velocity" and merger.eps_d == 2.0
    assert (merger.stage1.eps_xyv, merger.stage1.min_samples) == (1.5, 4)
    assert stage2.named_steps["filter"].vr_threshold == 0.3
    labels = stage2.fit_predict(scenes.data)
    assert labels.shape == (len(scenes.data),)
    # Stage 2 only merges stage 1's clusters: each merged cluster is a union of stage-1 clusters.
    fitted = stage2.named_steps["merge"]
    pairs = {(a, b) for a, b in zip(fitted.stage1_labels_, labels, strict=True) if a >= 0}
    assert len({a for a, _ in pairs}) == len(pairs)


def test_causal_sets_every_stage(scenes):
    pipe = object_pipeline(2, causal=True)
    assert pipe.named_steps["filter"].causal and pipe.named_steps["merge"].stage1.causal
    offline = object_pipeline(2).fit_predict(scenes.data)
    causal = pipe.fit_predict(scenes.data)
    assert offline.shape == causal.shape and not np.array_equal(offline, causal)


def test_search_spaces_name_parameters_of_the_pipelines_and_keep_the_papers_ranges():
    for stage in (1, 2):
        params = object_pipeline(stage).get_params()
        assert set(object_search_space(stage)) <= set(params)
    paper8, paper12 = search_space(8), search_space(12)
    for key in ("cluster__eps_xyv", "cluster__vr_scale"):
        assert object_search_space(1)[key].bounds == paper8[key].bounds
    assert object_search_space(1)["filter__vr_threshold"].bounds == paper8["cluster__vr_min"].bounds
    for key, dimension in object_search_space(2).items():
        assert dimension.bounds == paper12[key].bounds


def test_gate_rule_is_one_rule_no_count_reaches():
    assert GATE_RULE["threshold_ratios"] == (1,) and GATE_RULE["min_neighbors"][0] >= 10**6


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"stage": 3}, "stage"),
        ({"stage": 1, "stage1_params": {"cluster__eps_xyv": 1.0}}, "stage1_params"),
        ({"stage": 2, "stage1_params": {"merge__eps_d": 1.0}}, "merge__eps_d"),
    ],
)
def test_bad_arguments_are_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        object_pipeline(**kwargs)


def test_pipelines_clone():
    pipe = object_pipeline(2, stage1_params={"cluster__min_samples": 5})
    assert clone(pipe).get_params()["merge__stage1__min_samples"] == 5
