"""Tables I and II and the error windows as combinations of per-sequence parts.

The filter of Eq. 1 counts neighbours within a sequence only, and an error
window belongs to one object, which never spans sequences.  So Table I
(:func:`filter_grid`), Table II (:func:`filter_settings_table`) and the
error windows (:func:`filter_error_windows`) of a data set can be computed
one sequence (or one block of whole sequences) at a time, where the
sequence lives, as a small *part*; the parts are combined in one process
into the result of the whole table.  The whole-table functions are that
combination of one part, the whole data set: there is one implementation.

* a grid or settings part holds, per cell (or setting), the *integer*
  counts of error windows, of background rows removed and of object rows
  removed, and the numbers of background and object rows.  Counts add up,
  and the combined shares are divisions of the summed integers, so the
  result does not depend on how the data set was split.
* an error-windows part holds the sequence's own rows of the windows table;
  the combination concatenates them in object order.

A grid part's size is three ``n_vr x n_d`` integer arrays (a settings part:
three per setting) plus one value per sequence it covers, whatever the
number of detections; an error-windows part has one row per (object,
window) of its sequences.

Objects of different parts are distinct objects: the whole-table functions
need object ids unique across sequences, and each part sees its own.

Times are placed into windows with a tolerance that depends on the largest
object time of the whole data set (``_filter._time_eps``: 1 ns unless the
times exceed about 10^6 s).  A part records the tolerance it used and the
largest object time it saw; the combination checks that every part used
the whole data set's tolerance, and otherwise says which ``time_eps`` to
compute the parts with.  (With timestamps in µs since a recording's start,
or RadarScenes-like values around 1.6e5 s, the tolerance is 1 ns in every
part.)
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from numbers import Real

import numpy as np
import pandas as pd
from sklearn.utils import Bunch
from sklearn.utils._param_validation import Interval, validate_params

from ._filter import (
    _WINDOW_CONSTRAINTS,
    FilterEvaluationOptions,
    _as_keep,
    _as_target,
    _count_settings,
    _grid_rows,
    _settings_rows,
    _shares,
    _time_eps,
    _Windows,
    _windows_frame,
)

__all__ = ["filter_error_windows", "filter_errors", "filter_grid", "filter_settings_table"]

_TIME_EPS_CONSTRAINT = {"time_eps": [Interval(Real, 0, None, closed="neither"), None]}
_TABLE_CONSTRAINTS = {"X": [pd.DataFrame], "target": ["array-like"], "options": [FilterEvaluationOptions, None]}
_KEEP_CONSTRAINTS = {"keep": ["array-like"], "target": ["array-like"], "t": ["array-like"]} | _WINDOW_CONSTRAINTS


# ----------------------------------------------------------------------------
# Parts
# ----------------------------------------------------------------------------
@dataclass(frozen=True, eq=False, kw_only=True)
class _Counted:
    """What every grid and settings part holds.

    Attributes
    ----------
    options : FilterEvaluationOptions
        The options the part was computed with; they must agree between
        parts (``n_jobs`` and ``verbose`` aside).
    errors, removed_background, removed_objects : ndarray of int64
        Per cell (or setting): error windows, background rows removed,
        object rows removed.
    n_background, n_objects : int
        Background rows (target -1) and object rows of the part.
    sequences : ndarray of float64 or None
        Distinct sequence numbers of the part; None when ``X`` has no
        ``sequence`` column (then the part must be the whole data set).
    t_abs_max : float
        Largest absolute object time, s; NaN without objects.
    time_eps : float
        Tolerance used to place times into windows, s; NaN without objects.
    elapsed_s : float
        Wall time of computing the part, s.
    """

    options: FilterEvaluationOptions
    errors: np.ndarray
    removed_background: np.ndarray
    removed_objects: np.ndarray
    n_background: int
    n_objects: int
    sequences: np.ndarray | None
    t_abs_max: float
    time_eps: float
    elapsed_s: float


@dataclass(frozen=True, eq=False, kw_only=True)
class FilterGridPart(_Counted):
    """Table I counts of one sequence (or block of whole sequences), from :func:`filter_grid_parts`.

    The counts are arrays of shape (n_vr, n_d): rows ``options.vr_thresholds``
    (m/s), columns ``options.d_xys`` (m), in ``options.frame``.  The other
    attributes are those of every part (``_Counted``).
    """


@dataclass(frozen=True, eq=False, kw_only=True)
class FilterSettingsPart(_Counted):
    """Table II counts of one sequence (or block of whole sequences), from :func:`filter_settings_table_parts`.

    Attributes
    ----------
    table : DataFrame
        The checked settings (with a ``frame`` column), as the result's
        leading columns; the counts are arrays of shape (n_settings,).

    The other attributes are those of every part (``_Counted``).
    """

    table: pd.DataFrame


@dataclass(frozen=True, eq=False, kw_only=True)
class ErrorWindowsPart:
    """Error windows of one sequence (or block of whole sequences), from :func:`filter_error_windows_parts`.

    Attributes
    ----------
    windows : DataFrame
        :func:`filter_error_windows` of the part.
    options : tuple
        ``(window, min_kept)``, s and share.
    t_abs_max, time_eps : float
        Largest absolute object time and the tolerance used, s; NaN without
        objects.
    """

    windows: pd.DataFrame
    options: tuple
    t_abs_max: float
    time_eps: float


def _counted(counts, options, start):
    """The fields of :class:`_Counted` from :func:`~._filter._count_settings`'s counts."""
    windows, sequence = counts["windows"], counts["sequence"]
    return {
        "options": options,
        "n_background": counts["n_background"],
        "n_objects": counts["n_objects"],
        "sequences": None if sequence is None else np.unique(sequence),
        "t_abs_max": windows.t_abs_max,
        "time_eps": windows.time_eps,
        "elapsed_s": time.perf_counter() - start,
    }


