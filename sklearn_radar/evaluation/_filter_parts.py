"""Mergeable per-sequence summaries of the filter evaluation, Tables I and II (issue 14).

The filter of Eq. 1 counts neighbours within a sequence only, and an error
window belongs to one object, which never spans sequences.  So Table I
(:func:`~sklearn_radar.evaluation.filter_grid`), Table II
(:func:`~sklearn_radar.evaluation.filter_settings_table`) and the error
windows (:func:`~sklearn_radar.evaluation.filter_error_windows`) of a data
set can be computed one sequence (or one block of whole sequences) at a
time, where the sequence lives, as a small *part*; the parts are combined
in one process into the result of the whole table:

* a grid or settings part holds, per cell (or setting), the *integer*
  counts of error windows, of background rows removed and of object rows
  removed, and the numbers of background and object rows.  Counts add up,
  and the combined shares are the same divisions of the same integers as
  the whole table's, so the result is equal bit for bit.
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
    _EVALUATION_CONSTRAINTS,
    _WINDOW_CONSTRAINTS,
    TABLE_I_D_XYS,
    TABLE_I_VR_THRESHOLDS,
    _as_keep,
    _as_target,
    _grid_counts,
    _grid_result,
    _settings_counts,
    _settings_result,
    _settings_rows,
    _time_eps,
    _Windows,
    _windows_frame,
)

_TIME_EPS_CONSTRAINT = {"time_eps": [Interval(Real, 0, None, closed="neither"), None]}


# ----------------------------------------------------------------------------
# Parts
# ----------------------------------------------------------------------------
@dataclass(frozen=True, eq=False, kw_only=True)
class _Counted:
    """What every grid and settings part holds besides its counts.

    Attributes
    ----------
    options : tuple
        The settings that must agree between parts: frame, ``dt`` (s),
        ``causal``, the rule of Eq. 1, ``window`` (s), ``min_kept`` and the
        grid axes (m/s, m) or the settings table.
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

    options: tuple
    n_background: int
    n_objects: int
    sequences: np.ndarray | None
    t_abs_max: float
    time_eps: float
    elapsed_s: float


@dataclass(frozen=True, eq=False, kw_only=True)
class FilterGridPart(_Counted):
    """Table I counts of one sequence (or block of whole sequences), from :func:`filter_grid_parts`.

    Attributes
    ----------
    frame : str
        "frame" (FCS) or "car" (CCS).
    vr_thresholds : ndarray of float64 of shape (n_vr,)
        Doppler thresholds eta_1, m/s (the rows).
    d_xys : ndarray of float64 of shape (n_d,)
        Spatial radii, m (the columns).
    errors, removed_background, removed_objects : ndarray of int64 of shape (n_vr, n_d)
        Per cell: error windows, background rows removed, object rows
        removed.

    The other attributes are those of every part (``_Counted``).
    """

    frame: str
    vr_thresholds: np.ndarray
    d_xys: np.ndarray
    errors: np.ndarray
    removed_background: np.ndarray
    removed_objects: np.ndarray


@dataclass(frozen=True, eq=False, kw_only=True)
class FilterSettingsPart(_Counted):
    """Table II counts of one sequence (or block of whole sequences), from :func:`filter_settings_table_parts`.

    Attributes
    ----------
    table : DataFrame
        The checked settings (with a ``frame`` column), as the result's
        leading columns.
    errors, removed_background, removed_objects : ndarray of int64 of shape (n_settings,)
        Per setting: error windows, background rows removed, object rows
        removed.

    The other attributes are those of every part (``_Counted``).
    """

    table: pd.DataFrame
    errors: np.ndarray
    removed_background: np.ndarray
    removed_objects: np.ndarray


