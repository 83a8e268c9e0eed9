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

from ._config import ENVIRONMENT_VARIABLE, get_config
from ._schema import (
    ANGLE_UNITS,
    DOPPLER_BAND,
    DOPPLER_MIN_DETECTIONS,
    DOPPLER_MIN_PREDICTED,
    DOPPLER_SAMPLE,
    DOPPLER_STATIC_SHARE,
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
    YAW_MAX_SLOPE,
    YAW_MIN_CORRELATION,
    YAW_MIN_STEPS,
    YAW_MIN_TURN,
    ColumnsRead,
    inexact_integers,
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
    dtype = getattr(X, "dtype", None)  # of an array before validation casts it to float64
    X = validated_input(estimator, X, reads, reset=reset)
    if isinstance(X, pd.DataFrame):
        present = [column for column in reads.names if column in X.columns]
        columns = {column: None for column in reads.names}
        columns.update({column: _numeric_column(X[column], column, name) for column in present})
        _check_exact_times(columns, {column: X[column].dtype for column in present}, name)
        check_plausible(columns, name, sensor=_sensor_of(X))
        check_unique_ids(X, columns, reads, name)
        return X, columns
    columns = _array_columns(X, reads, name)
    _check_exact_times(columns, dict.fromkeys(columns, dtype), name)
    check_plausible(columns, name, layout=reads.layout, n_columns=X.shape[1])
    return X, columns


def _check_exact_times(columns, dtypes, where):
    """A µs ``timestamp`` in a float type too narrow for its magnitude (float32 above 16.8 s) has been rounded."""
    values, dtype = columns.get("timestamp"), dtypes.get("timestamp")
    if values is None or dtype is None or not len(values):
        return
    problem = inexact_integers(np.max(np.abs(values)), dtype, "timestamp", "µs")
    if problem:
        raise ValueError(f"{where}: {problem}")


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


#: Odd 64-bit multipliers mixing the bits of the columns into one key per row (splitmix64's constants).
_MIX = (np.uint64(0x9E3779B97F4A7C15), np.uint64(0xBF58476D1CE4E5B9), np.uint64(0x94D049BB133111EB))
#: Rows whose first column hashes into the lowest 1/2**_BUCKET_BITS are compared: copies of a row share the hash.
_BUCKET_BITS = 5
#: Tables of at most this many rows are compared in full.
_ALL_ROWS = 2**12


def check_unique_ids(X, columns, reads, where):
    """Raise a ValueError when rows of the DataFrame ``X`` repeat a ``uuid`` (unless the checks are switched off).

    Rows are first compared by a 64-bit key of the first three columns
    read and the sequence (a copied row repeats them; two detections do
    not), then rows whose keys repeat by uuid.  Tables of at most 4096 rows
    are compared in full; in a larger one, each row with its neighbour, and
    the rows whose first column hashes into a fixed 1/32 of the hashes
    (which holds every copy of each row it holds).  So a table concatenated
    with itself and rows repeated in place are found, a single row copied
    elsewhere with probability 1/32.

    Parameters
    ----------
    X : DataFrame
    columns : dict of str to ndarray or None
        The columns read, float64.
    reads : ColumnsRead
    where : str
        Prefix of the message.
    """
    if "uuid" not in X.columns or len(X) < 2 or not get_config()["check_plausibility"]:
        return
    names = [name for name in (*reads.required[:3], "sequence") if columns.get(name) is not None]
    first = columns[names[0]].view(np.uint64)
    if len(first) <= _ALL_ROWS:
        rows = np.arange(len(first))
    else:
        compared = (first * _MIX[0]) >> np.uint64(64 - _BUCKET_BITS) == 0  # a fixed part of one column's values
        adjacent = first[1:] == first[:-1]
        compared[1:] |= adjacent
        compared[:-1] |= adjacent
        rows = np.flatnonzero(compared)
    key = np.zeros(len(rows), dtype=np.uint64)
    for k, name in enumerate(names):
        key ^= columns[name][rows].view(np.uint64) * _MIX[k % len(_MIX)]
        key ^= key >> np.uint64(29)
    rows = rows[_repeated(key)]
    if not len(rows):
        return
    ids = np.asarray(X["uuid"].to_numpy()[rows]).astype(str)
    repeated = _repeated(ids)
    if not repeated.any():
        return
    rows, ids = rows[repeated], ids[repeated]
    pair = rows[ids == ids[0]]
    problem = (
        f"column 'uuid' holds {str(ids[0])!r} in rows {pair[0]} and {pair[1]} (at least {len(set(ids.tolist()))} "
        f"uuid(s) repeat): the table holds duplicate rows (a table concatenated with itself, or rows repeated), which "
        f"count twice in every neighbourhood, while a uuid names one detection. Keep each row once, e.g. "
        f"X.drop_duplicates('uuid')"
    )
    raise ValueError(plausibility_message(where, [problem]))


def _repeated(values):
    """Mask of the entries of ``values`` (1-D, sortable) that occur more than once."""
    order = np.argsort(values, kind="stable")
    same = values[order[1:]] == values[order[:-1]]
    mask = np.zeros(len(values), dtype=bool)
    mask[order[1:][same]] = True
    mask[order[:-1][same]] = True
    return mask


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
    is known) within :data:`~sklearn_radar._schema.SCAN_SPACING`.  When all
    are, columns present together are compared: the ego speed with the path
    of the ego positions (``SPEED_PATH_*``), the ego yaw with its rate
    (``YAW_*``) and ``vr`` with the Doppler of the static world
    (``DOPPLER_*``).  Rows may come in any order.  Nothing is checked when
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
    if problems:
        misplaced = _misplaced_columns(columns, sequence, layout) if layout is not None else []
        raise ValueError(plausibility_message(where, problems, layout, n_columns, misplaced))
    # One column against another only in units that are each plausible, so that the first message names the cause.
    problems = _motion_problems(columns, sequence, bounds or {})
    if problems:
        raise ValueError(plausibility_message(where, problems, layout, n_columns))


