"""Evaluation of the Doppler-density filter: Sec. "Filtering Results", Tables I and II.

The filter of Eq. 1 (:class:`~sklearn_radar.DopplerDensityFilter`) is tuned
on two parameters, the Doppler threshold ``eta_1`` (``vr_threshold``, m/s)
and the spatial radius ``d_xy`` (m).  The paper enumerates a grid of both
and, for every cell, counts the *errors*: the number of times a labelled
road user kept less than 75 % of its detections during a whole 150 ms time
frame (Table I).  For a few promising settings it then reports the share of
background detections removed (Table II).

This module holds the evaluation's options (:class:`FilterEvaluationOptions`),
its checks, the error windows and the counting; the tables themselves are
sums of per-sequence counts (:mod:`sklearn_radar.evaluation._filter_parts`).

Units: positions and radii in m, velocities in m/s, times in s, shares in
[0, 1] unless a column says percent.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from numbers import Integral, Real
from typing import ClassVar

import numpy as np
import pandas as pd
from joblib import Parallel, delayed
from sklearn.utils._param_validation import (
    HasMethods,
    Interval,
    StrOptions,
    validate_parameter_constraints,
    validate_params,
)

from .._validation import check_filter_rule
from ..preprocessing import FrameTransform
from ..preprocessing._doppler_density_filter import _doppler_density_keep, _neighbor_counts

__all__ = [
    "PAPER_TABLE_II",
    "FilterEvaluationOptions",
    "filter_removal_rates",
    "plot_filter_errors",
]

#: Tolerance (s) when placing times into windows: timestamps are integer µs
#: scaled to s, so a detection meant to lie exactly on a window edge may sit
#: a rounding error below it.  Raised to a few float64 spacings of the
#: largest time when those are coarser (very large absolute timestamps).
_TIME_EPS = 1e-9

#: Table II of Scheiner et al. (2019): the filter settings discussed in the
#: paper, their background removal rate (percent) and their number of errors.
#: ``frame`` uses the names of :class:`~sklearn_radar.FrameTransform`
#: ("car" = CCS, "frame" = FCS).
PAPER_TABLE_II = pd.DataFrame(
    {
        "frame": ["car", "frame", "frame", "frame", "frame"],
        "vr_threshold": [0.10, 0.10, 0.35, 0.20, 0.35],
        "d_xy": [1.4, 1.4, 0.8, 1.4, 1.2],
        "paper_removal_rate": [25.10, 29.10, 31.47, 35.45, 36.91],
        "paper_errors": np.array([0, 0, 0, 1, 1], dtype=np.int64),
    }
)

#: Table I's axes: Doppler thresholds eta_1 (m/s) and radii d_xy (m), the defaults of :class:`FilterEvaluationOptions`.
TABLE_I_VR_THRESHOLDS = (0.05, 0.10, 0.15, 0.20, 0.25, 0.30, 0.35)
TABLE_I_D_XYS = (0.8, 1.0, 1.2, 1.4, 1.6, 1.8, 2.0)


# ----------------------------------------------------------------------------
# Input checks
# ----------------------------------------------------------------------------
def _as_keep(keep, name="keep"):
    keep = np.asarray(keep)
    if keep.ndim != 1:
        raise ValueError(f"{name} must be 1-D, got shape {keep.shape}")
    if keep.dtype.kind == "b":
        return keep
    if keep.dtype.kind not in "iuf" or not np.all((keep == 0) | (keep == 1)):
        raise ValueError(f"{name} must be boolean (or 0/1), got dtype {keep.dtype}")
    return keep.astype(bool)


def _as_target(target, n_rows):
    target = np.asarray(target)
    if target.ndim != 1:
        raise ValueError(f"target must be 1-D, got shape {target.shape}")
    if target.dtype.kind == "f":
        if not np.all(np.isfinite(target)) or np.any(target != np.round(target)):
            raise ValueError("target must hold integer instance ids (-1 = background)")
    elif target.dtype.kind not in "iu":
        raise ValueError(f"target must hold integer instance ids, got dtype {target.dtype}")
    target = target.astype(np.int64)
    if len(target) != n_rows:
        raise ValueError(f"keep and target have different lengths: {n_rows} and {len(target)}")
    if np.any(target < -1):
        raise ValueError("target must be -1 (background) or a non-negative instance id")
    return target


#: Constraints of the error-window rule, shared by every function that counts errors.
_WINDOW_CONSTRAINTS = {
    "window": [Interval(Real, 0, None, closed="neither")],
    "min_kept": [Interval(Real, 0, 1, closed="both")],
}


def _check_grid(values, name, allow_zero):
    values = np.asarray(values, dtype=np.float64).ravel()
    if len(values) == 0:
        raise ValueError(f"{name} must not be empty")
    low_ok = values >= 0 if allow_zero else values > 0
    if not np.all(np.isfinite(values) & low_ok):
        raise ValueError(f"{name} must be finite and {'>= 0' if allow_zero else '> 0'}, got {values.tolist()}")
    if len(np.unique(values)) != len(values):
        raise ValueError(f"{name} must not repeat values, got {values.tolist()}")
    return values


def _floats(values):
    return tuple(float(value) for value in np.asarray(values, dtype=np.float64).ravel())


@dataclass(frozen=True, kw_only=True)
class FilterEvaluationOptions:
    """The options of the filter evaluation (Tables I and II), checked once, when made.

    One frozen (hashable, comparable) object for
    :func:`~sklearn_radar.evaluation.filter_grid`,
    :func:`~sklearn_radar.evaluation.filter_settings_table` and their
    per-sequence parts.  A cell of the grid, or a setting of the table,
    equals ``FrameTransform(frame=frame)`` followed by
    ``DopplerDensityFilter(vr_threshold=..., d_xy=..., dt=dt, causal=causal,
    threshold_ratios=threshold_ratios, min_neighbors=min_neighbors)``
    (Eq. 1), scored with :func:`~sklearn_radar.evaluation.filter_errors`
    (``window``, ``min_kept``).  Each option is kept as the attribute of the
    same name, the array-likes as tuples (of floats; of ints for
    ``min_neighbors``).

    Parameters
    ----------
    vr_thresholds : array-like of float, default=(0.05, 0.10, ..., 0.35)
        Table I's rows: distinct Doppler thresholds ``eta_1``, m/s, each
        >= 0 (the paper: 0.05 to 0.35 m/s).  Table II takes its thresholds
        from its settings instead.
    d_xys : array-like of float, default=(0.8, 1.0, ..., 2.0)
        Table I's columns: distinct spatial radii ``d_xy``, m, each > 0 (the
        paper: 0.8 to 2.0 m).  Table II takes its radii from its settings.
    frame : {"frame", "car"}, default="frame"
        Coordinate system: "frame" (FCS) or "car" (CCS); for Table II the
        frame of the settings that lack a ``frame`` column.
    dt : float, default=0.25
        Neighbour time window of Eq. 1, s, >= 0.
    causal : bool, default=False
        Count only neighbours at or before a detection's time.
    threshold_ratios : array-like of float, default=(1, 5, 10, 50)
        ``eta_1 / eta_i`` of Eq. 1, each > 0.
    min_neighbors : array-like of int, default=(2, 3, 4, 10)
        ``N_i`` of Eq. 1, each >= 1, one per ratio; the neighbour counts are
        capped at their maximum.
    window : float, default=0.15
        Error window, s, > 0.
    min_kept : float, default=0.75
        Share of an object's detections per window that must be kept, in
        [0, 1].
    n_jobs : int, default=None
        Number of (frame, ``d_xy``) pairs processed in parallel (joblib
        threads; the neighbour-count kernel releases the GIL).  None means
        1, -1 all cores.  Does not change the results, so two options that
        differ only in ``n_jobs`` or ``verbose`` compare equal.
    verbose : int or bool, default=0
        If > 0, print one line per finished (frame, ``d_xy``) pair to
        stdout.

    Raises
    ------
    InvalidParameterError
        A ValueError naming the option of a wrong type or out of range.
    ValueError
        If an axis is empty or repeats a value, or ``threshold_ratios`` and
        ``min_neighbors`` do not form a rule of Eq. 1.

    Examples
    --------
    >>> from sklearn_radar.evaluation import FilterEvaluationOptions
    >>> options = FilterEvaluationOptions(vr_thresholds=(0.1, 0.2), d_xys=(1.4,), frame="car")
    >>> options.vr_thresholds, options.window
    ((0.1, 0.2), 0.15)
    """

    vr_thresholds: tuple = TABLE_I_VR_THRESHOLDS
    d_xys: tuple = TABLE_I_D_XYS
    frame: str = "frame"
    dt: float = 0.25
    causal: bool = False
    threshold_ratios: tuple = (1.0, 5.0, 10.0, 50.0)
    min_neighbors: tuple = (2, 3, 4, 10)
    window: float = 0.15
    min_kept: float = 0.75
    n_jobs: int | None = field(default=None, compare=False)
    verbose: int = field(default=0, compare=False)

    _parameter_constraints: ClassVar[dict] = {
        "vr_thresholds": ["array-like"],
        "d_xys": ["array-like"],
        "frame": [StrOptions({"frame", "car"})],
        "dt": [Interval(Real, 0, None, closed="left")],
        "causal": ["boolean"],
        "threshold_ratios": ["array-like"],
        "min_neighbors": ["array-like"],
        **_WINDOW_CONSTRAINTS,
        "n_jobs": [Integral, None],
        "verbose": ["verbose"],
    }

    def __post_init__(self):
        values = {option.name: getattr(self, option.name) for option in fields(self)}
        validate_parameter_constraints(self._parameter_constraints, values, caller_name=type(self).__name__)
        ratios, n_min = check_filter_rule(self.threshold_ratios, self.min_neighbors)
        checked = {
            "vr_thresholds": _floats(_check_grid(self.vr_thresholds, "vr_thresholds", allow_zero=True)),
            "d_xys": _floats(_check_grid(self.d_xys, "d_xys", allow_zero=False)),
            "dt": float(self.dt),
            "causal": bool(self.causal),
            "threshold_ratios": _floats(ratios),
            "min_neighbors": tuple(int(n) for n in n_min),
            "window": float(self.window),
            "min_kept": float(self.min_kept),
        }
        for name, value in checked.items():
            object.__setattr__(self, name, value)  # frozen: the checked values, set once here


# ----------------------------------------------------------------------------
# Removal rates of one keep mask
# ----------------------------------------------------------------------------
def _removed(keep, background):
    """Background rows and object rows that ``keep`` removes: counts, so that parts add up."""
    removed = ~keep
    return int(np.count_nonzero(removed & background)), int(np.count_nonzero(removed & ~background))


def _shares(removed, n):
    """Removed share(s) of a group of ``n`` rows, 0.0 when the group is empty (as :func:`filter_removal_rates`)."""
    removed = np.asarray(removed, dtype=np.int64)
    return removed / n if n else np.zeros(removed.shape)


@validate_params({"keep": ["array-like"], "target": ["array-like"]}, prefer_skip_nested_validation=True)
def filter_removal_rates(keep, target) -> dict:
    """Shares of background and of object detections that a filter removed.

    Read more in the :ref:`User Guide <user-guide-filter>`.

    Parameters
    ----------
    keep : array-like of bool, shape (n_detections,)
        Filter output, False = removed (the ``keep`` column of
        :class:`~sklearn_radar.DopplerDensityFilter`).
    target : array-like of int, shape (n_detections,)
        Instance id per detection, -1 for background.

    Returns
    -------
    rates : dict
        ``background_removed`` : float in [0, 1]
            Share of background rows (``target == -1``) with ``keep`` False;
            the paper's "removal rate" (as a share, not percent).
        ``objects_removed`` : float in [0, 1]
            Share of object rows (``target >= 0``) with ``keep`` False.
        ``n_background``, ``n_objects`` : int
            Number of background and object rows.

        A share is 0.0 when its group is empty.

    Examples
    --------
    >>> from sklearn_radar.evaluation import filter_removal_rates
    >>> rates = filter_removal_rates([False, True, True, False], [-1, -1, 3, 3])
    >>> rates["background_removed"], rates["objects_removed"]
    (0.5, 0.5)
    """
    keep = _as_keep(keep)
    background = _as_target(target, len(keep)) == -1
    n_background = int(background.sum())
    n_objects = int(len(keep) - n_background)
    removed_background, removed_objects = _removed(keep, background)
    return {
        "background_removed": removed_background / n_background if n_background else 0.0,
        "objects_removed": removed_objects / n_objects if n_objects else 0.0,
        "n_background": n_background,
        "n_objects": n_objects,
    }


# ----------------------------------------------------------------------------
# Error windows
# ----------------------------------------------------------------------------
def _windows_frame(windows, keep, min_kept):
    """:func:`filter_error_windows`'s table of prepared windows and a checked boolean ``keep``."""
    kept = windows.kept(keep)
    share = kept / np.maximum(windows.n, 1)  # n >= 1 for every listed window
    return pd.DataFrame(
        {
            "instance": windows.instance,
            "start_s": windows.start_s,
            "n": windows.n,
            "kept": kept,
            "kept_share": share,
            "error": windows.errors(kept, min_kept),
        }
    )


