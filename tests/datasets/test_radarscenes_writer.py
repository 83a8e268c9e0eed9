"""Tests of the RadarScenes writer, against the devkit (radar_scenes 1.0.4)."""

import json

import pandas as pd
import pytest

from sklearn_radar._schema import (
    RADAR_DATA_COLUMNS,
    RADARSCENES_MOUNTING,
)
from sklearn_radar.datasets import _radarscenes_format, make_scenes
from sklearn_radar.datasets._radarscenes_reader import load_radarscenes
from sklearn_radar.datasets._radarscenes_writer import write_radarscenes

from ._radarscenes_data import (
    assert_bunch_equal,
    check_devkit_reads,
    failing_on_second_call,
    make_test_bunch,
    read_h5,
    subset,
)


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


def test_devkit_opens_what_we_write(written):
    check_devkit_reads(*written)


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


def test_failed_write_leaves_nothing_behind(tmp_path, monkeypatch):
    parent = tmp_path / "out"
    parent.mkdir()
    failing_on_second_call(monkeypatch)
    with pytest.raises(OSError, match="simulated"):
        write_radarscenes(make_test_bunch(), parent / "data")
    assert list(parent.iterdir()) == []


def test_write_into_existing_empty_folder(tmp_path):
    (tmp_path / "data").mkdir()
    bunch = make_test_bunch()
    assert write_radarscenes(bunch, tmp_path / "data") == tmp_path / "data"
    assert_bunch_equal(load_radarscenes(tmp_path / "data"), bunch)


def test_simulated_scenes_round_trip_and_devkit(tmp_path):
    bunch = make_scenes(n_sequences=2, duration=3.0, random_state=0)
    root = write_radarscenes(bunch, tmp_path / "data")
    assert_bunch_equal(load_radarscenes(root), bunch)
    check_devkit_reads(root, bunch)
