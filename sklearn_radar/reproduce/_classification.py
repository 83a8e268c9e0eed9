"""The classification step (the paper's next stage) and its records: a classifier trained on each setting's clusters.

For each setting of :data:`~._constants.CLASSIFIED` (a paper's experiment: the run's tuned one where it ran, the
paper's otherwise; the object experiment and the learned grouping where the run has them) and the strongest offline
scikit-learn baseline, a
:class:`~sklearn_radar.classification.ClusterClassifier` is trained on the clusters of the training half (in this
process: it needs all its examples at once) and scored on each test sequence where it lives with
:func:`~sklearn_radar.metrics.semantic_scores`; beside them the
:class:`~sklearn_radar.classification.PointClassifier` (no clustering).  Why: :ref:`user-guide-classification`.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import pandas as pd
from sklearn.base import clone
from sklearn.frozen import FrozenEstimator
from sklearn.pipeline import Pipeline

from ..classification import ROAD_USER_CLASSES, ClusterClassifier, PointClassifier, road_user_class
from ..experiments import (
    BASELINE_INPUT,
    SKLEARN_BASELINES,
    SLIDING_BASELINE,
    baseline_pipeline,
    experiment_pipeline,
    object_pipeline,
)
from ..metrics import background_share, semantic_scores
from ._constants import BASELINES, BEST_STAGE1, CLASSIFIED, LEARNED, OBJECTS, SCORE_WINDOW_S
from ._context import Outcome
from ._records import JsonRecord, record
from ._tracking import run_setting_pipeline, tracked_setting

#: Name of the point-wise classifier's row.
POINT_WISE = "point-wise (no clustering)"

#: The file of the saved classifier (:func:`~sklearn_radar.classification.save_classifier`: the whole pipeline
#: from raw detections, for ``sklearn-radar cluster --classifier``) of each classified experiment, and of the
#: strongest baseline, in the run's folder.
CLASSIFIER_FILES = {
    **{f"#{key}" if isinstance(key, int) else key: f"classifier_{key}.joblib" for key in CLASSIFIED},
    "baseline": "classifier_baseline.joblib",
}

#: The scores of :class:`SemanticScores` kept per test sequence, for the paired comparisons.
PER_SEQUENCE = ("pq", "map", "macro_f1", "mcov")

#: Columns of the detection table the models do not read.
_NOT_INPUT = ("uuid", "label_id")


@record
class SemanticScores(JsonRecord):
    """Semantic instance-segmentation scores (:func:`~sklearn_radar.metrics.semantic_scores`), per 0.5 s time window.

    Attributes
    ----------
    window_s : float
        Window length, s.
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
    precision_at_recall : dict of str to list of float or None, default=None
        By class name (those present in the truth): the interpolated precision at recall 0, 0.01, ..., 1, the
        precision-recall curve whose mean is the class's AP (3 decimals); None in results of older versions.
    """

    window_s: float
    pq: float
    sq: float
    rq: float
    map: float
    macro_f1: float
    mcov: float
    per_class: dict[str, dict[str, float]]
    precision_at_recall: dict[str, list[float]] | None = None


@record
class ClassifiedSetting(JsonRecord):
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
        Share of the clustering's segments (per time window) with no detection of an annotated road user; None for the
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


@record
class ClassificationResult(JsonRecord):
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


def classified_settings(needed):
    """``[(name, source, pipelines, params)]``: :data:`CLASSIFIED`, then the strongest baseline; a pipeline a repeat.

    A paper's experiment missing from the run takes the paper's setting; the object experiment and the learned
    grouping, which have none, are left out where the run lacks them.
    """
    found = [setting for key in CLASSIFIED if (setting := _classified(key, needed)) is not None]
    best = strongest_offline_baseline(needed.get(BASELINES))
    if best is not None:
        name, result = best
        pipelines = [baseline_pipeline(name).set_params(**r.params) for r in result.repeats or [result]]
        found.append((name, "tuned baseline", pipelines, result.params))
    return found


def setting_name(key):
    """The row name of a classified setting: ``"#8"`` for an experiment number, the step key otherwise."""
    return f"#{key}" if isinstance(key, int) else key


def _classified(key, needed):
    """``(name, source, pipelines, params)`` of one key of :data:`CLASSIFIED`; None when the run lacks it."""
    result = needed.get(str(key))
    if isinstance(key, int):
        pipeline, params, source = tracked_setting(key, result)
        return setting_name(key), source, [pipeline, *_later_repeats(key, result, needed)], params
    if result is None:
        return None
    if key == OBJECTS:
        pipelines = [
            object_pipeline(2, stage1_params=r.stage1_params, params=r.params) for r in result.repeats or [result.kept]
        ]
        return (
            setting_name(key),
            "PQ-tuned object experiment",
            pipelines,
            {**result.kept.stage1_params, **result.kept.params},
        )
    if key == LEARNED:
        if result.model is None:  # read back from a results.json: the fitted model is not there
            return None
        model = result.model
        frozen = Pipeline([*model.steps[:-1], (model.steps[-1][0], FrozenEstimator(model.steps[-1][1]))])
        return setting_name(key), "learned grouping (fitted on the training half)", [frozen], result.params
    raise ValueError(f"the classification step does not know the setting {key!r}")


def _later_repeats(number, result, needed):
    """The pipelines of repeats 2, 3, ... of experiment ``number``'s search (none for a single run)."""
    if result is None or not result.repeats:
        return []
    stage1s = [result.stage1_params] * len(result.repeats)
    best = needed.get(str(BEST_STAGE1))
    if result.stage1_params is not None and best is not None and len(best.repeats or []) == len(result.repeats):
        stage1s = [{k: v for k, v in r.params.items() if k.startswith("cluster__")} for r in best.repeats]
    return [
        run_setting_pipeline(number, r.params, stage1)
        for r, stage1 in zip(result.repeats[1:], stage1s[1:], strict=True)
    ]


