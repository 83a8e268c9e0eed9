"""Cluster features: hand cases, properties, and a slow per-segment loop as the reference of the vectorised code."""

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sklearn_radar import FrameTransform, RadarDBSCAN
from sklearn_radar.classification import CLUSTER_FEATURES, cluster_features
from sklearn_radar.cluster import estimate_velocity
from sklearn_radar.datasets import make_scenes

WORKING = ["n_detections", "duration", "extent_along", "extent_across", "vr_mean", "vr_std", "vr_range"]


def _table(**columns):
    n = len(next(iter(columns.values())))
    base = {"x": np.zeros(n), "y": np.zeros(n), "v_r": np.zeros(n), "t": np.zeros(n)}
    return pd.DataFrame({**base, **{name: np.asarray(values, dtype=float) for name, values in columns.items()}})


def _principal_coordinates(position):
    """Coordinates of positions along their first and second principal axes (eigenvectors of the covariance)."""
    _, vectors = np.linalg.eigh(np.cov(position.T, bias=True).reshape(2, 2))
    centred = position - position.mean(axis=0)
    return centred @ vectors[:, 1], centred @ vectors[:, 0]  # eigh: ascending eigenvalues


def _reference(X, labels, window):
    """The feature table computed segment by segment with plain numpy and the per-cluster velocity estimate."""
    labels = np.asarray(labels)
    X = X.select_dtypes("number").astype(np.float64)  # the float32 columns of the table, in double precision
    sequence = X["sequence"].to_numpy() if "sequence" in X else np.zeros(len(X))
    t = X["t"].to_numpy()
    index = np.zeros(len(X), dtype=np.int64)
    if window is not None:
        for s in np.unique(sequence):
            mine = sequence == s
            index[mine] = np.floor((t[mine] - t[mine].min()) / window)
    segments = {}
    for row in range(len(X)):
        if labels[row] >= 0:
            segments.setdefault((sequence[row], labels[row], index[row]), []).append(row)
    records = []
    for key in sorted(segments):
        rows = np.array(segments[key])
        d = X.iloc[rows]
        record = dict(zip(("sequence", "cluster", "window"), key, strict=True))
        position = d[["x", "y"]].to_numpy()
        along, across = _principal_coordinates(position)
        v_r = d["v_r"].to_numpy()
        record.update(
            n_detections=len(rows),
            duration=np.ptp(d["t"]),
            extent_along=np.ptp(along),
            extent_across=np.ptp(across),
            vr_mean=v_r.mean(),
            vr_std=v_r.std(),
            vr_range=np.ptp(v_r),
        )
        if "rcs" in d:
            record.update(rcs_mean=d["rcs"].mean(), rcs_std=d["rcs"].to_numpy().std(), rcs_max=d["rcs"].max())
        if "range_sc" in d:
            record["range_mean"] = d["range_sc"].mean()
        if "azimuth_sc" in d and "sensor_yaw" in d:
            azimuth = (d["azimuth_sc"] + d["sensor_yaw"]).to_numpy()
            mean = np.arctan2(np.sin(azimuth).mean(), np.cos(azimuth).mean())
            deviation = np.angle(np.exp(1j * (azimuth - mean)))
            record["azimuth_spread"] = np.sqrt(np.mean(deviation**2))
            heading = d["heading"].to_numpy() if "heading" in d else 0.0
            vx, vy, _ = estimate_velocity(v_r, azimuth + heading)
            record["speed"] = np.hypot(vx, vy)
            predicted = vx * np.cos(azimuth + heading) + vy * np.sin(azimuth + heading)
            record["speed_residual"] = np.sqrt(np.mean((v_r - predicted) ** 2))
            t = d["t"].to_numpy()
            moved = position - np.outer(t - t.mean(), [vx, vy])  # NaN throughout when the velocity is unknown
            length, width = _principal_coordinates(moved) if np.isfinite(vx) else (np.nan, np.nan)
            record["length"], record["width"] = np.ptp(length), np.ptp(width)
        if "sensor_id" in d:
            record["n_sensors"] = len(set(d["sensor_id"]))
        records.append(record)
    return pd.DataFrame(records)


