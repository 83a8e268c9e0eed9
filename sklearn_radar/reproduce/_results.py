"""Typed results of a reproduce run and their JSON form, ``results.json``.

A run fills these dataclasses as it goes; ``results.json`` is
:meth:`RunResults.to_json_dict` written with ``json.dumps(indent=1)``: the
same keys, in the same order, as the untyped dictionaries that came before,
and :meth:`RunResults.from_json_dict` reads it back.  Every dataclass is
keyword-only: a field that is missing or misspelt raises TypeError where the
object is built (or read back), not when the report reads it after a run.

Parameter settings (``params``, ``paper_params``, ...) stay dictionaries of
pipeline parameters (``{"cluster__eps_xy": 0.6, ...}``): their keys are the
estimators', not this module's.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any

from ._constants import PAPER_N_ITER

_RECORD = {"slots": True, "kw_only": True}


def _flat(record):
    """The fields of a dataclass without nested records, in declaration order, as a dictionary."""
    return {f.name: getattr(record, f.name) for f in fields(record)}


def _put(document, key, value):
    """Set ``document[key] = value`` unless ``value`` is None (an optional key is absent, not null)."""
    if value is not None:
        document[key] = value
    return document


@dataclass(**_RECORD)
class Budget:
    """Data size and optimisation budget of a run.

    Attributes
    ----------
    label : str
        Name of the budget in the report, e.g. ``"reduced (default run)"``.
    n_iter : int
        Bayesian-optimisation iterations per tuned experiment.
    n_initial_points : int
        Random points among them.
    cv_folds : int
        Folds of the grouped cross-validation on the training half.
    n_sequences : int or None, default=None
        Simulated sequences; None when read back from ``results.json``,
        which records the data in ``meta.data`` instead.
    duration : float or None, default=None
        Length of each simulated sequence, s; None as ``n_sequences``.
    """

    label: str
    n_iter: int
    n_initial_points: int
    cv_folds: int
    n_sequences: int | None = None
    duration: float | None = None

    @classmethod
    def default(cls, n_iter=None):
        """The default run's budget: 4 sequences x 20 s, 10 iterations (30 % random), 2 folds.

        Parameters
        ----------
        n_iter : int, default=None
            Iterations instead of 10.

        Returns
        -------
        budget : Budget
        """
        n_iter = 10 if n_iter is None else n_iter
        return cls(
            label="reduced (default run)",
            n_iter=n_iter,
            n_initial_points=max(1, round(0.3 * n_iter)),
            cv_folds=2,
            n_sequences=4,
            duration=20.0,
        )

    @classmethod
    def full(cls, n_iter=None):
        """The paper's budget (``--full``): 17 sequences x 30 s, 100 iterations (30 random), 3 folds.

        Parameters
        ----------
        n_iter : int, default=None
            Iterations instead of 100.

        Returns
        -------
        budget : Budget
        """
        n_iter = PAPER_N_ITER if n_iter is None else n_iter
        return cls(
            label="the paper's (--full)",
            n_iter=n_iter,
            n_initial_points=max(1, round(0.3 * n_iter)),
            cv_folds=3,
            n_sequences=17,
            duration=30.0,
        )

    @property
    def reduced(self):
        """bool : Whether the run had fewer iterations than the paper's 100."""
        return self.n_iter < PAPER_N_ITER

    def to_json_dict(self):
        """The ``meta.budget`` entry of ``results.json`` (without the data size)."""
        return {
            "label": self.label,
            "n_iter": self.n_iter,
            "n_initial_points": self.n_initial_points,
            "cv_folds": self.cv_folds,
        }

    @classmethod
    def from_json_dict(cls, document):
        """Read :meth:`to_json_dict`'s form back."""
        return cls(**document)


@dataclass(**_RECORD)
class DataMeta:
    """The data of a run and its split by sequence (``meta.data``).

    Attributes
    ----------
    source : str
        Where the data came from (simulation and seed, or a RadarScenes folder).
    n_detections, n_sequences : int
        Size of the data.
    n_train, n_test : int
        Detections in the training and the test half.
    train_sequences, test_sequences : list of int
        Sequences of each half.
    """

    source: str
    n_detections: int
    n_sequences: int
    n_train: int
    n_test: int
    train_sequences: list[int]
    test_sequences: list[int]

    def to_json_dict(self):
        """The ``meta.data`` entry of ``results.json``."""
        return _flat(self)

    @classmethod
    def from_json_dict(cls, document):
        """Read :meth:`to_json_dict`'s form back."""
        return cls(**document)