@validate_params(_TABLE_CONSTRAINTS | _TIME_EPS_CONSTRAINT, prefer_skip_nested_validation=True)
def filter_grid_parts(X, target, options=None, *, time_eps=None) -> FilterGridPart:
    """Table I counts of one sequence (or block of whole sequences), for :func:`combine_filter_grid`.

    Parameters
    ----------
    X : DataFrame
        Raw detection table of whole sequences (with its ``sequence``
        column, unless it is the whole data set).
    target : array-like of int, shape (n_detections,)
        Instance id per detection, -1 for background.
    options : FilterEvaluationOptions, default=None
        As in :func:`filter_grid`; every part of one data set needs the
        same.
    time_eps : float, default=None
        Tolerance, s, of placing times into windows; None: the one
        derived from this part's largest object time.  Give it when
        :func:`combine_filter_grid` asks for it.

    Returns
    -------
    part : FilterGridPart
        Integer counts per cell (errors, background and object rows
        removed) and the part's row counts; a few kB.

    See Also
    --------
    combine_filter_grid : merges the parts into :func:`filter_grid`'s Bunch.
    """
    start = time.perf_counter()
    options = FilterEvaluationOptions() if options is None else options
    counts = _count_settings(X, target, _grid_rows(options), options, time_eps, "grid")
    shape = (len(options.vr_thresholds), len(options.d_xys))
    return FilterGridPart(
        errors=counts["errors"].reshape(shape),
        removed_background=counts["removed_background"].reshape(shape),
        removed_objects=counts["removed_objects"].reshape(shape),
        **_counted(counts, options, start),
    )


@validate_params(
    {"settings": [pd.DataFrame, None]} | _TABLE_CONSTRAINTS | _TIME_EPS_CONSTRAINT,
    prefer_skip_nested_validation=True,
)
def filter_settings_table_parts(X, target, settings=None, options=None, *, time_eps=None) -> FilterSettingsPart:
    """Table II counts of one sequence (or block of whole sequences), for :func:`combine_filter_settings_table`.

    Parameters
    ----------
    X : DataFrame
        Raw detection table of whole sequences.
    target : array-like of int, shape (n_detections,)
        Instance id per detection, -1 for background.
    settings, options
        As in :func:`filter_settings_table`; every part of one data set
        needs the same.
    time_eps : float, default=None
        Tolerance, s, of placing times into windows, as in
        :func:`filter_grid_parts`.

    Returns
    -------
    part : FilterSettingsPart
        Integer counts per setting and the part's row counts.

    See Also
    --------
    combine_filter_settings_table : merges the parts into :func:`filter_settings_table`'s table.
    """
    start = time.perf_counter()
    options = FilterEvaluationOptions() if options is None else options
    table = _settings_rows(settings, options.frame)
    counts = _count_settings(X, target, table, options, time_eps, "settings")
    return FilterSettingsPart(
        table=table,
        errors=counts["errors"],
        removed_background=counts["removed_background"],
        removed_objects=counts["removed_objects"],
        **_counted(counts, options, start),
    )


