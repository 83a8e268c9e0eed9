"""The cluster-level Doppler gate ``cluster_vr_min`` of RadarDBSCAN and ClusterMerger."""

from functools import cache

import numpy as np
import pandas as pd
import pytest

from sklearn_radar import ClusterMerger, DopplerDensityFilter, FrameTransform, RadarDBSCAN
from sklearn_radar.cluster import ScanStream
from sklearn_radar.datasets import make_scenes


def _stage1(gate=None, **params):
    return RadarDBSCAN(
        metric="xy", eps_xy=1.0, eps_vr=5.0, min_samples=3, vr_min=-np.inf, cluster_vr_min=gate, **params
    )


def _blob(x0, y0, v_r, times, sequence=1):
    """Three detections 0.3 m apart per scan, all with Doppler ``v_r`` (m/s)."""
    rows = [(x0, y0 + dy, v_r, t, sequence) for t in times for dy in (0.0, 0.3, 0.6)]
    return pd.DataFrame(rows, columns=["x", "y", "v_r", "t", "sequence"])


def _static_and_moving(sequence_static=1, sequence_moving=1):
    times = np.round(np.arange(0.0, 0.5, 0.1), 3)
    return pd.concat(
        [_blob(0.0, 0.0, 0.05, times, sequence_static), _blob(10.0, 10.0, 4.0, times, sequence_moving)],
        ignore_index=True,
    )


@cache
def _simulated():
    scenes = make_scenes(n_sequences=2, duration=6.0, random_state=0)
    return DopplerDensityFilter().fit_transform(FrameTransform().fit_transform(scenes.data))


def _medians(X, labels):
    speed = pd.Series(np.abs(X["v_r"].to_numpy())).groupby(labels).median()
    return speed.drop(-1, errors="ignore")


@pytest.mark.parametrize("make", [lambda g: _stage1(g), lambda g: _merger(g)])
def test_gate_removes_only_the_static_cluster(make):
    X = _static_and_moving()
    static = X["v_r"].to_numpy() < 1
    ungated = make(None).fit_predict(X)
    assert len(set(ungated[static])) == 1 and ungated[static][0] >= 0
    labels = make(0.2).fit_predict(X)
    assert len(labels) == len(X)
    assert np.all(labels[static] == -1)
    np.testing.assert_array_equal(labels[~static], 0)  # renumbered consecutively
    # A gate above every median removes everything, one below every median nothing.
    assert np.all(make(5.0).fit_predict(X) == -1)
    np.testing.assert_array_equal(make(0.01).fit_predict(X), ungated)


def _merger(gate, **params):
    return ClusterMerger(stage1=_stage1(), cluster_vr_min=gate, **params)


def test_gated_cores_are_not_listed():
    X = _static_and_moving()
    static = np.flatnonzero(X["v_r"].to_numpy() < 1)
    ungated = _stage1().fit(X)
    gated = _stage1(0.2).fit(X)
    assert np.isin(static, ungated.core_sample_indices_).any()
    np.testing.assert_array_equal(
        gated.core_sample_indices_, np.setdiff1d(ungated.core_sample_indices_, static, assume_unique=True)
    )
    assert np.all(gated.labels_[gated.core_sample_indices_] >= 0)


@pytest.mark.parametrize(
    "make",
    [
        lambda **kw: RadarDBSCAN(**kw),
        lambda **kw: RadarDBSCAN(metric="xy", vr_min=-np.inf, **kw),
        lambda **kw: ClusterMerger(**kw),
    ],
)
def test_default_is_off_and_gate_zero_only_removes_clusters_of_zero_median(make):
    X = _simulated()
    default = make().fit_predict(X)
    np.testing.assert_array_equal(make(cluster_vr_min=None).fit_predict(X), default)
    for gate in (0.0, 0.3):
        labels = make(cluster_vr_min=gate).fit_predict(X)
        assert len(labels) == len(X)
        medians = _medians(X, default)
        removed = np.isin(default, medians.index[medians <= gate])
        np.testing.assert_array_equal(labels == -1, (default == -1) | removed)
        # The kept clusters are the same partition, renumbered consecutively.
        kept = labels >= 0
        assert len(set(zip(labels[kept], default[kept], strict=True))) == len(np.unique(labels[kept]))
        np.testing.assert_array_equal(np.unique(labels[kept]), np.arange(len(np.unique(labels[kept]))))


