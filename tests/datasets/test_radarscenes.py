"""Tests of the RadarScenes reader and writer, against the devkit (radar_scenes 1.0.4)."""

import json
import shutil

import h5py
import numpy as np
import pandas as pd
import pytest
from radar_scenes.coordinate_transformation import transform_detections_sequence_to_car
from radar_scenes.sequence import Sequence, get_training_sequences
from sklearn.utils import Bunch

from sklearn_radar._schema import (
    ODOMETRY_COLUMNS,
    RADAR_DATA_COLUMNS,
    RADARSCENES_MOUNTING,
    attach_context,
    instance_target,
    make_frame,
    nearest_odometry_index,
)
from sklearn_radar.datasets import _radarscenes_format, _radarscenes_writer, make_scenes
from sklearn_radar.datasets._radarscenes_reader import load_radarscenes
from sklearn_radar.datasets._radarscenes_writer import write_radarscenes

SEQUENCES = {2: "train", 5: "validation"}
ODOMETRY_PERIOD = 20_000  # µs, 50 Hz
SCAN_PERIOD = 60_000  # µs


# --------------------------------------------------------------------------
# A small consistent bunch, built by hand
# --------------------------------------------------------------------------


def _ego_odometry(number, t0, n_rows):
    """Constant speed and yaw rate, poses integrated exactly, cast to float32."""
    timestamp = t0 + ODOMETRY_PERIOD * np.arange(n_rows, dtype=np.int64)
    t = (timestamp - t0) / 1e6
    vx, yaw_rate, yaw0 = 8.0 + number, 0.2 * (-1) ** number, 0.3 * number
    yaw = yaw0 + yaw_rate * t
    table = {
        "sequence": np.full(n_rows, number),
        "timestamp": timestamp,
        "x_seq": 100.0 * number + vx / yaw_rate * (np.sin(yaw) - np.sin(yaw0)),
        "y_seq": -50.0 - vx / yaw_rate * (np.cos(yaw) - np.cos(yaw0)),
        "yaw_seq": yaw,
        "vx": np.full(n_rows, vx),
        "yaw_rate": np.full(n_rows, yaw_rate),
    }
    return make_frame(table, ODOMETRY_COLUMNS, table="test odometry")


def _scan_schedule(t0, rng):
    """(timestamp, sensor_id, n_detections) of 3 scans per sensor, unsynchronised, in time order."""
    scans = [
        (t0 + 5_000 + SCAN_PERIOD * j + 13_001 * sensor, sensor, int(rng.integers(2, 5)))
        for sensor in RADARSCENES_MOUNTING
        for j in range(3)
    ]
    return sorted(scans)


def _radar_data(number, scans, odometry, rng):
    """The 14 radar_data fields of one sequence, coordinates from the format's formulas."""
    n = sum(count for _, _, count in scans)
    timestamp = np.repeat([ts for ts, _, _ in scans], [c for _, _, c in scans])
    sensor_id = np.repeat([s for _, s, _ in scans], [c for _, _, c in scans])
    ego_row = nearest_odometry_index(timestamp, odometry["timestamp"])
    ego_fields = ("x_seq", "y_seq", "yaw_seq", "vx", "yaw_rate")
    ego = {name: odometry[name].to_numpy(np.float64)[ego_row] for name in ego_fields}
    mount = {key: np.array([RADARSCENES_MOUNTING[s][key] for s in sensor_id]) for key in ("x", "y", "yaw")}
    range_sc = rng.uniform(2.0, 60.0, n).astype(np.float32).astype(np.float64)
    azimuth_sc = rng.uniform(-1.0, 1.0, n).astype(np.float32).astype(np.float64)
    angle = azimuth_sc + mount["yaw"]
    x_cc = mount["x"] + range_sc * np.cos(angle)
    y_cc = mount["y"] + range_sc * np.sin(angle)
    c, s = np.cos(ego["yaw_seq"]), np.sin(ego["yaw_seq"])
    vr_compensated = rng.normal(0.0, 3.0, n)
    sensor_velocity = (ego["vx"] - ego["yaw_rate"] * mount["y"], ego["yaw_rate"] * mount["x"])
    is_object = rng.random(n) < 0.4
    return {
        "timestamp": timestamp,
        "sensor_id": sensor_id,
        "range_sc": range_sc,
        "azimuth_sc": azimuth_sc,
        "rcs": rng.normal(0.0, 10.0, n),
        "vr": vr_compensated - sensor_velocity[0] * np.cos(angle) - sensor_velocity[1] * np.sin(angle),
        "vr_compensated": vr_compensated,
        "x_cc": x_cc,
        "y_cc": y_cc,
        "x_seq": ego["x_seq"] + c * x_cc - s * y_cc,
        "y_seq": ego["y_seq"] + s * x_cc + c * y_cc,
        "uuid": np.array([f"{number:04d}{i:028x}" for i in range(n)]),
        "track_id": np.where(is_object, np.array([f"track_{k % 3}" for k in range(n)]), ""),
        "label_id": np.where(is_object, 0, 11),
    }