@dataclass(**_RECORD)
class RunMeta:
    """What ran, on what, with which budget (``meta``).

    Attributes
    ----------
    version : str
        sklearn-radar version.
    seed : int
        Random seed of the data, the split and the searches.
    budget : Budget
    data : DataMeta
    completed : list of str
        Step keys finished, in run order (``"filter"``, ``"1"``, ...).
    interrupted : bool, default=False
        Whether the run was interrupted.
    wall_time_s : float or None, default=None
        Wall time of the whole run, s; None until it finishes (the key is then absent).
    objective : {"v1", "pq"}, default="v1"
        What the searches maximised and ``params.json``'s ``best`` ranks by: the paper's radar
        V-measure, or the panoptic quality of moving road users per 0.5 s frame.
    repeats : int, default=1
        Searches per tuned experiment and baseline, with the seeds ``seed``, ``seed + 1``, ... on the same
        split (the key is absent for 1).
    """

    version: str
    seed: int
    budget: Budget
    data: DataMeta
    completed: list[str] = field(default_factory=list)
    interrupted: bool = False
    wall_time_s: float | None = None
    objective: str = "v1"
    repeats: int = 1

    def to_json_dict(self):
        """The ``meta`` entry of ``results.json``."""
        document = {
            "version": self.version,
            "seed": self.seed,
            "budget": self.budget.to_json_dict(),
            "data": self.data.to_json_dict(),
            "completed": list(self.completed),
            "interrupted": self.interrupted,
            "objective": self.objective,
        }
        _put(document, "repeats", self.repeats if self.repeats != 1 else None)
        return _put(document, "wall_time_s", self.wall_time_s)

    @classmethod
    def from_json_dict(cls, document):
        """Read :meth:`to_json_dict`'s form back."""
        document = dict(document)
        budget = Budget.from_json_dict(document.pop("budget"))
        data = DataMeta.from_json_dict(document.pop("data"))
        return cls(budget=budget, data=data, **document)


@dataclass(**_RECORD)
class DataStatistics:
    """Statistics of the run's data, to judge how close to real radar data it is (``statistics``).

    Attributes
    ----------
    summary : dict
        The summary figures of :func:`~sklearn_radar.datasets.scene_statistics`
        (detections, sequences, static share, ...), JSON numbers.
    text : str
        :func:`~sklearn_radar.datasets.format_statistics` of them, as printed
        by ``sklearn-radar simulate``.
    """

    summary: dict[str, Any]
    text: str

    def to_json_dict(self):
        """The ``statistics`` entry of ``results.json``."""
        return _flat(self)

    @classmethod
    def from_json_dict(cls, document):
        """Read :meth:`to_json_dict`'s form back (None stays None)."""
        return None if document is None else cls(**document)


# ----------------------------------------------------------------------------- the filter (Tables I and II)


@dataclass(**_RECORD)
class GridTable:
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

    def to_json_dict(self):
        """The ``split`` dictionary."""
        return _flat(self)

    @classmethod
    def from_json_dict(cls, document):
        """Read :meth:`to_json_dict`'s form back."""
        return cls(**document)


@dataclass(**_RECORD)
class FilterGridResult:
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

    def to_json_dict(self):
        """One coordinate system of ``filter.table_i``."""
        return {"errors": self.errors.to_json_dict(), "background_removed": self.background_removed.to_json_dict()}

    @classmethod
    def from_json_dict(cls, document):
        """Read :meth:`to_json_dict`'s form back."""
        return cls(**{key: GridTable.from_json_dict(value) for key, value in document.items()})


@dataclass(**_RECORD)
class FilterSettingRow:
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

    def to_json_dict(self):
        """One record of ``filter.table_ii``."""
        return _flat(self)

    @classmethod
    def from_json_dict(cls, document):
        """Read :meth:`to_json_dict`'s form back."""
        return cls(**document)


@dataclass(**_RECORD)
class BestRemoval:
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

    def to_json_dict(self):
        """One entry of ``filter.best_removal_with_zero_errors``."""
        return _flat(self)

    @classmethod
    def from_json_dict(cls, document):
        """Read :meth:`to_json_dict`'s form back (None stays None)."""
        return None if document is None else cls(**document)