def test_gate_zero_removes_clusters_whose_doppler_is_all_zero():
    times = np.round(np.arange(0.0, 0.5, 0.1), 3)
    X = pd.concat([_blob(0.0, 0.0, 0.0, times), _blob(10.0, 10.0, 0.05, times)], ignore_index=True)
    none = _stage1().fit_predict(X)
    zero = _stage1(0.0).fit_predict(X)
    assert np.unique(none).tolist() == [0, 1]
    zero_doppler = X["v_r"].to_numpy() == 0
    assert np.all(zero[zero_doppler] == -1)
    np.testing.assert_array_equal(zero[~zero_doppler], 0)


def test_gate_with_sequences():
    # The same positions in two sequences: the static blob in sequence 1, the moving one in sequence 2,
    # and a moving copy of the static blob's place in sequence 2.
    X = pd.concat([_static_and_moving(1, 2), _blob(0.0, 0.0, 4.0, np.round(np.arange(0.0, 0.5, 0.1), 3), 2)])
    X = X.reset_index(drop=True)
    labels = _stage1(0.2).fit_predict(X)
    static = X["v_r"].to_numpy() < 1
    assert np.all(labels[static] == -1)
    assert np.all(labels[~static] >= 0)
    assert len(np.unique(labels[~static])) == 2
    for label in np.unique(labels[~static]):
        assert X["sequence"][labels == label].nunique() == 1


def test_merger_gate_is_applied_after_merging():
    # One object moving at 2 m/s along x, seen with Doppler 3 m/s, then (after a 0.3 s gap that splits
    # stage 1) twice with Doppler 0.1 m/s: the second part alone fails a 1 m/s gate, the merged cluster passes.
    first = np.round(np.arange(0.0, 0.45, 0.1), 3)
    second = np.array([0.7, 0.8])
    rows = [(2.0 * t, dy, 3.0, t, 1) for t in first for dy in (0.0, 0.3, 0.6)]
    rows += [(2.0 * t, dy, 0.1, t, 1) for t in second for dy in (0.0, 0.3, 0.6)]
    X = pd.DataFrame(rows, columns=["x", "y", "v_r", "t", "sequence"])
    slow = X["v_r"].to_numpy() < 1

    merged = _merger(1.0).fit(X)
    assert len(np.unique(merged.stage1_labels_)) == 2  # stage 1 splits the object
    assert len(merged.merges_) == 1
    np.testing.assert_array_equal(merged.labels_, 0)  # the merged cluster's median (3 m/s) passes

    unmerged = _merger(1.0, eps_t2=0.2).fit(X)  # the 0.3 s gap is too long: the slow part alone is gated
    assert len(unmerged.merges_) == 0
    assert np.all(unmerged.labels_[slow] == -1)
    np.testing.assert_array_equal(unmerged.labels_[~slow], 0)
    np.testing.assert_array_equal(_stage1(1.0).fit_predict(X), unmerged.labels_)


def test_streaming_refuses_the_gate():
    X = _static_and_moving()
    with pytest.raises(ValueError, match="cluster_vr_min"):
        RadarDBSCAN(cluster_vr_min=0.2).partial_fit(X)
    with pytest.raises(ValueError, match="cluster_vr_min"):
        ScanStream(RadarDBSCAN(cluster_vr_min=0.2))
    # causal=True fit applies it in hindsight, to whole clusters.
    causal = _stage1(0.2, causal=True).fit_predict(X)
    assert np.all(causal[X["v_r"].to_numpy() < 1] == -1)
    assert np.all(causal[X["v_r"].to_numpy() > 1] == 0)


@pytest.mark.parametrize("estimator", [RadarDBSCAN, ClusterMerger])
def test_negative_gate_is_rejected(estimator):
    with pytest.raises(ValueError, match="cluster_vr_min"):
        estimator(cluster_vr_min=-0.1).fit(_static_and_moving())