def strongest_offline_baseline(baselines):
    """``(name, result)`` of the offline baseline with the best cross-validated score; None without baselines."""
    scored = [
        (name, result)
        for name, result in (baselines or {}).items()
        if result.instance_test is not None and name != SLIDING_BASELINE and name in SKLEARN_BASELINES
    ]
    return max(scored, key=lambda item: item[1].search.cv_best, default=None)


def classifier_model(pipeline):
    """The pipeline with its clusterer wrapped in a :class:`ClusterClassifier` (stage 0 unchanged)."""
    steps = [(name, clone(step)) for name, step in pipeline.steps[:-1]]
    clusterer = clone(pipeline.steps[-1][1])
    model = clone(pipeline)
    model.steps = [*steps, ("classify", ClusterClassifier(clusterer, window=SCORE_WINDOW_S))]
    return model


def point_model():
    """The point-wise classifier after the FCS and filter input of the baselines (#3's stage 0)."""
    model = experiment_pipeline(BASELINE_INPUT)
    model.steps[-1] = ("classify", PointClassifier())
    return model


def model_input(data):
    """A detection table as the models read it: every column but ``uuid`` and ``label_id`` (fit reads ``track_id``)."""
    return data[[c for c in data.columns if c not in _NOT_INPUT]]


def training_table(sequence):
    """One training sequence: its :func:`model_input` and its detections' road-user classes."""
    data = sequence.scenes.data
    return model_input(data), road_user_class(data["label_id"])


def classified_sequence(sequence, model):
    """One test sequence classified by the fitted ``model``: its scores' arrays (``clusters`` None point-wise)."""
    data = sequence.scenes.data
    working = model[:-1].transform(model_input(data))
    classifier = model[-1]
    clusters = None
    if isinstance(classifier, ClusterClassifier):
        clusters = classifier._cluster(working, len(working))  # as it clusters: a fresh clone, or a frozen model
        found = classifier.predict_instances_of(working, clusters)
    else:
        found = classifier.predict_instances(working)
    return {
        "id": sequence.id,
        "classes_true": road_user_class(data["label_id"]),
        "instances_true": np.asarray(sequence.scenes.target, dtype=np.int64),
        "target": np.asarray(sequence.target, dtype=np.int64),
        "times": data["timestamp"].to_numpy(dtype=np.float64) * 1e-6,
        "classes_pred": found["class"].to_numpy(),
        "instances_pred": found["instance"].to_numpy(),
        "confidence": found["confidence"].to_numpy(),
        "clusters": clusters,
    }