@dataclass(**_RECORD)
class FilterWindows:
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

    def to_json_dict(self):
        """The ``filter.windows`` entry of ``results.json``."""
        return _flat(self)

    @classmethod
    def from_json_dict(cls, document):
        """Read :meth:`to_json_dict`'s form back (None stays None)."""
        return None if document is None else cls(**document)


@dataclass(**_RECORD)
class FilterResult:
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

    def to_json_dict(self):
        """The ``filter`` entry of ``results.json``."""
        document = {
            "table_i": {frame: grid.to_json_dict() for frame, grid in self.table_i.items()},
            "table_ii": [row.to_json_dict() for row in self.table_ii],
            "best_removal_with_zero_errors": {
                frame: None if best is None else best.to_json_dict()
                for frame, best in self.best_removal_with_zero_errors.items()
            },
            "wall_time_s": self.wall_time_s,
        }
        return _put(document, "windows", None if self.windows is None else self.windows.to_json_dict())

    @classmethod
    def from_json_dict(cls, document):
        """Read :meth:`to_json_dict`'s form back."""
        document = dict(document)
        windows = FilterWindows.from_json_dict(document.pop("windows", None))
        table_i = {frame: FilterGridResult.from_json_dict(grid) for frame, grid in document.pop("table_i").items()}
        table_ii = [FilterSettingRow.from_json_dict(row) for row in document.pop("table_ii")]
        best = document.pop("best_removal_with_zero_errors")
        best = {frame: BestRemoval.from_json_dict(removal) for frame, removal in best.items()}
        return cls(table_i=table_i, table_ii=table_ii, best_removal_with_zero_errors=best, windows=windows, **document)


# ----------------------------------------------------------------------------- experiments and baselines


@dataclass(**_RECORD)
class SearchRecord:
    """A Bayesian-optimisation search on the training half.

    Attributes
    ----------
    cv_best : float
        Mean cross-validated V1 of the kept setting.
    convergence : list of float
        Mean cross-validated V1 of each iteration, in order.
    best_source : str
        ``"search"``, or the paper's setting when it scored at least as well
        (:data:`~sklearn_radar.reproduce._constants.SOURCE_PAPER`).
    search_wall_time_s : float
    cv_start_from : float or None, default=None
        Mean cross-validated V1 of the paper's setting, scored beside the
        search; None where there is none (the scikit-learn baselines).
    """

    cv_best: float
    convergence: list[float]
    best_source: str
    search_wall_time_s: float
    cv_start_from: float | None = None

    #: The keys of a search in a flat experiment or baseline record of ``results.json``.
    KEYS = ("cv_best", "convergence", "best_source", "cv_start_from", "search_wall_time_s")

    def to_json_dict(self):
        """The search's keys, as they appear in an experiment's or a baseline's record."""
        document = {"cv_best": self.cv_best, "convergence": list(self.convergence), "best_source": self.best_source}
        _put(document, "cv_start_from", self.cv_start_from)
        document["search_wall_time_s"] = self.search_wall_time_s
        return document

    @classmethod
    def split_json_dict(cls, document):
        """Split a flat record into (search or None, the other keys).

        Parameters
        ----------
        document : dict
            An experiment's or a baseline's record of ``results.json``.

        Returns
        -------
        search : SearchRecord or None
            None when the record has none of the search's keys.
        rest : dict
            The record without them.
        """
        search = {key: value for key, value in document.items() if key in cls.KEYS}
        rest = {key: value for key, value in document.items() if key not in cls.KEYS}
        return (cls(**search) if search else None), rest


@dataclass(**_RECORD)
class InstanceScores:
    """Object-level scores of one labelling of the test half (``instance_test``).

    Attributes
    ----------
    frame_s : float
        Length of the evaluation frames, s.
    pq, sq, rq : float
        Panoptic, segmentation and recognition quality (RQ is the F1 score), 0-1.
    precision, recall : float
        Of the per-frame segment matches (IoU > 0.5), 0-1.
    mcov, mwcov : float
        Mean and size-weighted mean coverage of the ground-truth segments, 0-1.
    background_segment_share : float
        Share of the predicted per-frame segments without any object detection, 0-1.
    background_cluster_share : float
        Share of the clusters without any object detection, 0-1.
    """

    frame_s: float
    pq: float
    sq: float
    rq: float
    precision: float
    recall: float
    mcov: float
    mwcov: float
    background_segment_share: float
    background_cluster_share: float

    def to_json_dict(self):
        """The ``instance_test`` entry of an experiment or baseline."""
        return _flat(self)

    @classmethod
    def from_json_dict(cls, document):
        """Read :meth:`to_json_dict`'s form back."""
        return cls(**document)


