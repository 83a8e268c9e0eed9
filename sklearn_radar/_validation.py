"""Input handling shared by the estimators: named columns or a positional array.

The estimators work on the detection table (:mod:`sklearn_radar._schema`)
and read the columns they need by name.  A plain numeric array is accepted
as well (scikit-learn's common checks and quick experiments use one); its
columns are read by position in :data:`ARRAY_LAYOUT`, missing trailing
columns take their defaults, and each stage writes its result back at its
own position, so that a Pipeline of arrays stays consistent.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from sklearn.utils.validation import validate_data

#: Working columns written by FrameTransform, read by the later stages:
#: x and y (m, car or frame coordinates), v_r (ego-motion-compensated radial
#: velocity, m/s), t (s) and heading (rad, the car's yaw in the x-y axes).
WORK_COLUMNS = ("x", "y", "v_r", "t", "heading")

#: Positions of the columns in a plain array, and their defaults when absent.
ARRAY_LAYOUT = {
    "x": 0.0,
    "y": 0.0,
    "v_r": 0.0,
    "t": 0.0,
    "sequence": 0.0,
    "keep": 1.0,
    "range_sc": 50.0,
    "heading": 0.0,
}


def read_columns(estimator, X, required, optional=(), *, reset, layout=None):
    """Validate ``X`` and return ``(X, columns)``, columns as float64 arrays by name.

    Parameters
    ----------
    estimator : estimator
        Receives ``n_features_in_`` (and ``feature_names_in_``) via
        :func:`~sklearn.utils.validation.validate_data`.
    X : DataFrame or array-like of shape (n_samples, n_features)
    required, optional : sequence of str
        Columns to read.  A DataFrame must hold every required column; an
        absent optional column is returned as None.  An array is read by
        position in ``layout`` and absent positions (required or optional)
        take their defaults.
    reset : bool
        True in ``fit``, False afterwards.
    layout : dict, default=None
        ``{name: default}`` in positional order; :data:`ARRAY_LAYOUT` if None.
    """
    layout = ARRAY_LAYOUT if layout is None else layout
    if isinstance(X, pd.DataFrame):
        validate_data(estimator, X, skip_check_array=True, reset=reset)
        if len(X) == 0:
            raise ValueError(f"{type(estimator).__name__}: X has 0 rows; at least 1 is required")
        missing = [name for name in required if name not in X.columns]
        if missing:
            raise ValueError(f"{type(estimator).__name__}: X is missing the column(s) {missing}")
        names = list(required) + [name for name in optional if name in X.columns]
        columns = {name: _numeric_column(X[name], name, estimator) for name in names}
        columns.update({name: None for name in optional if name not in X.columns})
        return X, columns
    X = validate_data(estimator, X, reset=reset, dtype=np.float64)
    positions = list(layout)
    columns = {}
    for name in list(required) + list(optional):
        position = positions.index(name)
        if position < X.shape[1]:
            columns[name] = X[:, position]
        else:
            columns[name] = np.full(X.shape[0], layout[name], dtype=np.float64)
    return X, columns


def write_columns(X, new_columns, layout=None):
    """``X`` with ``new_columns`` added (DataFrame) or written at their positions (array).

    Rows are never added, dropped or reordered, and ``X`` is not modified.
    An array is padded with the defaults of ``layout`` up to the last
    written position.
    """
    if isinstance(X, pd.DataFrame):
        return X.assign(**{name: np.asarray(values) for name, values in new_columns.items()})
    layout = ARRAY_LAYOUT if layout is None else layout
    positions = list(layout)
    width = max(X.shape[1], max(positions.index(name) for name in new_columns) + 1)
    out = np.empty((X.shape[0], width), dtype=np.float64)
    out[:, : X.shape[1]] = X
    for position in range(X.shape[1], width):
        out[:, position] = layout[positions[position]]
    for name, values in new_columns.items():
        out[:, positions.index(name)] = values
    return out


def _numeric_column(series, name, estimator):
    values = series.to_numpy()
    if values.dtype.kind == "b":
        values = values.astype(np.float64)
    if values.dtype.kind not in "iuf":
        raise ValueError(
            f"{type(estimator).__name__}: column {name!r} must be numeric, got dtype {series.dtype}"
        )
    values = values.astype(np.float64)
    if not np.all(np.isfinite(values)):
        raise ValueError(f"{type(estimator).__name__}: column {name!r} contains NaN or infinity")
    return values


def sequence_slices(sequence):
    """Row indices of each sequence, for per-sequence processing (order preserved)."""
    if sequence is None:
        return [slice(None)]
    codes, inverse = np.unique(sequence, return_inverse=True)
    if len(codes) == 1:
        return [slice(None)]
    order = np.argsort(inverse, kind="stable")
    bounds = np.searchsorted(inverse[order], np.arange(len(codes) + 1))
    return [order[bounds[k] : bounds[k + 1]] for k in range(len(codes))]
