"""Reading the detections of the clusters only: the classifier stage touches few rows of a large table.

:func:`~sklearn_radar._validation.read_columns` converts and checks every
row of every column an estimator reads.  ClusterClassifier's features depend
on the clustered detections only (a tenth to a fifth of a filtered table),
and on the time and sequence of all detections (the windows start at each
sequence's first detection).  Converting and checking all rows of its twelve
columns would cost a large share of its prediction time
(:ref:`classification-cost`), so it validates X as
``read_columns`` does (names or width, a numeric array, no empty input),
then reads ``t`` and ``sequence`` for all rows and the other columns only
at the rows it uses, each checked as ``read_columns`` checks it: numeric,
finite, physically plausible.
"""

from __future__ import annotations

import pandas as pd

from .._schema import ColumnsRead
from .._validation import _array_columns, _numeric_column, _sensor_of, check_plausible


def time_columns(estimator, X, reads):
    """``t`` (s) and ``sequence`` (None when absent) of every row, checked (the scan spacing per sensor too)."""
    every = ColumnsRead(required=("t",), optional=("sequence",), layout=reads.layout)
    return columns_at(estimator, X, every, None)


def columns_at(estimator, X, reads, rows, *, skip=()):
    """The columns of ``reads`` (float64; None when absent) at ``rows`` (None: all), checked.

    Parameters
    ----------
    estimator : estimator
        Named in the error messages.
    X : DataFrame or ndarray
        Validated by :func:`~sklearn_radar._validation.validated_input`.
    reads : ColumnsRead
    rows : ndarray of int or None
    skip : tuple of str, default=()
        Columns not to read (None in the result).

    Returns
    -------
    columns : dict of str to ndarray or None
    """
    name = type(estimator).__name__
    names = [column for column in reads.names if column not in skip]
    if isinstance(X, pd.DataFrame):
        columns = {
            column: _numeric_column(X[column], column, name, rows) if column in X.columns else None for column in names
        }
        check_plausible(columns, name, sensor=_sensor_of(X) if rows is None else None)
        return columns
    every = _array_columns(X, reads, name)  # validated: float64 and finite
    columns = {
        column: every[column] if every[column] is None or rows is None else every[column][rows] for column in names
    }
    check_plausible(columns, name, layout=reads.layout, n_columns=X.shape[1])
    return columns