def _instance_from_json(rest):
    """Turn the optional ``instance_test`` entry of a parsed record into :class:`InstanceScores`."""
    if rest.get("instance_test") is not None:
        rest["instance_test"] = InstanceScores.from_json_dict(rest["instance_test"])
    return rest


def _repeats_from_json(rest):
    """Turn the optional ``repeats`` entry of a parsed record into a list of :class:`RepeatResult`."""
    if rest.get("repeats") is not None:
        rest["repeats"] = [RepeatResult.from_json_dict(record) for record in rest["repeats"]]
    return rest


@dataclass(**_RECORD)
class RepeatResult:
    """One repeat of an experiment or baseline: its search with its own seed, and the kept setting's test scores.

    Attributes
    ----------
    seed : int
        Random seed of the repeat's search (the run's seed plus the repeat's index).
    params : dict
        The setting scored on the test half, as pipeline parameters.
    v1_test : float
        Radar V-measure on the test half, 0-1.
    n_clusters_test : int
        Clusters found on the test half.
    search : SearchRecord or None, default=None
        The repeat's search; None for #10 and #11, which take the same repeat's #8 setting.
    instance_test : InstanceScores or None, default=None
        Object-level scores on the test half.
    """

    seed: int
    params: dict[str, Any]
    v1_test: float
    n_clusters_test: int
    search: SearchRecord | None = None
    instance_test: InstanceScores | None = None

    def to_json_dict(self):
        """One entry of a record's ``repeats``: the seed, the search's keys, then the test scores."""
        document = {"seed": self.seed}
        if self.search is not None:
            document.update(self.search.to_json_dict())
        document.update(params=self.params, v1_test=self.v1_test, n_clusters_test=self.n_clusters_test)
        if self.instance_test is not None:
            document["instance_test"] = self.instance_test.to_json_dict()
        return document

    @classmethod
    def from_json_dict(cls, document):
        """Read :meth:`to_json_dict`'s form back."""
        search, rest = SearchRecord.split_json_dict(document)
        return cls(search=search, **_instance_from_json(rest))


def repeated_scores(result, score="v1"):
    """The test scores of an experiment or baseline, one per repeat (one value for a single run).

    Parameters
    ----------
    result : ExperimentResult or BaselineResult
    score : {"v1", "pq"}, default="v1"
        The radar V-measure or the panoptic quality.

    Returns
    -------
    scores : list of float
        Per repeat, in order; ``[]`` for PQ when the record has no object-level scores.
    """
    records = result.repeats or [result]
    if score == "v1":
        return [float(r.v1_test) for r in records]
    return [float(r.instance_test.pq) for r in records if r.instance_test is not None]