def plausibility_message(where, problems, layout=None, n_columns=None, misplaced=()):
    """The error message for a list of problem descriptions (the first in full, the others listed).

    For an array (``layout`` given) whose layout looks wrong (several problems, more columns than the layout, or
    ``misplaced``: descriptions of columns that look like another column), that comes first.
    """
    found = f"{problems[0]}."
    if len(problems) > 1:
        found += (
            f" Also {len(problems) - 1} more: "
            + "; ".join(problems[1:4])
            + ("; and more" if len(problems) > 4 else "")
            + "."
        )
    switch = (
        " If the data is right, sklearn_radar.set_config(check_plausibility=False) turns these checks off (for the "
        f"command line and worker processes: the environment variable {ENVIRONMENT_VARIABLE}=0)."
    )
    if layout is None:
        return f"{where}: implausible input: {found}{switch}"
    expected = (
        f"{_layout_text(layout)}. Pass the detection table as a DataFrame (columns are found by name), or an array "
        f"in that order."
    )
    wider = n_columns is not None and n_columns > len(layout.columns)
    if misplaced or len(problems) > 1 or wider:
        evidence = "".join(f" {text}." for text in misplaced)
        return (
            f"{where}: implausible input: X is a plain array of {n_columns} column(s), so the layout (column order) "
            f"looks wrong: {expected}{evidence} Values out of their limits: {found}{switch}"
        )
    return (
        f"{where}: implausible input: {found} X is a plain array of {n_columns} column(s), check the unit, or the "
        f"layout (column order): {expected}{switch}"
    )


def _misplaced_columns(columns, sequence, layout):
    """Columns out of their limits that hold µs timestamps instead (spaced as scans): a column order gone wrong."""
    rule = SCAN_SPACING["timestamp"]
    found = []
    for name, values in columns.items():
        if values is None or name not in PLAUSIBLE_VALUES or _range_problem(name, values, name) is None:
            continue
        medians = median_scan_spacing(values, sequence)[0]
        if len(medians) and np.all((rule.low <= medians) & (medians <= rule.high)):
            found.append(
                f"Column {layout.position(name)}, read as {name!r}, holds values like µs timestamps (up to "
                f"{values.max():.6g}, distinct values a median {np.median(medians):.3g} apart, as scans are)"
            )
    return found


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


