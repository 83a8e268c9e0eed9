"""Read and write the RadarScenes on-disk format.

A RadarScenes *data folder* holds ``sensors.json``, ``sequences.json`` and
one ``sequence_N/`` folder per recording with ``radar_data.h5`` (HDF5
datasets ``radar_data`` and ``odometry``) and ``scenes.json``.  The reader
turns such a folder into the data :class:`~sklearn.utils.Bunch` described in
:mod:`sklearn_radar._schema`; the writer does the reverse, so that simulated
data can be opened with the RadarScenes devkit.

Every malformed input raises :class:`FileNotFoundError` (missing file or
folder) or :class:`ValueError` naming the file and, where there is one, the
field.  Values are checked where they are read: a NaN or infinite number in
a field of ``radar_data.h5`` (``radar_data`` or ``odometry``) or in the
mounting of ``sensors.json`` is rejected, as is a ``sequences.json`` that
lists no sequence or a ``scenes.json`` whose ``sequence_name`` names another
sequence than its folder.  Physical plausibility (units) is checked as the
estimators check it (:func:`sklearn_radar._validation.check_plausible`):
the measured fields of ``radar_data`` with the scan spacing per sensor, the
odometry's speed, yaw rate and position, and the mounting of
``sensors.json``.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import tempfile
import uuid as uuid_module
from dataclasses import dataclass
from numbers import Integral
from pathlib import Path

import h5py
import numpy as np
import pandas as pd
from sklearn.utils import Bunch
from sklearn.utils._param_validation import validate_params

from .._files import TEMPORARY_PREFIX, blocking_file, folder_mode, process_alive, remove_entry
from .._schema import (
    CONTEXT_COLUMNS,
    DETECTION_COLUMNS,
    ODOMETRY_COLUMNS,
    RADAR_DATA_COLUMNS,
    attach_context,
    column_names,
    instance_target,
    make_frame,
    nearest_odometry_index,
)
from .._validation import check_plausible

__all__ = ["load_radarscenes", "write_radarscenes"]

_SEQUENCE_COLUMN = next(c for c in CONTEXT_COLUMNS if c.name == "sequence")
_STRING_FIELDS = [c.name for c in RADAR_DATA_COLUMNS if c.dtype == "str"]
_ODOMETRY_FILE_COLUMNS = tuple(c for c in ODOMETRY_COLUMNS if c.name != "sequence")
_CATEGORIES = ("train", "validation")
_SEQUENCE_NAME = re.compile(r"sequence_(\d+)")
_STRING_BYTES = 32

# File dtypes: not documented by RadarScenes; these load with devkit 1.0.4.
_RADAR_FILE_TYPES = {"timestamp": "<u8", "sensor_id": "u1", "uuid": "S32", "track_id": "S32", "label_id": "u1"}
RADAR_DATA_H5_DTYPE = np.dtype(
    [(name, _RADAR_FILE_TYPES.get(name, "<f4")) for name in column_names(RADAR_DATA_COLUMNS)]
)
ODOMETRY_H5_DTYPE = np.dtype(
    [(name, "<u8" if name == "timestamp" else "<f4") for name in column_names(_ODOMETRY_FILE_COLUMNS)]
)


# --------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------


@validate_params(
    {"path": [str, os.PathLike], "sequences": [str, Integral, "array-like", None]},
    prefer_skip_nested_validation=True,
)
def load_radarscenes(path, sequences=None) -> Bunch:
    """Load RadarScenes sequences into the data Bunch.

    Read more in the :ref:`User Guide <user-guide-data>`.

    Parameters
    ----------
    path : str or path-like
        The dataset's ``data/`` folder (holding ``sensors.json``,
        ``sequences.json`` and ``sequence_N/``), or its parent folder.
    sequences : str, int or list of str or int, default=None
        Sequences to load, as names (``"sequence_3"``) or numbers (``3``);
        a single one need not be in a list.  ``None`` loads every sequence
        listed in ``sequences.json``.

    Returns
    -------
    bunch : :class:`~sklearn.utils.Bunch`
        ``data`` (DataFrame, one row per detection with the columns of
        ``sklearn_radar._schema.DETECTION_COLUMNS``; positions in m,
        angles in rad, velocities in m/s, timestamps in µs), ``target``
        (int64 instance label, -1 for background), ``groups`` (int64
        sequence number), ``odometry`` (DataFrame with
        ``sklearn_radar._schema.ODOMETRY_COLUMNS``), ``sensors``
        (mounting in m and rad, indexed by ``sensor_id``), ``sequences``
        (``sequence``, ``name``, ``category``) and ``DESCR``.

    Raises
    ------
    FileNotFoundError
        If the folder, a JSON file, a sequence folder or an HDF5 file is missing.
    ValueError
        If a file is malformed or inconsistent; the message names the file
        and the field.  Also if a requested sequence is not listed in
        ``sequences.json`` or its name is not of the form ``sequence_N``,
        if time runs backwards in ``radar_data`` or ``odometry``, and if a
        value is physically implausible (a range in mm, an azimuth in
        degrees, timestamps in s, a Doppler in km/h, a yaw in degrees, a
        mounting outside the car, ...; the
        bounds of ``sklearn_radar._schema.PLAUSIBLE_VALUES``, switched off by
        ``sklearn_radar.set_config(check_plausibility=False)``).

    See Also
    --------
    write_radarscenes : the reverse.
    sklearn_radar.datasets.make_scenes : simulated data in the same layout.
    """
    data_dir = _resolve_data_dir(Path(path))
    mounting = _read_sensors_json(data_dir / "sensors.json")
    catalogue = _read_sequences_json(data_dir / "sequences.json")
    numbers = _select_sequences(catalogue, sequences, data_dir / "sequences.json")
    parts = [_load_sequence(data_dir / f"sequence_{n}", n, mounting) for n in numbers]
    data = _concat([detections for detections, _ in parts], DETECTION_COLUMNS)
    odometry = _concat([odometry for _, odometry in parts], ODOMETRY_COLUMNS)
    return Bunch(
        data=data,
        target=instance_target(data["track_id"], data["sequence"]),
        groups=data["sequence"].to_numpy(dtype=np.int64),
        odometry=odometry,
        sensors=_sensors_frame(mounting),
        sequences=_sequences_frame(numbers, [catalogue[n] for n in numbers]),
        DESCR=(f"RadarScenes detections loaded from {data_dir}: {len(numbers)} sequence(s), {len(data)} detection(s)."),
    )


def _resolve_data_dir(path: Path) -> Path:
    if not path.is_dir():
        raise FileNotFoundError(f"RadarScenes folder not found: {path}")
    if not (path / "sequences.json").exists() and (path / "data").is_dir():
        return path / "data"
    return path


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


def _read_sensors_json(file: Path) -> dict:
    """``{sensor_id: {"x": m, "y": m, "yaw": rad}}`` from ``sensors.json``."""
    content = _expect_mapping(_read_json(file), file, "the top level")
    mounting = {}
    for name, entry in content.items():
        entry = _expect_mapping(entry, file, name)
        sensor_id = _json_int(_field(entry, "id", file, name), file, f"{name}.id")
        if sensor_id in mounting:
            raise ValueError(f"{file}: field '{name}.id': sensor id {sensor_id} occurs twice")
        mounting[sensor_id] = {
            key: _json_float(_field(entry, key, file, name), file, f"{name}.{key}") for key in ("x", "y", "yaw")
        }
    mounting = dict(sorted(mounting.items()))
    _check_plausible_mounting(mounting, file)
    return mounting


def _read_sequences_json(file: Path) -> dict:
    """``{sequence number: category}`` from ``sequences.json``."""
    content = _expect_mapping(_read_json(file), file, "the top level")
    entries = _expect_mapping(_field(content, "sequences", file, "the top level"), file, "'sequences'")
    catalogue = {}
    for name, entry in entries.items():
        match = _SEQUENCE_NAME.fullmatch(name)
        if match is None:
            raise ValueError(f"{file}: sequence name {name!r} is not of the form 'sequence_N'")
        entry = _expect_mapping(entry, file, name)
        category = _field(entry, "category", file, name)
        if category not in _CATEGORIES:
            raise ValueError(f"{file}: field '{name}.category' must be one of {list(_CATEGORIES)}, got {category!r}")
        catalogue[int(match.group(1))] = category
    if not catalogue:
        raise ValueError(f"{file}: field 'sequences' lists no sequence")
    return catalogue


def _select_sequences(catalogue: dict, sequences, file: Path) -> list:
    if sequences is None:
        return sorted(catalogue)
    if isinstance(sequences, (str, int, np.integer)):
        sequences = [sequences]
    numbers = sorted({_sequence_number(item) for item in sequences})
    unknown = [f"sequence_{n}" for n in numbers if n not in catalogue]
    if unknown:
        raise ValueError(f"{file}: sequence(s) {unknown} are not listed")
    return numbers


def _sequence_number(item) -> int:
    if isinstance(item, (bool, np.bool_)):
        raise TypeError(f"a sequence must be a name 'sequence_N' or an int, got {item!r}")
    if isinstance(item, (int, np.integer)):
        return int(item)
    if isinstance(item, str):
        match = _SEQUENCE_NAME.fullmatch(item)
        if match is None:
            raise ValueError(f"sequence name {item!r} is not of the form 'sequence_N'")
        return int(match.group(1))
    raise TypeError(f"a sequence must be a name 'sequence_N' or an int, got {item!r}")


def _load_sequence(sequence_dir: Path, number: int, mounting: dict):
    """Detections (with context columns) and odometry of one sequence folder."""
    if not sequence_dir.is_dir():
        raise FileNotFoundError(f"RadarScenes sequence folder not found: {sequence_dir}")
    h5_file = sequence_dir / "radar_data.h5"
    radar_array, odometry_array = _read_radar_data_h5(h5_file)
    radar = _file_frame(radar_array, RADAR_DATA_COLUMNS, f"{h5_file} [radar_data]")
    odometry = _file_frame(odometry_array, _ODOMETRY_FILE_COLUMNS, f"{h5_file} [odometry]")
    _check_sorted(radar["timestamp"], f"{h5_file} [radar_data]")
    _check_sorted(odometry["timestamp"], f"{h5_file} [odometry]")
    _check_plausible_radar_data(radar, f"{h5_file} [radar_data]")
    _check_plausible_odometry(odometry, f"{h5_file} [odometry]")
    _check_mounting(radar["sensor_id"], mounting, h5_file)
    scenes_file = sequence_dir / "scenes.json"
    scenes_content = _read_json(scenes_file)
    _check_sequence_name(scenes_content, sequence_dir.name, scenes_file)
    odometry_index = _detection_odometry_index(scenes_content, radar, len(odometry), scenes_file)
    # Only the sensors present: attach_context sizes a lookup table by the largest id.
    present = {k: mounting[k] for k in np.unique(radar["sensor_id"]).tolist()} or mounting
    detections = attach_context(radar, number, odometry_index, odometry, present)
    doppler = {name: detections[name].to_numpy(dtype=np.float64) for name in _DOPPLER_COLUMNS}
    check_plausible(doppler, f"{h5_file} [radar_data]")  # vr against the ego motion
    odometry.insert(0, "sequence", np.full(len(odometry), number, dtype=np.int64))
    return detections, odometry


def _read_radar_data_h5(file: Path):
    """The ``radar_data`` and ``odometry`` structured arrays of one HDF5 file."""
    if not file.is_file():
        raise FileNotFoundError(f"RadarScenes file not found: {file}")
    try:
        with h5py.File(file, "r") as h5:
            return tuple(_read_compound(h5, name, file) for name in ("radar_data", "odometry"))
    except OSError as exc:
        raise ValueError(f"{file}: not a readable HDF5 file ({exc})") from exc


def _read_compound(h5, name: str, file: Path) -> np.ndarray:
    dataset = h5.get(name)
    if not isinstance(dataset, h5py.Dataset):
        raise ValueError(f"{file}: no HDF5 dataset {name!r}; not a RadarScenes radar_data.h5")
    try:
        array = dataset[()]
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{file}: dataset {name!r} cannot be read ({exc})") from exc
    if not isinstance(array, np.ndarray) or array.ndim != 1 or array.dtype.names is None:
        raise ValueError(f"{file}: dataset {name!r} must be a 1-D compound array")
    return array


def _file_frame(array: np.ndarray, columns, table: str) -> pd.DataFrame:
    """Validate and cast the fields of a structured array to the in-memory schema."""
    fields = {}
    for name in array.dtype.names:
        values = array[name]
        if values.ndim != 1:
            raise ValueError(f"{table}: field {name!r} must be scalar, got shape {values.shape[1:]}")
        if name in _STRING_FIELDS:
            values = _decode_strings(values, f"{table}: field {name!r}")
        fields[name] = values
    frame = make_frame(fields, columns, table=table)
    _check_finite(frame, table)
    return frame


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


def _decode_strings(values: np.ndarray, where: str) -> np.ndarray:
    if values.dtype.kind not in "SO":
        return values  # make_frame reports the wrong dtype
    try:
        if values.dtype.kind == "S":
            return np.char.decode(values, "ascii")
        decoded = [item.decode("ascii") if isinstance(item, bytes) else item for item in values]
    except UnicodeDecodeError as exc:
        raise ValueError(f"{where} must hold ASCII strings ({exc})") from exc
    if not all(isinstance(item, str) for item in decoded):
        raise ValueError(f"{where} must hold strings")
    return np.array(decoded, dtype=object)


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


def _concat(frames: list, columns) -> pd.DataFrame:
    if not frames:
        empty = {c.name: np.array([], dtype="U1" if c.dtype == "str" else c.dtype) for c in columns}
        return make_frame(empty, columns, table="empty")
    return pd.concat(frames, ignore_index=True)


def _sensors_frame(mounting: dict) -> pd.DataFrame:
    index = pd.Index(list(mounting), dtype=np.int64, name="sensor_id")
    return pd.DataFrame(
        {key: np.array([m[key] for m in mounting.values()], dtype=np.float64) for key in ("x", "y", "yaw")},
        index=index,
    )


def _sequences_frame(numbers, categories) -> pd.DataFrame:
    return pd.DataFrame(
        {
            "sequence": np.asarray(numbers, dtype=np.int64),
            "name": pd.array([f"sequence_{n}" for n in numbers], dtype="str"),
            "category": pd.array(list(categories), dtype="str"),
        }
    )


# --------------------------------------------------------------------------
# Writing
# --------------------------------------------------------------------------


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


#: The file by which ``write_radarscenes(..., overwrite=True)`` knows a folder it wrote: the files it wrote.
MANIFEST = "sklearn_radar_manifest.json"
_MANIFEST_TOOL = "sklearn_radar.datasets.write_radarscenes"


def check_output_folder(path, overwrite, flag="overwrite=True"):
    """Refuse ``path`` as the output of :func:`write_radarscenes` unless writing there deletes nothing of others.

    ``path`` may be absent or an empty folder; with ``overwrite`` it may
    also be a data folder that :func:`write_radarscenes` wrote (see
    :func:`_foreign_entry`).

    Parameters
    ----------
    path : str or path-like
        The data folder to write.
    overwrite : bool
        Whether a folder written before may be replaced.
    flag : str, default="overwrite=True"
        How the error names the overwrite option (the command line's is ``--overwrite``).

    Raises
    ------
    FileExistsError
        In one line, naming ``path`` and why it is not replaced.
    """
    path = Path(path)
    blocking = blocking_file(path)
    if blocking is not None and blocking != path:
        raise FileExistsError(f"cannot create {path}: {blocking} is a file, not a folder")
    if not _is_occupied(path):
        return
    foreign = _foreign_entry(path)
    if foreign is not None:
        raise FileExistsError(f"{path} {foreign}; it is not replaced, even with {flag}: choose another folder")
    if not overwrite:
        raise FileExistsError(f"{path} exists and is not empty (data written before); pass {flag} to replace it")


def _is_occupied(path: Path) -> bool:
    """Whether anything is at ``path`` but an empty folder (a symbolic link counts, whatever it points to)."""
    if path.is_symlink():
        return True
    return path.exists() and (not path.is_dir() or any(path.iterdir()))


def _foreign_entry(path: Path):
    """Why ``path`` is not a data folder that the writer wrote (a phrase), or None if it is one.

    It is one if its manifest names the writer and lists every file below
    it; it may lack listed files (deleted since), but holds nothing else
    and no symbolic link (the writer makes none).
    """
    if path.is_symlink():
        return "is a symbolic link"
    if not path.is_dir():
        return "is a file, not a data folder"
    try:
        manifest = json.loads((path / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        manifest = None
    listed = manifest.get("files") if isinstance(manifest, dict) and manifest.get("tool") == _MANIFEST_TOOL else None
    if not isinstance(listed, list):
        return f"exists and was not written by sklearn-radar (it has no {MANIFEST})"
    listed = {*(name for name in listed if isinstance(name, str)), MANIFEST}
    folders = {folder.as_posix() for name in listed for folder in Path(name).parents}
    for entry in sorted(path.rglob("*")):
        name = entry.relative_to(path).as_posix()
        ours = name in folders if entry.is_dir() and not entry.is_symlink() else name in listed and entry.is_file()
        if not ours or entry.is_symlink():
            return f"holds {name}, which sklearn-radar did not write"
    return None


def _remove_stale_temporaries(path: Path) -> None:
    """Delete what a killed writer of ``path`` left beside it.

    Its staging folders (``.sklearn-radar-tmp-<pid>-<name>.*.tmp``, and
    ``.<name>.*.tmp`` of older versions) go when process ``<pid>`` no longer
    runs; a set-aside old copy (``*.old``) only when ``path`` exists, as it
    may otherwise be the only copy of the data.
    """
    name = re.escape(path.name)
    pattern = re.compile(rf"(?:{re.escape(TEMPORARY_PREFIX)}(?P<pid>\d+)-{name}|\.{name})\.[^/]+\.(?P<kind>tmp|old)")
    try:
        entries = list(path.parent.iterdir())
    except OSError:
        return
    for entry in entries:
        match = pattern.fullmatch(entry.name)
        if match is None or (match["kind"] == "old" and not path.exists()):
            continue
        if match["pid"] is not None and process_alive(int(match["pid"])):
            continue
        remove_entry(entry)  # one removed meanwhile, or not ours to remove: the write goes on


def _move_into_place(staging: Path, path: Path, overwrite: bool) -> None:
    """Rename ``staging`` to ``path``; an existing ``path`` is swapped out, then deleted."""
    check_output_folder(path, overwrite)  # again: the folder may have changed while the data were written
    if not _is_occupied(path):
        if path.exists():
            path.rmdir()
        os.rename(staging, path)
        return
    aside = path.with_name(f"{TEMPORARY_PREFIX}{os.getpid()}-{path.name}.{uuid_module.uuid4().hex}.old")
    os.rename(path, aside)
    try:
        os.rename(staging, path)
    except BaseException:
        os.rename(aside, path)
        raise
    if aside.is_dir() and not aside.is_symlink():
        shutil.rmtree(aside)
    else:
        aside.unlink()
