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

from ._config import get_config
from ._schema import (
    MIN_DETECTIONS_PER_SCAN,
    MIN_SCANS_FOR_SPACING,
    PLAUSIBLE_VALUES,
    SCAN_SPACING,
    SPEED_PATH_MAX_GAP,
    SPEED_PATH_MIN_PATH,
    SPEED_PATH_RATIO,
    SPEED_UNITS,
    TIME_UNIT_NAMES,
    WORK_LAYOUT,
    ColumnsRead,
)


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
    X = validated_input(estimator, X, reads, reset=reset)
    if isinstance(X, pd.DataFrame):
        present = [column for column in reads.names if column in X.columns]
        columns = {column: None for column in reads.names}
        columns.update({column: _numeric_column(X[column], column, name) for column in present})
        check_plausible(columns, name, sensor=_sensor_of(X))
        return X, columns
    columns = _array_columns(X, reads, name)
    check_plausible(columns, name, layout=reads.layout, n_columns=X.shape[1])
    return X, columns


def validated_input(estimator, X, reads: ColumnsRead, *, reset):
    """X validated as :func:`read_columns` validates it (names or width, a numeric array, rows), columns unread.

    Parameters
    ----------
    estimator : estimator
        Receives ``n_features_in_`` (and ``feature_names_in_``).
    X : DataFrame or array-like
    reads : ColumnsRead
    reset : bool
        True in ``fit``.

    Returns
    -------
    X : DataFrame or ndarray of float64
    """
    name = type(estimator).__name__
    if isinstance(X, pd.DataFrame):
        validate_data(estimator, X, skip_check_array=True, reset=reset)
        if len(X) == 0:
            raise ValueError(f"{name}: X has 0 rows; at least 1 is required")
        missing = [column for column in reads.required if column not in X.columns]
        if missing:
            raise ValueError(f"{name}: X is missing the column(s) {missing}")
        return X
    _refuse_other_frames(X, reads.layout, name)
    return _validate_array(estimator, X, reads.layout, reset=reset)


def _sensor_of(X):
    """The integer ``sensor_id`` column of a DataFrame, when it has one (for the per-sensor scan spacing)."""
    if "sensor_id" not in X.columns:
        return None
    sensor = X["sensor_id"].to_numpy()
    return sensor if sensor.dtype.kind in "iu" else None


def _refuse_other_frames(X, layout, name):
    """A table that is not a pandas DataFrame (polars, pyarrow) would be read by position: refuse it by name.

    Its columns would otherwise be taken in the positional layout, a silent wrong answer for the detection table.
    """
    if hasattr(X, "columns") and (hasattr(X, "to_pandas") or hasattr(X, "__dataframe__")):
        kind = f"{type(X).__module__.split('.')[0]}.{type(X).__name__}"
        raise ValueError(
            f"{name}: X is a {kind}, whose columns would be read by position; sklearn-radar reads a table by "
            f"column name from a pandas DataFrame only: pass X.to_pandas(), or a numeric array in the order of the "
            f"{layout.name} {list(layout.columns)}"
        )


def _validate_array(estimator, X, layout, *, reset):
    """``validate_data`` as float64; an array that is not numeric is blamed on its layout."""
    try:
        return validate_data(estimator, X, reset=reset, dtype=np.float64)
    except ValueError as error:
        if "could not convert" not in str(error):
            raise
        raise ValueError(
            f"{type(estimator).__name__}: X is an array with non-numeric values ({error}), so its layout looks "
            f"wrong: {_layout_text(layout)}.  The detection table (whose uuid and track_id hold strings) must be "
            f"passed as the DataFrame itself, not as .to_numpy(); its columns are then found by name."
        ) from error


def _layout_text(layout):
    return f"a plain array is read by position as the {layout.name}, columns {list(layout.columns)}"


def _array_columns(X, reads, name):
    """The columns of ``reads`` from a validated array, by position; see :func:`read_columns`."""
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
    return columns


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


