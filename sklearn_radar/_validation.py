"""Input handling shared by the estimators: named columns or a positional array.

The estimators work on the detection table (:mod:`sklearn_radar._schema`)
and read the columns they need by name.  A plain numeric array is accepted
as well (scikit-learn's common checks and quick experiments use one).  What
each estimator reads, and how an array holds it, is one contract defined in
:mod:`sklearn_radar._schema` (:class:`~sklearn_radar._schema.ColumnsRead`,
:data:`~sklearn_radar._schema.WORK_LAYOUT`): here it is only applied.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from sklearn.utils.validation import validate_data

from ._schema import WORK_LAYOUT, ColumnsRead


def read_columns(estimator, X, reads: ColumnsRead, *, reset):
    """Validate ``X`` and return ``(X, columns)``, columns as float64 arrays by name.

    Parameters
    ----------
    estimator : estimator
        Receives ``n_features_in_`` (and ``feature_names_in_``) via
        :func:`~sklearn.utils.validation.validate_data`.
    X : DataFrame or array-like of shape (n_samples, n_features)
        Detections.
    reads : ColumnsRead
        The columns to read.  A DataFrame must hold every required column;
        an absent optional column is returned as None.  An array is read by
        position in ``reads.layout``: an absent column takes its neutral
        value, or is None (optional) or an error (required) when it has none.
    reset : bool
        True in ``fit``, False afterwards.

    Returns
    -------
    X : DataFrame or ndarray
        The validated input.
    columns : dict of str to ndarray or None
        Every column of ``reads``.
    """
    name = type(estimator).__name__
    if isinstance(X, pd.DataFrame):
        validate_data(estimator, X, skip_check_array=True, reset=reset)
        if len(X) == 0:
            raise ValueError(f"{name}: X has 0 rows; at least 1 is required")
        missing = [column for column in reads.required if column not in X.columns]
        if missing:
            raise ValueError(f"{name}: X is missing the column(s) {missing}")
        present = [column for column in reads.names if column in X.columns]
        columns = {column: None for column in reads.names}
        columns.update({column: _numeric_column(X[column], column, estimator) for column in present})
        return X, columns
    X = validate_data(estimator, X, reset=reset, dtype=np.float64)
    layout = reads.layout
    columns = {}
    for column in reads.names:
        position = layout.position(column)
        if position < X.shape[1]:
            columns[column] = X[:, position]
        elif column in layout.neutral:
            columns[column] = np.full(X.shape[0], layout.neutral[column], dtype=np.float64)
        elif column in reads.required:
            raise ValueError(
                f"{name}: the {layout.name} has {X.shape[1]} column(s); column {column!r} "
                f"(position {position}) is required"
            )
        else:
            columns[column] = None
    return X, columns


def write_columns(X, new_columns, layout=WORK_LAYOUT):
    """``X`` with ``new_columns`` added (DataFrame) or written at their positions (array).

    Rows are never added, dropped or reordered, and ``X`` is not modified.
    An array is widened up to the last written position; the columns in
    between take their neutral values (a ValueError names one that has none).

    Parameters
    ----------
    X : DataFrame or ndarray of shape (n_samples, n_features)
        The input of a transformer.
    new_columns : dict of str to array-like of shape (n_samples,)
        Columns to add or overwrite.
    layout : ArrayLayout, default=WORK_LAYOUT
        Positions of the columns of an array.

    Returns
    -------
    Xt : DataFrame or ndarray
        X with the new columns.
    """
    if isinstance(X, pd.DataFrame):
        return X.assign(**{name: np.asarray(values) for name, values in new_columns.items()})
    width = max(X.shape[1], max(layout.position(name) for name in new_columns) + 1)
    out = np.empty((X.shape[0], width), dtype=np.float64)
    out[:, : X.shape[1]] = X
    for position in range(X.shape[1], width):
        column = layout.columns[position]
        if column in new_columns:
            continue
        if column not in layout.neutral:
            raise ValueError(f"cannot widen the {layout.name}: column {column!r} has no neutral value")
        out[:, position] = layout.neutral[column]
    for name, values in new_columns.items():
        out[:, layout.position(name)] = values
    return out


def check_filter_rule(threshold_ratios, min_neighbors):
    """Eq. 1's ratios eta_1 / eta_i and neighbour minima N_i as arrays; ValueError names a bad one."""
    ratios = np.asarray(threshold_ratios, dtype=np.float64).ravel()
    min_neighbors_ = np.asarray(min_neighbors).ravel()
    if len(ratios) == 0 or len(ratios) != len(min_neighbors_):
        raise ValueError(
            "threshold_ratios and min_neighbors must be non-empty and of equal length, "
            f"got {len(ratios)} and {len(min_neighbors_)}"
        )
    if not np.all(ratios > 0):
        raise ValueError(f"threshold_ratios must be positive, got {threshold_ratios!r}")
    if min_neighbors_.dtype.kind not in "iu" or not np.all(min_neighbors_ >= 1):
        raise ValueError(f"min_neighbors must be integers >= 1, got {min_neighbors!r}")
    return ratios, min_neighbors_


def _numeric_column(series, name, estimator):
    values = series.to_numpy()
    if values.dtype.kind == "b":
        values = values.astype(np.float64)
    if values.dtype.kind not in "iuf":
        raise ValueError(f"{type(estimator).__name__}: column {name!r} must be numeric, got dtype {series.dtype}")
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