@dataclass(**_RECORD)
class ExperimentResult:
    """One experiment of Tables III and IV, re-run (``experiments.N``).

    Attributes
    ----------
    number : int
        Experiment, 1-13.
    method, frame, filtered, stage
        The experiment's description (:class:`~sklearn_radar.experiments.PaperExperiment`).
    paper_v1_percent : float
        The paper's V1, %.
    paper_params : dict
        The paper's setting, as pipeline parameters.
    params : dict
        The setting scored on the test half, as pipeline parameters.
    v1_test : float
        Radar V-measure on the test half, 0-1.
    n_clusters_test : int
        Clusters found on the test half.
    wall_time_s : float
        Wall time of the experiment (search and scoring), s.
    stage1_params : dict or None, default=None
        Stage 2 only: the fixed stage-1 setting (#8's).
    derived_from_8 : str or None, default=None
        #10 and #11 only: whether #8's setting was tuned or the paper's.
    search : SearchRecord or None, default=None
        The search, for the tuned experiments.
    instance_test : InstanceScores or None, default=None
        Object-level scores on the test half.
    n_merges_test : int or None, default=None
        Stage 2 only: pairs of stage-1 clusters that met the merge criterion
        on the test half (``ClusterMerger.merges_``); 0 means the experiment
        returned its stage-1 clustering unchanged.
    n_stage1_clusters_test : int or None, default=None
        Stage 2 only: stage-1 clusters on the test half, before merging.
    repeats : list of RepeatResult or None, default=None
        Every repeat of a run with more than one (``meta.repeats``), the
        first being the one whose values the other fields hold; None for a
        single run and for the fixed expert setting, which no seed changes.
    """

    number: int
    method: str
    frame: str
    filtered: bool
    stage: int
    paper_v1_percent: float
    paper_params: dict[str, Any]
    params: dict[str, Any]
    v1_test: float
    n_clusters_test: int
    wall_time_s: float
    stage1_params: dict[str, Any] | None = None
    derived_from_8: str | None = None
    search: SearchRecord | None = None
    instance_test: InstanceScores | None = None
    n_merges_test: int | None = None
    n_stage1_clusters_test: int | None = None
    repeats: list[RepeatResult] | None = None

    def to_json_dict(self):
        """The experiment's record in ``results.json``: the search's keys flat among the others."""
        document = {
            "number": self.number,
            "method": self.method,
            "frame": self.frame,
            "filtered": self.filtered,
            "stage": self.stage,
            "paper_v1_percent": self.paper_v1_percent,
            "paper_params": self.paper_params,
        }
        _put(document, "stage1_params", self.stage1_params)
        _put(document, "derived_from_8", self.derived_from_8)
        if self.search is not None:
            document.update(self.search.to_json_dict())
        document.update(
            params=self.params, v1_test=self.v1_test, wall_time_s=self.wall_time_s, n_clusters_test=self.n_clusters_test
        )
        _put(document, "n_stage1_clusters_test", self.n_stage1_clusters_test)
        _put(document, "n_merges_test", self.n_merges_test)
        if self.instance_test is not None:
            document["instance_test"] = self.instance_test.to_json_dict()
        if self.repeats is not None:
            document["repeats"] = [repeat.to_json_dict() for repeat in self.repeats]
        return document

    @classmethod
    def from_json_dict(cls, document):
        """Read :meth:`to_json_dict`'s form back."""
        search, rest = SearchRecord.split_json_dict(document)
        return cls(search=search, **_repeats_from_json(_instance_from_json(rest)))


@dataclass(**_RECORD)
class BaselineResult:
    """A scikit-learn clusterer tuned and scored like the experiments (``baselines.NAME``).

    Attributes
    ----------
    search : SearchRecord
    params : dict
        The kept setting, as pipeline parameters.
    v1_test : float
        Radar V-measure on the test half, 0-1.
    n_clusters_test : int
        Clusters found on the test half.
    wall_time_s : float
        Wall time of the search and scoring, s.
    instance_test : InstanceScores or None, default=None
        Object-level scores on the test half.
    repeats : list of RepeatResult or None, default=None
        Every repeat of a run with more than one, the first being the one
        whose values the other fields hold; None for a single run.
    """

    search: SearchRecord
    params: dict[str, Any]
    v1_test: float
    n_clusters_test: int
    wall_time_s: float
    instance_test: InstanceScores | None = None
    repeats: list[RepeatResult] | None = None

    def to_json_dict(self):
        """The baseline's record in ``results.json``: the search's keys first."""
        document = {
            **self.search.to_json_dict(),
            "params": self.params,
            "v1_test": self.v1_test,
            "wall_time_s": self.wall_time_s,
            "n_clusters_test": self.n_clusters_test,
        }
        if self.instance_test is not None:
            document["instance_test"] = self.instance_test.to_json_dict()
        if self.repeats is not None:
            document["repeats"] = [repeat.to_json_dict() for repeat in self.repeats]
        return document

    @classmethod
    def from_json_dict(cls, document):
        """Read :meth:`to_json_dict`'s form back."""
        search, rest = SearchRecord.split_json_dict(document)
        return cls(search=search, **_repeats_from_json(_instance_from_json(rest)))


# ----------------------------------------------------------------------------- the filter's effect


@dataclass(**_RECORD)
class ClusteringCost:
    """Clustering time and clusters on the test half, filtered or not.

    Attributes
    ----------
    clustering_s : float
        Clustering time of the test half, s: each test sequence's best of
        three clustering runs (stage 0 done before), summed over the
        sequences.
    n_clusters : int
        Clusters, summed over the test sequences.
    """

    clustering_s: float
    n_clusters: int

    def to_json_dict(self):
        """``filter_effect.filtered`` or ``filter_effect.unfiltered``."""
        return _flat(self)

    @classmethod
    def from_json_dict(cls, document):
        """Read :meth:`to_json_dict`'s form back."""
        return cls(**document)