def make_test_bunch(seed=0):
    """A consistent two-sequence bunch with four sensors, 3 scans each."""
    rng = np.random.default_rng(seed)
    detections, odometries = [], []
    for number in SEQUENCES:
        t0 = 156_862_647_501 + 10**9 * number
        odometry = _ego_odometry(number, t0, n_rows=15)
        scans = _scan_schedule(t0, rng)
        radar = make_frame(_radar_data(number, scans, odometry, rng), RADAR_DATA_COLUMNS, "test radar")
        odometry_index = nearest_odometry_index(radar["timestamp"], odometry["timestamp"])
        detections.append(attach_context(radar, number, odometry_index, odometry, RADARSCENES_MOUNTING))
        odometries.append(odometry)
    data = pd.concat(detections, ignore_index=True)
    return Bunch(
        data=data,
        target=instance_target(data["track_id"], data["sequence"]),
        groups=data["sequence"].to_numpy(np.int64),
        odometry=pd.concat(odometries, ignore_index=True),
        sensors=pd.DataFrame.from_dict(RADARSCENES_MOUNTING, orient="index")
        .rename_axis("sensor_id")
        .sort_index()[["x", "y", "yaw"]]
        .astype(np.float64),
        sequences=pd.DataFrame(
            {
                "sequence": np.array(list(SEQUENCES), dtype=np.int64),
                "name": pd.array([f"sequence_{n}" for n in SEQUENCES], dtype="str"),
                "category": pd.array(list(SEQUENCES.values()), dtype="str"),
            }
        ),
        DESCR="test bunch",
    )


def assert_bunch_equal(actual, expected):
    for key in ("data", "odometry", "sequences", "sensors"):
        pd.testing.assert_frame_equal(actual[key], expected[key])
    np.testing.assert_array_equal(actual.target, expected.target)
    np.testing.assert_array_equal(actual.groups, expected.groups)
    assert actual.target.dtype == np.int64 and actual.groups.dtype == np.int64


def subset(bunch, numbers):
    keep = bunch.data["sequence"].isin(numbers).to_numpy()
    data = bunch.data[keep].reset_index(drop=True)
    return Bunch(
        data=data,
        target=instance_target(data["track_id"], data["sequence"]),
        groups=data["sequence"].to_numpy(np.int64),
        odometry=bunch.odometry[bunch.odometry["sequence"].isin(numbers)].reset_index(drop=True),
        sensors=bunch.sensors,
        sequences=bunch.sequences[bunch.sequences["sequence"].isin(numbers)].reset_index(drop=True),
    )


# --------------------------------------------------------------------------
# File surgery helpers
# --------------------------------------------------------------------------


@pytest.fixture
def written(tmp_path):
    """A written copy of the test bunch: (data folder, bunch)."""
    bunch = make_test_bunch()
    return write_radarscenes(bunch, tmp_path / "data"), bunch


def read_h5(file):
    with h5py.File(file, "r") as h5:
        return h5["radar_data"][()], h5["odometry"][()]


def rewrite_h5(file, **datasets):
    with h5py.File(file, "w") as h5:
        for name, array in datasets.items():
            h5.create_dataset(name, data=array)