def _numeric_column(series, name, where, rows=None):
    """A DataFrame column (at ``rows``, None: all) as float64; a ValueError, prefixed by ``where``, if it is not
    numeric or not finite."""
    values = series.to_numpy()
    if rows is not None:
        values = values[rows]
    if values.dtype.kind not in "biuf":
        raise ValueError(f"{where}: column {name!r} must be numeric, got dtype {series.dtype}")
    values = values.astype(np.float64)
    if not np.all(np.isfinite(values)):
        raise ValueError(f"{where}: column {name!r} contains NaN or infinity")
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


# --------------------------------------------------------------------------
# Physical plausibility (the bounds are sklearn_radar._schema.PLAUSIBLE_VALUES and SCAN_SPACING)
# --------------------------------------------------------------------------


def check_plausible(columns, where, *, sequence=None, sensor=None, layout=None, n_columns=None, bounds=None):
    """Raise a ValueError when a column holds a physically implausible value (unless switched off).

    Every column of ``columns`` with a bound in
    :data:`~sklearn_radar._schema.PLAUSIBLE_VALUES` must lie within it, and
    the time columns ``timestamp`` (µs) and ``t`` (s) must have a median
    spacing of distinct scan times per sequence (and per sensor, where it
    is known) within :data:`~sklearn_radar._schema.SCAN_SPACING`.  Rows may
    come in any order.  Nothing is checked when
    ``sklearn_radar.get_config()["check_plausibility"]`` is False.

    Parameters
    ----------
    columns : dict of str to ndarray or None
        Columns by name; None (absent) and unbounded columns are skipped.
    where : str
        Prefix of the message (estimator or file name).
    sequence : ndarray, default=None
        Sequence of each row; None: ``columns["sequence"]`` if present, else one sequence.
    sensor : ndarray, default=None
        Sensor of each row, when known.
    layout : ArrayLayout, default=None
        The layout the columns were read by, for array input: the message then says so.
    n_columns : int, default=None
        Width of that array.
    bounds : dict of str to str, default=None
        The bound of a column stored under another name, e.g. ``{"vx": "ego_vx"}`` for the odometry.

    Raises
    ------
    ValueError
        Naming the column, the value seen, the likely cause and, for an
        array, the layout it was read by.
    """
    if not get_config()["check_plausibility"]:
        return
    if sequence is None:
        sequence = columns.get("sequence")
    problems = [
        problem
        for name, values in columns.items()
        if values is not None and len(values)
        for problem in (
            _range_problem(name, values, (bounds or {}).get(name, name)),
            _spacing_problem(name, values, sequence, sensor),
        )
        if problem is not None
    ]
    if not problems:  # the speed is compared with the path only in units that are each plausible
        problems = [p for p in (_speed_path_problem(columns, sequence, bounds or {}),) if p is not None]
    if problems:
        raise ValueError(plausibility_message(where, problems, layout, n_columns))


def plausibility_message(where, problems, layout=None, n_columns=None):
    """The error message for a list of problem descriptions (the first in full, the others listed)."""
    text = f"{where}: implausible input: {problems[0]}."
    if len(problems) > 1:
        text += (
            f" Also {len(problems) - 1} more: "
            + "; ".join(problems[1:4])
            + ("; and more" if len(problems) > 4 else "")
            + "."
        )
    if layout is not None:
        wider = n_columns is not None and n_columns > len(layout.columns)
        if len(problems) > 1 or wider:
            verdict = "so the layout (column order) looks wrong"
        else:
            verdict = "check the unit, or the layout (column order)"
        text += (
            f" X is a plain array of {n_columns} column(s), {verdict}: {_layout_text(layout)}. "
            f"Pass the detection table as a DataFrame (columns are found by name), or an array in that order."
        )
    return text + " If the data is right, sklearn_radar.set_config(check_plausibility=False) turns these checks off."


def _range_problem(name, values, bound_name):
    bound = PLAUSIBLE_VALUES.get(bound_name)
    if bound is None:
        return None
    low, high = values.min(), values.max()
    if low < bound.low:
        row = int(np.argmin(values))
        return (
            f"column {name!r} holds {low:.6g} {bound.unit} (row {row}), below the plausible {bound.low:.6g} "
            f"{bound.unit}: {bound.too_low}"
        )
    if high > bound.high:
        row = int(np.argmax(values))
        return (
            f"column {name!r} holds {high:.6g} {bound.unit} (row {row}), above the plausible {bound.high:.6g} "
            f"{bound.unit}: {bound.too_high}"
        )
    return None