def _time_eps(t_abs_max):
    """Tolerance (s) of placing times into windows when the largest object time is ``t_abs_max`` (s)."""
    return max(_TIME_EPS, 8 * float(np.spacing(t_abs_max)))


class _Windows:
    """The complete, occupied (object, time window) cells of a labelling.

    They depend on ``target``, ``t`` and ``window`` only, not on the filter,
    so a grid search builds them once and counts kept detections per cell.
    ``time_eps`` (s) replaces the tolerance derived from the largest object
    time; ``t_abs_max`` and ``time_eps`` record what was used (NaN without
    objects), so that per-sequence parts can check they used the whole data
    set's tolerance.
    """

    def __init__(self, target, t, window, time_eps=None):
        t = np.asarray(t, dtype=np.float64)
        if t.shape != target.shape:
            raise ValueError(f"t must have the shape of target {target.shape}, got {t.shape}")
        if not isinstance(window, Real) or not np.isfinite(window) or window <= 0:
            raise ValueError(f"window must be a positive number of seconds, got {window!r}")
        self.rows = np.zeros(0, np.int64)  # object rows that lie in a complete window
        self.cell = np.zeros(0, np.int64)  # their window number, 0 .. n_cells - 1
        self.instance = np.zeros(0, np.int64)
        self.start_s = np.zeros(0, np.float64)
        self.n = np.zeros(0, np.int64)
        self.t_abs_max = self.time_eps = float("nan")
        object_rows = np.flatnonzero(target >= 0)
        if len(object_rows) == 0:
            return
        obj_t = t[object_rows]
        if not np.all(np.isfinite(obj_t)):
            raise ValueError("t contains NaN or infinity")
        instances, inverse = np.unique(target[object_rows], return_inverse=True)
        inverse = inverse.ravel()
        self.t_abs_max = float(np.abs(obj_t).max())
        self.time_eps = _time_eps(self.t_abs_max) if time_eps is None else float(time_eps)
        eps = self.time_eps / window  # in windows

        # First and last time of every object: sort by object, reduce per block.
        order = np.argsort(inverse, kind="stable")
        starts = np.searchsorted(inverse[order], np.arange(len(instances)))
        t_sorted = obj_t[order]
        t0 = np.minimum.reduceat(t_sorted, starts)
        t1 = np.maximum.reduceat(t_sorted, starts)
        n_windows = np.floor((t1 - t0) / window + eps).astype(np.int64)

        # Window k of each detection; keep those in a complete window (k < n_windows).
        k = np.floor((obj_t - t0[inverse]) / window + eps).astype(np.int64)
        complete = k < n_windows[inverse]
        if not np.any(complete):
            return
        offsets = np.concatenate(([0], np.cumsum(n_windows)[:-1]))
        keys, cell, n = np.unique(offsets[inverse[complete]] + k[complete], return_inverse=True, return_counts=True)

        # Back from the flat key to (object, k); keys are sorted, hence so are the cells.
        owner = np.searchsorted(offsets, keys, side="right") - 1
        self.rows = object_rows[complete]
        self.cell = cell.ravel().astype(np.int64)
        self.instance = instances[owner].astype(np.int64)
        self.start_s = t0[owner] + (keys - offsets[owner]) * window
        self.n = n.astype(np.int64)

    def kept(self, keep):
        """Kept detections per window."""
        return np.bincount(self.cell, weights=keep[self.rows], minlength=len(self.n)).astype(np.int64)

    def errors(self, kept, min_kept):
        """Error flag per window: ``kept / n < min_kept``."""
        return kept / np.maximum(self.n, 1) < min_kept