@dataclass(frozen=True, eq=False, kw_only=True)
class ErrorWindowsPart:
    """Error windows of one sequence (or block of whole sequences), from :func:`filter_error_windows_parts`.

    Attributes
    ----------
    windows : DataFrame
        :func:`~sklearn_radar.evaluation.filter_error_windows` of the part.
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


def _grid_options(frame, dt, causal, threshold_ratios, min_neighbors, window, min_kept):
    ratios = tuple(np.asarray(threshold_ratios, dtype=np.float64).ravel().tolist())
    n_min = tuple(np.asarray(min_neighbors, dtype=np.float64).ravel().tolist())
    return (frame, float(dt), bool(causal), ratios, n_min, float(window), float(min_kept))


def _sequences(sequence):
    return None if sequence is None else np.unique(sequence)


@validate_params(
    {"vr_thresholds": ["array-like"], "d_xys": ["array-like"]} | _EVALUATION_CONSTRAINTS | _TIME_EPS_CONSTRAINT,
    prefer_skip_nested_validation=True,
)
def filter_grid_parts(
    X,
    target,
    vr_thresholds=TABLE_I_VR_THRESHOLDS,
    d_xys=TABLE_I_D_XYS,
    *,
    frame="frame",
    dt=0.25,
    causal=False,
    threshold_ratios=(1, 5, 10, 50),
    min_neighbors=(2, 3, 4, 10),
    window=0.15,
    min_kept=0.75,
    n_jobs=None,
    verbose=0,
    time_eps=None,
) -> FilterGridPart:
    """Table I counts of one sequence (or block of whole sequences), for :func:`combine_filter_grid`.

    Parameters
    ----------
    X : DataFrame
        Raw detection table of whole sequences (with its ``sequence``
        column, unless it is the whole data set).
    target : array-like of int, shape (n_detections,)
        Instance id per detection, -1 for background.
    vr_thresholds, d_xys, frame, dt, causal, threshold_ratios, min_neighbors, window, min_kept, n_jobs, verbose
        As in :func:`~sklearn_radar.evaluation.filter_grid` (m/s, m, s);
        every part of one data set needs the same.
    time_eps : float, default=None
        Tolerance, s, of placing times into windows; None: the one
        ``filter_grid`` derives from this part's largest object time.  Give
        it when :func:`combine_filter_grid` asks for it.

    Returns
    -------
    part : FilterGridPart
        Integer counts per cell (errors, background and object rows
        removed) and the part's row counts; a few kB.

    See Also
    --------
    combine_filter_grid : merges the parts into ``filter_grid``'s Bunch.
    """
    start = time.perf_counter()
    counts = _grid_counts(
        X, target, vr_thresholds, d_xys, frame, dt, causal, threshold_ratios, min_neighbors, window, min_kept,
        n_jobs, verbose, time_eps,
    )  # fmt: skip
    options = _grid_options(frame, dt, causal, threshold_ratios, min_neighbors, window, min_kept)
    return FilterGridPart(
        options=(*options, tuple(counts.vr_thresholds.tolist()), tuple(counts.d_xys.tolist())),
        n_background=counts.n_background,
        n_objects=counts.n_objects,
        sequences=_sequences(counts.sequence),
        t_abs_max=counts.windows.t_abs_max,
        time_eps=counts.windows.time_eps,
        elapsed_s=time.perf_counter() - start,
        frame=frame,
        vr_thresholds=counts.vr_thresholds,
        d_xys=counts.d_xys,
        errors=counts.errors,
        removed_background=counts.removed_background,
        removed_objects=counts.removed_objects,
    )


@validate_params(
    {"settings": [pd.DataFrame, None]} | _EVALUATION_CONSTRAINTS | _TIME_EPS_CONSTRAINT,
    prefer_skip_nested_validation=True,
)
def filter_settings_table_parts(
    X,
    target,
    settings=None,
    *,
    frame="frame",
    dt=0.25,
    causal=False,
    threshold_ratios=(1, 5, 10, 50),
    min_neighbors=(2, 3, 4, 10),
    window=0.15,
    min_kept=0.75,
    n_jobs=None,
    verbose=0,
    time_eps=None,
) -> FilterSettingsPart:
    """Table II counts of one sequence (or block of whole sequences), for :func:`combine_filter_settings_table`.

    Parameters
    ----------
    X : DataFrame
        Raw detection table of whole sequences.
    target : array-like of int, shape (n_detections,)
        Instance id per detection, -1 for background.
    settings, frame, dt, causal, threshold_ratios, min_neighbors, window, min_kept, n_jobs, verbose
        As in :func:`~sklearn_radar.evaluation.filter_settings_table`
        (m/s, m, s); every part of one data set needs the same.
    time_eps : float, default=None
        Tolerance, s, of placing times into windows, as in
        :func:`filter_grid_parts`.

    Returns
    -------
    part : FilterSettingsPart
        Integer counts per setting and the part's row counts.

    See Also
    --------
    combine_filter_settings_table : merges the parts into ``filter_settings_table``'s table.
    """
    start = time.perf_counter()
    table = _settings_rows(settings, frame)
    counts = _settings_counts(
        X, target, table, dt, causal, threshold_ratios, min_neighbors, window, min_kept, n_jobs, verbose, time_eps
    )
    options = _grid_options(frame, dt, causal, threshold_ratios, min_neighbors, window, min_kept)[1:]
    return FilterSettingsPart(
        options=options,
        n_background=counts.n_background,
        n_objects=counts.n_objects,
        sequences=_sequences(counts.sequence),
        t_abs_max=counts.windows.t_abs_max,
        time_eps=counts.windows.time_eps,
        elapsed_s=time.perf_counter() - start,
        table=table,
        errors=counts.errors,
        removed_background=counts.removed_background,
        removed_objects=counts.removed_objects,
    )


@validate_params(
    {"keep": ["array-like"], "target": ["array-like"], "t": ["array-like"]}
    | _WINDOW_CONSTRAINTS
    | _TIME_EPS_CONSTRAINT,
    prefer_skip_nested_validation=True,
)
def filter_error_windows_parts(keep, target, t, window=0.15, min_kept=0.75, *, time_eps=None) -> ErrorWindowsPart:
    """Error windows of one sequence (or block of whole sequences), for :func:`combine_error_windows`.

    Parameters
    ----------
    keep : array-like of bool, shape (n_detections,)
        Filter output of the part's rows, False = removed.
    target : array-like of int, shape (n_detections,)
        Instance id per detection, -1 for background.
    t : array-like of float, shape (n_detections,)
        Detection time, s.
    window : float, default=0.15
        Window length, s, > 0.
    min_kept : float, default=0.75
        Share of an object's detections per window that must be kept, in
        [0, 1].
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


