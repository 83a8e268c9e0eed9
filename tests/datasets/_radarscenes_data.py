"""A small RadarScenes data set built by hand, and helpers that edit written files.

Shared by the tests of the RadarScenes reader, writer, checks and output folder.
"""

import json

import h5py
import numpy as np
import pandas as pd
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
from sklearn_radar.datasets import _radarscenes_writer

SEQUENCES = {2: "train", 5: "validation"}


ODOMETRY_PERIOD = 20_000  # µs, 50 Hz


SCAN_PERIOD = 60_000  # µs


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


def failing_on_second_call(monkeypatch):
    original = _radarscenes_writer._write_radar_data_h5
    calls = []

    def write_then_fail(*args):
        calls.append(args)
        if len(calls) == 2:
            raise OSError("disk full (simulated)")
        original(*args)

    monkeypatch.setattr(_radarscenes_writer, "_write_radar_data_h5", write_then_fail)
