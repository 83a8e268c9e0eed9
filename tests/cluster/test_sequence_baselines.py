"""The per-sequence scikit-learn baselines equal scikit-learn on scaled (x, y, v_r, t) of the gated rows; the
sliding-window one equals scikit-learn on each scan's past window, with ids handed on as a slow loop hands them."""

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.cluster import DBSCAN, HDBSCAN

from sklearn_radar.cluster import SequenceDBSCAN, SequenceHDBSCAN, SlidingDBSCAN


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


@pytest.mark.parametrize(
    "model",
    [SequenceDBSCAN(eps=3.0, vr_min=-np.inf), SequenceHDBSCAN(vr_min=-np.inf), SlidingDBSCAN(eps=3.0, vr_min=-np.inf)],
)
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


@pytest.mark.parametrize(
    "make",
    [
        lambda g: SequenceDBSCAN(eps=2.0, vr_min=g),
        lambda g: SequenceHDBSCAN(vr_min=g),
        lambda g: SlidingDBSCAN(eps=2.0, vr_min=g),
    ],
)
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


@pytest.mark.parametrize("model", [SequenceDBSCAN(), SequenceHDBSCAN(), SlidingDBSCAN()])
def test_plain_array_without_sequence(model):
    X = _data(5)
    array = X[["x", "y", "v_r", "t"]].to_numpy()
    labels = model.fit(array).labels_
    assert labels.shape == (len(X),)
    np.testing.assert_array_equal(labels, model.fit(X[["x", "y", "v_r", "t"]]).labels_)


def _scanned(seed=0, n_scans=40, per_scan=12, dt=0.05, sequences=(1,)):
    """Detections in scans of ``per_scan`` rows every ``dt`` s, a few moving blobs plus clutter, rows shuffled."""
    rng = np.random.default_rng(seed)
    frames = []
    for sequence in sequences:
        t = np.repeat(np.arange(n_scans) * dt, per_scan)
        blob = rng.integers(0, 3, len(t))
        frames.append(
            pd.DataFrame(
                {
                    "x": blob * 6.0 + 2.0 * t + rng.normal(0, 0.4, len(t)),
                    "y": blob * 3.0 + rng.normal(0, 0.4, len(t)),
                    "v_r": 2.0 + blob + rng.normal(0, 0.2, len(t)),
                    "t": t,
                    "sequence": sequence,
                    "keep": rng.uniform(size=len(t)) > 0.05,
                }
            )
        )
    X = pd.concat(frames, ignore_index=True)
    return X.iloc[rng.permutation(len(X))].reset_index(drop=True)


def _slow_sliding(X, eps, min_samples, vr_scale, t_scale, vr_min, window):
    """The rule written out: per sequence, per scan, scikit-learn's DBSCAN on the past window; ids handed on."""
    labels = np.full(len(X), -1)
    next_id = 0
    gated = _gated(X, vr_min)
    for _, rows in X.groupby("sequence").indices.items():
        rows = rows[gated[rows]]
        t = X["t"].to_numpy()[rows]
        for now in np.unique(t):
            in_window = rows[(t > now - window) & (t <= now)]
            in_window = in_window[np.argsort(X["t"].to_numpy()[in_window], kind="stable")]
            if len(in_window) < min_samples:
                continue
            found = DBSCAN(eps=eps, min_samples=min_samples).fit_predict(_features(X, in_window, vr_scale, t_scale))
            is_new = X["t"].to_numpy()[in_window] == now
            for cluster in sorted(set(found[is_new].tolist()) - {-1}):
                members = in_window[found == cluster]
                old = [labels[r] for r in members if labels[r] >= 0 and X["t"][r] < now]
                if old:
                    given_id = min(old)
                else:
                    given_id, next_id = next_id, next_id + 1
                labels[in_window[is_new & (found == cluster)]] = given_id
    return labels


@pytest.mark.parametrize(("eps", "min_samples", "window"), [(1.5, 3, 0.3), (1.0, 2, 0.12), (2.5, 5, 1.0)])
def test_sliding_dbscan_equals_the_rule_written_out(eps, min_samples, window):
    X = _scanned(sequences=(1, 2))
    params = dict(eps=eps, min_samples=min_samples, vr_scale=2.0, t_scale=3.0, vr_min=0.3, window=window)
    labels = SlidingDBSCAN(**params).fit(X).labels_
    reference = _slow_sliding(X, **params)
    assert (reference >= 0).sum() > len(X) / 2
    assert _same_partition(labels, reference)
    np.testing.assert_array_equal(labels == -1, reference == -1)


def test_sliding_dbscan_on_one_scan_is_dbscan_on_that_scan():
    X = _data(6).assign(t=1.0, sequence=1)
    labels = SlidingDBSCAN(eps=1.5, min_samples=3, vr_min=0.3, window=0.1).fit(X).labels_
    reference = SequenceDBSCAN(eps=1.5, min_samples=3, vr_min=0.3).fit(X).labels_
    assert (reference >= 0).any()
    assert _same_partition(labels, reference)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), cut=st.integers(1, 39), window=st.floats(0.06, 1.0))
def test_sliding_dbscan_is_causal(seed, cut, window):
    # Labels of the scans up to a time do not depend on anything after it (up to renaming).
    X = _scanned(seed=seed)
    model = SlidingDBSCAN(eps=1.5, min_samples=3, vr_min=0.3, window=window)
    labels = model.fit(X).labels_
    past = (X["t"] <= cut * 0.05 + 1e-9).to_numpy()
    assert _same_partition(labels[past], model.fit(X[past]).labels_)


def test_sliding_dbscan_ids_persist_across_scans():
    # One blob seen in every scan, shorter window than the recording: one id throughout.
    t = np.repeat(np.arange(30) * 0.05, 5)
    rng = np.random.default_rng(0)
    X = pd.DataFrame({"x": rng.normal(0, 0.2, len(t)), "y": rng.normal(0, 0.2, len(t)), "v_r": 3.0, "t": t})
    labels = SlidingDBSCAN(eps=1.0, min_samples=3, window=0.2).fit(X).labels_
    assert np.all(labels == 0)


def test_hdbscan_with_more_min_samples_than_rows_finds_noise_not_an_error():
    # scikit-learn's HDBSCAN raises when min_samples exceeds the rows; a sequence that small has no cluster.
    X = _data(7, n=60)
    labels = SequenceHDBSCAN(min_cluster_size=3, min_samples=40, vr_min=-np.inf).fit(X).labels_
    assert labels.shape == (len(X),) and np.all(labels == -1)
    big = pd.concat([X.assign(sequence=1), _data(8, n=400).assign(sequence=2)], ignore_index=True)
    labels = SequenceHDBSCAN(min_cluster_size=3, min_samples=40, vr_min=-np.inf).fit(big).labels_
    assert np.all(labels[:60] == -1)