@validate_params(_KEEP_CONSTRAINTS | _TIME_EPS_CONSTRAINT, prefer_skip_nested_validation=True)
def filter_error_windows_parts(keep, target, t, window=0.15, min_kept=0.75, *, time_eps=None) -> ErrorWindowsPart:
    """Error windows of one sequence (or block of whole sequences), for :func:`combine_error_windows`.

    Parameters
    ----------
    keep, target, t, window, min_kept
        As in :func:`filter_error_windows`, for the part's rows (s).
    time_eps : float, default=None
        Tolerance, s, of placing times into windows, as in
        :func:`filter_grid_parts`.

    Returns
    -------
    part : ErrorWindowsPart
        The part's windows table and the tolerance it used.
    """
    keep = _as_keep(keep)
    target = _as_target(target, len(keep))
    windows = _Windows(target, t, window, time_eps)
    return ErrorWindowsPart(
        windows=_windows_frame(windows, keep, min_kept),
        options=(float(window), float(min_kept)),
        t_abs_max=windows.t_abs_max,
        time_eps=windows.time_eps,
    )


# ----------------------------------------------------------------------------
# Combining
# ----------------------------------------------------------------------------
def _check_parts(parts, kind, producer):
    """The parts as a list, all of ``kind``, computed with the same options and tolerance."""
    parts = list(parts)
    if not parts:
        raise ValueError(f"parts must not be empty: give one {producer}(...) per sequence")
    wrong = sorted({type(part).__name__ for part in parts if not isinstance(part, kind)})
    if wrong:
        raise ValueError(f"parts must hold {producer}(...) results, got {wrong}")
    first = parts[0].options
    for part in parts[1:]:
        if part.options != first:
            raise ValueError(f"parts were computed with different options: {first} and {part.options}")
    seen = [part.t_abs_max for part in parts if not np.isnan(part.t_abs_max)]
    if seen:
        needed = _time_eps(max(seen))
        used = sorted({part.time_eps for part in parts if not np.isnan(part.t_abs_max) and part.time_eps != needed})
        if used:
            raise ValueError(
                f"parts placed times into windows with a tolerance of {used} s, the whole data set needs "
                f"{needed!r} s: compute the parts again with time_eps={needed!r}"
            )
    return parts


def _check_sequences(parts):
    """No sequence in two parts; no part without a sequence column beside others."""
    if len(parts) == 1:
        return
    if any(part.sequences is None for part in parts):
        raise ValueError(
            "parts: X has no column 'sequence', so all its rows are one sequence and it cannot be split into parts"
        )
    sequences = np.concatenate([part.sequences for part in parts])
    values, counts = np.unique(sequences, return_counts=True)
    if np.any(counts > 1):
        repeated = values[counts > 1].tolist()
        raise ValueError(f"parts: sequence(s) {repeated} lie in more than one part; split the data by sequence")


def _summed(parts):
    """The parts' counts, summed; the removed shares as divisions of the sums."""
    total = Bunch(
        **{
            name: sum(getattr(part, name) for part in parts)
            for name in ("errors", "removed_background", "removed_objects", "n_background", "n_objects")
        }
    )
    total.background_removed = _shares(total.removed_background, total.n_background)
    total.objects_removed = _shares(total.removed_objects, total.n_objects)
    return total