@dataclass(frozen=True, **_RECORD)
class FilterEffectFigures:
    """The filter's effect in three numbers.

    Attributes
    ----------
    time_saving_percent : float
        Clustering time saved by filtering, %.
    fewer_clusters_per_sequence_percent : float
        Fewer clusters per sequence with the filter, mean over sequences, %.
    fewer_clusters_overall_percent : float
        Fewer clusters overall, %.
    """

    time_saving_percent: float
    fewer_clusters_per_sequence_percent: float
    fewer_clusters_overall_percent: float

    def to_json_dict(self):
        """The three numbers under their keys."""
        return _flat(self)

    @classmethod
    def from_json_dict(cls, document):
        """Read :meth:`to_json_dict`'s form back."""
        return cls(**document)


#: The paper's figures of the filter's effect (Section V).
PAPER_FILTER_EFFECT = FilterEffectFigures(
    time_saving_percent=3.1, fewer_clusters_per_sequence_percent=23.6, fewer_clusters_overall_percent=28.6
)


@dataclass(**_RECORD)
class FilterEffectResult:
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
    measured: FilterEffectFigures
    paper: FilterEffectFigures = PAPER_FILTER_EFFECT

    def to_json_dict(self):
        """The ``filter_effect`` entry of ``results.json``."""
        return {
            "setting": self.setting,
            "setting_source": self.setting_source,
            "filtered": self.filtered.to_json_dict(),
            "unfiltered": self.unfiltered.to_json_dict(),
            **self.measured.to_json_dict(),
            "paper": self.paper.to_json_dict(),
        }

    @classmethod
    def from_json_dict(cls, document):
        """Read :meth:`to_json_dict`'s form back."""
        document = dict(document)
        measured = {f.name: document.pop(f.name) for f in fields(FilterEffectFigures) if f.name in document}
        return cls(
            setting=document.pop("setting"),
            setting_source=document.pop("setting_source"),
            filtered=ClusteringCost.from_json_dict(document.pop("filtered")),
            unfiltered=ClusteringCost.from_json_dict(document.pop("unfiltered")),
            measured=FilterEffectFigures.from_json_dict(measured),
            paper=FilterEffectFigures.from_json_dict(document.pop("paper")),
            **document,
        )


# ----------------------------------------------------------------------------- the whole run


@dataclass(**_RECORD)
class FigureRecord:
    """The figures drawn for the report (not part of ``results.json``: they are drawn after it is saved).

    Attributes
    ----------
    drawn : dict of str to str
        Figure name (``"table1_heatmap"``, ``"scene"``, ``"convergence"``) -> file name in the output folder.
    missing : str or None, default=None
        Why no figure was drawn (matplotlib missing).
    """

    drawn: dict[str, str] = field(default_factory=dict)
    missing: str | None = None

    def to_json_dict(self):
        """``{name: file name, ..., "missing": reason}``."""
        return _put(dict(self.drawn), "missing", self.missing)

    @classmethod
    def from_json_dict(cls, document):
        """Read :meth:`to_json_dict`'s form back."""
        document = dict(document or {})
        missing = document.pop("missing", None)
        return cls(drawn=document, missing=missing)