def _assert_same(table, reference):
    if len(reference) == 0:  # no segment: the loop has no row to name the columns
        assert len(table) == 0
        return
    assert list(table.columns) == list(reference.columns)
    assert len(table) == len(reference)
    for column in table.columns:
        np.testing.assert_allclose(
            table[column].to_numpy(dtype=float), reference[column].to_numpy(dtype=float), atol=1e-7, err_msg=column
        )


@pytest.fixture(scope="module")
def simulated():
    """Two simulated sequences after FrameTransform, and their RadarDBSCAN clusters."""
    X = FrameTransform().fit_transform(make_scenes(n_sequences=2, duration=5.0, random_state=1).data)
    labels = RadarDBSCAN(metric="xyv", vr_min=-np.inf).fit(X).labels_
    assert labels.max() > 20  # many clusters, static and moving
    return X, labels


@pytest.mark.parametrize("window", [None, 0.5, 0.15])
def test_equals_the_per_segment_loop_on_simulated_data(simulated, window):
    X, labels = simulated
    table = cluster_features(X, labels, window=window)
    _assert_same(table, _reference(X, labels, window))
    assert list(table.columns[3:]) == list(CLUSTER_FEATURES)  # a full detection table gives every feature
    assert table["speed"].notna().any() and table["speed"].isna().any()  # known and unknown velocities occur


@settings(max_examples=60, deadline=None)
@given(
    n=st.integers(1, 40),
    n_labels=st.integers(1, 5),
    seed=st.integers(0, 2**31 - 1),
    window=st.sampled_from([None, 0.3, 1.0]),
)
def test_equals_the_per_segment_loop_on_random_tables(n, n_labels, seed, window):
    rng = np.random.default_rng(seed)
    X = _table(
        x=rng.normal(0, 3, n),
        y=rng.normal(0, 3, n),
        v_r=rng.normal(0, 2, n),
        t=rng.uniform(0, 2, n).round(2),
        sequence=rng.integers(1, 3, n),
        rcs=rng.normal(0, 5, n),
        range_sc=rng.uniform(1, 50, n),
        azimuth_sc=rng.uniform(-1, 1, n),
        sensor_yaw=rng.choice([-1.48, -0.44, 0.44, 1.48], n),
        sensor_id=rng.integers(1, 5, n),
    )
    labels = rng.integers(-1, n_labels, n)
    _assert_same(cluster_features(X, labels, window=window), _reference(X, labels, window))


@settings(max_examples=40, deadline=None)
@given(n=st.integers(2, 30), seed=st.integers(0, 2**31 - 1), angle=st.floats(-np.pi, np.pi))
def test_row_order_and_a_rigid_motion_do_not_change_the_features(n, seed, angle):
    rng = np.random.default_rng(seed)
    X = _table(x=rng.normal(0, 3, n), y=rng.normal(0, 3, n), v_r=rng.normal(0, 1, n), t=rng.uniform(0, 1, n))
    labels = rng.integers(-1, 3, n)
    table, rows = cluster_features(X, labels, window=0.5, return_rows=True)
    # Rows permuted: the same table, and each detection still points at its segment.
    order = rng.permutation(n)
    permuted, permuted_rows = cluster_features(X.iloc[order], labels[order], window=0.5, return_rows=True)
    _assert_same(permuted, table)
    np.testing.assert_array_equal(permuted_rows, rows[order])
    # Rotated and shifted positions: the same extents (they are measured along the principal axes).
    c, s = np.cos(angle), np.sin(angle)
    moved = X.assign(x=100.0 + c * X["x"] - s * X["y"], y=-50.0 + s * X["x"] + c * X["y"])
    _assert_same(cluster_features(moved, labels, window=0.5), table)


