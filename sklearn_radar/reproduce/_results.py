"""Typed results of a reproduce run and their JSON form, ``results.json``.

A run fills these dataclasses as it goes; ``results.json`` is
:meth:`RunResults.to_json_dict` written with ``json.dumps(indent=1)``, and
:meth:`RunResults.from_json_dict` (or :meth:`RunResults.read`) reads it back.
Every dataclass is keyword-only: a field that is missing or misspelt raises
TypeError where the object is built, and ValueError naming the file and the
key where it is read back, not when the report reads it after a run.

The JSON form is derived from the fields, by one converter (``_to_json``,
``_from_json``) instead of a pair of methods per record.  Its rules are
those of the format it replaced, so that ``results.json`` stays byte for byte
the same:

- the keys are the field names, in declaration order (the fields are
  declared in the order of the JSON keys);
- a field whose default is None is absent while it is None, not null
  (a None in a required field, or in a dictionary, is written as null);
- a field declared with ``_WRITTEN_FLAT`` metadata is written as its record's (or
  dictionary's) keys among its owner's, not as a nested object;
- a field declared with ``_NOT_WRITTEN`` is not written (and read back if
  present), one with ``_ABSENT_AT_DEFAULT`` is absent at its default;
- dictionary keys typed ``int`` are written as strings; numbers and strings
  are written as they are, for :func:`json.dumps` to format.

A converter over :func:`dataclasses.fields` rather than a library: the
libraries tried write other bytes or read other values (the comparison:
:ref:`contributing-decisions`).

Parameter settings (``params``, ``paper_params``, ...) stay dictionaries of
pipeline parameters (``{"cluster__eps_xy": 0.6, ...}``): their keys are the
estimators', not this module's.
"""

from __future__ import annotations

import functools
import json
import types
import typing
from dataclasses import MISSING, dataclass, field, fields, is_dataclass
from pathlib import Path
from typing import Any, NamedTuple

from ..experiments import OBJECT_EXPERIMENT
from ._constants import PAPER_N_ITER

_RECORD = {"slots": True, "kw_only": True}

# ----------------------------------------------------------------------------- the JSON converter

_HOW = "results_json"  # the key of a field's metadata that says how it is written
#: ``field(metadata=...)`` of a field written as its record's (or dictionary's) keys among its owner's,
_WRITTEN_FLAT = {_HOW: "flat"}
#: of a field that the JSON form does not hold,
_NOT_WRITTEN = {_HOW: "not written"}
#: of a field whose key is absent while it has its default.
_ABSENT_AT_DEFAULT = {_HOW: "absent at default"}


class _Field(NamedTuple):
    name: str
    how: str | None
    default: Any
    required: bool
    holds_records: bool  # else its value is written as it is
    record: type | None  # the record class of a (possibly optional) record type
    read: Any  # _reader of its type


def _optional_of(hint):
    """X for ``X | None``, else None."""
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        args = [arg for arg in typing.get_args(hint) if arg is not type(None)]
        return args[0] if len(args) == 1 else None
    return None


def _holds_records(hint):
    return is_dataclass(hint) or any(_holds_records(arg) for arg in typing.get_args(hint))


@functools.cache
def _plan(cls):
    """The fields of a record class, in declaration order, with what the converter needs to know of them."""
    hints = typing.get_type_hints(cls)
    return tuple(
        _Field(
            name=f.name,
            how=f.metadata.get(_HOW),
            default=f.default,
            required=f.default is MISSING and f.default_factory is MISSING,
            holds_records=_holds_records(hints[f.name]),
            record=next((h for h in (_optional_of(hints[f.name]), hints[f.name]) if is_dataclass(h)), None),
            read=_reader(hints[f.name]),
        )
        for f in fields(cls)
    )


