"""The records of the filter's steps: Tables I and II with their error windows, and the filter's effect."""

from __future__ import annotations

from dataclasses import field
from typing import Any

from ._records import WRITTEN_FLAT, JsonRecord, record


@record
class GridTable(JsonRecord):
    """A table of Table I (rows: eta_1 in m/s, columns: d_xy in m), as ``DataFrame.to_dict(orient="split")``.

    Attributes
    ----------
    index : list of float
        Velocity thresholds eta_1, m/s.
    columns : list of float
        Distances d_xy, m.
    data : list of list
        One row per threshold.
    """

    index: list
    columns: list
    data: list

    @classmethod
    def from_frame(cls, frame):
        """From a DataFrame of :func:`~sklearn_radar.evaluation.filter_grid`."""
        return cls(**frame.to_dict(orient="split"))

    def to_frame(self):
        """The table as a DataFrame."""
        import pandas as pd

        return pd.DataFrame(self.data, index=self.index, columns=self.columns)


@record
class FilterGridResult(JsonRecord):
    """Table I in one coordinate system: error counts and background removal per filter setting.

    Attributes
    ----------
    errors : GridTable
        (object, 150 ms window) cases in which a moving object kept less than 75 % of its detections.
    background_removed : GridTable
        Share of the background removed, 0-1.
    """

    errors: GridTable
    background_removed: GridTable


@record
class FilterSettingRow(JsonRecord):
    """One row of Table II: a setting of the paper, its removal rates and errors, ours and the paper's.

    Attributes
    ----------
    frame : {"car", "frame"}
        Coordinate system.
    vr_threshold : float
        eta_1, m/s.
    d_xy : float
        m.
    paper_removal_rate : float
        The paper's background removal, %.
    paper_errors : int
        The paper's error count.
    removal_rate : float
        Our background removal, %.
    object_removal_rate : float
        Share of the object detections removed, %.
    errors : int
        Our error count.
    """

    frame: str
    vr_threshold: float
    d_xy: float
    paper_removal_rate: float
    paper_errors: int
    removal_rate: float
    object_removal_rate: float
    errors: int


@record
class BestRemoval(JsonRecord):
    """The filter setting that removes the most background with at most a given number of errors.

    Attributes
    ----------
    vr_threshold : float
        eta_1, m/s.
    d_xy : float
        m.
    background_removed : float
        Share of the background removed, 0-1.
    """

    vr_threshold: float
    d_xy: float
    background_removed: float


@record
class FilterWindows(JsonRecord):
    """The (object, window) cases behind the error counts, at one filter setting (``filter.windows``).

    An object's window is an *error* when the filter keeps less than
    ``min_kept`` of its detections in it
    (:func:`~sklearn_radar.evaluation.filter_error_windows`).  A window of
    ``n`` detections fails as soon as ``ceil((1 - min_kept) n)`` of them
    go, one for ``n <= 3`` at 75 %: the sparser the objects, the more errors.

    Attributes
    ----------
    frame : {"car", "frame"}
        Coordinate system.
    vr_threshold : float
        eta_1, m/s.
    d_xy : float
        m.
    window_s : float
        Window length, s (the paper: 0.15).
    min_kept : float
        Smallest kept share of a window that is not an error, 0-1 (the paper: 0.75).
    n_windows : int
        Complete windows holding a detection of their object.
    n_errors : int
        Error windows among them.
    mean_detections : float
        Mean detections per window.
    mean_detections_error : float or None
        Mean detections per error window; None without errors.
    n_errors_sparse : int
        Error windows with at most 3 detections (one removed detection fails them).
    """

    frame: str
    vr_threshold: float
    d_xy: float
    window_s: float
    min_kept: float
    n_windows: int
    n_errors: int
    mean_detections: float
    mean_detections_error: float | None
    n_errors_sparse: int


@record
class FilterResult(JsonRecord):
    """The filter evaluation: Tables I and II (``filter``).

    Attributes
    ----------
    table_i : dict of str to FilterGridResult
        Per coordinate system (``"frame"``, ``"car"``).
    table_ii : list of FilterSettingRow
    best_removal_with_zero_errors : dict of str to BestRemoval or None
        Per coordinate system; None where no grid cell has 0 errors.
    wall_time_s : float
    windows : FilterWindows or None, default=None
        The error windows at the paper's chosen setting; None in results of
        older versions.
    """

    table_i: dict[str, FilterGridResult]
    table_ii: list[FilterSettingRow]
    best_removal_with_zero_errors: dict[str, BestRemoval | None]
    wall_time_s: float
    windows: FilterWindows | None = None


@record
class ClusteringCost(JsonRecord):
    """Clustering time and clusters on the test half, filtered or not.

    Attributes
    ----------
    clustering_s : float
        Clustering time of the test half, s: the median over the timing
        rounds of ``clustering_times_s``.
    n_clusters : int
        Clusters, summed over the test sequences.
    clustering_times_s : list of float or None, default=None
        Each timing round's clustering time of the test half, s (stage 0
        done before; each sequence clustered once a round, the times
        summed); None in results of older versions, which timed each
        sequence's fastest of three runs.
    """

    clustering_s: float
    n_clusters: int
    clustering_times_s: list[float] | None = None


def time_savings_percent(filtered, unfiltered):
    """The clustering time filtering saved in each timing round, % of the unfiltered round's."""
    return [100 * (1 - f / u) for f, u in zip(filtered.clustering_times_s, unfiltered.clustering_times_s, strict=True)]


@record(frozen=True)
class FilterEffectFigures(JsonRecord):
    """The filter's effect in three numbers.

    Attributes
    ----------
    time_saving_percent : float
        Clustering time saved by filtering, %: ours the mean over the timing rounds of each round's saving.
    fewer_clusters_per_sequence_percent : float
        Fewer clusters per sequence with the filter, mean over sequences, %.
    fewer_clusters_overall_percent : float
        Fewer clusters overall, %.
    """

    time_saving_percent: float
    fewer_clusters_per_sequence_percent: float
    fewer_clusters_overall_percent: float


#: The paper's figures of the filter's effect (Section V).
PAPER_FILTER_EFFECT = FilterEffectFigures(
    time_saving_percent=3.1, fewer_clusters_per_sequence_percent=23.6, fewer_clusters_overall_percent=28.6
)


@record
class FilterEffectResult(JsonRecord):
    """Clustering with and without the filter at #8's setting (``filter_effect``).

    Attributes
    ----------
    setting : dict
        #8's setting, as pipeline parameters.
    setting_source : str
        ``"tuned #8"`` or ``"paper's #8"``.
    filtered, unfiltered : ClusteringCost
    measured : FilterEffectFigures
        Ours (flat in the JSON record).
    paper : FilterEffectFigures, default=PAPER_FILTER_EFFECT
        The paper's.
    """

    setting: dict[str, Any]
    setting_source: str
    filtered: ClusteringCost
    unfiltered: ClusteringCost
    measured: FilterEffectFigures = field(metadata=WRITTEN_FLAT)
    paper: FilterEffectFigures = PAPER_FILTER_EFFECT
