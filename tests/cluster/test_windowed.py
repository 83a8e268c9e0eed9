"""The scikit-learn baselines per time window equal scikit-learn run window by window."""

import numpy as np
import pandas as pd
from sklearn.cluster import DBSCAN, HDBSCAN

from sklearn_radar.cluster import WindowedDBSCAN, WindowedHDBSCAN


def _data(seed=0, n=600):
    rng = np.random.default_rng(seed)
    return pd.DataFrame(
        {
            "x": rng.uniform(0, 15, n),
            "y": rng.uniform(0, 15, n),
            "v_r": rng.normal(0, 3, n),
            "t": rng.uniform(0, 1.0, n),
            "sequence": rng.integers(1, 3, n),
        }
    )


def _same_partition(a, b):
    pairs = set(zip(a.tolist(), b.tolist(), strict=True))
    return len(pairs) == len(set(a.tolist())) == len(set(b.tolist()))


def _windows(X, window=0.25):
    start = X.groupby("sequence")["t"].transform("min")
    return X["sequence"].astype(str) + ":" + np.floor((X["t"] - start) / window).astype(int).astype(str)


def test_windowed_dbscan_equals_sklearn_per_window():
    X = _data()
    labels = WindowedDBSCAN(eps=1.2, min_samples=3, vr_scale=2.0).fit(X).labels_
    for _, rows in X.groupby(_windows(X)).indices.items():
        features = np.c_[X["x"].to_numpy()[rows], X["y"].to_numpy()[rows], X["v_r"].to_numpy()[rows] / 2.0]
        reference = DBSCAN(eps=1.2, min_samples=3).fit(features)
        core = reference.core_sample_indices_
        assert _same_partition(labels[rows][core], reference.labels_[core])
        np.testing.assert_array_equal(labels[rows] == -1, reference.labels_ == -1)
    # No cluster spans two windows.
    windows = _windows(X)
    for label in set(labels.tolist()) - {-1}:
        assert windows[labels == label].nunique() == 1


def test_windowed_hdbscan_equals_sklearn_per_window():
    X = _data(1)
    labels = WindowedHDBSCAN(min_cluster_size=4, vr_scale=2.0).fit(X).labels_
    for _, rows in X.groupby(_windows(X)).indices.items():
        features = np.c_[X["x"].to_numpy()[rows], X["y"].to_numpy()[rows], X["v_r"].to_numpy()[rows] / 2.0]
        reference = HDBSCAN(min_cluster_size=4, copy=True).fit_predict(features)
        assert _same_partition(labels[rows], reference)


def test_removed_rows_are_noise():
    X = _data(2).assign(keep=True)
    X.loc[::2, "keep"] = False
    for model in (WindowedDBSCAN(eps=2.0), WindowedHDBSCAN()):
        labels = model.fit(X).labels_
        assert (labels[~X["keep"].to_numpy()] == -1).all()


def test_windows_with_fewer_rows_than_min_samples_are_noise_not_an_error():
    # Scikit-learn's HDBSCAN raises when min_samples exceeds the rows: such a window has no cluster.
    X = _data(3, n=500)
    X = X[(X["sequence"] == 2) | (np.arange(len(X)) % 8 == 0)].reset_index(drop=True)  # sequence 1 sparse
    labels = WindowedHDBSCAN(min_cluster_size=3, min_samples=30).fit(X).labels_
    counts = X.groupby(_windows(X))["t"].transform("size").to_numpy()
    assert (counts < 30).any() and (counts >= 30).any()
    assert np.all(labels[counts < 30] == -1)
    for _, rows in X.groupby(_windows(X)).indices.items():
        if len(rows) >= 30:  # the others as scikit-learn finds them
            features = np.c_[X["x"].to_numpy()[rows], X["y"].to_numpy()[rows], X["v_r"].to_numpy()[rows]]
            reference = HDBSCAN(min_cluster_size=3, min_samples=30, copy=True).fit_predict(features)
            assert _same_partition(labels[rows], reference)