@dataclass(**_RECORD)
class RunResults:
    """Everything a reproduce run measured: ``results.json`` in memory.

    Attributes
    ----------
    meta : RunMeta
    experiments : dict of int to ExperimentResult, default={}
        By experiment number, in run order.
    filter : FilterResult or None, default=None
        None when the filter evaluation did not run (the key is then absent).
    filter_effect : FilterEffectResult or None, default=None
    baselines : dict of str to BaselineResult or None, default=None
        By clusterer name.
    figures : FigureRecord, default=FigureRecord()
        Figures drawn; written to ``results.json`` only on request.
    statistics : DataStatistics or None, default=None
        Statistics of the data; None in results of older versions.
    """

    meta: RunMeta
    experiments: dict[int, ExperimentResult] = field(default_factory=dict)
    filter: FilterResult | None = None
    filter_effect: FilterEffectResult | None = None
    baselines: dict[str, BaselineResult] | None = None
    figures: FigureRecord = field(default_factory=FigureRecord)
    statistics: DataStatistics | None = None

    def v1_test(self):
        """Test V1 by experiment number, for the experiments that ran.

        Returns
        -------
        scores : dict of int to float
        """
        return {number: result.v1_test for number, result in self.experiments.items()}

    def to_json_dict(self, *, figures=False):
        """What ``results.json`` holds.

        Parameters
        ----------
        figures : bool, default=False
            Also add the ``figures`` entry (the figures drawn), which
            ``results.json`` does not hold.

        Returns
        -------
        document : dict
            ``meta``, ``statistics`` (when measured), ``experiments`` (keyed by the number as a string), then
            ``filter``, ``filter_effect`` and ``baselines`` where they ran.
        """
        document = {"meta": self.meta.to_json_dict()}
        _put(document, "statistics", None if self.statistics is None else self.statistics.to_json_dict())
        document["experiments"] = {str(number): result.to_json_dict() for number, result in self.experiments.items()}
        _put(document, "filter", None if self.filter is None else self.filter.to_json_dict())
        _put(document, "filter_effect", None if self.filter_effect is None else self.filter_effect.to_json_dict())
        if self.baselines is not None:
            document["baselines"] = {name: result.to_json_dict() for name, result in self.baselines.items()}
        if figures:
            document["figures"] = self.figures.to_json_dict()
        return document

    @classmethod
    def from_json_dict(cls, document):
        """Read ``results.json`` (or :meth:`to_json_dict`'s form) back.

        Parameters
        ----------
        document : dict

        Returns
        -------
        results : RunResults

        Raises
        ------
        TypeError
            If a record lacks a field or has one that is not known.
        """
        document = dict(document)
        meta = RunMeta.from_json_dict(document.pop("meta"))
        statistics = DataStatistics.from_json_dict(document.pop("statistics", None))
        experiments = {}
        for key, record in document.pop("experiments", {}).items():
            result = ExperimentResult.from_json_dict(record)
            if str(result.number) != key:
                raise ValueError(f"results.json: experiment {key!r} holds the record of #{result.number}")
            experiments[result.number] = result
        filter_ = document.pop("filter", None)
        effect = document.pop("filter_effect", None)
        baselines = document.pop("baselines", None)
        if baselines is not None:
            baselines = {name: BaselineResult.from_json_dict(record) for name, record in baselines.items()}
        return cls(
            meta=meta,
            experiments=experiments,
            filter=None if filter_ is None else FilterResult.from_json_dict(filter_),
            filter_effect=None if effect is None else FilterEffectResult.from_json_dict(effect),
            baselines=baselines,
            figures=FigureRecord.from_json_dict(document.pop("figures", None)),
            statistics=statistics,
            **document,
        )

    def to_params_dict(self):
        """What ``params.json`` holds: each experiment's setting and the best one; None before any experiment.

        Returns
        -------
        document : dict or None
            ``{"best": key, "objective": ..., "experiments": {key: {"experiment",
            "v1_test", ["pq_test",] "params", "stage1_params"}}}``; ``best`` is the
            first experiment with the highest test score of the run's objective.
        """
        experiments = {}
        for number, result in self.experiments.items():
            entry = {"experiment": result.number, "v1_test": result.v1_test}
            if result.instance_test is not None:
                entry["pq_test"] = result.instance_test.pq
            entry.update(params=result.params, stage1_params=result.stage1_params)
            experiments[str(number)] = entry
        if not experiments:
            return None
        score = "pq_test" if self.meta.objective == "pq" else "v1_test"
        best = max(experiments, key=lambda key: experiments[key].get(score, float("-inf")))
        return {"best": best, "objective": self.meta.objective, "experiments": experiments}


__all__ = [
    "PAPER_FILTER_EFFECT",
    "BaselineResult",
    "BestRemoval",
    "Budget",
    "ClusteringCost",
    "DataMeta",
    "DataStatistics",
    "ExperimentResult",
    "FigureRecord",
    "FilterEffectFigures",
    "FilterEffectResult",
    "FilterGridResult",
    "FilterResult",
    "FilterSettingRow",
    "FilterWindows",
    "GridTable",
    "RepeatResult",
    "RunMeta",
    "RunResults",
    "SearchRecord",
    "repeated_scores",
]
