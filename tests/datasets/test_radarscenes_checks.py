"""Tests of the checks of what the RadarScenes reader reads.

Time order, ``scenes.json`` against ``radar_data.h5``, JSON fields and finite values.
"""

import json

import numpy as np
import pytest

from sklearn_radar.datasets._radarscenes_reader import load_radarscenes

from ._radarscenes_data import assert_bunch_equal, edit_json, read_h5, rewrite_h5, scene_items


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
