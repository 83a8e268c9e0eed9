"""The object experiment: the paper's #8 and #12 (FCS, the paper's filter, Eq. 5, Eq. 6 merging), tuned for PQ."""

import numpy as np
import pytest
from sklearn.base import clone

from sklearn_radar import ClusterMerger, RadarDBSCAN
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import (
    experiment_pipeline,
    object_pipeline,
    object_search_space,
    paper_params,
    search_space,
)


@pytest.fixture(scope="module")
def scenes():
    return make_scenes(n_sequences=2, duration=4.0, random_state=3)


STAGE1 = {"cluster__eps_xyv": 1.2, "cluster__vr_scale": 1.5, "cluster__min_samples": 3.0, "cluster__vr_min": 0.4}


def test_untuned_it_is_the_papers_8_and_12(scenes):
    for stage, number in ((1, 8), (2, 12)):
        ours = object_pipeline(stage).fit_predict(scenes.data)
        paper = experiment_pipeline(number).fit_predict(scenes.data)
        np.testing.assert_array_equal(ours, paper)
        assert len(np.unique(ours[ours >= 0])) > 3


def test_stage2_runs_on_the_tuned_stage1_and_keeps_8s_setting_elsewhere(scenes):
    stage2 = object_pipeline(2, stage1_params=STAGE1, params={"merge__eps_d": 2.0})
    merger = stage2.named_steps["merge"]
    assert isinstance(merger, ClusterMerger) and merger.mode == "velocity" and merger.eps_d == 2.0
    assert isinstance(merger.stage1, RadarDBSCAN)
    for key, value in {**paper_params(8), **STAGE1}.items():
        assert getattr(merger.stage1, key.removeprefix("cluster__")) == value
    labels = stage2.fit_predict(scenes.data)
    assert labels.shape == (len(scenes.data),)
    # Stage 2 only merges stage 1's clusters: each merged cluster is a union of the tuned stage 1's clusters.
    stage1 = object_pipeline(1, params=STAGE1).fit_predict(scenes.data)
    np.testing.assert_array_equal(stage2.named_steps["merge"].stage1_labels_, stage1)
    pairs = {(a, b) for a, b in zip(stage1, labels, strict=True) if a >= 0}
    assert len({a for a, _ in pairs}) == len(pairs)
    assert len(np.unique(labels[labels >= 0])) < len(np.unique(stage1[stage1 >= 0]))


def test_causal_sets_every_stage(scenes):
    pipe = object_pipeline(2, causal=True)
    assert pipe.named_steps["filter"].causal and pipe.named_steps["merge"].stage1.causal
    assert pipe.named_steps["merge"].causal_min_size and not object_pipeline(2).named_steps["merge"].causal_min_size
    assert object_pipeline(1, causal=True).named_steps["cluster"].causal
    offline = object_pipeline(2).fit_predict(scenes.data)
    causal = pipe.fit_predict(scenes.data)
    assert offline.shape == causal.shape and not np.array_equal(offline, causal)


def test_search_spaces_are_the_papers_and_a_minimum_cluster_size():
    for stage, number in ((1, 8), (2, 12)):
        space = object_search_space(stage)
        assert set(space) <= set(object_pipeline(stage).get_params())
        papers = {key: dimension for key, dimension in space.items() if key != "merge__min_cluster_size"}
        assert papers == search_space(number)
    size = object_search_space(2)["merge__min_cluster_size"]
    assert (size.low, size.high) == (1, 300)  # 1 is off: the search can choose the paper's #12
    assert "merge__min_cluster_size" not in search_space(12)


def test_min_cluster_size_prunes_the_merged_clusters(scenes):
    plain = object_pipeline(2, stage1_params=STAGE1).fit_predict(scenes.data)
    pruned = object_pipeline(2, stage1_params=STAGE1, params={"merge__min_cluster_size": 30}).fit_predict(scenes.data)
    ids, counts = np.unique(plain[plain >= 0], return_counts=True)
    np.testing.assert_array_equal(pruned >= 0, np.isin(plain, ids[counts >= 30]))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"stage": 3}, "stage"),
        ({"stage": 1, "stage1_params": {"cluster__eps_xyv": 1.0}}, "stage1_params"),
        ({"stage": 2, "stage1_params": {"merge__eps_d": 1.0}}, "merge__eps_d"),
        ({"stage": 2, "stage1_params": {"filter__vr_threshold": 0.3}}, "filter__vr_threshold"),
    ],
)
def test_bad_arguments_are_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        object_pipeline(**kwargs)


def test_pipelines_clone():
    pipe = object_pipeline(2, stage1_params={"cluster__min_samples": 5})
    assert clone(pipe).get_params()["merge__stage1__min_samples"] == 5