# ----------------------------------------------------------------------------
# Counting: Tables I and II are counts of filter settings
# ----------------------------------------------------------------------------
def _working_columns(X, frame):
    """FrameTransform once; the float64 arrays the filter reads."""
    Xt = FrameTransform(frame=frame).fit_transform(X)
    columns = {name: Xt[name].to_numpy(dtype=np.float64) for name in ("x", "y", "v_r", "t")}
    columns["sequence"] = Xt["sequence"].to_numpy(dtype=np.float64) if "sequence" in Xt.columns else None
    return columns


def _scores(c, counts, vr_threshold, background, windows, options):
    """(errors, background rows removed, object rows removed) of one setting: counts, so that parts add up."""
    keep = _doppler_density_keep(
        c["v_r"], counts, float(vr_threshold), np.asarray(options.threshold_ratios), np.asarray(options.min_neighbors)
    )
    errors = int(np.count_nonzero(windows.errors(windows.kept(keep), options.min_kept)))
    return (errors, *_removed(keep, background))


def _measure(tasks, background, windows, options):
    """Score filter settings, sharing the neighbour counts of each (frame, d_xy).

    Parameters
    ----------
    tasks : list of (columns, d_xy, vr_thresholds)
        Working columns of one frame, one radius d_xy (m) and the Doppler
        thresholds eta_1 (m/s) to score with its counts.
    background : ndarray of bool
        Rows with target -1.
    windows : _Windows
        The prepared error windows.
    options : FilterEvaluationOptions
        Eq. 1's rule, ``dt``, ``causal``, ``min_kept`` and ``n_jobs`` (tasks
        processed in parallel, joblib threads; the count kernel releases the
        GIL).

    Yields
    ------
    (k, errors, removed_background, removed_objects)
        Per finished task k (in completion order), int64 arrays over its
        thresholds: error windows, background rows and object rows removed.
    """
    cap = max(options.min_neighbors)

    def measure(k):
        c, d_xy, vr_thresholds = tasks[k]
        # n_jobs=1 inside: the parallelism is over the tasks.
        counts = _neighbor_counts(
            c["x"], c["y"], c["t"], c["sequence"], float(d_xy), options.dt, options.causal, cap, 1
        )
        cells = [_scores(c, counts, vr, background, windows, options) for vr in vr_thresholds]
        errors, background_removed, objects_removed = (np.array(v, dtype=np.int64) for v in zip(*cells, strict=True))
        return k, errors, background_removed, objects_removed

    yield from Parallel(n_jobs=options.n_jobs, prefer="threads", return_as="generator_unordered")(
        delayed(measure)(k) for k in range(len(tasks))
    )


