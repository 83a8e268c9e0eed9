"""The data Bunch that :func:`load_radarscenes` and :func:`make_scenes` return.

Its tables are described in :mod:`sklearn_radar._schema`.  Read more in the
:ref:`User Guide <user-guide-data>`.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from sklearn.utils import Bunch

from .._schema import instance_target


def data_bunch(data, odometry, mounting, numbers, categories, description) -> Bunch:
    """The data Bunch of the detection table ``data`` and the ``odometry`` of the sequences ``numbers``.

    ``mounting`` is ``{sensor_id: {"x": m, "y": m, "yaw": rad}}``, ``categories``
    the category of each sequence (``"train"`` or ``"validation"``) and
    ``description`` the Bunch's ``DESCR``.
    """
    return Bunch(
        data=data,
        target=instance_target(data["track_id"], data["sequence"]),
        groups=data["sequence"].to_numpy(dtype=np.int64),
        odometry=odometry,
        sensors=mounting_frame(mounting),
        sequences=sequences_frame(numbers, categories),
        DESCR=description,
    )


def mounting_frame(mounting) -> pd.DataFrame:
    """The sensor mounting as a DataFrame indexed by ``sensor_id`` (columns x, y in m, yaw in rad)."""
    ids = sorted(int(k) for k in mounting)
    frame = pd.DataFrame(
        {field: np.array([float(mounting[k][field]) for k in ids]) for field in ("x", "y", "yaw")},
        index=pd.Index(np.array(ids, dtype=np.int64), name="sensor_id"),
    )
    return frame


def sequences_frame(numbers, categories) -> pd.DataFrame:
    """The ``sequences`` table: number, name ``sequence_N`` and category of each sequence."""
    return pd.DataFrame(
        {
            "sequence": np.asarray(numbers, dtype=np.int64),
            "name": pd.array([f"sequence_{n}" for n in numbers], dtype="str"),
            "category": pd.array(list(categories), dtype="str"),
        }
    )