@functools.cache
def _own_keys(cls):
    """The keys of a record's JSON object that its fields (flattened records' included) claim."""
    keys = []
    for f in _plan(cls):
        if f.how != "flat":
            keys.append(f.name)
        elif f.record is not None:
            keys.extend(_own_keys(f.record))
    return frozenset(keys)


def _to_json(value):
    """The JSON form of a record, or of a dictionary or list of them, for :func:`json.dumps`."""
    if is_dataclass(value):
        return _record_to_json(value)
    if isinstance(value, dict):
        return {str(key) if isinstance(key, int) else key: _to_json(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [_to_json(item) for item in value]
    return value


def _record_to_json(record):
    document = {}
    for f in _plan(type(record)):
        value = getattr(record, f.name)
        if (
            f.how == "not written"
            or (value is None and f.default is None)
            or (f.how == "absent at default" and value == f.default)
        ):
            continue
        value = _to_json(value) if f.holds_records else value
        if f.how == "flat":
            document.update(value)
        else:
            document[f.name] = value
    return document


def _from_json(hint, document, source):
    """Read :func:`_to_json`'s form of type ``hint`` back; ValueError naming ``source`` and the key if it is bad."""
    try:
        return _reader(hint)(document)
    except _BadDocument as error:
        path, problem = error.args
        raise ValueError(f"{source}: {'.'.join(map(str, path)) or 'the document'} {problem}") from None


class _BadDocument(Exception):
    """([keys from the document's top to the bad value], what is wrong with it)."""

    def within(self, key):
        self.args[0].insert(0, key)
        return self


def _expect(value, kinds, what):
    if not isinstance(value, kinds) or (isinstance(value, bool) and bool not in kinds):
        raise _BadDocument([], f"should be {what}, not {type(value).__name__} {value!r:.40}")


_SCALARS = {
    float: ((int, float), "a number"),
    int: ((int,), "an integer"),
    str: ((str,), "a string"),
    bool: ((bool,), "true or false"),
}


def _as_is(value):
    return value


@functools.cache
def _reader(hint):
    """The function that checks a parsed JSON value of type ``hint`` and returns it as that type."""
    inner = _optional_of(hint)
    if inner is not None:
        read = _reader(inner)
        return lambda value: None if value is None else read(value)
    if is_dataclass(hint):
        return functools.partial(_read_record, hint)
    origin, args = typing.get_origin(hint) or hint, typing.get_args(hint)
    if origin is dict:
        key_type, item_type = args or (str, Any)
        return functools.partial(_read_dict, _read_int_key if key_type is int else _as_is, _reader(item_type))
    if origin is list:
        return functools.partial(_read_list, _reader(args[0] if args else Any))
    if hint in _SCALARS:
        return functools.partial(_read_scalar, *_SCALARS[hint])
    return _as_is


def _read_scalar(kinds, what, value):
    _expect(value, kinds, what)
    return value


def _read_int_key(key):
    if not key.lstrip("-").isdigit():
        raise _BadDocument([], f"has the key {key!r}, which is not an integer")
    return int(key)


def _read_dict(read_key, read_item, document):
    _expect(document, (dict,), "an object")
    if read_key is read_item is _as_is:
        return document
    read = {}
    for key, item in document.items():
        read_as = read_key(key)
        try:
            read[read_as] = read_item(item)
        except _BadDocument as error:
            raise error.within(key) from None
    return read


def _read_list(read_item, document):
    _expect(document, (list,), "a list")
    if read_item is _as_is or (
        getattr(read_item, "func", None) is _read_scalar and {type(item) for item in document} <= set(read_item.args[0])
    ):
        return document  # the common case, checked at once
    read = []
    for index, item in enumerate(document):
        try:
            read.append(read_item(item))
        except _BadDocument as error:
            raise error.within(index) from None
    return read


def _read_record(cls, document):
    _expect(document, (dict,), f"an object ({cls.__name__})")
    own, plan = _own_keys(cls), _plan(cls)
    unknown = [key for key in document if key not in own]
    collects_the_rest = any(f.how == "flat" and f.record is None for f in plan)
    if unknown and not collects_the_rest:
        raise _BadDocument([], f"has the key {unknown[0]!r}, which {cls.__name__} does not know")
    values = {}
    for f in plan:
        if f.how == "flat" and f.record is not None:
            part = {key: document[key] for key in _own_keys(f.record) if key in document}
            if part or f.required:
                values[f.name] = _read_record(f.record, part)
        elif f.how == "flat":
            values[f.name] = f.read({key: document[key] for key in unknown})
        elif f.name in document:
            try:
                values[f.name] = f.read(document[f.name])
            except _BadDocument as error:
                raise error.within(f.name) from None
        elif f.required:
            raise _BadDocument([], f"lacks the key {f.name!r} ({cls.__name__})")
    return cls(**values)


class _JsonRecord:
    """``to_json_dict`` and ``from_json_dict`` of every record, by the module's rules."""

    __slots__ = ()

    def to_json_dict(self):
        """The record's JSON form (see the module's rules).

        Returns
        -------
        document : dict
        """
        return _to_json(self)

    @classmethod
    def from_json_dict(cls, document, *, source="results.json"):
        """Read :meth:`to_json_dict`'s form back.

        Parameters
        ----------
        document : dict
            Parsed JSON.
        source : str, default="results.json"
            Where it was read, for the error messages.

        Returns
        -------
        record : instance of the class

        Raises
        ------
        ValueError
            Naming ``source`` and the key, if a key is missing or not known, or a value has the wrong type.
        """
        record = _from_json(cls, document, source)
        cls._check_read(document, source)
        return record

    @classmethod
    def _check_read(cls, document, source):
        """Raise ValueError naming ``source`` if a read document breaks a rule its types do not say."""


@dataclass(**_RECORD)
class Budget(_JsonRecord):
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
    n_sequences: int | None = field(default=None, metadata=_NOT_WRITTEN)
    duration: float | None = field(default=None, metadata=_NOT_WRITTEN)

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


@dataclass(**_RECORD)
class DataMeta(_JsonRecord):
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


@dataclass(**_RECORD)
class RunMeta(_JsonRecord):
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
    objective : {"v1", "pq"}, default="v1"
        What the searches maximised and ``params.json``'s ``best`` ranks by (its cross-validated training
        score): the paper's radar V-measure, or the panoptic quality of moving road users per 0.5 s frame.
    repeats : int, default=1
        Searches per tuned experiment and baseline, with the seeds ``seed``, ``seed + 1``, ... on the same
        split (the key is absent for 1).
    wall_time_s : float or None, default=None
        Wall time of the whole run, s; None until it finishes (the key is then absent).
    """

    version: str
    seed: int
    budget: Budget
    data: DataMeta
    completed: list[str] = field(default_factory=list)
    interrupted: bool = False
    objective: str = "v1"
    repeats: int = field(default=1, metadata=_ABSENT_AT_DEFAULT)
    wall_time_s: float | None = None


@dataclass(**_RECORD)
class DataStatistics(_JsonRecord):
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


# ----------------------------------------------------------------------------- the filter (Tables I and II)


@dataclass(**_RECORD)
class GridTable(_JsonRecord):
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


@dataclass(**_RECORD)
class FilterGridResult(_JsonRecord):
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


@dataclass(**_RECORD)
class FilterSettingRow(_JsonRecord):
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


@dataclass(**_RECORD)
class BestRemoval(_JsonRecord):
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


@dataclass(**_RECORD)
class FilterWindows(_JsonRecord):
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


@dataclass(**_RECORD)
class FilterResult(_JsonRecord):
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


# ----------------------------------------------------------------------------- experiments and baselines


@dataclass(**_RECORD)
class SearchRecord(_JsonRecord):
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
    cv_start_from : float or None, default=None
        Mean cross-validated V1 of the paper's setting, scored beside the
        search; None where there is none (the scikit-learn baselines).
    search_wall_time_s : float
    """

    cv_best: float
    convergence: list[float]
    best_source: str
    cv_start_from: float | None = None
    search_wall_time_s: float


@dataclass(**_RECORD)
class InstanceScores(_JsonRecord):
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


@dataclass(**_RECORD)
class RepeatResult(_JsonRecord):
    """One repeat of an experiment or baseline: its search with its own seed, and the kept setting's test scores.

    Attributes
    ----------
    seed : int
        The repeat's seed (the run's seed plus the repeat's index); its search's seed is derived from it and the
        experiment or baseline (``reproduce._steps.search_seed``).
    search : SearchRecord or None, default=None
        The repeat's search; None for #10 and #11, which take the same repeat's #8 setting.
    params : dict
        The setting scored on the test half, as pipeline parameters.
    v1_test : float
        Radar V-measure on the test half, 0-1.
    n_clusters_test : int
        Clusters found on the test half.
    instance_test : InstanceScores or None, default=None
        Object-level scores on the test half.
    """

    seed: int
    search: SearchRecord | None = field(default=None, metadata=_WRITTEN_FLAT)
    params: dict[str, Any]
    v1_test: float
    n_clusters_test: int
    instance_test: InstanceScores | None = None


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
class ExperimentResult(_JsonRecord):
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
    stage1_params : dict or None, default=None
        Stage 2 only: the fixed stage-1 setting (#8's).
    derived_from_8 : str or None, default=None
        #10 and #11 only: whether #8's setting was tuned or the paper's.
    search : SearchRecord or None, default=None
        The search, for the tuned experiments.
    params : dict
        The setting scored on the test half, as pipeline parameters.
    v1_test : float
        Radar V-measure on the test half, 0-1.
    wall_time_s : float
        Wall time of the experiment (search and scoring), s.
    n_clusters_test : int
        Clusters found on the test half.
    n_stage1_clusters_test : int or None, default=None
        Stage 2 only: stage-1 clusters on the test half, before merging.
    n_merges_test : int or None, default=None
        Stage 2 only: pairs of stage-1 clusters that met the merge criterion
        on the test half (``ClusterMerger.merges_``); 0 means the experiment
        returned its stage-1 clustering unchanged.
    instance_test : InstanceScores or None, default=None
        Object-level scores on the test half.
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
    stage1_params: dict[str, Any] | None = None
    derived_from_8: str | None = None
    search: SearchRecord | None = field(default=None, metadata=_WRITTEN_FLAT)
    params: dict[str, Any]
    v1_test: float
    wall_time_s: float
    n_clusters_test: int
    n_stage1_clusters_test: int | None = None
    n_merges_test: int | None = None
    instance_test: InstanceScores | None = None
    repeats: list[RepeatResult] | None = None


@dataclass(**_RECORD)
class BaselineResult(_JsonRecord):
    """A scikit-learn clusterer tuned and scored like the experiments (``baselines.NAME``).

    Attributes
    ----------
    search : SearchRecord
    params : dict
        The kept setting, as pipeline parameters.
    v1_test : float
        Radar V-measure on the test half, 0-1.
    wall_time_s : float
        Wall time of the search and scoring, s.
    n_clusters_test : int
        Clusters found on the test half.
    instance_test : InstanceScores or None, default=None
        Object-level scores on the test half.
    repeats : list of RepeatResult or None, default=None
        Every repeat of a run with more than one, the first being the one
        whose values the other fields hold; None for a single run.
    """

    search: SearchRecord = field(metadata=_WRITTEN_FLAT)
    params: dict[str, Any]
    v1_test: float
    wall_time_s: float
    n_clusters_test: int
    instance_test: InstanceScores | None = None
    repeats: list[RepeatResult] | None = None


@dataclass(**_RECORD)
class ObjectRepeat(_JsonRecord):
    """One repeat of the object experiment: its two searches' kept settings, scored offline and causally.

    Attributes
    ----------
    seed : int
        The run's seed plus the repeat's index; each search draws from its own stream of it (``search_seed``).
    stage1_params, params : dict
        The kept stage-1 (``cluster__``) and stage-2 (``merge__``) settings.
    v1_test : float
        Radar V-measure on the test half, 0-1 (offline).
    n_clusters_test : int
        Clusters found on the test half (offline).
    instance_test : InstanceScores
        Object-level scores on the test half, offline.
    causal_v1_test : float
        Radar V-measure of the same setting run causally.
    causal_instance_test : InstanceScores
        Object-level scores of the same setting run causally.
    """

    seed: int
    stage1_params: dict[str, Any]
    params: dict[str, Any]
    v1_test: float
    n_clusters_test: int
    instance_test: InstanceScores
    causal_v1_test: float
    causal_instance_test: InstanceScores


@dataclass(**_RECORD)
class ObjectExperimentResult(_JsonRecord):
    """Beyond the paper: the object experiment (``objects``), tuned for PQ whatever the run's objective.

    Stage 1 (#8) is searched first, then stage 2 (#12's Eq. 6 velocity merging) on it
    (:func:`~sklearn_radar.experiments.object_pipeline`); the kept setting is scored on the test half offline and
    causally.

    Attributes
    ----------
    stage1_search, search : SearchRecord
        The stage-1 and the stage-2 search of the first repeat (their CV scores are PQ).
    kept : ObjectRepeat
        The first repeat: its settings and scores (written among this record's keys).
    wall_time_s : float
        Searches and scoring, s.
    repeats : list of ObjectRepeat or None, default=None
        Every repeat of a run with more than one (the first is ``kept``); None for a single run.
    """

    stage1_search: SearchRecord
    search: SearchRecord
    kept: ObjectRepeat = field(metadata=_WRITTEN_FLAT)
    wall_time_s: float
    repeats: list[ObjectRepeat] | None = None

    @property
    def every_repeat(self):
        """list of ObjectRepeat : The repeats, or the one run."""
        return self.repeats or [self.kept]


# ----------------------------------------------------------------------------- the filter's effect


@dataclass(**_RECORD)
class ClusteringCost(_JsonRecord):
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
    """The clustering time that filtering saved in each timing round, % of the unfiltered round's.

    Parameters
    ----------
    filtered, unfiltered : ClusteringCost
        With their ``clustering_times_s``.

    Returns
    -------
    savings : list of float
        Per round, in order.
    """
    return [100 * (1 - f / u) for f, u in zip(filtered.clustering_times_s, unfiltered.clustering_times_s, strict=True)]


@dataclass(frozen=True, **_RECORD)
class FilterEffectFigures(_JsonRecord):
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


@dataclass(**_RECORD)
class FilterEffectResult(_JsonRecord):
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
    measured: FilterEffectFigures = field(metadata=_WRITTEN_FLAT)
    paper: FilterEffectFigures = PAPER_FILTER_EFFECT


# ----------------------------------------------------------------------------- object tracking online


@dataclass(**_RECORD)
class TrackingScores(_JsonRecord):
    """How well object ids follow the moving road users over time (:func:`~sklearn_radar.metrics.tracking_scores`).

    Summed over the test sequences (a track never crosses sequences, so the
    identity assignment, and every count, is the sum of the sequences').

    Attributes
    ----------
    frame_s : float
        Frame length, s.
    mota, idf1 : float
        From the summed counts; NaN without ground-truth objects.
    id_switches, misses, false_positives, n_objects, n_matches, idtp, idfp, idfn, n_frames : int
    """

    frame_s: float
    mota: float
    idf1: float
    id_switches: int
    misses: int
    false_positives: int
    n_objects: int
    n_matches: int
    idtp: int
    idfp: int
    idfn: int
    n_frames: int


@dataclass(**_RECORD)
class TrackingResult(_JsonRecord):
    """One setting streamed through :class:`~sklearn_radar.online.OnlinePipeline` on the test half (``tracking``).

    Attributes
    ----------
    number : int
        The experiment whose setting streams.
    method : str
    setting_source : str
        ``"tuned #13"`` or ``"fixed #1"`` (the run's setting), ``"paper's #13"`` (the experiment did not run).
    params : dict
        The setting, as pipeline parameters (stage 1's included for stage 2).
    reported : TrackingScores
        The ids as given with each detection when its scan was labelled.
    final : TrackingScores
        The ids after every alias (stage-1 meetings, stage-2 merges) resolved to the surviving one.
    n_scans : int
    n_aliases : int
        Merges reported as aliases, summed over the test sequences.
    """

    number: int
    method: str
    setting_source: str
    params: dict[str, Any]
    reported: TrackingScores
    final: TrackingScores
    n_scans: int
    n_aliases: int


# ----------------------------------------------------------------------------- the classifier of clusters


@dataclass(**_RECORD)
class SemanticScores(_JsonRecord):
    """Semantic instance-segmentation scores (:func:`~sklearn_radar.metrics.semantic_scores`), per 0.5 s frame.

    Attributes
    ----------
    frame_s : float
        Frame length, s.
    pq, sq, rq : float
        Class-aware panoptic quality and its factors, the mean over the classes.
    map : float
        Mean average precision at IoU 0.5 over the classes (COCO's 101-point interpolation).
    macro_f1 : float
        Point-wise F1 per class (background included), their mean.
    mcov : float
        Mean coverage of the annotated instances' segments, class-agnostic.
    per_class : dict of str to dict of str to float
        By class name: ``{"pq", "ap", "f1"}``.
    """

    frame_s: float
    pq: float
    sq: float
    rq: float
    map: float
    macro_f1: float
    mcov: float
    per_class: dict[str, dict[str, float]]


@dataclass(**_RECORD)
class ClassifiedSetting(_JsonRecord):
    """One clustering with the classifier trained on its clusters, or the point-wise classifier, on the test half.

    Attributes
    ----------
    name : str
        ``"#8"``, a baseline's name, or ``"point-wise (no clustering)"``.
    setting_source : str
        Where the clustering's setting comes from (``"tuned #8"``, ``"paper's #13"``, ``"tuned baseline"``, ...).
    params : dict
        The clustering's setting, as pipeline parameters (empty for the point-wise classifier).
    scores : SemanticScores
        On the whole test half.
    per_sequence : dict of str to list of float
        ``pq``, ``map``, ``macro_f1`` and ``mcov`` of each test sequence, in order (the paired comparisons'
        data).
    background_share_before : float or None
        Share of the clustering's segments (per frame) with no detection of an annotated road user; None for the
        point-wise classifier, which has no clusters.
    background_share_after : float
        The same share among the segments the classifier keeps as road users.
    n_training_examples : int
        The classifier's training examples: segments, or detections for the point-wise classifier.
    classifier_file : str or None, default=None
        The saved classifier, in the run's folder.
    repeats : list of SemanticScores or None, default=None
        With ``--repeats``: the scores of the classifier on the clusters of each repeat's setting (the first is
        ``scores``); None for a single run, the fixed #1 and the point-wise classifier.
    """

    name: str
    setting_source: str
    params: dict[str, Any]
    scores: SemanticScores
    per_sequence: dict[str, list[float]]
    background_share_before: float | None
    background_share_after: float
    n_training_examples: int
    classifier_file: str | None = None
    repeats: list[SemanticScores] | None = None


@dataclass(**_RECORD)
class ClassificationResult(_JsonRecord):
    """The classification step: the classifier on the clusters of several settings and the point-wise one.

    Attributes
    ----------
    settings : dict of str to ClassifiedSetting
        By name, in the order of the report's table.
    test_sequences : list of int
    wall_time_s : float
    """

    settings: dict[str, ClassifiedSetting]
    test_sequences: list[int]
    wall_time_s: float


# ----------------------------------------------------------------------------- the whole run


@dataclass(**_RECORD)
class FigureRecord(_JsonRecord):
    """The figures drawn for the report (not part of ``results.json``: they are drawn after it is saved).

    Attributes
    ----------
    drawn : dict of str to str
        Figure name (``"table1_heatmap"``, ``"scene"``, ``"convergence"``) -> file name in the output folder.
    missing : str or None, default=None
        Why no figure was drawn (matplotlib missing).
    """

    drawn: dict[str, str] = field(default_factory=dict, metadata=_WRITTEN_FLAT)
    missing: str | None = None


@dataclass(**_RECORD)
class RunResults(_JsonRecord):
    """Everything a reproduce run measured: ``results.json`` in memory.

    Attributes
    ----------
    meta : RunMeta
    statistics : DataStatistics or None, default=None
        Statistics of the data; None in results of older versions.
    experiments : dict of int to ExperimentResult, default={}
        By experiment number, in run order.
    filter : FilterResult or None, default=None
        None when the filter evaluation did not run (the key is then absent).
    filter_effect : FilterEffectResult or None, default=None
    baselines : dict of str to BaselineResult or None, default=None
        By clusterer name.
    objects : ObjectExperimentResult or None, default=None
        The object experiment, when it ran.
    tracking : dict of int to TrackingResult or None, default=None
        The online pipeline's object ids scored over time, by experiment number; None when it did not run
        (and in results of older versions).
    classification : ClassificationResult or None, default=None
        The classifier of clusters on the test half, when it ran.
    figures : FigureRecord, default=FigureRecord()
        Figures drawn; written to ``results.json`` only on request.
    """

    meta: RunMeta
    statistics: DataStatistics | None = None
    experiments: dict[int, ExperimentResult] = field(default_factory=dict)
    filter: FilterResult | None = None
    filter_effect: FilterEffectResult | None = None
    baselines: dict[str, BaselineResult] | None = None
    objects: ObjectExperimentResult | None = None
    tracking: dict[int, TrackingResult] | None = None
    classification: ClassificationResult | None = None
    figures: FigureRecord = field(default_factory=FigureRecord, metadata=_NOT_WRITTEN)

    def v1_test(self):
        """Test V1 by experiment number, for the experiments that ran.

        Returns
        -------
        scores : dict of int to float
        """
        return {number: result.v1_test for number, result in self.experiments.items()}

    def saved_classifiers(self):
        """The files of the classifiers the classification step saved in the run's folder, in order.

        Returns
        -------
        names : list of str
        """
        if self.classification is None:
            return []
        return [row.classifier_file for row in self.classification.settings.values() if row.classifier_file]

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
            ``filter``, ``filter_effect``, ``baselines``, ``objects``, ``tracking`` and ``classification``
            where they ran.
        """
        document = _to_json(self)
        if figures:
            document["figures"] = _to_json(self.figures)
        return document

    @classmethod
    def _check_read(cls, document, source):
        for key, result in document.get("experiments", {}).items():
            if str(result["number"]) != key:
                raise ValueError(f"{source}: experiment {key!r} holds the record of #{result['number']}")

    @classmethod
    def read(cls, path):
        """Read a ``results.json`` file.

        Parameters
        ----------
        path : str or Path

        Returns
        -------
        results : RunResults

        Raises
        ------
        ValueError
            Naming the file and the key, if the file is not valid JSON or not a run's results.
        """
        path = Path(path)
        try:
            document = json.loads(path.read_text(encoding="utf-8"))
        except json.JSONDecodeError as error:
            raise ValueError(f"{path}: not JSON ({error})") from None
        return cls.from_json_dict(document, source=str(path))

    def to_params_dict(self):
        """What ``params.json`` holds: each experiment's setting and the best one; None before any experiment.

        Returns
        -------
        document : dict or None
            ``{"best": key, "best_reason": text, "objective": ..., "experiments": {key: {"experiment",
            "v1_test", ["pq_test",] "cv_<objective>", "params", "stage1_params"}}}``.  ``cv_v1`` (or
            ``cv_pq``) is the kept setting's mean cross-validated score of the run's objective on the
            training half, null for a setting no search of that objective kept (the expert setting, #10 and
            #11, the object experiment of a V1 run).  ``best`` is the first experiment with the highest such
            score (never chosen by a test score), the only experiment when one ran, else null; ``best_reason``
            says which rule chose it.  The object experiment, when it ran, is the key ``"objects"`` (with
            ``causal_pq_test`` besides).  An experiment whose clusters the classification step classified has
            ``"classifier"``: the file of its saved classifier in the run's folder (``sklearn-radar cluster
            --classifier``).
        """
        objective = self.meta.objective
        cv_key = f"cv_{objective}"
        experiments = {}
        for number, result in self.experiments.items():
            entry = {"experiment": result.number, "v1_test": result.v1_test}
            if result.instance_test is not None:
                entry["pq_test"] = result.instance_test.pq
            entry[cv_key] = None if result.search is None else result.search.cv_best
            entry.update(params=result.params, stage1_params=result.stage1_params)
            classified = (self.classification.settings if self.classification else {}).get(f"#{number}")
            if classified is not None and classified.classifier_file:
                entry["classifier"] = classified.classifier_file
            experiments[str(number)] = entry
        if self.objects is not None:
            experiments[OBJECT_EXPERIMENT] = {
                "experiment": OBJECT_EXPERIMENT,
                "v1_test": self.objects.kept.v1_test,
                "pq_test": self.objects.kept.instance_test.pq,
                "causal_pq_test": self.objects.kept.causal_instance_test.pq,
                # Its searches maximise PQ whatever the run's objective.
                cv_key: self.objects.search.cv_best if objective == "pq" else None,
                "params": self.objects.kept.params,
                "stage1_params": self.objects.kept.stage1_params,
            }
        if not experiments:
            return None
        best, reason = _best_setting(experiments, cv_key, objective)
        return {"best": best, "best_reason": reason, "objective": objective, "experiments": experiments}


def _best_setting(experiments, cv_key, objective):
    """``(key, why)`` of ``params.json``'s best setting: the highest cross-validated training score, never a test one.

    See :ref:`user-guide-command-line` for the rule and the settings without such a score.
    """
    scored = {key: entry[cv_key] for key, entry in experiments.items() if entry[cv_key] is not None}
    name = OBJECTIVE_NAMES[objective]
    if scored:
        best = max(scored, key=scored.get)  # the first of equal scores
        among = f"the best of {len(scored)} searched settings" if len(scored) > 1 else "the run's only searched setting"
        return best, f"{among} by cross-validated {name} on the training half ({scored[best]:.3f})"
    if len(experiments) == 1:
        return next(iter(experiments)), "the run's only setting"
    return None, f"no setting of the run has a cross-validated {name} (none was searched for it)"


#: How ``params.json`` names each objective.
OBJECTIVE_NAMES = {"v1": "V1", "pq": "PQ"}


__all__ = [
    "PAPER_FILTER_EFFECT",
    "BaselineResult",
    "BestRemoval",
    "Budget",
    "ClassificationResult",
    "ClassifiedSetting",
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
    "ObjectExperimentResult",
    "ObjectRepeat",
    "RepeatResult",
    "RunMeta",
    "RunResults",
    "SearchRecord",
    "SemanticScores",
    "TrackingResult",
    "TrackingScores",
    "repeated_scores",
    "time_savings_percent",
]
