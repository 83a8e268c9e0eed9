"""The per-sequence scikit-learn baselines equal scikit-learn on scaled (x, y, v_r, t) of the gated rows."""

import numpy as np
import pandas as pd
import pytest
from sklearn.cluster import DBSCAN, HDBSCAN

from sklearn_radar.cluster import SequenceDBSCAN, SequenceHDBSCAN


def _data(seed=0, n=800):
    rng = np.random.default_rng(seed)
    return pd.DataFrame(
        {
            "x": rng.uniform(0, 12, n),
            "y": rng.uniform(0, 12, n),
            "v_r": rng.normal(0, 2, n),
            "t": rng.uniform(0, 3.0, n),
            "sequence": rng.integers(1, 4, n),
            "keep": rng.uniform(size=n) > 0.1,
        }
    )


def _features(X, rows, vr_scale, t_scale):
    return np.c_[
        X["x"].to_numpy()[rows],
        X["y"].to_numpy()[rows],
        X["v_r"].to_numpy()[rows] / vr_scale,
        X["t"].to_numpy()[rows] * t_scale,
    ]


def _gated(X, vr_min):
    return (np.abs(X["v_r"].to_numpy()) > vr_min) & X["keep"].to_numpy()


def _same_partition(a, b):
    pairs = set(zip(a.tolist(), b.tolist(), strict=True))
    return len(pairs) == len(set(a.tolist())) == len(set(b.tolist()))


def test_sequence_dbscan_equals_sklearn_per_sequence():
    X = _data()
    labels = SequenceDBSCAN(eps=1.5, min_samples=3, vr_scale=2.0, t_scale=3.0, vr_min=0.3).fit(X).labels_
    gated = _gated(X, 0.3)
    for _, rows in X.groupby("sequence").indices.items():
        rows = rows[gated[rows]]
        reference = DBSCAN(eps=1.5, min_samples=3).fit_predict(_features(X, rows, 2.0, 3.0))
        assert (reference >= 0).any()
        # Exact labels up to renaming, border points included (the row order is kept).
        assert _same_partition(labels[rows], reference)
        np.testing.assert_array_equal(labels[rows] == -1, reference == -1)


def test_sequence_dbscan_equals_sklearn_on_one_sequence_without_a_gate():
    X = _data(1).assign(sequence=7, keep=True)
    labels = SequenceDBSCAN(eps=1.2, min_samples=4, t_scale=2.0, vr_min=-np.inf).fit(X).labels_
    reference = DBSCAN(eps=1.2, min_samples=4).fit_predict(_features(X, np.arange(len(X)), 1.0, 2.0))
    assert _same_partition(labels, reference)
    np.testing.assert_array_equal(labels == -1, reference == -1)


def test_sequence_hdbscan_equals_sklearn_per_sequence():
    X = _data(2)
    labels = SequenceHDBSCAN(min_cluster_size=4, vr_scale=2.0, t_scale=3.0, vr_min=0.3).fit(X).labels_
    gated = _gated(X, 0.3)
    for _, rows in X.groupby("sequence").indices.items():
        rows = rows[gated[rows]]
        reference = HDBSCAN(min_cluster_size=4, copy=True).fit_predict(_features(X, rows, 2.0, 3.0))
        assert _same_partition(labels[rows], reference)


@pytest.mark.parametrize("model", [SequenceDBSCAN(eps=3.0, vr_min=-np.inf), SequenceHDBSCAN(vr_min=-np.inf)])
def test_sequences_never_share_a_cluster(model):
    # Three copies of the same detections, one per sequence: without the sequence column they would merge.
    one = _data(3, n=300).drop(columns="sequence")
    X = pd.concat([one.assign(sequence=s) for s in (1, 2, 3)], ignore_index=True)
    labels = model.fit(X).labels_
    assert (labels >= 0).any()
    for label in set(labels.tolist()) - {-1}:
        assert X["sequence"][labels == label].nunique() == 1
    n = len(one)
    assert _same_partition(labels[:n], labels[n : 2 * n]) and _same_partition(labels[:n], labels[2 * n :])


@pytest.mark.parametrize("make", [lambda g: SequenceDBSCAN(eps=2.0, vr_min=g), lambda g: SequenceHDBSCAN(vr_min=g)])
def test_gate_and_keep_make_noise_and_rows_in_equal_rows_out(make):
    X = _data(4)
    for gate in (-np.inf, 0.0, 1.0, 2.5):
        labels = make(gate).fit(X).labels_
        assert labels.shape == (len(X),)
        assert np.all(labels[~_gated(X, gate)] == -1)
        assert np.all(labels[np.abs(X["v_r"].to_numpy()) <= gate] == -1)
        assert np.all(labels[~X["keep"].to_numpy()] == -1)
        kept = np.unique(labels[labels >= 0])
        np.testing.assert_array_equal(kept, np.arange(len(kept)))
    assert np.all(make(100.0).fit(X).labels_ == -1)  # everything gated: all noise, no error


@pytest.mark.parametrize("model", [SequenceDBSCAN(), SequenceHDBSCAN()])
def test_plain_array_without_sequence(model):
    X = _data(5)
    array = X[["x", "y", "v_r", "t"]].to_numpy()
    labels = model.fit(array).labels_
    assert labels.shape == (len(X),)
    np.testing.assert_array_equal(labels, model.fit(X[["x", "y", "v_r", "t"]]).labels_)