def test_principal_extents_of_a_rotated_rectangle():
    # Corners of a 4 m x 2 m rectangle and its centre, turned by 30 degrees.
    corners = np.array([[-2.0, -1.0], [2.0, -1.0], [2.0, 1.0], [-2.0, 1.0], [0.0, 0.0]])
    a = np.deg2rad(30.0)
    turned = corners @ np.array([[np.cos(a), np.sin(a)], [-np.sin(a), np.cos(a)]])
    table = cluster_features(_table(x=turned[:, 0] + 7.0, y=turned[:, 1] - 3.0), [4] * 5)
    np.testing.assert_allclose(table[["extent_along", "extent_across"]].to_numpy()[0], [4.0, 2.0], atol=1e-12)
    assert table[["sequence", "cluster", "window", "n_detections"]].to_numpy().tolist() == [[0, 4, 0, 5]]


def test_windows_start_at_each_sequences_first_detection_noise_included():
    # Sequence 1 starts at 0.0 s with a noise detection; sequence 2 at 10.2 s.  Frames of 0.5 s.
    X = _table(t=[0.0, 0.3, 0.6, 1.1, 10.2, 10.9], sequence=[1, 1, 1, 1, 2, 2])
    labels = [-1, 0, 0, 0, 0, 0]
    table, rows = cluster_features(X, labels, window=0.5, return_rows=True)
    assert table[["sequence", "cluster", "window", "n_detections"]].to_numpy().tolist() == [
        [1, 0, 0, 1],  # 0.3 s
        [1, 0, 1, 1],  # 0.6 s
        [1, 0, 2, 1],  # 1.1 s
        [2, 0, 0, 1],  # 10.2 s: the same label in another sequence is another segment
        [2, 0, 1, 1],  # 10.9 s
    ]
    assert rows.tolist() == [-1, 0, 1, 2, 3, 4]
    whole = cluster_features(X, labels)
    np.testing.assert_allclose(whole[["sequence", "n_detections", "duration"]], [[1, 3, 0.8], [2, 2, 0.7]])


def test_statistics_by_hand():
    X = _table(
        v_r=[1.0, 2.0, 6.0],
        rcs=[-10.0, 0.0, 4.0],
        range_sc=[10.0, 12.0, 14.0],
        azimuth_sc=[np.pi - 0.1, -np.pi + 0.1, np.pi],  # around the back: the spread must not jump across +-pi
        sensor_yaw=[0.0, 0.0, 0.0],
        sensor_id=[1, 4, 1],
    )
    row = cluster_features(X, [0, 0, 0]).iloc[0]
    assert row["vr_mean"] == 3.0 and row["vr_range"] == 5.0
    assert row["vr_std"] == pytest.approx(np.sqrt(14 / 3))
    assert row["rcs_mean"] == -2.0 and row["rcs_max"] == 4.0
    assert row["range_mean"] == 12.0
    assert row["azimuth_spread"] == pytest.approx(np.sqrt(0.02 / 3))
    assert row["n_sensors"] == 2


def test_velocity_of_a_rigid_object_and_its_residual():
    # Six detections of an object moving at (3, -4) m/s, seen at spread lines of sight: the residual is 0;
    # one detection with 2 m/s of micro-Doppler on top makes it sqrt(4 / 6) (RMS over all detections).
    azimuth = np.linspace(-0.4, 0.4, 6)
    v_r = 3.0 * np.cos(azimuth) - 4.0 * np.sin(azimuth)
    X = _table(v_r=v_r, azimuth_sc=azimuth, sensor_yaw=np.zeros(6))
    row = cluster_features(X, [0] * 6).iloc[0]
    assert row["speed"] == pytest.approx(5.0) and row["speed_residual"] == pytest.approx(0.0, abs=1e-9)
    limb = cluster_features(X.assign(v_r=v_r + np.r_[2.0, np.zeros(5)]), [0] * 6).iloc[0]
    assert limb["speed"] == pytest.approx(5.0) and limb["speed_residual"] == pytest.approx(np.sqrt(4 / 6))
    # Two detections: too few for Eq. 6, the velocity and its residual are unknown.
    two = cluster_features(X.iloc[:2], [0, 0]).iloc[0]
    assert np.isnan(two["speed"]) and np.isnan(two["speed_residual"])