def run_classification(env, key, needed):
    """The classifier trained on each setting's training clusters, and the point-wise one, scored on the test half."""
    start = time.perf_counter()
    tables = env.sequences.map(training_table, env.train, executor=env.executor)
    X_train = pd.concat([X for X, _ in tables], ignore_index=True)
    y_train = np.concatenate([y for _, y in tables])
    rows, lines, models = {}, [], {}
    jobs = [(name, source, pipelines, params) for name, source, pipelines, params in classified_settings(needed)]
    jobs.append((POINT_WISE, "FCS and filter, per detection", [None], {}))
    for name, source, pipelines, params in jobs:
        file = _classifier_file(name, source)
        repeats = []
        for pipeline in pipelines:
            model = point_model() if pipeline is None else classifier_model(pipeline)
            model.fit(X_train, y_train)
            parts = env.sequences.map(classified_sequence, env.test, model, executor=env.executor)
            repeats.append(_classified_setting(name, source, params, model, parts, file))
            if file is not None and len(repeats) == 1:
                models[file] = model
        rows[name] = repeats[0]
        if len(repeats) > 1:
            rows[name].repeats = [r.scores for r in repeats]
        scores = rows[name].scores
        lines.append(
            f"    {name}: class PQ {scores.pq:.3f}, mAP@0.5 {scores.map:.3f}, macro-F1 {scores.macro_f1:.3f}, "
            f"mCov {scores.mcov:.3f}" + (f" (first of {len(repeats)} repeats)" if len(repeats) > 1 else "")
        )
    result = ClassificationResult(settings=rows, test_sequences=list(env.test), wall_time_s=time.perf_counter() - start)
    return Outcome(result, "\n".join(lines), models=models)


def _classifier_file(name, source):
    """The file the classifier of ``name`` is saved to; None point-wise and for a paper's setting (no params.json)."""
    if name == POINT_WISE or source.startswith("paper's"):
        return None
    return CLASSIFIER_FILES.get(name, CLASSIFIER_FILES["baseline"])


def _classified_setting(name, source, params, model, parts, file):
    """The :class:`ClassifiedSetting` of one fitted model from its test sequences' arrays."""
    pooled = {k: np.concatenate([p[k] for p in parts]) for k in parts[0] if k not in ("id", "clusters")}
    groups = np.concatenate([np.full(len(p["times"]), p["id"]) for p in parts])
    scores = _scores(pooled, groups)
    per_sequence = {k: [] for k in PER_SEQUENCE}
    for part in parts:
        one = _scores(part, np.full(len(part["times"]), part["id"]))
        for k in PER_SEQUENCE:
            per_sequence[k].append(float(getattr(one, k)))
    before = None
    if parts[0]["clusters"] is not None:
        before = _background_share(pooled, np.concatenate([p["clusters"] for p in parts]), groups)
    return ClassifiedSetting(
        name=name,
        setting_source=source,
        params=params,
        scores=scores,
        per_sequence=per_sequence,
        background_share_before=before,
        background_share_after=_background_share(pooled, pooled["instances_pred"], groups),
        n_training_examples=model[-1].n_training_examples_,
        classifier_file=file,
    )


def _scores(arrays, groups):
    found = semantic_scores(
        arrays["classes_true"],
        arrays["instances_true"],
        arrays["classes_pred"],
        arrays["instances_pred"],
        arrays["confidence"],
        times=arrays["times"],
        groups=groups,
        window=SCORE_WINDOW_S,
    )
    per_class = {
        ROAD_USER_CLASSES[int(code)]: {k: float(v) for k, v in figures.items()}
        for code, figures in found["per_class"].items()
        if int(code) in ROAD_USER_CLASSES
    }
    curves = {
        ROAD_USER_CLASSES[int(code)]: [round(float(p), 3) for p in precision]
        for code, precision in found["precision_at_recall"].items()
        if int(code) in ROAD_USER_CLASSES
    }
    return SemanticScores(
        window_s=SCORE_WINDOW_S,
        **{k: float(found[k]) for k in ("pq", "sq", "rq", "map", "macro_f1", "mcov")},
        per_class=per_class,
        precision_at_recall=curves,
    )


def _background_share(arrays, labels, groups):
    """Share of the per-window segments of ``labels`` without a road user of the pre-clustered target."""
    share = background_share(arrays["target"], labels, times=arrays["times"], groups=groups, window=SCORE_WINDOW_S)
    return float(share.background_segment_share)
