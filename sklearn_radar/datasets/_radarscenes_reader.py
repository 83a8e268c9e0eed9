"""Read the RadarScenes on-disk format into the data Bunch.

The reader turns a RadarScenes data folder (:mod:`._radarscenes_format`)
into the data :class:`~sklearn.utils.Bunch` described in
:mod:`sklearn_radar._schema`.  Every malformed input raises
:class:`FileNotFoundError` (missing file or folder) or :class:`ValueError`
naming the file and, where there is one, the field
(:mod:`._radarscenes_checks`).
"""

from __future__ import annotations

import os
from numbers import Integral
from pathlib import Path

import h5py
import numpy as np
import pandas as pd
from sklearn.utils import Bunch
from sklearn.utils._param_validation import validate_params

from .._schema import (
    DETECTION_COLUMNS,
    ODOMETRY_COLUMNS,
    RADAR_DATA_COLUMNS,
    attach_context,
    make_frame,
)
from .._validation import check_plausible
from ._bunch import data_bunch
from ._radarscenes_checks import (
    _DOPPLER_COLUMNS,
    _check_finite,
    _check_mounting,
    _check_plausible_mounting,
    _check_plausible_odometry,
    _check_plausible_radar_data,
    _check_sequence_name,
    _check_sorted,
    _detection_odometry_index,
    _expect_mapping,
    _field,
    _json_float,
    _json_int,
    _read_json,
)
from ._radarscenes_format import _CATEGORIES, _ODOMETRY_FILE_COLUMNS, _SEQUENCE_NAME, _STRING_FIELDS

__all__ = ["load_radarscenes"]


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
    categories = [catalogue[n] for n in numbers]
    description = (
        f"RadarScenes detections loaded from {data_dir}: {len(numbers)} sequence(s), {len(data)} detection(s)."
    )
    return data_bunch(data, odometry, mounting, numbers, categories, description)


def _resolve_data_dir(path: Path) -> Path:
    if not path.is_dir():
        raise FileNotFoundError(f"RadarScenes folder not found: {path}")
    if not (path / "sequences.json").exists() and (path / "data").is_dir():
        return path / "data"
    return path


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


def _concat(frames: list, columns) -> pd.DataFrame:
    if not frames:
        empty = {c.name: np.array([], dtype="U1" if c.dtype == "str" else c.dtype) for c in columns}
        return make_frame(empty, columns, table="empty")
    return pd.concat(frames, ignore_index=True)
