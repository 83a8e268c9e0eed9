"""Tests of the detection-table schema helpers, on hand-computed cases."""

import numpy as np
import pandas as pd
import pytest

from sklearn_radar._schema import (
    DETECTION_COLUMNS,
    RADAR_DATA_COLUMNS,
    RADARSCENES_MOUNTING,
    attach_context,
    check_columns,
    describe_columns,
    instance_target,
    make_frame,
    nearest_odometry_index,
)


def test_instance_target_numbers_objects_by_first_appearance():
    assert instance_target(["b", "", "a", "b", ""]).tolist() == [0, -1, 1, 0, -1]


def test_instance_target_separates_equal_track_ids_of_different_sequences():
    target = instance_target(["a", "a", "", "a"], sequence=[1, 1, 2, 2])
    assert target.tolist() == [0, 0, -1, 1]


def test_instance_target_of_only_background():
    assert instance_target(["", ""]).tolist() == [-1, -1]


@pytest.mark.parametrize("shape", [(4, 23), (4, 1)])
def test_instance_target_of_a_table_says_what_it_expects(shape):
    # Issue 46: instance_target(df) returned an (n, 23) array.
    table = pd.DataFrame(np.full(shape, "a", dtype=object), columns=[f"c{k}" for k in range(shape[1])])
    with pytest.raises(
        ValueError,
        match=rf"instance_target expects track_id as one id per detection \(1-D, e\.g\. data\['track_id'\] .*got a "
        rf"DataFrame of shape \({shape[0]}, {shape[1]}\); for the table use instance_target\(data\['track_id'\], "
        r"data\['sequence'\]\)",
    ):
        instance_target(table)
    with pytest.raises(ValueError, match=r"got a ndarray of shape \(2, 2\)"):
        instance_target(np.array([["a", ""], ["b", "a"]]))
    assert instance_target(table["c0"]).tolist() == [0, 0, 0, 0]


def test_make_frame_refuses_integers_a_float_type_has_rounded():
    rows = _radar_rows()
    rows["timestamp"] = np.array([1.58e11, 1.58e11 + 16384, 1.58e11 + 32768], dtype=np.float32)
    with pytest.raises(ValueError, match=r"detections: column 'timestamp' is float32, .* steps by 16384 µs"):
        make_frame(rows, RADAR_DATA_COLUMNS, table="detections")
    rows["timestamp"] = np.array([0.0, 60_000.0, 120_000.0], dtype=np.float32)  # exact below 2**24
    assert make_frame(rows, RADAR_DATA_COLUMNS, table="detections")["timestamp"].tolist() == [0, 60_000, 120_000]


def test_nearest_odometry_index_prefers_the_earlier_row_on_ties():
    index = nearest_odometry_index([0, 5, 10, 14, 15, 16, 100, -3], [0, 10, 20])
    assert index.tolist() == [0, 0, 1, 1, 1, 2, 2, 0]
    assert nearest_odometry_index([3, 9], [7]).tolist() == [0, 0]


def _radar_rows(n=3, sensor_id=(1, 2, 4)):
    return {
        "timestamp": np.arange(n) * 1000,
        "sensor_id": np.array(sensor_id[:n]),
        **{c.name: np.linspace(0, 1, n) for c in RADAR_DATA_COLUMNS if c.dtype == "float32"},
        "uuid": np.array([f"{i:032x}" for i in range(n)]),
        "track_id": np.array(["", "t1", ""]),
        "label_id": np.array([11, 0, 11]),
    }


def test_make_frame_casts_to_the_schema_and_decodes_bytes():
    rows = _radar_rows()
    rows["uuid"] = np.array([u.encode() for u in rows["uuid"]], dtype="S32")
    frame = make_frame(rows, RADAR_DATA_COLUMNS, table="t")
    assert list(frame.columns) == [c.name for c in RADAR_DATA_COLUMNS]
    assert frame["range_sc"].dtype == np.float32 and frame["timestamp"].dtype == np.int64
    assert frame["uuid"].iloc[1] == f"{1:032x}"


@pytest.mark.parametrize(
    "change, match",
    [
        (lambda r: r.pop("rcs"), r"radar_data\.h5: missing column\(s\) \['rcs'\]"),
        (lambda r: r.__setitem__("range_sc", np.array(["a", "b", "c"])), "'range_sc' must be numeric"),
        (lambda r: r.__setitem__("sensor_id", np.array([1.0, 2.5, 3.0])), "'sensor_id' must hold integers"),
        (lambda r: r.__setitem__("track_id", np.arange(3)), "'track_id' must hold strings"),
    ],
)
def test_make_frame_names_the_table_and_the_bad_column(change, match):
    rows = _radar_rows()
    change(rows)
    with pytest.raises(ValueError, match=match):
        make_frame(rows, RADAR_DATA_COLUMNS, table="radar_data.h5")


def test_attach_context_copies_pose_and_mounting_per_row():
    radar = make_frame(_radar_rows(), RADAR_DATA_COLUMNS, table="t")
    odometry = pd.DataFrame(
        {"x_seq": [1.0, 2.0], "y_seq": [3.0, 4.0], "yaw_seq": [0.1, 0.2], "vx": [5.0, 6.0], "yaw_rate": [0.0, 0.5]}
    )
    data = attach_context(radar, 7, np.array([1, 0, 1]), odometry, RADARSCENES_MOUNTING)
    assert list(data.columns) == [c.name for c in DETECTION_COLUMNS]
    assert data["sequence"].tolist() == [7, 7, 7]
    np.testing.assert_allclose(data["ego_vx"], [6.0, 5.0, 6.0])
    np.testing.assert_allclose(data["sensor_x"], [3.663, 3.86, 3.663], rtol=1e-6)
    np.testing.assert_allclose(data["sensor_yaw"], [-1.48418552, -0.436185662, 1.484], rtol=1e-6)


def test_attach_context_rejects_a_sensor_without_mounting():
    radar = make_frame(_radar_rows(sensor_id=(1, 2, 9)), RADAR_DATA_COLUMNS, table="t")
    odometry = pd.DataFrame({k: [0.0] for k in ("x_seq", "y_seq", "yaw_seq", "vx", "yaw_rate")})
    with pytest.raises(ValueError, match=r"sensor_id \[9\] has no mounting"):
        attach_context(radar, 1, np.zeros(3, int), odometry, RADARSCENES_MOUNTING)


def test_check_columns_names_what_is_missing():
    with pytest.raises(ValueError, match=r"missing the column\(s\) \['vr'\]"):
        check_columns(pd.DataFrame({"x_cc": [1.0]}), ["x_cc", "vr"])
    with pytest.raises(ValueError, match="must be a pandas DataFrame"):
        check_columns(np.zeros((2, 2)), ["x_cc"])


def test_describe_columns_lists_every_column_with_its_unit():
    text = describe_columns()
    for column in DETECTION_COLUMNS:
        assert column.name in text
    assert "µs" in text and "rad/s" in text
