"""ClusterMerger's min_cluster_size: whole merged clusters offline, a confirmation rule with causal_min_size=True."""

import numpy as np
import pytest

from sklearn_radar import ClusterMerger, DopplerDensityFilter, FrameTransform, RadarDBSCAN
from sklearn_radar.datasets import make_scenes


@pytest.fixture(scope="module")
def work():
    scenes = make_scenes(n_sequences=2, duration=6.0, random_state=3, difficulty="realistic")
    return DopplerDensityFilter().fit_transform(FrameTransform().fit_transform(scenes.data))


def merger(**params):
    stage1 = RadarDBSCAN(eps_xyv=1.2, vr_scale=2.0, min_samples=3.0, vr_min=0.5)
    return ClusterMerger(mode="velocity", eps_d=2.0, eps_phi=0.8, eps_v=2.5, stage1=stage1, **params)


def assert_same_partition(a, b):
    np.testing.assert_array_equal(a < 0, b < 0)
    pairs = set(zip(a[a >= 0].tolist(), b[b >= 0].tolist(), strict=True))
    assert len(pairs) == len(set(a[a >= 0].tolist())) == len(set(b[b >= 0].tolist()))


def test_default_keeps_every_cluster(work):
    np.testing.assert_array_equal(
        merger().fit(work).labels_, merger(min_cluster_size=1, causal_min_size=True).fit(work).labels_
    )


@pytest.mark.parametrize("min_size", [5, 40])
def test_offline_drops_whole_clusters_below_the_size(work, min_size):
    full = merger().fit(work).labels_
    ids, counts = np.unique(full[full >= 0], return_counts=True)
    assert counts.min() < min_size <= counts.max()  # the case removes some clusters and keeps others
    expected = np.where(np.isin(full, ids[counts >= min_size]), full, -1)
    labels = merger(min_cluster_size=min_size).fit(work).labels_
    assert_same_partition(labels, expected)
    assert labels.max() + 1 == np.sum(counts >= min_size)  # consecutive ids


def test_causal_counts_each_cluster_up_to_each_detection(work):
    full = merger().fit(work).labels_
    t = work["t"].to_numpy()
    so_far = np.array(
        [np.sum((full == label) & (t <= ti)) if label >= 0 else 0 for label, ti in zip(full, t, strict=True)]
    )
    labels = merger(min_cluster_size=8, causal_min_size=True).fit(work).labels_
    assert_same_partition(labels, np.where(so_far >= 8, full, -1))
    offline = merger(min_cluster_size=8).fit(work).labels_
    assert np.sum(labels >= 0) < np.sum(offline >= 0)  # a cluster's first detections wait for confirmation


def test_stage1_labels_and_merges_are_not_pruned(work):
    plain, pruned = merger().fit(work), merger(min_cluster_size=30).fit(work)
    np.testing.assert_array_equal(plain.stage1_labels_, pruned.stage1_labels_)
    np.testing.assert_array_equal(plain.merges_, pruned.merges_)


@pytest.mark.parametrize("params", [{"min_cluster_size": 0}, {"min_cluster_size": 2.5}, {"causal_min_size": "yes"}])
def test_bad_values_are_refused_by_name(work, params):
    with pytest.raises(ValueError, match=next(iter(params))):
        merger(**params).fit(work)
