"""The records of the tuned steps: the experiments, the scikit-learn baselines and the object experiment."""

from __future__ import annotations

from dataclasses import field
from typing import Any

from ._records import NOT_WRITTEN, WRITTEN_FLAT, JsonRecord, record


@record
class SearchRecord(JsonRecord):
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


@record
class InstanceScores(JsonRecord):
    """Object-level scores of one labelling of the test half (``instance_test``).

    Attributes
    ----------
    window_s : float
        Length of the evaluation's time windows, s.
    pq, sq, rq : float
        Panoptic, segmentation and recognition quality (RQ is the F1 score), 0-1.
    precision, recall : float
        Of the per-window segment matches (IoU > 0.5), 0-1.
    mcov, mwcov : float
        Mean and size-weighted mean coverage of the ground-truth segments, 0-1.
    background_segment_share : float
        Share of the predicted per-window segments without any object detection, 0-1.
    background_cluster_share : float
        Share of the clusters without any object detection, 0-1.
    """

    window_s: float
    pq: float
    sq: float
    rq: float
    precision: float
    recall: float
    mcov: float
    mwcov: float
    background_segment_share: float
    background_cluster_share: float


@record
class RepeatResult(JsonRecord):
    """One repeat of an experiment or baseline: its search with its own seed, and the kept setting's test scores.

    Attributes
    ----------
    seed : int
        The repeat's seed (the run's seed plus the repeat's index); its search's seed is derived from it and the
        experiment or baseline (``reproduce._tuning.search_seed``).
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
    search: SearchRecord | None = field(default=None, metadata=WRITTEN_FLAT)
    params: dict[str, Any]
    v1_test: float
    n_clusters_test: int
    instance_test: InstanceScores | None = None


def repeated_scores(result, score="v1"):
    """The test ``score`` (``"v1"`` or ``"pq"``) of an experiment or baseline per repeat; ``[]`` for a missing PQ."""
    records = result.repeats or [result]
    if score == "v1":
        return [float(r.v1_test) for r in records]
    return [float(r.instance_test.pq) for r in records if r.instance_test is not None]


@record
class ExperimentResult(JsonRecord):
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
    search: SearchRecord | None = field(default=None, metadata=WRITTEN_FLAT)
    params: dict[str, Any]
    v1_test: float
    wall_time_s: float
    n_clusters_test: int
    n_stage1_clusters_test: int | None = None
    n_merges_test: int | None = None
    instance_test: InstanceScores | None = None
    repeats: list[RepeatResult] | None = None


@record
class BaselineResult(JsonRecord):
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

    search: SearchRecord = field(metadata=WRITTEN_FLAT)
    params: dict[str, Any]
    v1_test: float
    wall_time_s: float
    n_clusters_test: int
    instance_test: InstanceScores | None = None
    repeats: list[RepeatResult] | None = None


@record
class ObjectRepeat(JsonRecord):
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


@record
class ObjectExperimentResult(JsonRecord):
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
    kept: ObjectRepeat = field(metadata=WRITTEN_FLAT)
    wall_time_s: float
    repeats: list[ObjectRepeat] | None = None

    @property
    def every_repeat(self):
        """list of ObjectRepeat : The repeats, or the one run."""
        return self.repeats or [self.kept]


@record
class InstanceErrors(JsonRecord):
    """Where a labelling of the test half loses panoptic quality (:func:`~sklearn_radar.metrics.instance_errors`).

    Attributes
    ----------
    n_true, n_pred : int
        Ground-truth and predicted per-window segments.
    matched, missed : int
        Ground-truth segments matched (IoU > 0.5) and not.
    noise, merged_with_object, merged_with_background, split : int
        The missed segments by cause (they add up to ``missed``).
    false : int
        Predicted segments that match none.
    background, part_of_object, several_objects : int
        The false segments by cause (they add up to ``false``).
    median_size_matched, median_size_missed : float
        Median detections of the matched and of the missed ground-truth segments (NaN without any).
    """

    n_true: int
    n_pred: int
    matched: int
    missed: int
    noise: int
    merged_with_object: int
    merged_with_background: int
    split: int
    false: int
    background: int
    part_of_object: int
    several_objects: int
    median_size_matched: float
    median_size_missed: float


@record
class LearnedCausalResult(JsonRecord):
    """The learned grouping's causal model (``LinkClustering(causal=True)``), fitted on the training half.

    Fitted as the offline one, on causal features, its thresholds tuned with the causal agglomeration; what
    ``sklearn-radar stream --experiment learned`` runs scan by scan.

    Attributes
    ----------
    model_file : str
        The fitted causal pipeline's file in the run's folder.
    link_threshold, objectness_threshold : float
        The tuned thresholds.
    min_cluster_size : int
        The tuned confirmation count, detections.
    cv_pq : float
        PQ of the tuned thresholds on the out-of-fold predictions of the training half.
    fit_wall_time_s : float
        Time of the fit, s.
    v1_test : float
        Radar V-measure on the test half, causal, 0-1.
    n_clusters_test : int
        Clusters found on the test half.
    instance_test : InstanceScores
        Object-level scores on the test half, causal (the stream's final ids).
    params : dict, default={}
        The causal pipeline's settings (``step__name``: value; empty in a run written before they were recorded).
    model : Pipeline or None, default=None
        The fitted causal pipeline itself, for the tracking step of the same run (not written: the file holds it).
    """

    model_file: str
    link_threshold: float
    objectness_threshold: float
    min_cluster_size: int
    cv_pq: float
    fit_wall_time_s: float
    v1_test: float
    n_clusters_test: int
    instance_test: InstanceScores
    params: dict[str, Any] = field(default_factory=dict)
    model: Any = field(default=None, compare=False, repr=False, metadata=NOT_WRITTEN)


@record
class LearnedResult(JsonRecord):
    """Beyond the paper: the learned grouping (``learned``), fitted on the training half, scored offline.

    The pipeline is :func:`~sklearn_radar.experiments._learned.learned_pipeline`: the object experiment's front and
    :class:`~sklearn_radar.cluster.LinkClustering`, fitted once with the pre-clustered target
    (:func:`~sklearn_radar.metrics.precluster_target`), its thresholds tuned for PQ inside ``fit``.

    Attributes
    ----------
    params : dict
        The pipeline's parameters as set (the front's and ``link__``'s).
    model_file : str
        The fitted pipeline's file in the run's folder.
    link_threshold, objectness_threshold : float
        The tuned thresholds (``LinkClustering.link_threshold_``, ``objectness_threshold_``).
    min_cluster_size : int
        The tuned minimum cluster size, detections.
    cv_pq : float
        PQ of the tuned thresholds on the out-of-fold predictions of the training half (``cv_score_``).
    n_training_pairs : int
        Candidate pairs of the training half.
    fit_wall_time_s : float
        Time of the fit, s.
    v1_test : float
        Radar V-measure on the test half, 0-1.
    n_clusters_test : int
        Clusters found on the test half.
    instance_test : InstanceScores
        Object-level scores on the test half, offline.
    errors : dict of str to InstanceErrors
        The error anatomy on the test half of the learned grouping, and of the object experiment's and the
        strongest offline baseline's kept settings where they ran, by name.
    wall_time_s : float
        Fit, scoring and error anatomy, s (the causal model's included).
    causal : LearnedCausalResult or None, default=None
        The causal model, fitted and scored beside (None in runs of older versions).
    model : Pipeline or None, default=None
        The fitted pipeline itself, for the classification step of the same run (not written: the file holds it).
    """

    params: dict[str, Any]
    model_file: str
    link_threshold: float
    objectness_threshold: float
    min_cluster_size: int
    cv_pq: float
    n_training_pairs: int
    fit_wall_time_s: float
    v1_test: float
    n_clusters_test: int
    instance_test: InstanceScores
    errors: dict[str, InstanceErrors]
    wall_time_s: float
    causal: LearnedCausalResult | None = None
    model: Any = field(default=None, compare=False, repr=False, metadata=NOT_WRITTEN)
