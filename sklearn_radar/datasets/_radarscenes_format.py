"""The RadarScenes on-disk layout: the sequence names and categories and the fields of ``radar_data.h5``.

A RadarScenes *data folder* holds ``sensors.json``, ``sequences.json`` and
one ``sequence_N/`` folder per recording with ``radar_data.h5`` (HDF5
datasets ``radar_data`` and ``odometry``) and ``scenes.json``.  Read more in the
:ref:`User Guide <user-guide-data>`.
"""

from __future__ import annotations

import re

import numpy as np

from .._schema import CONTEXT_COLUMNS, ODOMETRY_COLUMNS, RADAR_DATA_COLUMNS, column_names

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