def retype(array, changes, values=None):
    """Copy of a structured array with some field dtypes changed (None drops the field)."""
    fields = [(name, changes.get(name, array.dtype[name])) for name in array.dtype.names]
    fields = [(name, dtype) for name, dtype in fields if dtype is not None]
    result = np.empty(len(array), dtype=fields)
    for name, _ in fields:
        result[name] = (values or {}).get(name, array[name])
    return result


def edit_json(file, edit):
    content = json.loads(file.read_text())
    edit(content)
    file.write_text(json.dumps(content))


def scene_items(content):
    return sorted(content["scenes"].items(), key=lambda item: item[1]["radar_indices"][0])


# --------------------------------------------------------------------------
# Round trip and devkit
# --------------------------------------------------------------------------


def test_round_trip_gives_the_same_bunch(written):
    root, bunch = written
    loaded = load_radarscenes(root)
    assert_bunch_equal(loaded, bunch)
    assert isinstance(loaded.DESCR, str) and loaded.DESCR
    assert isinstance(loaded.data.index, pd.RangeIndex)


def test_written_layout_and_json_keys(written):
    root, _ = written
    sensors = json.loads((root / "sensors.json").read_text())
    assert sensors["radar_1"] == {"id": 1, **RADARSCENES_MOUNTING[1]}
    sequences = json.loads((root / "sequences.json").read_text())["sequences"]
    assert sequences["sequence_5"]["category"] == "validation"
    assert sequences["sequence_2"]["sensors"] == ["radar_1", "radar_2", "radar_3", "radar_4"]
    assert sequences["sequence_2"]["scenes"] == 12
    scenes = json.loads((root / "sequence_2" / "scenes.json").read_text())
    assert list(scenes) == ["sequence_name", "category", "first_timestamp", "last_timestamp", "scenes"]
    first = scenes["scenes"][str(scenes["first_timestamp"])]
    assert list(first) == [
        "sensor_id",
        "prev_timestamp",
        "next_timestamp",
        "prev_timestamp_same_sensor",
        "next_timestamp_same_sensor",
        "odometry_timestamp",
        "odometry_index",
        "image_name",
        "radar_indices",
    ]
    assert first["prev_timestamp"] is None and first["radar_indices"][0] == 0
    radar_data, odometry = read_h5(root / "sequence_2" / "radar_data.h5")
    assert radar_data.dtype == _radarscenes_format.RADAR_DATA_H5_DTYPE
    assert odometry.dtype == _radarscenes_format.ODOMETRY_H5_DTYPE
    assert radar_data.dtype.names == tuple(c.name for c in RADAR_DATA_COLUMNS)


def check_devkit_reads(root, bunch):
    """Open every written sequence with the devkit and compare with the bunch."""
    for number in bunch.sequences["sequence"]:
        seq_data = bunch.data[bunch.data["sequence"] == number]
        scan_sensor = seq_data.groupby("timestamp")["sensor_id"].first()
        sequence = Sequence.from_json(str(root / f"sequence_{number}" / "scenes.json"))
        file_radar, _ = read_h5(root / f"sequence_{number}" / "radar_data.h5")
        assert len(sequence) == len(scan_sensor)
        scenes = list(sequence.scenes())
        assert [scene.timestamp for scene in scenes] == scan_sensor.index.tolist()
        np.testing.assert_array_equal(np.concatenate([scene.radar_data for scene in scenes]), file_radar)
        for sensor in np.unique(scan_sensor):
            own = list(sequence.scenes(sensor_id=int(sensor)))
            assert [scene.timestamp for scene in own] == scan_sensor.index[scan_sensor == sensor].tolist()
        for scene in scenes:
            radar = scene.radar_data
            x_cc, y_cc = transform_detections_sequence_to_car(radar["x_seq"], radar["y_seq"], scene.odometry_data)
            np.testing.assert_allclose(x_cc, radar["x_cc"], atol=1e-3, rtol=0)
            np.testing.assert_allclose(y_cc, radar["y_cc"], atol=1e-3, rtol=0)
    train = bunch.sequences.loc[bunch.sequences["category"] == "train", "name"].tolist()
    assert sorted(get_training_sequences(str(root / "sequences.json"))) == sorted(train)