def _settings_rows(settings, frame):
    """The checked settings table (Table II's rows), with a ``frame`` column; None means :data:`PAPER_TABLE_II`."""
    table = (PAPER_TABLE_II if settings is None else settings).copy().reset_index(drop=True)
    missing = [name for name in ("vr_threshold", "d_xy") if name not in table.columns]
    if missing:
        raise ValueError(f"settings is missing the column(s) {missing}")
    if "frame" not in table.columns:
        table.insert(0, "frame", frame)
    unknown = sorted(set(table["frame"]) - {"frame", "car"})
    if unknown:
        raise ValueError(f"settings: frame must be 'frame' or 'car', got {unknown}")
    _check_grid(table["vr_threshold"].unique(), "settings vr_threshold", allow_zero=True)
    _check_grid(table["d_xy"].unique(), "settings d_xy", allow_zero=False)
    return table


def _grid_rows(options):
    """Table I as a settings table: one row per cell, row-major (``vr_threshold`` slow, ``d_xy`` fast)."""
    vr, d_xy = np.meshgrid(options.vr_thresholds, options.d_xys, indexing="ij")
    return pd.DataFrame({"frame": options.frame, "vr_threshold": vr.ravel(), "d_xy": d_xy.ravel()})


def _count_settings(X, target, table, options, time_eps, label):
    """The integer counts of the filter settings in the rows of the checked ``table``.

    Each distinct frame is transformed once, the neighbour counts are
    computed once per (frame, ``d_xy``) (they do not depend on the Doppler
    threshold) and only Eq. 1 itself per row.  ``label`` names the table in
    the progress lines.

    Returns
    -------
    counts : dict
        ``errors``, ``removed_background``, ``removed_objects``: int64 arrays
        of shape (n_rows,); ``n_background``, ``n_objects``: ints;
        ``windows``: the error windows (their ``t_abs_max`` and
        ``time_eps``); ``sequence``: the sequence column (None without one).
    """
    target = _as_target(target, len(X))
    working = {name: _working_columns(X, name) for name in table["frame"].unique()}
    # t does not depend on the frame, so neither do the error windows.
    first = next(iter(working.values()))
    windows = _Windows(target, first["t"], options.window, time_eps)
    groups = list(table.groupby(["frame", "d_xy"], sort=False).groups.items())
    tasks = [
        (working[frame_name], d_xy, table.loc[rows, "vr_threshold"].to_numpy(dtype=np.float64))
        for (frame_name, d_xy), rows in groups
    ]
    background = target == -1
    errors, removed_background, removed_objects = (np.zeros(len(table), dtype=np.int64) for _ in range(3))
    results = _measure(tasks, background, windows, options)
    for done, (k, cell_errors, cell_background, cell_objects) in enumerate(results, start=1):
        (frame_name, d_xy), rows = groups[k]
        positions = table.index.get_indexer(rows)
        errors[positions], removed_background[positions], removed_objects[positions] = (
            cell_errors,
            cell_background,
            cell_objects,
        )
        if options.verbose > 0:
            print(f"filter {label} [{frame_name}] d_xy={d_xy:.2f} m: {done}/{len(groups)} done", flush=True)
    n_background = int(np.count_nonzero(background))
    return {
        "errors": errors,
        "removed_background": removed_background,
        "removed_objects": removed_objects,
        "n_background": n_background,
        "n_objects": len(target) - n_background,
        "windows": windows,
        "sequence": first["sequence"],
    }