@validate_params({"parts": [list, tuple]}, prefer_skip_nested_validation=True)
def combine_filter_grid(parts) -> Bunch:
    """Merge :func:`filter_grid_parts` of whole sequences into :func:`filter_grid`'s Bunch (Table I).

    Parameters
    ----------
    parts : list of FilterGridPart
        One per sequence (or block of whole sequences), in any order, all
        with the same options; no sequence in two parts.

    Returns
    -------
    result : Bunch
        :func:`filter_grid` of the concatenated sequences.  ``elapsed_s``
        is the sum of the parts' wall times, s (their compute time, not the
        wall time of a whole-table run).

    Raises
    ------
    ValueError
        If ``parts`` is empty or mixed, the parts' options differ, a
        sequence lies in two parts, or a part used another time tolerance
        than the whole data set needs.
    """
    parts = _check_parts(parts, FilterGridPart, "filter_grid_parts")
    _check_sequences(parts)
    options, total = parts[0].options, _summed(parts)
    index = pd.Index(np.asarray(options.vr_thresholds), name="vr_threshold")
    columns = pd.Index(np.asarray(options.d_xys), name="d_xy")
    return Bunch(
        **{
            name: pd.DataFrame(total[name], index=index, columns=columns)
            for name in ("errors", "background_removed", "objects_removed")
        },
        frame=options.frame,
        n_background=total.n_background,
        n_objects=total.n_objects,
        elapsed_s=float(sum(part.elapsed_s for part in parts)),
    )


@validate_params({"parts": [list, tuple]}, prefer_skip_nested_validation=True)
def combine_filter_settings_table(parts) -> pd.DataFrame:
    """Merge :func:`filter_settings_table_parts` of whole sequences into :func:`filter_settings_table`'s table.

    Parameters
    ----------
    parts : list of FilterSettingsPart
        One per sequence (or block of whole sequences), in any order, all
        with the same settings and options; no sequence in two parts.

    Returns
    -------
    table : DataFrame
        :func:`filter_settings_table` of the concatenated sequences.

    Raises
    ------
    ValueError
        As :func:`combine_filter_grid`, and when the parts' settings differ.
    """
    parts = _check_parts(parts, FilterSettingsPart, "filter_settings_table_parts")
    table = parts[0].table
    for part in parts[1:]:
        if not part.table.equals(table) or list(part.table.columns) != list(table.columns):
            raise ValueError("parts were computed with different settings tables")
    _check_sequences(parts)
    total = _summed(parts)
    table = table.copy()
    table["removal_rate"] = 100.0 * total.background_removed
    table["object_removal_rate"] = 100.0 * total.objects_removed
    table["errors"] = total.errors.astype(np.int64)
    return table


@validate_params({"parts": [list, tuple]}, prefer_skip_nested_validation=True)
def combine_error_windows(parts) -> pd.DataFrame:
    """Merge :func:`filter_error_windows_parts` into :func:`filter_error_windows`'s table.

    The windows of an object lie in its part, so the whole table's rows are
    the parts' rows; the combination puts them in object order (the whole
    table is sorted by ``instance`` and ``start_s``) on a fresh index.

    Parameters
    ----------
    parts : list of ErrorWindowsPart
        One per sequence (or block of whole sequences), in any order, all
        with the same ``window`` and ``min_kept``.

    Returns
    -------
    windows : DataFrame
        :func:`filter_error_windows` of the concatenated rows.

    Raises
    ------
    ValueError
        If ``parts`` is empty or mixed, the parts' options or time
        tolerances differ, or two parts hold windows of the same object id
        (the table names objects by id, so ids must be unique across
        sequences, as ``make_scenes`` and ``load_radarscenes`` number them).
    """
    parts = _check_parts(parts, ErrorWindowsPart, "filter_error_windows_parts")
    ids = np.concatenate([part.windows["instance"].unique() for part in parts])
    values, counts = np.unique(ids, return_counts=True)
    if np.any(counts > 1):
        raise ValueError(
            f"parts: object id(s) {values[counts > 1][:10].tolist()} have windows in more than one part; "
            "number the objects uniquely across sequences"
        )
    windows = pd.concat([part.windows for part in parts], ignore_index=True)
    return windows.sort_values("instance", kind="stable", ignore_index=True)