def test_devkit_opens_what_we_write(written):
    check_devkit_reads(*written)


def test_load_subset_by_name_and_by_int(written):
    root, bunch = written
    expected = subset(bunch, [5])
    for selection in (["sequence_5"], [5], [np.int64(5)]):
        assert_bunch_equal(load_radarscenes(root, sequences=selection), expected)
    assert_bunch_equal(load_radarscenes(root, sequences=[5, "sequence_2"]), bunch)


def test_load_via_parent_folder(tmp_path):
    bunch = make_test_bunch()
    write_radarscenes(bunch, tmp_path / "RadarScenes" / "data")
    assert_bunch_equal(load_radarscenes(str(tmp_path / "RadarScenes")), bunch)


def test_round_trip_of_a_subset_bunch(tmp_path):
    expected = subset(make_test_bunch(), [2])
    write_radarscenes(expected, tmp_path / "data")
    assert_bunch_equal(load_radarscenes(tmp_path / "data"), expected)


def test_round_trip_of_a_sequence_without_detections(tmp_path):
    bunch = make_test_bunch()
    keep = (bunch.data["sequence"] == 2).to_numpy()
    bunch.data = bunch.data[keep].reset_index(drop=True)
    bunch.target, bunch.groups = bunch.target[keep], bunch.groups[keep]
    root = write_radarscenes(bunch, tmp_path / "data")
    assert_bunch_equal(load_radarscenes(root), bunch)
    scenes = json.loads((root / "sequence_5" / "scenes.json").read_text())
    assert scenes["scenes"] == {} and scenes["first_timestamp"] is None


def test_loader_takes_ego_row_from_scenes_json(written):
    root, _ = written
    scenes_file = root / "sequence_2" / "scenes.json"
    key, scene = scene_items(json.loads(scenes_file.read_text()))[0]
    edit_json(scenes_file, lambda content: content["scenes"][key].update(odometry_index=7))
    loaded = load_radarscenes(root, sequences=[2])
    start, end = scene["radar_indices"]
    assert (loaded.data["ego_x_seq"].iloc[start:end] == loaded.odometry["x_seq"].iloc[7]).all()


def test_load_accepts_other_widths(written):
    root, bunch = written
    file = root / "sequence_5" / "radar_data.h5"
    radar_data, odometry = read_h5(file)
    wide_radar = retype(
        radar_data,
        {
            "timestamp": "<i8",
            "sensor_id": "<i4",
            "label_id": "<f8",
            "range_sc": "<f8",
            "uuid": "S40",
            "track_id": "S33",
        },
    )
    wide_odometry = retype(odometry, {"timestamp": "<f8", "x_seq": "<f8"})
    rewrite_h5(file, radar_data=wide_radar, odometry=wide_odometry)
    assert_bunch_equal(load_radarscenes(root), bunch)


# --------------------------------------------------------------------------
# Reader errors
# --------------------------------------------------------------------------


def test_load_missing_folder(tmp_path):
    with pytest.raises(FileNotFoundError, match="nowhere"):
        load_radarscenes(tmp_path / "nowhere")


@pytest.mark.parametrize(
    "name", ["sensors.json", "sequences.json", "sequence_2/scenes.json", "sequence_5/radar_data.h5"]
)
def test_load_missing_file(written, name):
    root, _ = written
    (root / name).unlink()
    with pytest.raises(FileNotFoundError, match=name):
        load_radarscenes(root)


def test_load_missing_sequence_folder(written):
    root, _ = written
    shutil.rmtree(root / "sequence_5")
    with pytest.raises(FileNotFoundError, match="sequence_5"):
        load_radarscenes(root)
    load_radarscenes(root, sequences=[2])


@pytest.mark.parametrize("name", ["sensors.json", "sequences.json", "sequence_2/scenes.json"])
def test_load_malformed_json(written, name):
    root, _ = written
    (root / name).write_text('{"sequences": {')
    with pytest.raises(ValueError, match=f"{name}.*malformed JSON"):
        load_radarscenes(root)