def _motion_problems(columns, sequence, bounds):
    """One column against another: the ego speed against its path, the yaw against its rate, Doppler against ego."""
    given = {bounds.get(name, name): name for name, values in columns.items() if values is not None}
    time_name = given.get("timestamp", given.get("t"))
    problems = []
    if time_name is not None and (
        {"ego_x_seq", "ego_y_seq", "ego_vx"} <= given.keys() or {"ego_yaw_seq", "ego_yaw_rate"} <= given.keys()
    ):
        steps = _ScanSteps(columns[time_name] * (1e-6 if "timestamp" in given else 1.0), sequence)
        problems += [_speed_path_problem(columns, given, time_name, steps), _yaw_problem(columns, given, steps)]
    problems.append(_doppler_problem(columns, given))
    return [problem for problem in problems if problem is not None]


def _speed_path_problem(columns, given, time_name, steps):
    """The ego speed integrated over time against the path of the ego positions (SPEED_PATH_RATIO), per sequence."""
    if not {"ego_x_seq", "ego_y_seq", "ego_vx"} <= given.keys():
        return None
    x, y, speed = (columns[given[name]][steps.rows] for name in ("ego_x_seq", "ego_y_seq", "ego_vx"))
    speed = np.abs(speed)
    path = steps.per_group(np.hypot(np.diff(x), np.diff(y)))
    integrated = steps.per_group(0.5 * (speed[1:] + speed[:-1]) * steps.dt)
    judged = np.maximum(path, integrated) >= SPEED_PATH_MIN_PATH
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(judged, integrated / path, 1.0)
    low, high = SPEED_PATH_RATIO
    bad = np.flatnonzero((ratio < low) | (ratio > high))
    if not len(bad):
        return None
    k = bad[np.argmax(np.abs(np.log(ratio[bad])))]
    return (
        f"column {given['ego_vx']!r} integrates to {integrated[k]:.4g} m over time while the ego positions "
        f"({given['ego_x_seq']!r}, {given['ego_y_seq']!r}) move {path[k]:.4g} m ({steps.group_name(k)}; ratio "
        f"{ratio[k]:.3g}, plausible {low:g}-{high:g}): {_speed_cause(ratio[k], given['ego_vx'], time_name)}"
    )


def _speed_cause(ratio, speed_name, time_name):
    for unit, per_metre_per_second in SPEED_UNITS.items():
        if abs(np.log(ratio / per_metre_per_second)) < 0.15:
            return f"{speed_name} looks like {unit}; sklearn-radar (as RadarScenes) uses m/s"
    return (
        f"their units disagree: check {speed_name} (m/s), the ego positions (m) and {time_name} "
        f"({'µs' if time_name == 'timestamp' else 's'})"
    )


def _yaw_problem(columns, given, steps):
    """The change of the ego yaw between scans against its rate integrated over time, per sequence (YAW_*)."""
    if not {"ego_yaw_seq", "ego_yaw_rate"} <= given.keys():
        return None
    yaw, rate = (columns[given[name]][steps.rows] for name in ("ego_yaw_seq", "ego_yaw_rate"))
    turned = _wrapped(_wrapped(np.diff(yaw), 360.0), 2 * np.pi)  # over a wrap in degrees or in rad
    integrated = 0.5 * (rate[1:] + rate[:-1]) * steps.dt
    n_steps = steps.per_group(np.ones_like(turned))
    covariance, variance = steps.per_group(turned * integrated), steps.per_group(integrated**2)
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = covariance / variance
        correlation = covariance / np.sqrt(variance * steps.per_group(turned**2))
    judged = (n_steps >= YAW_MIN_STEPS) & (steps.per_group(np.abs(integrated)) >= YAW_MIN_TURN)
    bad = np.flatnonzero(judged & (slope > YAW_MAX_SLOPE) & (correlation >= YAW_MIN_CORRELATION))
    if not len(bad):
        return None
    k = bad[np.argmax(slope[bad])]
    yaw_name, rate_name = given["ego_yaw_seq"], given["ego_yaw_rate"]
    degrees = abs(np.log(slope[k] / ANGLE_UNITS["degrees"])) < 0.15
    cause = (
        f"{yaw_name} looks like degrees; sklearn-radar (as RadarScenes) uses rad"
        if degrees
        else f"their units disagree: check {yaw_name} (rad), {rate_name} (rad/s) and the time"
    )
    return (
        f"column {yaw_name!r} changes {slope[k]:.3g} times as much as {rate_name!r} integrated over time "
        f"({steps.group_name(k)}; least-squares slope over {n_steps[k]:.0f} steps between scans, correlation "
        f"{correlation[k]:.2f}, plausible up to {YAW_MAX_SLOPE:g}): {cause}"
    )


