"""Tests of the scene simulator: determinism, the RadarScenes formulas, and realism figures."""

import numpy as np
import pandas as pd
import pytest
from sklearn.cluster import DBSCAN
from sklearn.metrics import v_measure_score

from sklearn_radar._schema import DETECTION_COLUMNS, RADARSCENES_MOUNTING, STATIC_LABEL
from sklearn_radar.datasets import make_scenes, scene_statistics
from sklearn_radar.datasets._sensor_model import FOV, MAX_RANGE


@pytest.fixture(scope="module")
def scenes():
    return make_scenes(n_sequences=4, duration=30.0, random_state=7)


def test_same_seed_gives_identical_data_and_other_seeds_differ():
    a = make_scenes(n_sequences=2, duration=3.0, random_state=3)
    b = make_scenes(n_sequences=2, duration=3.0, random_state=3)
    c = make_scenes(n_sequences=2, duration=3.0, random_state=4)
    pd.testing.assert_frame_equal(a.data, b.data)
    pd.testing.assert_frame_equal(a.odometry, b.odometry)
    np.testing.assert_array_equal(a.target, b.target)
    assert len(a.data) != len(c.data) or not a.data.equals(c.data)


def test_table_has_the_schema_and_one_label_per_row(scenes):
    data = scenes.data
    assert list(data.columns) == [c.name for c in DETECTION_COLUMNS]
    for column in DETECTION_COLUMNS:
        if column.dtype != "str":
            assert data[column.name].dtype == np.dtype(column.dtype), column.name
    assert isinstance(data.index, pd.RangeIndex)
    assert len(scenes.target) == len(scenes.groups) == len(data)
    np.testing.assert_array_equal(scenes.groups, data["sequence"])
    assert list(scenes.sequences["name"]) == [f"sequence_{n}" for n in (1, 2, 3, 4)]


def test_rows_are_sorted_and_each_scan_has_one_sensor(scenes):
    data = scenes.data
    key = data["sequence"].to_numpy() * 10**13 + data["timestamp"].to_numpy()
    assert np.all(np.diff(key) >= 0)
    assert (data.groupby(["sequence", "timestamp"])["sensor_id"].nunique() == 1).all()


def test_labels_track_ids_and_uuids_agree(scenes):
    data = scenes.data
    background = data["track_id"] == ""
    np.testing.assert_array_equal(background, data["label_id"] == STATIC_LABEL)
    np.testing.assert_array_equal(background, scenes.target == -1)
    assert data["uuid"].is_unique
    assert (data["uuid"].str.len() == 32).all()


def test_coordinates_follow_the_radarscenes_formulas(scenes):
    d = {
        name: scenes.data[name].to_numpy(dtype=float)
        for name in scenes.data.columns
        if name not in ("uuid", "track_id")
    }
    mount = np.array([[RADARSCENES_MOUNTING[int(s)][f] for f in ("x", "y", "yaw")] for s in d["sensor_id"]])
    np.testing.assert_allclose(mount, np.c_[d["sensor_x"], d["sensor_y"], d["sensor_yaw"]], atol=1e-6)
    angle = d["azimuth_sc"] + mount[:, 2]
    x_cc = mount[:, 0] + d["range_sc"] * np.cos(angle)
    y_cc = mount[:, 1] + d["range_sc"] * np.sin(angle)
    np.testing.assert_allclose(d["x_cc"], x_cc, atol=1e-4)
    np.testing.assert_allclose(d["y_cc"], y_cc, atol=1e-4)
    c, s = np.cos(d["ego_yaw_seq"]), np.sin(d["ego_yaw_seq"])
    np.testing.assert_allclose(d["x_seq"], d["ego_x_seq"] + c * x_cc - s * y_cc, atol=1e-3)
    np.testing.assert_allclose(d["y_seq"], d["ego_y_seq"] + s * x_cc + c * y_cc, atol=1e-3)
    # vr = vr_compensated - v_s . u, v_s = (vx - yaw_rate * y_s, yaw_rate * x_s)
    v_sx = d["ego_vx"] - d["ego_yaw_rate"] * mount[:, 1]
    v_sy = d["ego_yaw_rate"] * mount[:, 0]
    np.testing.assert_allclose(d["vr"], d["vr_compensated"] - (v_sx * np.cos(angle) + v_sy * np.sin(angle)), atol=1e-4)


def test_ego_columns_come_from_the_odometry_row_nearest_in_time(scenes):
    for number, rows in scenes.data.groupby("sequence"):
        odo = scenes.odometry[scenes.odometry["sequence"] == number]
        scans = rows.drop_duplicates("timestamp")
        gap = np.abs(scans["timestamp"].to_numpy()[:, None] - odo["timestamp"].to_numpy()[None, :])
        nearest = odo.iloc[np.argmin(gap, axis=1)]
        for odo_name, det_name in (("x_seq", "ego_x_seq"), ("yaw_seq", "ego_yaw_seq"), ("vx", "ego_vx")):
            np.testing.assert_array_equal(scans[det_name].to_numpy(), nearest[odo_name].to_numpy())


def test_static_targets_ahead_approach_while_the_ego_drives(scenes):
    data = scenes.data
    # Static scatterers only: ghosts and some clutter are labelled static but carry a Doppler of their own.
    ahead = (
        (data["label_id"] == STATIC_LABEL)
        & (data["vr_compensated"].abs() < 0.5)
        & data["sensor_id"].isin([2, 3])
        & (data["ego_vx"] > 5.0)
        & (data["x_cc"] > 20.0)
        & (data["y_cc"].abs() < 5.0)
    )
    assert ahead.sum() > 100
    # Negative radial velocity means approaching (RadarScenes issue #16).
    assert (data.loc[ahead, "vr"] < 0).mean() > 0.99
    assert data.loc[data["label_id"] == STATIC_LABEL, "vr_compensated"].abs().median() < 0.1