def _sum_counts(parts):
    return {
        name: sum(getattr(part, name) for part in parts)
        for name in ("errors", "removed_background", "removed_objects", "n_background", "n_objects")
    }


@validate_params({"parts": [list, tuple]}, prefer_skip_nested_validation=True)
def combine_filter_grid(parts) -> Bunch:
    """Merge :func:`filter_grid_parts` of whole sequences into ``filter_grid``'s Bunch (Table I).

    Parameters
    ----------
    parts : list of FilterGridPart
        One per sequence (or block of whole sequences), in any order, all
        with the same options; no sequence in two parts.

    Returns
    -------
    result : Bunch
        Equal to :func:`~sklearn_radar.evaluation.filter_grid` of the
        concatenated sequences: ``errors`` (int), ``background_removed``
        and ``objects_removed`` (shares in [0, 1], the same divisions of the
        same integer counts), ``frame``, ``n_background`` and
        ``n_objects``.  ``elapsed_s`` is the sum of the parts' wall times,
        s (their compute time, not the wall time of a whole-table run).

    Raises
    ------
    ValueError
        If ``parts`` is empty or mixed, the parts' options differ, a
        sequence lies in two parts, or a part used another time tolerance
        than the whole data set needs.
    """
    parts = _check_parts(parts, FilterGridPart, "filter_grid_parts")
    _check_sequences(parts)
    first = parts[0]
    counts = Bunch(vr_thresholds=first.vr_thresholds, d_xys=first.d_xys, **_sum_counts(parts))
    return _grid_result(counts, first.frame, float(sum(part.elapsed_s for part in parts)))


@validate_params({"parts": [list, tuple]}, prefer_skip_nested_validation=True)
def combine_filter_settings_table(parts) -> pd.DataFrame:
    """Merge :func:`filter_settings_table_parts` of whole sequences into ``filter_settings_table``'s table.

    Parameters
    ----------
    parts : list of FilterSettingsPart
        One per sequence (or block of whole sequences), in any order, all
        with the same settings and options; no sequence in two parts.

    Returns
    -------
    table : DataFrame
        Equal to :func:`~sklearn_radar.evaluation.filter_settings_table` of
        the concatenated sequences: the settings' columns, then
        ``removal_rate`` and ``object_removal_rate`` (percent) and
        ``errors`` (int).

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
    return _settings_result(Bunch(table=table, **_sum_counts(parts)))


@validate_params({"parts": [list, tuple]}, prefer_skip_nested_validation=True)
def combine_error_windows(parts) -> pd.DataFrame:
    """Merge :func:`filter_error_windows_parts` into ``filter_error_windows``'s table.

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
        Equal to :func:`~sklearn_radar.evaluation.filter_error_windows` of
        the concatenated rows: ``instance``, ``start_s`` (s), ``n``,
        ``kept``, ``kept_share`` and ``error``.

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