def _spacing_problem(name, times, sequence, sensor):
    spacing_rule = SCAN_SPACING.get(name)
    if spacing_rule is None:
        return None
    medians, sequences, sensors = median_scan_spacing(times, sequence, sensor)
    if not len(medians):
        return None
    worst = int(np.argmin(medians)) if medians.min() < spacing_rule.low else int(np.argmax(medians))
    spacing = medians[worst]
    if spacing_rule.low <= spacing <= spacing_rule.high:
        return None
    group = "one sequence" if sequences is None else f"sequence {sequences[worst]:g}"
    if sensors is not None:
        group += f", sensor {sensors[worst]:g}"
    side = (
        f"below the plausible {spacing_rule.low:g}"
        if spacing < spacing_rule.low
        else f"above the plausible {spacing_rule.high:g}"
    )
    unit = spacing_rule.likely_unit(spacing, per_sensor=sensors is not None)
    if unit == spacing_rule.unit:  # no other unit makes it a typical spacing
        cause = spacing_rule.too_dense if spacing < spacing_rule.low else "no radar scans that seldom"
    else:
        cause = f"{name} looks like {TIME_UNIT_NAMES[unit]}; {spacing_rule.convention}"
    return (
        f"column {name!r}: distinct scan times are a median {spacing:.3g} {spacing_rule.unit} apart ({group}), "
        f"{side} {spacing_rule.unit}: {cause}"
    )


def _speed_path_problem(columns, sequence, bounds):
    """The ego speed integrated over time against the path of the ego positions (SPEED_PATH_RATIO), per sequence."""
    given = {bounds.get(name, name): name for name, values in columns.items() if values is not None}
    if not {"ego_x_seq", "ego_y_seq", "ego_vx"} <= given.keys() or not {"timestamp", "t"} & given.keys():
        return None
    time_name = given.get("timestamp", given.get("t"))
    seconds = columns[time_name] * (1e-6 if "timestamp" in given else 1.0)
    x, y, speed = (columns[given[name]] for name in ("ego_x_seq", "ego_y_seq", "ego_vx"))
    path, integrated, sequences = _path_and_integrated_speed(seconds, x, y, speed, sequence)
    judged = np.maximum(path, integrated) >= SPEED_PATH_MIN_PATH
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(judged, integrated / path, 1.0)
    low, high = SPEED_PATH_RATIO
    bad = np.flatnonzero((ratio < low) | (ratio > high))
    if not len(bad):
        return None
    k = bad[np.argmax(np.abs(np.log(ratio[bad])))]
    group = "one sequence" if sequences is None else f"sequence {sequences[k]:g}"
    return (
        f"column {given['ego_vx']!r} integrates to {integrated[k]:.4g} m over time while the ego positions "
        f"({given['ego_x_seq']!r}, {given['ego_y_seq']!r}) move {path[k]:.4g} m ({group}; ratio {ratio[k]:.3g}, "
        f"plausible {low:g}-{high:g}): {_speed_cause(ratio[k], given['ego_vx'], time_name)}"
    )


def _speed_cause(ratio, speed_name, time_name):
    for unit, per_metre_per_second in SPEED_UNITS.items():
        if abs(np.log(ratio / per_metre_per_second)) < 0.15:
            return f"{speed_name} looks like {unit}; sklearn-radar (as RadarScenes) uses m/s"
    return (
        f"their units disagree: check {speed_name} (m/s), the ego positions (m) and {time_name} "
        f"({'µs' if time_name == 'timestamp' else 's'})"
    )


