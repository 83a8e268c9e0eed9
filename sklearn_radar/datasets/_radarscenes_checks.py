"""Checks of what the RadarScenes reader reads: JSON fields, finite and plausible values, time order, and
``scenes.json`` against ``radar_data.h5``.

Every malformed input raises :class:`FileNotFoundError` (missing file) or
:class:`ValueError` naming the file and, where there is one, the field.
Values are checked where they are read: a NaN or infinite number in a field
of ``radar_data.h5`` (``radar_data`` or ``odometry``) or in the mounting of
``sensors.json`` is rejected, as is a ``scenes.json`` whose
``sequence_name`` names another sequence than its folder.  Physical
plausibility (units) is checked as the estimators check it
(:func:`sklearn_radar._validation.check_plausible`): the measured fields of
``radar_data`` with the scan spacing per sensor, the odometry's speed, yaw
rate and position, and the mounting of ``sensors.json``.  Read more in the
:ref:`User Guide <user-guide-plausibility>`.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from .._validation import check_plausible
from ._radarscenes_format import _STRING_FIELDS


def _read_json(file: Path):
    if not file.is_file():
        raise FileNotFoundError(f"RadarScenes file not found: {file}")
    try:
        with open(file, encoding="utf-8") as stream:
            return json.load(stream)
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{file}: malformed JSON ({exc})") from exc


def _expect_mapping(value, file, where):
    if not isinstance(value, dict):
        raise ValueError(f"{file}: {where} must be a JSON object, got {type(value).__name__}")
    return value


def _field(mapping, key, file, where):
    if key not in mapping:
        raise ValueError(f"{file}: {where} is missing the field {key!r}")
    return mapping[key]


def _json_int(value, file, field):
    int64 = np.iinfo(np.int64)
    if isinstance(value, bool) or not isinstance(value, int) or not int64.min <= value <= int64.max:
        raise ValueError(f"{file}: field {field!r} must be a 64-bit integer, got {value!r}")
    return value


def _json_float(value, file, field):
    finite = isinstance(value, (int, float)) and not isinstance(value, bool)
    try:
        finite = finite and bool(np.isfinite(float(value)))
    except OverflowError:  # an integer beyond the float range
        finite = False
    if not finite:
        raise ValueError(f"{file}: field {field!r} must be a finite number, got {value!r}")
    return float(value)


def _check_finite(frame: pd.DataFrame, table: str) -> None:
    """Policy: a measured value is a finite number; NaN or inf is rejected here, where the file is known."""
    for name in frame.columns:
        values = frame[name].to_numpy()
        if values.dtype.kind != "f":
            continue
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            value = values[bad[0]]
            kind = "NaN" if np.isnan(value) else ("inf" if value > 0 else "-inf")
            raise ValueError(
                f"{table}: field {name!r} holds {kind} in row {bad[0]} ({bad.size} non-finite value(s)); "
                f"RadarScenes values must be finite numbers"
            )


def _check_sequence_name(content, name: str, file: Path) -> None:
    """A ``scenes.json`` that names a sequence must name the one whose folder holds it."""
    if isinstance(content, dict) and "sequence_name" in content and content["sequence_name"] != name:
        raise ValueError(
            f"{file}: field 'sequence_name' is {content['sequence_name']!r}, but the file lies in the folder {name}"
        )


def _check_sorted(timestamps: pd.Series, table: str) -> None:
    """Time must not run backwards: RadarScenes stores rows in time order (and so every sensor's scans)."""
    values = timestamps.to_numpy()
    backwards = np.flatnonzero(np.diff(values) < 0)
    if backwards.size:
        row = int(backwards[0]) + 1
        raise ValueError(
            f"{table}: field 'timestamp' is not sorted ascending: time runs backwards at row {row} "
            f"({values[row]} µs after {values[row - 1]} µs); RadarScenes stores rows in time order"
        )


def _check_plausible_radar_data(radar: pd.DataFrame, table: str) -> None:
    """Physical plausibility of the measured fields (sklearn_radar._schema.PLAUSIBLE_VALUES), per sensor."""
    numeric = [name for name in radar.columns if name not in ("sensor_id", "label_id", *_STRING_FIELDS)]
    columns = {name: radar[name].to_numpy(dtype=np.float64) for name in numeric}
    check_plausible(columns, table, sensor=radar["sensor_id"].to_numpy())


#: The odometry fields under the names of the detection columns whose bounds and comparisons apply to them.
_ODOMETRY_BOUNDS = {
    "vx": "ego_vx",
    "yaw_rate": "ego_yaw_rate",
    "x_seq": "ego_x_seq",
    "y_seq": "ego_y_seq",
    "yaw_seq": "ego_yaw_seq",
}
#: The detection columns the Doppler of the static world is predicted from (and vr).
_DOPPLER_COLUMNS = ("vr", "azimuth_sc", "sensor_x", "sensor_y", "sensor_yaw", "ego_vx", "ego_yaw_rate")


def _check_plausible_odometry(odometry: pd.DataFrame, table: str) -> None:
    columns = {name: odometry[name].to_numpy(dtype=np.float64) for name in ("timestamp", *_ODOMETRY_BOUNDS)}
    check_plausible(columns, table, bounds=_ODOMETRY_BOUNDS)


def _check_plausible_mounting(mounting: dict, file: Path) -> None:
    """Every sensor must sit on the car, looking in a direction given in rad."""
    sensors = list(mounting)
    columns = {field: np.array([mounting[k][field] for k in sensors], dtype=np.float64) for field in ("x", "y", "yaw")}
    where = f"{file} (rows are the sensors {sensors})"
    check_plausible(columns, where, bounds={"x": "sensor_x", "y": "sensor_y", "yaw": "sensor_yaw"})


def _check_mounting(sensor_id: pd.Series, mounting: dict, file: Path) -> None:
    unknown = sorted(set(np.unique(sensor_id).tolist()) - set(mounting))
    if unknown:
        raise ValueError(f"{file}: field 'sensor_id' has values {unknown} missing from sensors.json")


@dataclass
class _SceneTable:
    """The scenes of a ``scenes.json``, one array entry per scene, ordered by ``start``."""

    timestamp: np.ndarray
    sensor_id: np.ndarray
    start: np.ndarray
    end: np.ndarray
    odometry_index: np.ndarray


def _detection_odometry_index(content, radar: pd.DataFrame, n_odometry: int, file: Path) -> np.ndarray:
    """Odometry row of every detection, checking ``scenes.json`` against ``radar_data``."""
    content = _expect_mapping(content, file, "the top level")
    scenes = _expect_mapping(_field(content, "scenes", file, "the top level"), file, "'scenes'")
    table = _scene_table(scenes, file)
    _check_scene_coverage(table, len(radar), file)
    lengths = table.end - table.start
    for field in ("timestamp", "sensor_id"):
        expected = np.repeat(getattr(table, field), lengths)
        mismatch = np.flatnonzero(expected != radar[field].to_numpy())
        if mismatch.size:
            raise ValueError(
                f"{file}: field {field!r} of the scene covering radar_data row {mismatch[0]} "
                f"disagrees with radar_data.h5"
            )
    outside = (table.odometry_index < 0) | (table.odometry_index >= n_odometry)
    if np.any(outside):
        raise ValueError(
            f"{file}: field 'odometry_index' of scene {table.timestamp[outside][0]} is outside "
            f"the {n_odometry} odometry rows"
        )
    return np.repeat(table.odometry_index, lengths)


def _scene_table(scenes: dict, file: Path) -> _SceneTable:
    rows = [_parse_scene(key, scene, file) for key, scene in scenes.items()]
    columns = np.array(rows, dtype=np.int64).reshape(len(rows), 5).T
    order = np.lexsort((columns[3], columns[2]))
    return _SceneTable(*(column[order] for column in columns))


def _parse_scene(key: str, scene, file: Path) -> tuple:
    where = f"scene {key}"
    try:
        timestamp = int(key)
    except ValueError:
        raise ValueError(f"{file}: scene key {key!r} is not an integer timestamp") from None
    scene = _expect_mapping(scene, file, where)
    sensor_id = _json_int(_field(scene, "sensor_id", file, where), file, f"{where}.sensor_id")
    odometry_index = _json_int(_field(scene, "odometry_index", file, where), file, f"{where}.odometry_index")
    indices = _field(scene, "radar_indices", file, where)
    if not isinstance(indices, list) or len(indices) != 2:
        raise ValueError(f"{file}: field '{where}.radar_indices' must be a list [start, end]")
    start, end = (_json_int(i, file, f"{where}.radar_indices") for i in indices)
    if start > end:
        raise ValueError(f"{file}: field '{where}.radar_indices' has start {start} > end {end}")
    return timestamp, sensor_id, start, end, odometry_index


def _check_scene_coverage(table: _SceneTable, n_detections: int, file: Path) -> None:
    """The scenes' ``radar_indices`` must tile ``[0, n_detections)`` without gaps or overlaps."""
    # Sorted by start, scene i must end where scene i+1 starts; the first starts at 0, the last ends at n.
    next_start = np.r_[table.start, n_detections]
    tiles = next_start[0] == 0 and np.array_equal(next_start[1:], table.end)
    if not tiles:
        raise ValueError(
            f"{file}: field 'radar_indices' of the scenes does not cover the {n_detections} "
            f"radar_data rows exactly once (out of range, gap or overlap)"
        )
