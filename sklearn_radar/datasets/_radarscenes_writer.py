"""Write the data Bunch as a RadarScenes data folder, which the RadarScenes devkit opens.

The write is atomic and never replaces what it did not write
(:mod:`._output_folder`).  Read more in the :ref:`User Guide <user-guide-data>`.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np
import pandas as pd
from sklearn.utils._param_validation import validate_params

from .._files import TEMPORARY_PREFIX, folder_mode
from .._schema import ODOMETRY_COLUMNS, RADAR_DATA_COLUMNS, make_frame, nearest_odometry_index
from ._output_folder import _MANIFEST_TOOL, MANIFEST, _move_into_place, _remove_stale_temporaries, check_output_folder
from ._radarscenes_format import (
    _CATEGORIES,
    _SEQUENCE_COLUMN,
    _STRING_BYTES,
    _STRING_FIELDS,
    ODOMETRY_H5_DTYPE,
    RADAR_DATA_H5_DTYPE,
)

__all__ = ["write_radarscenes"]


@dataclass
class _PreparedSequence:
    """Everything written for one sequence, built before touching the disk."""

    name: str
    radar_data: np.ndarray
    odometry: np.ndarray
    scenes: dict
    summary: dict


@validate_params(
    {"bunch": [dict], "path": [str, os.PathLike], "overwrite": ["boolean"]},
    prefer_skip_nested_validation=True,
)
def write_radarscenes(bunch, path, overwrite=False) -> Path:
    """Write a data Bunch as a RadarScenes data folder.

    The folder holds ``sensors.json``, ``sequences.json`` and, per sequence,
    ``sequence_N/radar_data.h5`` and ``sequence_N/scenes.json``; the
    RadarScenes devkit opens it with ``Sequence.from_json``.  The ego
    columns of ``bunch.data`` are not written: each scene points to the
    odometry row nearest in time
    (:func:`~sklearn_radar._schema.nearest_odometry_index`).

    Read more in the :ref:`User Guide <user-guide-data>`.

    Parameters
    ----------
    bunch : :class:`~sklearn.utils.Bunch` or dict
        As returned by :func:`load_radarscenes` or
        :func:`~sklearn_radar.datasets.make_scenes`; needs ``data``,
        ``odometry``, ``sensors`` and ``sequences``.  Timestamps are in µs,
        positions in m, angles in rad, velocities in m/s.
    path : str or path-like
        The data folder to create (an empty folder is used as it is).
    overwrite : bool, default=False
        Replace ``path`` if it is a data folder that this function wrote
        before: one whose manifest (``sklearn_radar_manifest.json``) lists
        every file in it.  Anything else (a file, a symbolic link, a folder
        without the manifest or holding a file it does not list, such as a
        real RadarScenes download or notes of your own) is never replaced.

    Returns
    -------
    path : pathlib.Path
        The written folder.

    Raises
    ------
    ValueError
        If the bunch lacks a key or column, two sensors share one timestamp
        in a sequence, or a string is not ASCII or longer than 32 bytes.
    FileExistsError
        If ``path`` exists and is not empty, and ``overwrite`` is False or
        ``path`` is not a data folder this function wrote; checked before
        anything is written.

    See Also
    --------
    load_radarscenes : the reverse.

    Notes
    -----
    The write is atomic: everything goes to a temporary sibling folder that
    is renamed to ``path`` at the end and removed on any error.  The folder
    also holds ``sklearn_radar_manifest.json``, the list of the files
    written, by which ``overwrite`` recognises it.
    """
    path = Path(path)
    data, odometry, sensors, sequences = _bunch_tables(bunch)
    check_output_folder(path, overwrite)
    prepared = [
        _prepare_sequence(number, category, data, odometry)
        for number, category in zip(sequences["sequence"], sequences["category"], strict=True)
    ]
    sensors_json = {
        f"radar_{sensor_id}": {"id": int(sensor_id), **{k: float(row[k]) for k in ("x", "y", "yaw")}}
        for sensor_id, row in sensors.iterrows()
    }
    sequences_json = {"sequences": {p.name: p.summary for p in prepared}}
    written = ["sensors.json", "sequences.json"]
    path.parent.mkdir(parents=True, exist_ok=True)
    _remove_stale_temporaries(path)
    prefix = f"{TEMPORARY_PREFIX}{os.getpid()}-{path.name}."
    staging = Path(tempfile.mkdtemp(prefix=prefix, suffix=".tmp", dir=path.parent))
    try:
        os.chmod(staging, folder_mode())  # mkdtemp creates 0700 whatever the umask
        _write_json(staging / "sensors.json", sensors_json)
        _write_json(staging / "sequences.json", sequences_json)
        for sequence in prepared:
            (staging / sequence.name).mkdir()
            h5_file = staging / sequence.name / "radar_data.h5"
            _write_radar_data_h5(h5_file, sequence.radar_data, sequence.odometry)
            _write_json(staging / sequence.name / "scenes.json", sequence.scenes)
            written += [f"{sequence.name}/radar_data.h5", f"{sequence.name}/scenes.json"]
        _write_json(staging / MANIFEST, {"tool": _MANIFEST_TOOL, "files": written})
        _move_into_place(staging, path, overwrite)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    return path


def _bunch_tables(bunch):
    """Validated copies of the four tables the writer needs."""
    missing = [key for key in ("data", "odometry", "sensors", "sequences") if key not in bunch]
    if missing:
        raise ValueError(f"bunch is missing the key(s) {missing}")
    for key in ("data", "odometry", "sensors", "sequences"):
        if not isinstance(bunch[key], pd.DataFrame):
            raise ValueError(f"bunch.{key} must be a pandas DataFrame, got {type(bunch[key]).__name__}")
    data = make_frame(bunch["data"], (*RADAR_DATA_COLUMNS, _SEQUENCE_COLUMN), table="bunch.data")
    odometry = make_frame(bunch["odometry"], ODOMETRY_COLUMNS, table="bunch.odometry")
    sensors = _bunch_sensors(bunch["sensors"])
    sequences = _bunch_sequences(bunch["sequences"])
    _check_sequences_known(data, "bunch.data", sequences)
    _check_sequences_known(odometry, "bunch.odometry", sequences)
    unknown = sorted(set(np.unique(data["sensor_id"]).tolist()) - set(sensors.index.tolist()))
    if unknown:
        raise ValueError(f"bunch.data: column 'sensor_id' has values {unknown} missing from bunch.sensors")
    return data, odometry, sensors, sequences


def _bunch_sensors(sensors: pd.DataFrame) -> pd.DataFrame:
    missing = [key for key in ("x", "y", "yaw") if key not in sensors.columns]
    if missing:
        raise ValueError(f"bunch.sensors is missing the column(s) {missing}")
    index = np.asarray(sensors.index)
    if index.dtype.kind not in "iu":
        raise ValueError(f"bunch.sensors must be indexed by integer sensor_id, got dtype {index.dtype}")
    _check_range(index, "bunch.sensors: index 'sensor_id'", 0, np.iinfo(np.uint8).max)
    if len(np.unique(index)) != len(index):
        raise ValueError("bunch.sensors: index 'sensor_id' has duplicates")
    try:
        return sensors[["x", "y", "yaw"]].astype(np.float64).sort_index()
    except (TypeError, ValueError) as exc:
        raise ValueError(f"bunch.sensors: columns x, y, yaw must be numeric ({exc})") from exc


def _bunch_sequences(sequences: pd.DataFrame) -> pd.DataFrame:
    missing = [key for key in ("sequence", "category") if key not in sequences.columns]
    if missing:
        raise ValueError(f"bunch.sequences is missing the column(s) {missing}")
    number = np.asarray(sequences["sequence"])
    if number.dtype.kind not in "iu" or np.any(number < 0) or len(np.unique(number)) != len(number):
        raise ValueError("bunch.sequences: column 'sequence' must hold distinct non-negative integers")
    bad = sorted(set(sequences["category"].tolist()) - set(_CATEGORIES), key=str)
    if bad:
        raise ValueError(f"bunch.sequences: column 'category' must be one of {list(_CATEGORIES)}, got {bad}")
    table = pd.DataFrame({"sequence": number.astype(np.int64), "category": list(sequences["category"])})
    return table.sort_values("sequence")


def _check_sequences_known(table: pd.DataFrame, where: str, sequences: pd.DataFrame) -> None:
    unknown = sorted(set(np.unique(table["sequence"]).tolist()) - set(sequences["sequence"].tolist()))
    if unknown:
        raise ValueError(f"{where}: column 'sequence' has values {unknown} missing from bunch.sequences")


def _check_range(values, where: str, low: int, high: int) -> None:
    values = np.asarray(values)
    if values.size and (values.min() < low or values.max() > high):
        raise ValueError(f"{where} must lie in [{low}, {high}]")


def _prepare_sequence(number, category, data, odometry) -> _PreparedSequence:
    name = f"sequence_{number}"
    radar = data[data["sequence"].to_numpy() == number].sort_values("timestamp", kind="stable")
    odometry = odometry[odometry["sequence"].to_numpy() == number].sort_values("timestamp", kind="stable")
    if len(radar) and not len(odometry):
        raise ValueError(f"bunch.odometry: {name} has detections but no odometry rows")
    radar_data = _radar_data_array(radar, name)
    odometry_array = _odometry_array(odometry, name)
    scenes = _scene_entries(radar_data, odometry_array["timestamp"], name)
    timestamps = [int(ts) for ts in scenes]
    return _PreparedSequence(
        name=name,
        radar_data=radar_data,
        odometry=odometry_array,
        scenes={
            "sequence_name": name,
            "category": category,
            "first_timestamp": timestamps[0] if timestamps else None,
            "last_timestamp": timestamps[-1] if timestamps else None,
            "scenes": scenes,
        },
        summary={
            "category": category,
            "scenes": len(scenes),
            "duration": (timestamps[-1] - timestamps[0]) / 1e6 if timestamps else 0.0,
            "sensors": [f"radar_{k}" for k in sorted(set(radar_data["sensor_id"].tolist()))],
        },
    )


def _radar_data_array(radar: pd.DataFrame, name: str) -> np.ndarray:
    where = f"bunch.data ({name})"
    _check_range(radar["timestamp"], f"{where}: column 'timestamp'", 0, np.iinfo(np.int64).max)
    _check_range(radar["sensor_id"], f"{where}: column 'sensor_id'", 0, np.iinfo(np.uint8).max)
    _check_range(radar["label_id"], f"{where}: column 'label_id'", 0, np.iinfo(np.uint8).max)
    array = np.empty(len(radar), dtype=RADAR_DATA_H5_DTYPE)
    for field in RADAR_DATA_H5_DTYPE.names:
        values = radar[field].to_numpy()
        if field in _STRING_FIELDS:
            values = _encode_strings(values, f"{where}: column {field!r}")
        array[field] = values
    return array


def _encode_strings(values: np.ndarray, where: str) -> np.ndarray:
    encoded = []
    for value in values:
        if not value.isascii() or len(value) > _STRING_BYTES:
            raise ValueError(f"{where} must hold ASCII strings of at most {_STRING_BYTES} bytes, got {value!r}")
        encoded.append(value.encode("ascii"))
    return np.array(encoded, dtype=f"S{_STRING_BYTES}")


def _odometry_array(odometry: pd.DataFrame, name: str) -> np.ndarray:
    where = f"bunch.odometry ({name}): column 'timestamp'"
    _check_range(odometry["timestamp"], where, 0, np.iinfo(np.int64).max)
    array = np.empty(len(odometry), dtype=ODOMETRY_H5_DTYPE)
    for field in ODOMETRY_H5_DTYPE.names:
        array[field] = odometry[field].to_numpy()
    return array


def _scene_entries(radar_data: np.ndarray, odometry_timestamps: np.ndarray, name: str) -> dict:
    """The ``scenes`` mapping of ``scenes.json``: one scan per distinct timestamp."""
    timestamps = radar_data["timestamp"].astype(np.int64)
    sensor_id = radar_data["sensor_id"].astype(np.int64)
    is_first_row_of_scan = np.ones(len(timestamps), dtype=bool)
    is_first_row_of_scan[1:] = timestamps[1:] != timestamps[:-1]
    start = np.flatnonzero(is_first_row_of_scan)
    end = np.r_[start[1:], len(timestamps)]
    scan_of_row = np.repeat(np.arange(len(start)), end - start)
    shared = np.flatnonzero(sensor_id != sensor_id[start][scan_of_row])
    if shared.size:
        raise ValueError(
            f"bunch.data ({name}): two sensors share timestamp {timestamps[shared[0]]}; "
            f"RadarScenes keys scenes by timestamp, so every scan needs its own"
        )
    scan_time = timestamps[start].tolist()
    scan_sensor = sensor_id[start].tolist()
    odometry_index = nearest_odometry_index(scan_time, odometry_timestamps).tolist()
    prev_same, next_same = _same_sensor_neighbours(scan_time, scan_sensor)
    n_scans = len(scan_time)
    return {
        str(scan_time[i]): {
            "sensor_id": scan_sensor[i],
            "prev_timestamp": scan_time[i - 1] if i > 0 else None,
            "next_timestamp": scan_time[i + 1] if i + 1 < n_scans else None,
            "prev_timestamp_same_sensor": prev_same[i],
            "next_timestamp_same_sensor": next_same[i],
            "odometry_timestamp": int(odometry_timestamps[odometry_index[i]]),
            "odometry_index": odometry_index[i],
            "image_name": "",  # no camera images; the devkit builds the path but never opens it
            "radar_indices": [int(start[i]), int(end[i])],
        }
        for i in range(n_scans)
    }


def _same_sensor_neighbours(scan_time: list, scan_sensor: list):
    """Previous and next timestamp of the same sensor for every scan (None at the ends)."""
    prev_same = [None] * len(scan_time)
    next_same = [None] * len(scan_time)
    last_scan_of = {}
    for i, sensor in enumerate(scan_sensor):
        if sensor in last_scan_of:
            j = last_scan_of[sensor]
            prev_same[i] = scan_time[j]
            next_same[j] = scan_time[i]
        last_scan_of[sensor] = i
    return prev_same, next_same


def _write_json(file: Path, content) -> None:
    with open(file, "w", encoding="utf-8") as stream:
        json.dump(content, stream, indent=1)


def _write_radar_data_h5(file: Path, radar_data: np.ndarray, odometry: np.ndarray) -> None:
    with h5py.File(file, "w") as h5:
        h5.create_dataset("radar_data", data=radar_data)
        h5.create_dataset("odometry", data=odometry)