# ----------------------------------------------------------------------------
# The whole data set: one part, combined
# ----------------------------------------------------------------------------
@validate_params(_KEEP_CONSTRAINTS, prefer_skip_nested_validation=True)
def filter_error_windows(keep, target, t, window=0.15, min_kept=0.75) -> pd.DataFrame:
    """Per object and complete time window: detections, kept detections, error flag.

    For each object (``target >= 0``) with first and last detection times
    ``t0`` and ``t1``, the windows are ``[t0 + k window, t0 + (k + 1) window)``
    for every ``k >= 0`` with ``t0 + (k + 1) window <= t1``: only complete
    windows count, so an object present for less than ``window`` has none,
    and detections after the last complete window are ignored.  A window
    with ``n > 0`` detections of which ``kept`` survive the filter is an
    *error* when ``kept / n < min_kept`` (the paper: 75 % within 150 ms).

    Read more in the :ref:`User Guide <user-guide-filter>`.

    Parameters
    ----------
    keep : array-like of bool, shape (n_detections,)
        Filter output, False = removed.
    target : array-like of int, shape (n_detections,)
        Instance id per detection, -1 for background (ignored).  Ids must be
        unique across sequences (as ``make_scenes(...).target`` is).
    t : array-like of float, shape (n_detections,)
        Detection time, s (the ``t`` column of
        :class:`~sklearn_radar.FrameTransform`, i.e. ``timestamp * 1e-6``).
    window : float, default=0.15
        Window length, s, > 0.
    min_kept : float, default=0.75
        Smallest share of an object's detections in a window that must be
        kept for the window not to be an error, in [0, 1].

    Returns
    -------
    windows : DataFrame
        One row per complete window that holds at least one detection of
        its object (empty windows cannot be errors and are not listed),
        sorted by ``instance`` and ``start_s``, with columns

        ``instance`` (int), ``start_s`` (float, s: ``t0 + k window``),
        ``n`` (int, detections), ``kept`` (int, detections kept),
        ``kept_share`` (float, ``kept / n``), ``error`` (bool).

    Notes
    -----
    Times are placed into windows with a tolerance of 1 ns (or a few
    float64 spacings of the largest time, if coarser), so that a detection
    meant to lie on a window edge (timestamps are integer µs) falls into the
    window that starts there.  The work is a few sorts of
    the object rows: no Python loop over objects or detections.

    See Also
    --------
    filter_errors : the number of error windows.
    """
    return combine_error_windows([filter_error_windows_parts(keep, target, t, window, min_kept)])


@validate_params(_KEEP_CONSTRAINTS, prefer_skip_nested_validation=True)
def filter_errors(keep, target, t, window=0.15, min_kept=0.75) -> int:
    """Number of (object, time window) cases in which an object lost too many detections.

    The paper's optimisation criterion for the filter (Table I): the number
    of times a labelled road user kept less than ``min_kept`` (75 %) of its
    detections during a whole time window of ``window`` (150 ms).  Windows
    are defined per object from its first detection on, and only complete
    windows count; see :func:`filter_error_windows` for the exact rule and
    for the windows themselves.

    Read more in the :ref:`User Guide <user-guide-filter>`.

    Parameters
    ----------
    keep, target, t, window, min_kept
        As in :func:`filter_error_windows` (s).

    Returns
    -------
    errors : int
        ``filter_error_windows(...)["error"].sum()``.

    Examples
    --------
    >>> from sklearn_radar.evaluation import filter_errors
    >>> t = [0.00, 0.05, 0.10, 0.15, 0.20, 0.30]       # one object, s
    >>> keep = [True, False, False, True, True, True]  # window [0, 0.15): 1 of 3 kept
    >>> filter_errors(keep, [0] * 6, t)
    1
    """
    return int(filter_error_windows(keep, target, t, window, min_kept)["error"].sum())


