"""Tests of the RadarScenes reader: which sequences it loads, from where, and the errors of malformed files."""

import json
import shutil

import numpy as np
import pytest

from sklearn_radar.datasets._radarscenes_reader import load_radarscenes
from sklearn_radar.datasets._radarscenes_writer import write_radarscenes

from ._radarscenes_data import (
    assert_bunch_equal,
    edit_json,
    make_test_bunch,
    read_h5,
    retype,
    rewrite_h5,
    scene_items,
    subset,
)


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


def test_load_unknown_sequence(written):
    root, _ = written
    with pytest.raises(ValueError, match=r"sequences\.json.*sequence_9"):
        load_radarscenes(root, sequences=["sequence_9"])
    with pytest.raises(ValueError, match="seq_2"):
        load_radarscenes(root, sequences=["seq_2"])