def _wrapped(angle, turn):
    """``angle`` wrapped to [-turn / 2, turn / 2)."""
    return np.mod(angle + turn / 2, turn) - turn / 2


def _doppler_problem(columns, given):
    """The Doppler of detections against that of a static target, from the ego motion (DOPPLER_*)."""
    if not {"vr", "azimuth_sc", "sensor_yaw", "ego_vx"} <= given.keys():
        return None
    every = max(1, -(-len(columns[given["vr"]]) // DOPPLER_SAMPLE))

    def sample(name):
        return columns[given[name]][::every] if name in given else 0.0

    angle, yaw_rate = sample("azimuth_sc") + sample("sensor_yaw"), sample("ego_yaw_rate")
    sensor_vx, sensor_vy = sample("ego_vx") - yaw_rate * sample("sensor_y"), yaw_rate * sample("sensor_x")
    static = -(sensor_vx * np.cos(angle) + sensor_vy * np.sin(angle))  # m/s: vr of a static target
    judged = np.abs(static) >= DOPPLER_MIN_PREDICTED
    n_judged = int(np.count_nonzero(judged))
    if n_judged < DOPPLER_MIN_DETECTIONS:
        return None
    ratio = sample("vr")[judged] / static[judged]
    share = {
        unit: float(np.mean(np.abs(ratio / factor - 1.0) <= DOPPLER_BAND))
        for unit, factor in {"m/s": 1.0, **SPEED_UNITS}.items()
    }
    unit = max(SPEED_UNITS, key=share.get)
    if share[unit] < DOPPLER_STATIC_SHARE:
        return None
    return (
        f"column {given['vr']!r}: {share[unit]:.0%} of {n_judged} detections seen while the ego moves have "
        f"{SPEED_UNITS[unit]:.3g} times the radial velocity a static target has from the ego motion (ego_vx, "
        f"ego_yaw_rate, the mounting and azimuth_sc), and {share['m/s']:.0%} that velocity, while most detections of "
        f"a raw table are static: {given['vr']} looks like {unit}; sklearn-radar (as RadarScenes) uses m/s"
    )


class _ScanSteps:
    """Consecutive distinct scans per sequence, rows in any order: the steps the ego's motion is integrated over.

    ``rows``: the first row of each run of equal (time, sequence), ordered by sequence, then time; ``dt`` (s)
    between consecutive ones; a step counts when both lie in one sequence, 0 < dt <= SPEED_PATH_MAX_GAP.
    """

    def __init__(self, seconds, sequence):
        keys = [] if sequence is None else [sequence]
        rows = _run_starts(seconds, *keys)
        self.rows = rows[np.lexsort((seconds[rows], *(key[rows] for key in keys)))]
        group = np.zeros(len(self.rows), dtype=np.int64)
        if keys:
            group = np.cumsum(np.r_[False, keys[0][self.rows][1:] != keys[0][self.rows][:-1]])
        self.dt = np.diff(seconds[self.rows])
        self.step = (group[1:] == group[:-1]) & (self.dt > 0) & (self.dt <= SPEED_PATH_MAX_GAP)
        self.step_group = group[1:][self.step]
        self.n_groups = int(group[-1]) + 1 if len(group) else 0
        first_of_group = np.r_[True, group[1:] != group[:-1]] if len(group) else np.zeros(0, dtype=bool)
        self.sequences = keys[0][self.rows][first_of_group] if keys else None

    def per_group(self, per_step):
        """Sum of a value per step (one per consecutive pair of ``rows``) over the counted steps of each sequence."""
        return np.bincount(self.step_group, weights=per_step[self.step], minlength=self.n_groups)

    def group_name(self, k):
        return "one sequence" if self.sequences is None else f"sequence {self.sequences[k]:g}"


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