def test_load_truncated_h5(written):
    root, _ = written
    file = root / "sequence_2" / "radar_data.h5"
    file.write_bytes(file.read_bytes()[: file.stat().st_size // 2])
    with pytest.raises(ValueError, match=r"sequence_2/radar_data\.h5"):
        load_radarscenes(root)


def test_load_non_hdf5_file(written):
    root, _ = written
    (root / "sequence_2" / "radar_data.h5").write_text("timestamp,sensor_id\n1,2\n")
    with pytest.raises(ValueError, match=r"sequence_2/radar_data\.h5.*HDF5"):
        load_radarscenes(root)


@pytest.mark.parametrize("missing", ["radar_data", "odometry"])
def test_load_foreign_h5(written, missing):
    root, _ = written
    file = root / "sequence_2" / "radar_data.h5"
    arrays = dict(zip(["radar_data", "odometry"], read_h5(file), strict=True))
    del arrays[missing]
    rewrite_h5(file, images=np.zeros(3), **arrays)
    with pytest.raises(ValueError, match=f"radar_data.h5.*{missing}"):
        load_radarscenes(root)


def test_load_dataset_that_is_not_compound(written):
    root, _ = written
    file = root / "sequence_2" / "radar_data.h5"
    rewrite_h5(file, radar_data=np.zeros((4, 14)), odometry=read_h5(file)[1])
    with pytest.raises(ValueError, match=r"radar_data\.h5.*radar_data.*compound"):
        load_radarscenes(root)


@pytest.mark.parametrize(
    "dataset, field", [("radar_data", "rcs"), ("radar_data", "track_id"), ("odometry", "yaw_rate")]
)
def test_load_missing_field(written, dataset, field):
    root, _ = written
    file = root / "sequence_2" / "radar_data.h5"
    arrays = dict(zip(["radar_data", "odometry"], read_h5(file), strict=True))
    arrays[dataset] = retype(arrays[dataset], {field: None})
    rewrite_h5(file, **arrays)
    with pytest.raises(ValueError, match=f"radar_data.h5 \\[{dataset}\\].*{field}"):
        load_radarscenes(root)


def test_load_string_where_float_belongs(written):
    root, _ = written
    file = root / "sequence_2" / "radar_data.h5"
    radar_data, odometry = read_h5(file)
    as_text = np.char.encode(radar_data["range_sc"].astype("U12"), "ascii")
    radar_data = retype(radar_data, {"range_sc": "S12"}, {"range_sc": as_text})
    rewrite_h5(file, radar_data=radar_data, odometry=odometry)
    with pytest.raises(ValueError, match=r"radar_data\.h5.*range_sc"):
        load_radarscenes(root)


def test_load_float_with_fraction_where_int_belongs(written):
    root, _ = written
    file = root / "sequence_2" / "radar_data.h5"
    radar_data, odometry = read_h5(file)
    fractional = radar_data["sensor_id"] + 0.5
    radar_data = retype(radar_data, {"sensor_id": "<f8"}, {"sensor_id": fractional})
    rewrite_h5(file, radar_data=radar_data, odometry=odometry)
    with pytest.raises(ValueError, match=r"radar_data\.h5.*sensor_id.*integers"):
        load_radarscenes(root)


def test_load_number_where_string_belongs(written):
    root, _ = written
    file = root / "sequence_2" / "radar_data.h5"
    radar_data, odometry = read_h5(file)
    numbers = np.arange(len(radar_data))
    rewrite_h5(file, radar_data=retype(radar_data, {"uuid": "<i8"}, {"uuid": numbers}), odometry=odometry)
    with pytest.raises(ValueError, match=r"radar_data\.h5.*uuid"):
        load_radarscenes(root)


def test_load_non_ascii_bytes(written):
    root, _ = written
    file = root / "sequence_2" / "radar_data.h5"
    radar_data, odometry = read_h5(file)
    radar_data["track_id"][0] = b"\xff\xfe"
    rewrite_h5(file, radar_data=radar_data, odometry=odometry)
    with pytest.raises(ValueError, match=r"radar_data\.h5.*track_id.*ASCII"):
        load_radarscenes(root)


@pytest.mark.parametrize("dataset", ["radar_data", "odometry"])
def test_load_unsorted_timestamps(written, dataset):
    root, _ = written
    file = root / "sequence_2" / "radar_data.h5"
    arrays = dict(zip(["radar_data", "odometry"], read_h5(file), strict=True))
    arrays[dataset] = arrays[dataset][::-1].copy()
    rewrite_h5(file, **arrays)
    with pytest.raises(ValueError, match=f"radar_data.h5 \\[{dataset}\\].*timestamp.*sorted"):
        load_radarscenes(root)


def _indices_out_of_range(content):
    scene_items(content)[-1][1]["radar_indices"][1] += 5


def _indices_with_gap(content):
    del content["scenes"][scene_items(content)[1][0]]


def _indices_overlapping(content):
    scene_items(content)[1][1]["radar_indices"][0] -= 1


def _sensor_mismatch(content):
    scene = scene_items(content)[0][1]
    scene["sensor_id"] = scene["sensor_id"] % 4 + 1


def _odometry_index_too_large(content):
    scene_items(content)[0][1]["odometry_index"] = 10**6


def _odometry_index_negative(content):
    scene_items(content)[2][1]["odometry_index"] = -1


def _odometry_index_as_text(content):
    scene_items(content)[0][1]["odometry_index"] = "3"


def _scene_without_radar_indices(content):
    del scene_items(content)[0][1]["radar_indices"]


def _scene_key_not_a_timestamp(content):
    key, _ = scene_items(content)[0]
    content["scenes"]["first"] = content["scenes"].pop(key)


def _scene_timestamp_mismatch(content):
    key, _ = scene_items(content)[0]
    content["scenes"][str(int(key) + 1)] = content["scenes"].pop(key)


@pytest.mark.parametrize(
    "edit, field",
    [
        (_indices_out_of_range, "radar_indices"),
        (_indices_with_gap, "radar_indices"),
        (_indices_overlapping, "radar_indices"),
        (_sensor_mismatch, "sensor_id"),
        (_odometry_index_too_large, "odometry_index"),
        (_odometry_index_negative, "odometry_index"),
        (_odometry_index_as_text, "odometry_index"),
        (_scene_without_radar_indices, "radar_indices"),
        (_scene_key_not_a_timestamp, "first"),
        (_scene_timestamp_mismatch, "timestamp"),
    ],
)
def test_load_scenes_json_inconsistent_with_radar_data(written, edit, field):
    root, _ = written
    edit_json(root / "sequence_5" / "scenes.json", edit)
    with pytest.raises(ValueError, match=f"sequence_5/scenes.json.*{field}"):
        load_radarscenes(root)


def test_load_sensors_json_missing_field(written):
    root, _ = written
    edit_json(root / "sensors.json", lambda content: content["radar_2"].pop("yaw"))
    with pytest.raises(ValueError, match=r"sensors\.json.*radar_2.*yaw"):
        load_radarscenes(root)


def test_load_sensor_without_mounting(written):
    root, _ = written
    edit_json(root / "sensors.json", lambda content: content.pop("radar_3"))
    with pytest.raises(ValueError, match=r"radar_data\.h5.*sensor_id.*sensors\.json"):
        load_radarscenes(root)


def test_load_sequences_json_bad_category(written):
    root, _ = written

    def set_bad_category(content):
        content["sequences"]["sequence_2"]["category"] = "test"

    edit_json(root / "sequences.json", set_bad_category)
    with pytest.raises(ValueError, match=r"sequences\.json.*category"):
        load_radarscenes(root)


def test_load_unknown_sequence(written):
    root, _ = written
    with pytest.raises(ValueError, match=r"sequences\.json.*sequence_9"):
        load_radarscenes(root, sequences=["sequence_9"])
    with pytest.raises(ValueError, match="seq_2"):
        load_radarscenes(root, sequences=["seq_2"])


# --------------------------------------------------------------------------
# Writer errors
# --------------------------------------------------------------------------


@pytest.mark.parametrize("key", ["data", "odometry", "sensors", "sequences"])
def test_write_bunch_missing_key(tmp_path, key):
    bunch = make_test_bunch()
    del bunch[key]
    with pytest.raises(ValueError, match=key):
        write_radarscenes(bunch, tmp_path / "data")
    assert not (tmp_path / "data").exists()


@pytest.mark.parametrize("table, column", [("data", "uuid"), ("data", "sequence"), ("odometry", "yaw_seq")])
def test_write_bunch_missing_column(tmp_path, table, column):
    bunch = make_test_bunch()
    bunch[table] = bunch[table].drop(columns=column)
    with pytest.raises(ValueError, match=f"bunch.{table}.*{column}"):
        write_radarscenes(bunch, tmp_path / "data")


def test_write_two_sensors_sharing_a_timestamp(tmp_path):
    bunch = make_test_bunch()
    data = bunch.data
    second_scan = data.index[data["timestamp"] == data["timestamp"].unique()[1]]
    data.loc[second_scan, "timestamp"] = data["timestamp"].iloc[0]
    with pytest.raises(ValueError, match="two sensors share timestamp"):
        write_radarscenes(bunch, tmp_path / "data")


@pytest.mark.parametrize("column, value", [("uuid", "u" * 33), ("track_id", "Straße"), ("track_id", "é")])
def test_write_string_not_representable(tmp_path, column, value):
    bunch = make_test_bunch()
    bunch.data.loc[3, column] = value
    with pytest.raises(ValueError, match=f"column '{column}'.*ASCII.*32"):
        write_radarscenes(bunch, tmp_path / "data")


def test_write_string_where_float_belongs(tmp_path):
    bunch = make_test_bunch()
    bunch.data["rcs"] = bunch.data["rcs"].astype(str)
    with pytest.raises(ValueError, match=r"bunch\.data.*rcs"):
        write_radarscenes(bunch, tmp_path / "data")


# --------------------------------------------------------------------------
# Atomicity
# --------------------------------------------------------------------------


def failing_on_second_call(monkeypatch):
    original = _radarscenes_writer._write_radar_data_h5
    calls = []

    def write_then_fail(*args):
        calls.append(args)
        if len(calls) == 2:
            raise OSError("disk full (simulated)")
        original(*args)

    monkeypatch.setattr(_radarscenes_writer, "_write_radar_data_h5", write_then_fail)


def test_failed_write_leaves_nothing_behind(tmp_path, monkeypatch):
    parent = tmp_path / "out"
    parent.mkdir()
    failing_on_second_call(monkeypatch)
    with pytest.raises(OSError, match="simulated"):
        write_radarscenes(make_test_bunch(), parent / "data")
    assert list(parent.iterdir()) == []


def test_existing_folder_is_kept_without_overwrite(written):
    root, _ = written
    before = sorted(p.relative_to(root) for p in root.rglob("*"))
    with pytest.raises(FileExistsError, match="overwrite"):
        write_radarscenes(subset(make_test_bunch(), [2]), root)
    assert sorted(p.relative_to(root) for p in root.rglob("*")) == before


def test_overwrite_replaces_existing_folder(written):
    root, _ = written
    expected = subset(make_test_bunch(), [2])
    write_radarscenes(expected, root, overwrite=True)
    assert_bunch_equal(load_radarscenes(root), expected)
    assert not (root / "sequence_5").exists()
    assert [p.name for p in root.parent.iterdir()] == ["data"]


def test_failed_overwrite_keeps_old_content(written, monkeypatch):
    root, bunch = written
    failing_on_second_call(monkeypatch)
    with pytest.raises(OSError, match="simulated"):
        write_radarscenes(make_test_bunch(seed=1), root, overwrite=True)
    assert_bunch_equal(load_radarscenes(root), bunch)
    assert [p.name for p in root.parent.iterdir()] == ["data"]


def test_write_into_existing_empty_folder(tmp_path):
    (tmp_path / "data").mkdir()
    bunch = make_test_bunch()
    assert write_radarscenes(bunch, tmp_path / "data") == tmp_path / "data"
    assert_bunch_equal(load_radarscenes(tmp_path / "data"), bunch)


# --------------------------------------------------------------------------
# Simulator output
# --------------------------------------------------------------------------


def test_simulated_scenes_round_trip_and_devkit(tmp_path):
    bunch = make_scenes(n_sequences=2, duration=3.0, random_state=0)
    root = write_radarscenes(bunch, tmp_path / "data")
    assert_bunch_equal(load_radarscenes(root), bunch)
    check_devkit_reads(root, bunch)


# --------------------------------------------------------------------------
# Corrupted values (issue 15, item 5): rejected at load time, naming file and field
# --------------------------------------------------------------------------

_RADAR_FLOAT_FIELDS = ["range_sc", "azimuth_sc", "rcs", "vr", "vr_compensated", "x_cc", "y_cc", "x_seq", "y_seq"]
_ODOMETRY_FLOAT_FIELDS = ["x_seq", "y_seq", "yaw_seq", "vx", "yaw_rate"]


def _corrupt_h5(dataset, field, value):
    def corrupt(root):
        file = root / "sequence_5" / "radar_data.h5"
        arrays = dict(zip(["radar_data", "odometry"], read_h5(file), strict=True))
        arrays[dataset][field][1] = value
        rewrite_h5(file, **arrays)
        return f"sequence_5/radar_data.h5 \\[{dataset}\\].*{field}.*(NaN|inf)"

    return corrupt


def _corrupt_sensor(key, text):
    def corrupt(root):
        file = root / "sensors.json"
        content = json.loads(file.read_text())
        name = sorted(content)[1]
        content[name][key] = "@@"
        file.write_text(json.dumps(content).replace('"@@"', text))
        return f"sensors.json.*{name}.{key}.*finite"

    return corrupt


def _empty_sequences_json(root):
    (root / "sequences.json").write_text(json.dumps({"sequences": {}}))
    return "sequences.json.*no sequence"


def _scenes_json_of_another_sequence(root):
    edit_json(root / "sequence_5" / "scenes.json", lambda content: content.update(sequence_name="sequence_2"))
    return "sequence_5/scenes.json.*sequence_name.*sequence_2"


_CORRUPTIONS = {
    **{
        f"radar_data.{field}={value}": _corrupt_h5("radar_data", field, value)
        for field in _RADAR_FLOAT_FIELDS
        for value in (np.nan, np.inf)
    },
    "radar_data.vr=-inf": _corrupt_h5("radar_data", "vr", -np.inf),
    **{
        f"odometry.{field}={value}": _corrupt_h5("odometry", field, value)
        for field in _ODOMETRY_FLOAT_FIELDS
        for value in (np.nan, -np.inf)
    },
    **{
        f"sensors.{key}={text}": _corrupt_sensor(key, text)
        for key in ("x", "y", "yaw")
        for text in ("NaN", "Infinity", "-Infinity", "1e999")
    },
    "sensors.x=10**400": _corrupt_sensor("x", "1" + "0" * 400),
    "empty sequences.json": _empty_sequences_json,
    "scenes.json of another sequence": _scenes_json_of_another_sequence,
}


@pytest.mark.parametrize("corrupt", list(_CORRUPTIONS.values()), ids=list(_CORRUPTIONS))
def test_load_rejects_corrupted_values_naming_file_and_field(written, corrupt):
    root, _ = written
    message = corrupt(root)
    with pytest.raises(ValueError, match=message):
        load_radarscenes(root)


def test_load_accepts_a_scenes_json_without_sequence_name(written):
    root, bunch = written
    edit_json(root / "sequence_5" / "scenes.json", lambda content: content.pop("sequence_name"))
    assert_bunch_equal(load_radarscenes(root), bunch)


def test_writing_onto_a_file_says_it_is_a_file(tmp_path):
    afile = tmp_path / "afile"
    afile.write_text("mine")
    with pytest.raises(FileExistsError, match="is a file"):
        write_radarscenes(make_test_bunch(), afile)
    assert afile.read_text() == "mine"