# ----------------------------------------------------------------------------
# Plot
# ----------------------------------------------------------------------------
@validate_params(
    {
        "errors": [pd.DataFrame],
        "ax": [HasMethods(["imshow", "text"]), None],
        "chosen": [tuple, None],
        "vmax": [Interval(Real, 0, None, closed="neither"), None],
        "colorbar": ["boolean"],
    },
    prefer_skip_nested_validation=True,
)
def plot_filter_errors(errors, ax=None, chosen=(0.10, 1.4), *, vmax=None, colorbar=True):
    """Heatmap of the filter error matrix (Table I).

    Read more in the :ref:`User Guide <user-guide-filter>`.

    Parameters
    ----------
    errors : DataFrame
        Error counts with index ``vr_threshold`` (m/s) and columns ``d_xy``
        (m), e.g. ``filter_grid(...).errors``.
    ax : matplotlib Axes, default=None
        Axes to draw into (anything with ``imshow`` and ``text``); a new
        figure when None.
    chosen : tuple of (vr_threshold, d_xy) or None, default=(0.10, 1.4)
        Setting marked with an asterisk (the paper's choice), centred above
        the cell's count, and an outline; None for no mark.  Matched to the
        grid with a tolerance of 1e-9.
    vmax : float or None, default=None
        Count of the darkest colour; the scale starts at 0.  None: the
        grid's largest count.  Give two grids the same ``vmax`` to compare
        their shades.
    colorbar : bool, default=True
        Draw a colour bar beside the axes (False: draw one yourself, e.g.
        one for several grids, from ``ax.images[0]``).

    Returns
    -------
    ax : matplotlib Axes
        With one text per cell (its count), the asterisk as one more text,
        ``d_xy`` on x, ``vr_threshold`` (eta_1) on y in the order of the
        table's rows (the first on top) and, with ``colorbar``, a colour
        bar.

    Raises
    ------
    ImportError
        When matplotlib is not installed.
    ValueError
        When ``chosen`` is not a cell of the grid.
    """
    try:
        import matplotlib.pyplot as plt
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError(
            "plot_filter_errors needs matplotlib, an optional dependency of sklearn-radar; "
            "install it with `pip install matplotlib` or `pip install sklearn-radar[plot]`."
        ) from exc
    values = errors.to_numpy(dtype=np.float64)
    vr_values = np.asarray(errors.index, dtype=np.float64)
    d_values = np.asarray(errors.columns, dtype=np.float64)
    if ax is None:
        _, ax = plt.subplots(figsize=(1.0 + 0.8 * len(d_values), 0.8 + 0.6 * len(vr_values)))

    finite = values[np.isfinite(values)]
    high = float(vmax) if vmax is not None else (float(finite.max()) if finite.size else 0.0)
    # The first row on top, as in the table; the scale from 0, so that a shade means one count.
    image = ax.imshow(
        values, origin="upper", aspect="auto", cmap="Reds", interpolation="nearest", vmin=0, vmax=max(high, 1.0)
    )
    if colorbar:
        ax.figure.colorbar(image, ax=ax, label="errors (object windows below min. kept share)")
    ax.set_xticks(np.arange(len(d_values)), [f"{d:.1f}" for d in d_values])
    ax.set_yticks(np.arange(len(vr_values)), [f"{v:.2f}" for v in vr_values])
    ax.set_xlabel("d_xy (m)")
    ax.set_ylabel("eta_1 (m/s)")

    for i in range(len(vr_values)):
        for j in range(len(d_values)):
            value = values[i, j]
            dark = high > 0 and np.isfinite(value) and value > 0.6 * high
            label = f"{value:g}" if np.isfinite(value) else "-"
            ax.text(j, i, label, ha="center", va="center", color="white" if dark else "black")

    if chosen is not None:
        vr_chosen, d_chosen = chosen
        rows = np.flatnonzero(np.isclose(vr_values, vr_chosen, rtol=0, atol=1e-9))
        cols = np.flatnonzero(np.isclose(d_values, d_chosen, rtol=0, atol=1e-9))
        if len(rows) == 0 or len(cols) == 0:
            raise ValueError(f"chosen={chosen!r} is not a cell of the error grid")
        i, j = rows[0], cols[0]
        dark = high > 0 and values[i, j] > 0.6 * high
        colour = "white" if dark else "black"
        # Centred in its cell, above the count (the first row is on top: up is -y).
        ax.text(j, i - 0.27, "*", ha="center", va="center", fontsize="large", fontweight="bold", color=colour)
        ax.add_patch(plt.Rectangle((j - 0.5, i - 0.5), 1, 1, fill=False, edgecolor=colour, linewidth=2))
    ax.set_title("Filter errors per setting (* chosen)")
    return ax
