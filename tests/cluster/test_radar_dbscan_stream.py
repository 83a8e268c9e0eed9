"""Causal RadarDBSCAN: the scan-by-scan stream (partial_fit) and its offline twin (causal=True)."""

import numpy as np
import pandas as pd
import pytest

from sklearn_radar import DopplerDensityFilter, FrameTransform, RadarDBSCAN
from sklearn_radar.datasets import make_scenes

PARAMS = dict(metric="xyv", eps_xyv=1.0, vr_scale=1.0, min_samples=3, vr_min=0.5)


@pytest.fixture(scope="module")
def detections():
    scenes = make_scenes(n_sequences=3, duration=8.0, random_state=5)
    return DopplerDensityFilter().fit_transform(FrameTransform().fit_transform(scenes.data))


def _same_partition(a, b):
    pairs = set(zip(a.tolist(), b.tolist(), strict=True))
    return len(pairs) == len(set(a.tolist())) == len(set(b.tolist()))


def _stream(model, X, by=("t", "sequence")):
    """Feed X scan by scan in global time order (sequences interleaved)."""
    labels = np.full(len(X), -2, dtype=np.int64)
    for _, rows in X.groupby(list(by), sort=True).indices.items():
        labels[rows] = model.partial_fit(X.iloc[rows]).labels_
    return labels


def test_stream_and_offline_causal_give_the_same_labels(detections):
    offline = RadarDBSCAN(causal=True, **PARAMS).fit(detections).labels_
    streamed = _stream(RadarDBSCAN(**PARAMS), detections)
    assert (streamed >= 0).mean() > 0.05
    np.testing.assert_array_equal(streamed == -1, offline == -1)
    for number in detections["sequence"].unique():
        rows = (detections["sequence"] == number).to_numpy()
        assert _same_partition(streamed[rows], offline[rows])


def test_stream_never_uses_the_future(detections):
    t = detections["t"].to_numpy()
    cut = np.quantile(t, 0.5)
    past = t <= cut
    full = RadarDBSCAN(causal=True, **PARAMS).fit(detections).labels_
    prefix = RadarDBSCAN(causal=True, **PARAMS).fit(detections[past]).labels_
    np.testing.assert_array_equal(full[past] == -1, prefix == -1)
    assert _same_partition(full[past], prefix)


def _scan(t, points, sequence=1):
    return pd.DataFrame([(x, y, 5.0, t, sequence) for x, y in points], columns=["x", "y", "v_r", "t", "sequence"])


def test_a_continuing_cluster_keeps_its_id_and_the_older_id_wins_a_merge():
    model = RadarDBSCAN(metric="xy", eps_xy=1.0, min_samples=2, vr_min=0.0)
    a = model.partial_fit(_scan(0.00, [(0.0, 0.0), (0.5, 0.0)])).labels_
    b = model.partial_fit(_scan(0.06, [(5.0, 0.0), (5.5, 0.0)])).labels_
    assert a[0] == a[1] and b[0] == b[1] and a[0] < b[0]
    moved = model.partial_fit(_scan(0.12, [(0.6, 0.0)])).labels_
    assert moved[0] == a[0]  # continues the first cluster
    bridge = model.partial_fit(_scan(0.18, [(1.4, 0.0), (2.2, 0.0), (3.0, 0.0), (3.8, 0.0), (4.6, 0.0)])).labels_
    assert set(bridge.tolist()) == {a[0]}  # both clusters meet: the older id wins
    after = model.partial_fit(_scan(0.24, [(5.2, 0.0), (5.6, 0.0)])).labels_
    assert set(after.tolist()) == {a[0]}  # the younger cluster's area now carries the older id


def test_detections_older_than_eps_t_are_forgotten():
    model = RadarDBSCAN(metric="xy", eps_xy=1.0, min_samples=2, vr_min=0.0, eps_t=0.25)
    first = model.partial_fit(_scan(0.0, [(0.0, 0.0), (0.3, 0.0)])).labels_
    later = model.partial_fit(_scan(0.30, [(0.0, 0.0), (0.3, 0.0)])).labels_
    assert first[0] >= 0 and later[0] >= 0 and later[0] != first[0]


def test_the_first_detection_of_an_object_cannot_be_core_without_a_past():
    # Offline, the first point sees its future neighbours; causally it is alone.
    X = pd.concat([_scan(0.0, [(0.0, 0.0)]), _scan(0.06, [(0.3, 0.0)]), _scan(0.12, [(0.6, 0.0)])], ignore_index=True)
    params = dict(metric="xy", eps_xy=1.0, min_samples=3, vr_min=0.0)
    assert RadarDBSCAN(**params).fit(X).labels_.tolist() == [0, 0, 0]
    assert RadarDBSCAN(causal=True, **params).fit(X).labels_.tolist() == [-1, -1, 0]


def test_time_must_not_go_back_within_a_sequence():
    model = RadarDBSCAN()
    model.partial_fit(_scan(1.0, [(0.0, 0.0)]))
    model.partial_fit(_scan(0.5, [(0.0, 0.0)], sequence=2))  # another sequence has its own clock
    with pytest.raises(ValueError, match="'t' goes back in time"):
        model.partial_fit(_scan(0.5, [(0.0, 0.0)]))


def test_fit_ends_the_stream():
    model = RadarDBSCAN(metric="xy", min_samples=2, vr_min=0.0)
    model.partial_fit(_scan(5.0, [(0.0, 0.0), (0.3, 0.0)]))
    model.fit(_scan(1.0, [(0.0, 0.0), (0.3, 0.0)]))
    assert model.partial_fit(_scan(0.0, [(0.0, 0.0), (0.3, 0.0)])).labels_.tolist() == [0, 0]


def test_scan_stream_on_arrays_equals_partial_fit(detections):
    from sklearn_radar.cluster import ScanStream

    stream = ScanStream(RadarDBSCAN(**PARAMS))
    labels = np.full(len(detections), -2, dtype=np.int64)
    for _, rows in detections.groupby(["t", "sequence"], sort=True).indices.items():
        scan = detections.iloc[rows]
        labels[rows] = stream.update(
            scan["x"], scan["y"], scan["v_r"], scan["t"].iloc[0], sequence=scan["sequence"].iloc[0], keep=scan["keep"]
        )
    np.testing.assert_array_equal(labels, _stream(RadarDBSCAN(**PARAMS), detections))


def test_scan_stream_rejects_ragged_or_non_finite_input():
    from sklearn_radar.cluster import ScanStream

    stream = ScanStream(RadarDBSCAN())
    with pytest.raises(ValueError, match="'y' must hold 2 finite values"):
        stream.update(x=[0.0, 1.0], y=[0.0], v_r=[1.0, 1.0], t=0.0)
    with pytest.raises(ValueError, match="'v_r' must hold 1 finite values"):
        stream.update(x=[0.0], y=[0.0], v_r=[np.nan], t=0.0)