@validate_params(_TABLE_CONSTRAINTS, prefer_skip_nested_validation=True)
def filter_grid(X, target, options=None) -> Bunch:
    """Enumerate the filter's two tuning parameters: the paper's Table I.

    For every pair of Doppler threshold ``eta_1`` (``vr_threshold``) and
    spatial radius ``d_xy`` of ``options`` this runs the filter of Eq. 1 and
    measures the errors (:func:`filter_errors`) and the removal rates
    (:func:`~sklearn_radar.evaluation.filter_removal_rates`).  The work is
    shared: the frame transform runs once, the neighbour counts once per
    ``d_xy`` (they do not depend on the Doppler threshold) and only Eq. 1
    itself per cell.  The result is the combination of one part
    (:func:`filter_grid_parts`), the whole data set.

    Read more in the :ref:`User Guide <user-guide-filter>`.

    Parameters
    ----------
    X : DataFrame
        Raw detection table (:mod:`sklearn_radar._schema`), e.g.
        ``make_scenes(...).data``; :class:`~sklearn_radar.FrameTransform`
        is applied here.
    target : array-like of int, shape (n_detections,)
        Instance id per detection, -1 for background, unique across
        sequences.
    options : FilterEvaluationOptions, default=None
        The grid's axes (m/s, m), the frame, Eq. 1's rule, the error window
        (s) and the parallelism; None: the paper's (Table I).

    Returns
    -------
    result : Bunch
        ``errors`` : DataFrame of int
            Error count per cell, index ``vr_threshold`` (m/s), columns
            ``d_xy`` (m): Table I.
        ``background_removed``, ``objects_removed`` : DataFrame of float
            Shares in [0, 1] on the same grid.
        ``frame`` : str
            The coordinate system used, "frame" (FCS) or "car" (CCS).
        ``n_background``, ``n_objects`` : int
            Number of background and object rows.
        ``elapsed_s`` : float
            Wall time of the enumeration, s.

    See Also
    --------
    filter_settings_table : Table II for chosen settings.
    plot_filter_errors : heatmap of ``result.errors``.

    Examples
    --------
    >>> from sklearn_radar.datasets import make_scenes
    >>> from sklearn_radar.evaluation import FilterEvaluationOptions, filter_grid
    >>> scenes = make_scenes(n_sequences=1, duration=3.0, random_state=0)
    >>> options = FilterEvaluationOptions(vr_thresholds=(0.1, 0.2), d_xys=(1.0, 1.4))
    >>> grid = filter_grid(scenes.data, scenes.target, options)
    >>> grid.errors.shape
    (2, 2)
    """
    return combine_filter_grid([filter_grid_parts(X, target, options)])


@validate_params({"settings": [pd.DataFrame, None]} | _TABLE_CONSTRAINTS, prefer_skip_nested_validation=True)
def filter_settings_table(X, target, settings=None, options=None) -> pd.DataFrame:
    """Measure chosen filter settings beside the paper's numbers: Table II.

    The result is the combination of one part
    (:func:`filter_settings_table_parts`), the whole data set.

    Read more in the :ref:`User Guide <user-guide-filter>`.

    Parameters
    ----------
    X : DataFrame
        Raw detection table; :class:`~sklearn_radar.FrameTransform` is
        applied once per distinct frame.
    target : array-like of int, shape (n_detections,)
        Instance id per detection, -1 for background.
    settings : DataFrame, default=None
        One row per setting with the columns ``vr_threshold`` (m/s),
        ``d_xy`` (m) and optionally ``frame`` ("frame" or "car";
        ``options.frame`` where absent).  Other columns are carried
        through.  None means :data:`PAPER_TABLE_II`.
    options : FilterEvaluationOptions, default=None
        Eq. 1's rule, the error window (s), the frame of the settings
        without one and the parallelism (over distinct (frame, ``d_xy``)
        pairs); its grid axes are not used.  None: the paper's.

    Returns
    -------
    table : DataFrame
        The columns of ``settings`` (for the default: ``frame``,
        ``vr_threshold``, ``d_xy``, ``paper_removal_rate`` in percent,
        ``paper_errors``) followed by the measured

        ``removal_rate`` (float, percent of background detections removed),
        ``object_removal_rate`` (float, percent of object detections
        removed) and ``errors`` (int, :func:`filter_errors`).

    Examples
    --------
    >>> from sklearn_radar.datasets import make_scenes
    >>> from sklearn_radar.evaluation import filter_settings_table
    >>> scenes = make_scenes(n_sequences=1, duration=3.0, random_state=0)
    >>> table = filter_settings_table(scenes.data, scenes.target)
    >>> list(table.columns)[-3:]
    ['removal_rate', 'object_removal_rate', 'errors']
    """
    return combine_filter_settings_table([filter_settings_table_parts(X, target, settings, options)])