def test_length_and_width_of_a_moving_rectangle():
    # A 4 m x 2 m body (corners and centre) moving at (3, -4) m/s along its long side, its detections 0.08 s
    # apart: the extents of the positions include the 2 m it travels in 0.4 s; length and width are the body's.
    heading, side = np.array([3.0, -4.0]) / 5.0, np.array([4.0, 3.0]) / 5.0
    along, across = np.array([-2.0, 2.0, -2.0, 2.0, 0.0, 0.0]), np.array([-1.0, -1.0, 1.0, 1.0, 0.0, 0.0])
    t = np.linspace(0.0, 0.4, 6)
    position = np.outer(along, heading) + np.outer(across, side) + np.outer(t, [3.0, -4.0]) + [10.0, 20.0]
    azimuth = np.linspace(-0.4, 0.4, 6)
    X = _table(
        x=position[:, 0],
        y=position[:, 1],
        v_r=3.0 * np.cos(azimuth) - 4.0 * np.sin(azimuth),
        t=t,
        azimuth_sc=azimuth,
        sensor_yaw=np.zeros(6),
    )
    row = cluster_features(X, [0] * 6).iloc[0]
    assert row["length"] == pytest.approx(4.0) and row["width"] == pytest.approx(2.0)
    assert row["extent_along"] > 5.0  # the travel is in the plain extents
    # Seen at one instant there is no travel: length and width are the principal extents.
    still = cluster_features(X.assign(t=0.0), [0] * 6).iloc[0]
    assert still["length"] == pytest.approx(still["extent_along"])
    assert still["width"] == pytest.approx(still["extent_across"])
    # Two detections: the velocity is unknown, and so are length and width.
    two = cluster_features(X.iloc[:2], [0, 0]).iloc[0]
    assert np.isnan(two["length"]) and np.isnan(two["width"])


def test_a_feature_without_its_columns_is_left_out():
    X = _table(x=[0.0, 1.0], rcs=[1.0, 2.0])
    assert list(cluster_features(X, [0, 0]).columns[3:]) == [*WORKING, "rcs_mean", "rcs_std", "rcs_max"]
    only_azimuth = _table(x=[0.0, 1.0], azimuth_sc=[0.0, 0.1])  # the line of sight needs sensor_yaw too
    assert list(cluster_features(only_azimuth, [0, 0]).columns[3:]) == WORKING


def test_no_cluster_gives_an_empty_table_with_every_column():
    X = _table(x=[0.0, 1.0], rcs=[1.0, 2.0], sensor_id=[1, 2])
    table, rows = cluster_features(X, [-1, -1], window=0.5, return_rows=True)
    assert len(table) == 0 and list(table.columns) == ["sequence", "cluster", "window", *WORKING, "rcs_mean",
                                                       "rcs_std", "rcs_max", "n_sensors"]  # fmt: skip
    assert rows.tolist() == [-1, -1]


@pytest.mark.parametrize(
    ("X", "labels", "match"),
    [
        (_table(x=[0.0, 1.0]), [0], "one label per row"),
        (_table(x=[0.0, 1.0]), [0.5, 0.0], "labels must be integers"),
        (_table(x=[0.0, 1.0]).drop(columns="t"), [0, 0], r"missing the column\(s\) \['t'\]"),
        (_table(x=[0.0, np.nan]), [0, 0], "'x' contains NaN"),
        (_table(x=[0.0, 1.0]).assign(rcs=["a", "b"]), [0, 0], "'rcs' must be numeric"),
        (_table(x=[0.0, 1.0], range_sc=[-5.0, 1.0]), [0, 0], "range_sc"),
    ],
)
def test_bad_input_names_the_problem(X, labels, match):
    with pytest.raises(ValueError, match=match):
        cluster_features(X, labels)