def test_odometry_is_50_hz_and_covers_the_radar_data(scenes):
    for number, odo in scenes.odometry.groupby("sequence"):
        step = np.diff(odo["timestamp"].to_numpy()) * 1e-6
        assert 0.019 < np.median(step) < 0.021
        radar = scenes.data.loc[scenes.data["sequence"] == number, "timestamp"]
        assert odo["timestamp"].min() <= radar.min() and odo["timestamp"].max() >= radar.max()


def test_four_unsynchronised_sensors_with_jittered_60_ms_cycles(scenes):
    seq = scenes.data[scenes.data["sequence"] == 1].drop_duplicates("timestamp")
    assert sorted(seq["sensor_id"].unique()) == [1, 2, 3, 4]
    first_scans = []
    for _, scans in seq.groupby("sensor_id"):
        cycle = np.diff(scans["timestamp"].to_numpy()) * 1e-6
        assert 0.055 < np.median(cycle) < 0.065
        assert 0.001 < np.std(cycle) < 0.01
        first_scans.append(scans["timestamp"].min())
    assert len(set(first_scans)) == 4


def test_detections_stay_in_the_field_of_view_and_range(scenes):
    assert scenes.data["azimuth_sc"].abs().max() < FOV + np.deg2rad(4.0)
    assert scenes.data["range_sc"].max() < MAX_RANGE + 10.0
    assert scenes.data["range_sc"].min() > 0


def test_most_detections_are_static_background():
    # The share varies with the number of road users drawn per sequence (3-12).
    shares = [
        scene_statistics(make_scenes(n_sequences=4, duration=20.0, random_state=seed))[0]["static_share"]
        for seed in range(3)
    ]
    assert 0.72 <= np.mean(shares) <= 0.88, shares
    assert all(0.65 <= share <= 0.95 for share in shares), shares


def test_road_users_of_every_class_appear(scenes):
    classes = set(scenes.data.loc[scenes.target >= 0, "label_id"])
    assert {0, 5, 7, 8} <= classes  # car, bicycle, pedestrian, pedestrian group
    assert classes & {2, 3}  # truck or bus


def test_object_count_per_sequence_respects_n_objects():
    # The easy preset: the realistic one's dense traffic adds road users beyond the base n_objects.
    scenes = make_scenes(n_sequences=6, duration=15.0, random_state=1, n_objects=(3, 5), difficulty="easy")
    objects = scenes.data.loc[scenes.target >= 0].groupby("sequence")["track_id"].agg(lambda t: t.str[:16].nunique())
    assert objects.max() <= 5
    assert objects.mean() >= 2.5


def test_detections_per_object_fall_with_range_and_grow_with_size(scenes):
    _, table = scene_statistics(scenes)
    near, far = table.columns[1], table.columns[2]  # (10, 25] m and (25, 50] m
    for label in ("CAR", "PEDESTRIAN"):
        assert table.loc[label, near] > table.loc[label, far]
    large = table.loc[table.index.isin(["TRUCK", "BUS"]), near].max()
    assert large > table.loc["CAR", near] > table.loc["PEDESTRIAN", near]


def test_pedestrians_show_micro_doppler_spread(scenes):
    objects = scenes.data[scenes.target >= 0].assign(instance=scenes.target[scenes.target >= 0])
    spread = objects.groupby(["instance", "timestamp"]).agg(
        std=("vr_compensated", "std"), n=("vr", "size"), label=("label_id", "first")
    )
    spread = spread[spread["n"] >= 2].groupby("label")["std"].median()
    assert spread[7] > 2 * spread[0]


def test_ego_drives_curves_changes_speed_and_stops(scenes):
    for _, odo in scenes.odometry.groupby("sequence"):
        t = odo["timestamp"].to_numpy() * 1e-6
        standing = odo["vx"].to_numpy() < 0.05
        assert np.sum(np.diff(t)[standing[:-1]]) >= 2.0
        assert odo["vx"].max() - odo["vx"].min() > 3.0
        assert odo["yaw_rate"].abs().max() > 0.02


def test_no_track_has_a_gap_longer_than_half_a_second(scenes):
    objects = scenes.data[scenes.target >= 0]
    for _, rows in objects.groupby("track_id"):
        assert np.diff(np.unique(rows["timestamp"].to_numpy())).max(initial=0) <= 500_000


def test_plain_dbscan_scores_well_between_0_and_1(scenes):
    data = scenes.data
    labels = np.full(len(data), -1)
    for number in np.unique(scenes.groups):
        rows = np.flatnonzero(scenes.groups == number)
        X = np.c_[
            data["x_seq"].to_numpy()[rows],
            data["y_seq"].to_numpy()[rows],
            data["vr_compensated"].to_numpy()[rows],
            data["timestamp"].to_numpy()[rows] * 4e-6,
        ]
        found = DBSCAN(eps=1.0, min_samples=4).fit_predict(X)
        labels[rows] = np.where(found >= 0, found + 100_000 * number, -1)
    score = v_measure_score(scenes.target, labels)
    assert 0.2 < score < 0.85, score


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(n_sequences=0), "n_sequences"),
        (dict(duration=0.1), "duration"),
        (dict(n_objects=(5, 2)), "n_objects"),
        (dict(static_density=0.0), "static_density"),
    ],
)
def test_bad_parameters_raise_a_clear_value_error(kwargs, match):
    with pytest.raises(ValueError, match=match):
        make_scenes(**kwargs)
