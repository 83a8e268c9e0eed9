"""Everything a reproduce run measured, ``results.json`` in memory, and what ``params.json`` holds.

``results.json`` is :meth:`RunResults.to_json_dict` written with ``json.dumps(indent=1)``, and
:meth:`RunResults.read` reads it back (the JSON form's rules: :mod:`._records`).  Parameter settings (``params``,
``paper_params``, ...) stay dictionaries of pipeline parameters (``{"cluster__eps_xy": 0.6, ...}``).
"""

from __future__ import annotations

import json
from dataclasses import field
from pathlib import Path
from typing import Any

from ..experiments import OBJECT_EXPERIMENT
from ..experiments._learned import LEARNED_EXPERIMENT
from ._budget import Budget
from ._classification import ClassificationResult
from ._experiment_records import BaselineResult, ExperimentResult, LearnedResult, ObjectExperimentResult
from ._filter_records import FilterEffectResult, FilterResult
from ._records import ABSENT_AT_DEFAULT, NOT_WRITTEN, WRITTEN_FLAT, JsonRecord, record, to_json
from ._tracking import TrackingStep


@record
class DataMeta(JsonRecord):
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


@record
class RunMeta(JsonRecord):
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
        score): the paper's radar V-measure, or the panoptic quality of moving road users per 0.5 s time window.
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
    repeats: int = field(default=1, metadata=ABSENT_AT_DEFAULT)
    wall_time_s: float | None = None


@record
class DataStatistics(JsonRecord):
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


@record
class FigureRecord(JsonRecord):
    """The figures drawn for the report (not part of ``results.json``: they are drawn after it is saved).

    Attributes
    ----------
    drawn : dict of str to str
        Figure name (``"table1_heatmap"``, ``"scene"``, ``"convergence"``) -> file name in the output folder.
    missing : str or None, default=None
        Why no figure was drawn (matplotlib missing).
    """

    drawn: dict[str, str] = field(default_factory=dict, metadata=WRITTEN_FLAT)
    missing: str | None = None


@record
class RunResults(JsonRecord):
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
    tracking : TrackingStep or None, default=None
        The settings streamed online, their object and track ids scored over time, the tuned Tracker and the
        baseline tracker; None when it did not run (and in results of older versions).
    classification : ClassificationResult or None, default=None
        The classifier of clusters on the test half, when it ran.
    learned : LearnedResult or None, default=None
        The learned grouping, when it ran.
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
    tracking: TrackingStep | None = None
    classification: ClassificationResult | None = None
    learned: LearnedResult | None = None
    figures: FigureRecord = field(default_factory=FigureRecord, metadata=NOT_WRITTEN)

    def v1_test(self):
        """Test V1 by experiment number (a dict of int to float), for the experiments that ran."""
        return {number: result.v1_test for number, result in self.experiments.items()}

    def saved_classifiers(self):
        """The file names of the models the run saved in its folder: the classifiers, then the learned grouping."""
        files = [] if self.learned is None else [self.learned.model_file]
        if self.learned is not None and self.learned.causal is not None:
            files.append(self.learned.causal.model_file)
        if self.classification is None:
            return files
        return [row.classifier_file for row in self.classification.settings.values() if row.classifier_file] + files

    def to_json_dict(self, *, figures=False):
        """What ``results.json`` holds, a dict; with ``figures``, also the figures drawn (which it does not hold)."""
        document = to_json(self)
        if figures:
            document["figures"] = to_json(self.figures)
        return document

    @classmethod
    def _check_read(cls, document, source):
        for key, result in document.get("experiments", {}).items():
            if str(result["number"]) != key:
                raise ValueError(f"{source}: experiment {key!r} holds the record of #{result['number']}")

    @classmethod
    def read(cls, path):
        """The :class:`RunResults` of the ``results.json`` file at ``path`` (ValueError naming the file and the key)."""
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
            ``causal_pq_test`` besides).  The learned grouping, when it ran, is the key ``"learned"``: its front's
            parameters (``params``), ``model`` (the fitted pipeline's file in the run's folder) and a null
            ``cv_<objective>`` (its thresholds are tuned inside its fit, on other folds than the run's searches, so
            it is not ranked).  An experiment whose clusters the classification step classified has
            ``"classifier"``: the file of its saved classifier in the run's folder (``sklearn-radar cluster
            --classifier``).  ``"tracker"``, when the tracking step tuned one: the
            :class:`~sklearn_radar.online.Tracker`'s parameters (``params``), the setting whose ids it was tuned
            on (``tuned_on``), ``criterion`` and its ``train_score`` on the training half (``sklearn-radar stream
            --track``).
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
        if self.learned is not None:
            experiments[LEARNED_EXPERIMENT] = {
                "experiment": LEARNED_EXPERIMENT,
                "v1_test": self.learned.v1_test,
                "pq_test": self.learned.instance_test.pq,
                cv_key: None,
                "params": {k: v for k, v in self.learned.params.items() if not k.startswith("link__")},
                "stage1_params": None,
                "model": self.learned.model_file,
            }
            if self.learned.causal is not None:
                experiments[LEARNED_EXPERIMENT]["causal_model"] = self.learned.causal.model_file
        for key in (OBJECT_EXPERIMENT, LEARNED_EXPERIMENT):
            classified = (self.classification.settings if self.classification else {}).get(key)
            if key in experiments and classified is not None and classified.classifier_file:
                experiments[key]["classifier"] = classified.classifier_file
        if not experiments:
            return None
        best, reason = _best_setting(experiments, cv_key, objective)
        document = {"best": best, "best_reason": reason, "objective": objective, "experiments": experiments}
        tracker = None if self.tracking is None else self.tracking.tracker
        if tracker is not None:
            document["tracker"] = to_json(tracker)
        return document


def _best_setting(experiments, cv_key, objective):
    """``(key, why)`` of ``params.json``'s best: the highest cross-validated score (:ref:`user-guide-command-line`)."""
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