def _path_and_integrated_speed(seconds, x, y, speed, sequence):
    """Per sequence: the path of (x, y) and the integral of ``|speed|`` over consecutive scans (gaps <= MAX_GAP)."""
    keys = [] if sequence is None else [sequence]
    rows = _run_starts(seconds, *keys)
    order = np.lexsort((seconds[rows], *(key[rows] for key in keys)))
    rows = rows[order]
    t, px, py, v = seconds[rows], x[rows], y[rows], np.abs(speed[rows])
    group = np.zeros(len(rows), dtype=np.int64)
    if keys:
        group = np.cumsum(np.r_[False, keys[0][rows][1:] != keys[0][rows][:-1]])
    dt = np.diff(t)
    step = (group[1:] == group[:-1]) & (dt > 0) & (dt <= SPEED_PATH_MAX_GAP)
    n_groups = int(group[-1]) + 1 if len(group) else 0
    path = np.bincount(group[1:][step], weights=np.hypot(np.diff(px), np.diff(py))[step], minlength=n_groups)
    integrated = np.bincount(group[1:][step], weights=(0.5 * (v[1:] + v[:-1]) * dt)[step], minlength=n_groups)
    first_of_group = np.r_[True, group[1:] != group[:-1]] if len(group) else np.zeros(0, dtype=bool)
    sequences = keys[0][rows][first_of_group] if keys else None
    return path, integrated, sequences


def _run_starts(*columns):
    """First row of each run of rows equal in every column: rows come scan by scan, so a few runs per scan."""
    start = np.zeros(len(columns[0]), dtype=bool)
    start[:1] = True
    for values in columns:
        start[1:] |= values[1:] != values[:-1]
    return np.flatnonzero(start)


def median_scan_spacing(times, sequence=None, sensor=None):
    """Median spacing of the distinct values of ``times`` within each sequence (and sensor), rows in any order.

    Parameters
    ----------
    times : ndarray of float, shape (n,)
        Scan time of each row (one scan: one time).
    sequence, sensor : ndarray of shape (n,) or None
        Group keys; None: one group.

    Returns
    -------
    medians : ndarray of float
        One per group with at least :data:`~sklearn_radar._schema.MIN_SCANS_FOR_SPACING` distinct times
        and on average at least :data:`~sklearn_radar._schema.MIN_DETECTIONS_PER_SCAN` rows per time.
    sequences, sensors : ndarray or None
        The keys of those groups (None when the key was not given).
    """
    keys = [key for key in (sensor, sequence) if key is not None]
    # Rows come scan by scan in most tables: work on runs of equal (time, keys), a few per scan, not on rows.
    starts = _run_starts(times, *keys)
    if len(starts) < MIN_SCANS_FOR_SPACING:  # fewer runs than scans needed (one scan of a stream): nothing to judge
        empty = np.zeros(0)
        return empty, (empty if sequence is not None else None), (empty if sensor is not None else None)
    run_rows = np.diff(np.r_[starts, len(times)])
    times, keys = times[starts], [key[starts] for key in keys]
    order = np.lexsort((times, *keys))  # by sequence, then sensor, then time
    times, run_rows, keys = times[order], run_rows[order], [key[order] for key in keys]
    new_group = np.zeros(len(times), dtype=bool)
    new_group[:1] = True
    for key in keys:
        new_group[1:] |= key[1:] != key[:-1]
    group_keys = [key[new_group] for key in keys]
    group_of_run = np.cumsum(new_group) - 1
    distinct = new_group.copy()
    distinct[1:] |= times[1:] != times[:-1]
    scan_times = times[distinct]
    scan_group = group_of_run[distinct]
    n_groups = int(scan_group[-1]) + 1 if len(scan_group) else 0
    n_scans = np.bincount(scan_group, minlength=n_groups)
    n_rows = np.bincount(group_of_run, weights=run_rows, minlength=n_groups)
    same_group = scan_group[1:] == scan_group[:-1]
    gaps = np.diff(scan_times)[same_group]
    gap_group = scan_group[1:][same_group]
    order = np.lexsort((gaps, gap_group))
    gaps, gap_group = gaps[order], gap_group[order]
    n_gaps = np.bincount(gap_group, minlength=n_groups)
    start = np.r_[0, np.cumsum(n_gaps)[:-1]]
    judged = np.flatnonzero((n_scans >= MIN_SCANS_FOR_SPACING) & (n_rows >= MIN_DETECTIONS_PER_SCAN * n_scans))
    lower = gaps[start[judged] + (n_gaps[judged] - 1) // 2]
    upper = gaps[start[judged] + n_gaps[judged] // 2]
    medians = 0.5 * (lower + upper)
    sequences = group_keys[-1][judged] if sequence is not None else None
    sensors = group_keys[0][judged] if sensor is not None else None
    return medians, sequences, sensors
