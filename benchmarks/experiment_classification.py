"""Classifying the object setting's clusters (issue #43): where class PQ goes, and clustering against point-wise.

For each preset and seed: ``make_scenes`` (``--n-sequences`` x ``--duration`` s), split into a training and a
test half of whole sequences (``sequence_train_test_split``, the seed's split); the object experiment
(``experiments.object_pipeline``: #12's velocity merging on #8 with a minimum cluster size) is tuned for
per-window PQ on the training half only, with the object-level ablation's search
(``benchmarks/ablation_object_level.py``, ``run_one``: stage 1, then stage 2 on it; ``--n-iter`` iterations
each, folds grouped by sequence).  Then, all trained on the training half and scored on the test half:

* ``clusters``: ``ClusterClassifier`` on the tuned setting's clusters (frame, filter, ClusterClassifier(merge));
* ``clusters, true segments``: the same, trained also on the ground truth's segments
  (``ClusterClassifier(true_segments=True)``);
* ``point (4 features)``: ``PointClassifier()``, the minimal row: v_r, RCS, range and azimuth of one detection;
* ``point (neighbourhood)``: ``PointClassifier(radius=--radius, time_window=--time-window)``, the same learner
  with each detection's neighbourhood (counts, x-y spread, Doppler and RCS statistics of the kept detections
  within the radius and +- the time window: offline, not causal, as the offline clustering is).

All three see the same frame transform and Doppler-density filter (the tuned setting's).  The scores are
``metrics.class_panoptic_quality`` per 0.5 s window (class-mean and per class), the class-agnostic PQ of the
same predicted instances (``metrics.panoptic_quality``: the road users kept), the clustering's PQ before the
classifier (every cluster, for the clusters; the agnostic PQ again for the point-wise ones), and
``metrics.class_errors`` of the clusters (the clusterer's own labels, so that a road user called background
counts as misclassified, not missed).  The tables give the mean over seeds and the paired differences (mean +-
standard error over seeds; a difference counts beyond 2 SE).

``--extra-training N`` adds N simulated sequences of the same preset (seed + 1000) to the training data of the
three classifiers (not to the tuning, which stays on the training half): how much the classes gain from more
examples.  ``--class-weight balanced`` gives the learner of all three balanced class weights.

``--perfect-clusters`` prints instead the F1 per class of the default learner on perfect clusters (each
object's own detections per 0.5 s window) of the test half, trained on ``--training-sizes`` other simulated
sequences: what the classes' signatures allow, and how it grows with the training data.

Run (the user guide's tables; about 5 minutes each on 2 busy cores, after the tuning, about 1 minute per preset
and seed at 10 iterations)::

    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/experiment_classification.py --seeds 0 1 2 \\
        --data realistic easy --tuned-dir /tmp/tuned
    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/experiment_classification.py --seeds 0 1 2 \\
        --data realistic easy --tuned-dir /tmp/tuned --extra-training 6

``--history`` trains, instead of the three models, the clusters' classifier with each ``history`` option of
``ClusterClassifier`` (None: the single window; ``"mean_proba"``; ``"features"``) and with an isotonic
``CalibratedClassifierCV`` learner (one fold per training sequence, ``LeaveOneGroupOut``, the sequences routed to it
by scikit-learn's metadata routing: no object's segments in two folds), and reports class PQ, mAP@0.5 and the
per-object macro-F1 (the test segments matched to an annotated road user, by the windows their cluster has been
seen in: 1, 2-3, 4-7, 8+), with the paired differences to the single window (mean +- 2 SE over seeds); with
``--online`` the test half's clusters are the final object ids of ``OnlinePipeline``'s causal replay (aliases
resolved, what ``stream --classifier`` classifies) instead of the offline ones.  The user guide's history tables::

    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/experiment_classification.py --history --seeds 0 1 2 3 4 \\
        --data realistic easy --tuned-dir /tmp/tuned [--extra-training 6] [--online]

``--learned`` classifies instead the learned grouping (``experiments._learned.learned_pipeline()``: the object
experiment's front at the paper's setting and ``LinkClustering`` with its defaults, its thresholds tuned inside its
fit) fitted on the training half with ``precluster_target``, beside the tuned object setting's clusters and the
neighbourhood point-wise classifier: each clustering's classifier with the single window and with
``history="mean_proba"`` (the learned grouping's also with ``"cluster_mean_proba"``, every window of a cluster
from all of them).  The learned grouping's classifier is trained on out-of-fold clusters of the training
half (each sequence clustered by a ``LinkClustering`` with the tuned thresholds fixed, fitted on the other
sequences: the kind of clusters the test half gets) and, as ``reproduce`` trains it, on the fitted model's own
clusters of its training data (``in-sample``), each also with the ground truth's segments beside the clusters
(``ClusterClassifier(true_segments=True)``); with ``--extra-training`` the grouping stays fitted on the training
half and labels the extra sequences with ``predict``.  The report gives per class PQ, the class PQ / clustering
PQ ratio, per-object macro-F1 by windows seen and the paired differences (mean +- 2 SE over seeds); the user
guide's tables (``--runs-file`` keeps the records as they come)::

    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/experiment_classification.py --learned --seeds 0 1 2 3 4 \\
        --data realistic easy --tuned-dir /tmp/tuned [--extra-training 6]

``--tuned-dir`` keeps each tuned setting in a JSON file (``tuned_<preset>_<seed>.json``) and reuses it, so a
second run (for example before and after a change to the classifier) scores the same clusters.
"""

from __future__ import annotations

import argparse
import json
import math
import pickle
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import sklearn
from sklearn.base import BaseEstimator, clone
from sklearn.calibration import CalibratedClassifierCV
from sklearn.ensemble import HistGradientBoostingClassifier
from sklearn.frozen import FrozenEstimator
from sklearn.metrics import f1_score
from sklearn.model_selection import GroupKFold, LeaveOneGroupOut
from sklearn.pipeline import Pipeline
from threadpoolctl import threadpool_limits

from sklearn_radar import FrameTransform
from sklearn_radar.classification import (
    ClusterClassifier,
    PointClassifier,
    cluster_features,
    predict_instances,
    road_user_class,
)
from sklearn_radar.classification._features import window_index
from sklearn_radar.classification._history import cluster_starts
from sklearn_radar.classification._targets import segment_targets
from sklearn_radar.classification._wrapped import DEFAULT_CLASSIFIER_PARAMS, default_classifier
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import object_pipeline
from sklearn_radar.experiments._learned import learned_pipeline
from sklearn_radar.metrics import (
    class_errors,
    class_panoptic_quality,
    panoptic_quality,
    precluster_target,
    semantic_scores,
)
from sklearn_radar.model_selection import sequence_train_test_split
from sklearn_radar.online import OnlinePipeline
from sklearn_radar.online._replay import replay

CLASS_NAMES = {0: "car", 1: "large vehicle", 2: "two-wheeler", 3: "pedestrian", 4: "pedestrian group"}
ERROR_KEYS = ("n_true", "tp", "misclassified", "missed", "n_pred", "wrong_class", "false")
#: The single-window classifier's row of ``--history``, the one the history options are paired against.
SINGLE = "single window"
#: ``--learned``: the object setting's clusters, the neighbourhood point-wise baseline and the learned rows.
OBJECTS, NEIGHBOURHOOD, LEARNED = "objects", "point (neighbourhood)", "learned (out-of-fold)"
#: The learned grouping's classifier rows: ``history`` and the suffix of the row's name.
HISTORY_ROWS = ((None, ""), ("mean_proba", ", mean proba"), ("cluster_mean_proba", ", cluster mean proba"))
#: Bins of the number of windows a cluster has been seen in (this one included): ``(label, low, high)``.
SEEN_BINS = (("1", 1, 1), ("2-3", 2, 3), ("4-7", 4, 7), ("8+", 8, np.inf))


def object_f1(Xt, labels, truth, classes_pred):
    """Per-object macro-F1 over the road-user classes, overall and by the windows the cluster has been seen in.

    The objects are the test segments (one cluster in one 0.5 s window) matched to an annotated road user (IoU >
    0.5, the training target's rule); a segment's prediction is its class (background counts as wrong).  The
    windows seen are the segment's rank in its cluster's windows (the history a causal classifier has).
    Returns ``{"all": (f1, n), label: (f1, n), ...}``.
    """
    classes, instances = truth
    sequence = Xt["sequence"].to_numpy()
    windows = window_index(Xt["t"].to_numpy(dtype=np.float64), sequence, 0.5)
    table, rows = cluster_features(Xt[["x", "y", "v_r", "t", "sequence"]], labels, window=0.5, return_rows=True)
    target = segment_targets(classes, instances, sequence, windows, rows, len(table))
    predicted = np.full(len(table), -1, dtype=np.int64)
    clustered = rows >= 0
    predicted[rows[clustered]] = classes_pred[clustered]
    first = cluster_starts(table)
    seen = np.arange(len(table)) - np.flatnonzero(first)[np.cumsum(first) - 1] + 1
    found = {}
    for label, low, high in (("all", 1, np.inf), *SEEN_BINS):
        mine = (target >= 0) & (seen >= low) & (seen <= high)
        present = sorted(np.unique(target[mine]).tolist())  # a class absent from the bin is not scored
        if not mine.any():  # no object in the bin (a short run): no score
            found[label] = (float("nan"), 0)
            continue
        score = f1_score(target[mine], predicted[mine], labels=present, average="macro", zero_division=0)
        found[label] = (float(score), int(mine.sum()))
    return found


def tuned_setting(preset, seed, options):
    """The object setting tuned for PQ on the training half: ``(stage-1 params, stage-2 params)``."""
    path = Path(options.tuned_dir) / f"tuned_{preset}_{seed}.json" if options.tuned_dir else None
    if path is not None and path.exists():
        found = json.loads(path.read_text())
    else:
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        import ablation_object_level as ablation

        chosen = [v for v in ablation.variants() if v.name in ("objects (stage 1)", "objects")]
        args = argparse.Namespace(
            n_sequences=options.n_sequences, duration=options.duration, n_iter=options.n_iter, cv_folds=2
        )
        found = ablation.run_one(preset, seed, chosen, args)
        found = {name: {"params": record["params"], "pq": record["pq"]} for name, record in found.items()}
        if path is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(json.dumps(found))
    return found["objects (stage 1)"]["params"], found["objects"]["params"]


def models(setting, options):
    """The classified pipelines, each on the tuned setting's frame transform and filter.

    The three of the module's docstring; with ``--history``, the clusters' classifier with each history option
    instead (and calibrated, for the confidences of mAP).
    """
    stage1, stage2 = setting
    pipeline = object_pipeline(2, stage1_params=stage1, params=stage2)
    front = pipeline.steps[:-1]
    learner = None
    if options.class_weight:
        learner = HistGradientBoostingClassifier(**DEFAULT_CLASSIFIER_PARAMS, class_weight=options.class_weight)
    if options.history:
        folds = LeaveOneGroupOut()  # a segment's fold is its sequence's (routed: see main), no object in two
        calibrated = CalibratedClassifierCV(default_classifier(), method="isotonic", cv=folds)
        variants = {
            SINGLE: {},
            "history: mean proba": {"history": "mean_proba"},
            "history: features": {"history": "features"},
            "single, calibrated": {"classifier": calibrated},
            "mean proba, calibrated": {"history": "mean_proba", "classifier": calibrated},
        }
        return {
            name: Pipeline([*clone(Pipeline(front)).steps, ("classify", ClusterClassifier(pipeline[-1], **params))])
            for name, params in variants.items()
        }
    point = dict(classifier=learner, eps_xy=1.0, eps_t=0.25)
    if options.learned:  # the object setting's rows the learned grouping is paired against
        return {
            name: Pipeline([*clone(Pipeline(front)).steps, ("classify", classify)])
            for name, classify in (
                (OBJECTS, ClusterClassifier(pipeline[-1], classifier=learner)),
                (f"{OBJECTS}, mean proba", ClusterClassifier(pipeline[-1], classifier=learner, history="mean_proba")),
                (NEIGHBOURHOOD, PointClassifier(**point, radius=options.radius, time_window=options.time_window)),
            )
        }
    return {
        "clusters": Pipeline(
            [*clone(Pipeline(front)).steps, ("classify", ClusterClassifier(pipeline[-1], classifier=learner))]
        ),
        "clusters, true segments": Pipeline(
            [
                *clone(Pipeline(front)).steps,
                ("classify", ClusterClassifier(pipeline[-1], classifier=learner, true_segments=True)),
            ]
        ),
        "point (4 features)": Pipeline([*clone(Pipeline(front)).steps, ("classify", PointClassifier(**point))]),
        "point (neighbourhood)": Pipeline(
            [
                *clone(Pipeline(front)).steps,
                ("classify", PointClassifier(**point, radius=options.radius, time_window=options.time_window)),
            ]
        ),
    }


def load_data(preset, seed, options):
    """One data set and its split: ``(X, classes, instances, test rows, X_train, y_train, train instances)``.

    The training data are the training half, plus ``--extra-training`` simulated sequences (seed + 1000); the
    train instances are ``precluster_target`` of them (the learned grouping's target, as in ``reproduce``).
    """
    scenes = make_scenes(
        n_sequences=options.n_sequences, duration=options.duration, difficulty=preset, random_state=seed
    )
    X, groups = scenes.data, scenes.groups
    classes = road_user_class(X["label_id"])
    instances = np.asarray(scenes.target)
    train, test = sequence_train_test_split(groups, test_size=0.5, random_state=seed)
    X_train, y_train = X.iloc[train], classes[train]
    train_instances = precluster_target(X, scenes.target)[train]
    if options.extra_training:  # more recordings for the classifiers only; the setting stays tuned on the half
        extra = make_scenes(
            n_sequences=options.extra_training,
            duration=options.duration,
            difficulty=preset,
            random_state=seed + 1000,
        )
        data = extra.data.assign(sequence=extra.data["sequence"] + int(groups.max()) + 1)
        X_train = pd.concat([X_train, data], ignore_index=True)
        y_train = np.concatenate([y_train, road_user_class(data["label_id"])])
        train_instances = np.concatenate([train_instances, precluster_target(extra.data, extra.target)])
    return X, classes, instances, test, X_train, y_train, train_instances


def run_one(preset, seed, options):
    """Tune, train and score every model on one data set; returns ``{model: record}``."""
    setting = tuned_setting(preset, seed, options)
    X, classes, instances, test, X_train, y_train, train_instances = load_data(preset, seed, options)
    truth = (classes[test], instances[test])
    records = {}
    online = None
    if options.online:  # the final object ids of the causal replay, aliases resolved (what stream classifies)
        stage1, stage2 = setting
        pipeline = object_pipeline(2, stage1_params=stage1, params=stage2)
        online = np.asarray(replay(OnlinePipeline(pipeline), X.iloc[test])["object_ids"], dtype=np.int64)
    for name, model in models(setting, options).items():
        start = time.perf_counter()
        model.fit(X_train, y_train)
        Xt = model[:-1].transform(X.iloc[test])
        classifier = model[-1]
        if isinstance(classifier, ClusterClassifier):
            labels = clone(classifier.clusterer).fit_predict(Xt) if online is None else online
            found = classifier.predict_instances_of(Xt, labels)
        else:
            found = predict_instances(classifier, Xt)
            labels = found["instance"].to_numpy()
        records[name] = score(Xt, labels, found, truth, classifier)
        _print(preset, seed, name, records[name], start)
    if options.learned:
        n_half = len(X) - len(test)  # the training half's rows come first in X_train
        records.update(run_learned(preset, seed, X.iloc[test], truth, X_train, y_train, train_instances, n_half))
    return records


class _GivenLabels(BaseEstimator):
    """A clusterer that returns the labels it was given: the out-of-fold training clusters, for ``fit``."""

    def __init__(self, labels=None):
        self.labels = labels

    def fit_predict(self, X, y=None):
        if len(X) != len(self.labels):
            raise ValueError(f"_GivenLabels: {len(self.labels)} labels for {len(X)} rows")
        return np.asarray(self.labels)


def out_of_fold_labels(link, Z, train_instances, n_folds=2):
    """Clusters of the training rows ``Z`` by LinkClustering models that did not see them.

    ``GroupKFold`` by sequence (``n_folds``, at most one per sequence): each fold is clustered by a clone of the
    fitted ``link`` with its tuned thresholds fixed, fitted on the other folds' sequences (no tuning inside).
    """
    sequence = Z["sequence"].to_numpy()
    fixed = clone(link).set_params(
        link_threshold=link.link_threshold_,
        objectness_threshold=link.objectness_threshold_,
        min_cluster_size=link.min_cluster_size_,
    )
    labels = np.full(len(Z), -1, dtype=np.int64)
    n_folds = min(n_folds, len(np.unique(sequence)))
    for fit_rows, held_out in GroupKFold(n_splits=n_folds).split(Z, groups=sequence):
        found = clone(fixed).fit(Z.iloc[fit_rows], train_instances[fit_rows]).predict(Z.iloc[held_out])
        labels[held_out] = np.where(found >= 0, found + labels.max() + 1, -1)
    return labels


def learned_clusters(preset, seed, X_test, X_train, train_instances, n_half):
    """The learned grouping fitted on the training half and its clusters: ``(link, Z, Xt, labels, oof, own)``.

    ``Z`` and ``Xt`` are the training data and the test half through the fitted front, ``labels`` the test half's
    clusters (``predict``), ``oof`` the training data's out-of-fold clusters (``out_of_fold_labels`` on the half,
    ``predict`` on the extra sequences) and ``own`` the fitted model's own clusters of its half (and ``predict`` on
    the extra sequences); see :func:`run_learned`.
    """
    start = time.perf_counter()
    model = learned_pipeline().fit(X_train.iloc[:n_half], train_instances[:n_half])
    link = model[-1]
    Z = model[:-1].transform(X_train)
    Xt = model[:-1].transform(X_test)
    labels = link.predict(Xt)
    fitted = time.perf_counter()
    oof = out_of_fold_labels(link, Z.iloc[:n_half], train_instances[:n_half])
    own = link.labels_  # what FrozenEstimator(link).predict gives for the training half
    if len(Z) > n_half:
        extra = link.predict(Z.iloc[n_half:])
        oof = np.concatenate([oof, np.where(extra >= 0, extra + oof.max() + 1, -1)])
        own = np.concatenate([own, np.where(extra >= 0, extra + own.max() + 1, -1)])
    print(
        f"  {preset} seed {seed} learned grouping: fit {fitted - start:.0f} s, "
        f"out-of-fold {time.perf_counter() - fitted:.0f} s; "
        f"thresholds link {link.link_threshold_} objectness {link.objectness_threshold_} "
        f"min size {link.min_cluster_size_}",
        flush=True,
    )
    return link, Z, Xt, labels, oof, own


def run_learned(preset, seed, X_test, truth, X_train, y_train, train_instances, n_half):
    """The learned grouping classified: ``{row: record}``.

    ``learned_pipeline()`` (the object experiment's front at the paper's setting, then ``LinkClustering`` tuned
    inside its fit) is fitted on the training half (the first ``n_half`` rows of the training data) with
    ``precluster_target``; the test half is clustered once by its ``predict``.  The ClusterClassifier is trained
    on the training data's clusters in two ways: ``out-of-fold`` (``out_of_fold_labels`` on the training half:
    clusters of models that never saw those sequences, the kind of clusters the test half gets) and ``in-sample``
    (``FrozenEstimator(link)``'s own labels of its training half, what ``reproduce`` trains on), each with the
    single window, with ``history="mean_proba"`` and with ``"cluster_mean_proba"``.  The ``--extra-training``
    sequences, like the object setting's, train only the classifiers: the grouping fitted on the half labels them
    by ``predict``, out of sample for both rows.
    """
    link, Z, Xt, labels, oof, own = learned_clusters(preset, seed, X_test, X_train, train_instances, n_half)
    records = {}
    in_sample = FrozenEstimator(link) if len(Z) == n_half else _GivenLabels(own)  # predict once, not per row
    for training, clusterer, true_segments in (
        ("out-of-fold", _GivenLabels(oof), False),
        ("in-sample", in_sample, False),
        ("out-of-fold + true segments", _GivenLabels(oof), True),
        ("in-sample + true segments", in_sample, True),
    ):
        for history, suffix in HISTORY_ROWS:
            name = f"learned ({training}){suffix}"
            start = time.perf_counter()
            classifier = ClusterClassifier(clusterer, history=history, true_segments=true_segments)
            classifier.fit(Z, y_train)
            found = classifier.predict_instances_of(Xt, labels)
            records[name] = score(Xt, labels, found, truth, classifier)
            _print(preset, seed, name, records[name], start)
    return records


def score(Xt, labels, found, truth, classifier):
    """The scores of one classified test half (``found``) with its clusters ``labels``."""
    classes, instances = truth
    times, sequence = Xt["t"].to_numpy(), Xt["sequence"].to_numpy()
    predicted = (found["class"].to_numpy(), found["instance"].to_numpy())
    scores = class_panoptic_quality(*truth, *predicted, times=times, groups=sequence)
    agnostic_true = np.where(classes >= 0, instances, -1)
    agnostic = panoptic_quality(agnostic_true, predicted[1], times=times, groups=sequence).pq
    errors = class_errors(
        *truth, predicted[0], labels, times=times, groups=sequence, confidence=found["confidence"].to_numpy()
    )
    clustering = panoptic_quality(agnostic_true, labels, times=times, groups=sequence).pq
    semantic = semantic_scores(
        *truth, *predicted, found["confidence"].to_numpy(), times=times, groups=sequence, window=0.5
    )
    return {
        "map": semantic["map"],
        "ap": {code: semantic["per_class"].get(code, {}).get("ap", 0.0) for code in CLASS_NAMES},
        "objects": object_f1(Xt, labels, truth, predicted[0]),
        "pq": scores.pq,
        "clustering_pq": clustering,
        "per_class": {code: scores.per_class[code].pq if code in scores.per_class else 0.0 for code in CLASS_NAMES},
        "agnostic_pq": agnostic,
        "errors": errors,
        "n_training_examples": int(getattr(classifier, "n_training_examples_", 0)),
    }


def _print(preset, seed, name, record, start):
    record["seconds"] = time.perf_counter() - start
    per_class = " ".join(f"{CLASS_NAMES[c].split()[-1][:5]} {v:.2f}" for c, v in record["per_class"].items())
    print(
        f"  {preset} seed {seed} {name:<22} class PQ {record['pq']:.3f} agnostic PQ {record['agnostic_pq']:.3f} "
        f"clustering PQ {record['clustering_pq']:.3f} [{per_class}] ({record['seconds']:.0f} s)",
        flush=True,
    )


def _mean_se(values):
    values = np.asarray(values, dtype=np.float64)
    if len(values) < 2:
        return float(values.mean()), float("nan")
    return float(values.mean()), float(values.std(ddof=1) / math.sqrt(len(values)))


def _fmt(values, signed=False):
    mean, se = _mean_se(values)
    text = f"{mean:+.3f}" if signed else f"{mean:.3f}"
    return text if math.isnan(se) else f"{text} ± {se:.3f}"


def report(preset, runs):
    """The tables of one preset: scores per model, paired differences, the confusion and the error places."""
    names = list(runs[0])
    lines = [f"\n{preset}: {len(runs)} seed(s), test half; mean ± SE over seeds"]
    header = ["model", "class PQ", "agnostic PQ", *(CLASS_NAMES[c] for c in CLASS_NAMES)]
    rows = []
    for name in names:
        cells = [name, _fmt([r[name]["pq"] for r in runs]), _fmt([r[name]["agnostic_pq"] for r in runs])]
        cells += [_fmt([r[name]["per_class"][c] for r in runs]) for c in CLASS_NAMES]
        rows.append(cells)
    lines.append(pd.DataFrame(rows, columns=header).to_string(index=False))
    for other in names[1:]:
        differences = [r["clusters"]["pq"] - r[other]["pq"] for r in runs]
        lines.append(f"class PQ, clusters - {other}: {_fmt(differences, signed=True)} (paired over seeds)")
    for key in ("agnostic_pq", "clustering_pq"):
        ratios = [r["clusters"]["pq"] / max(r["clusters"][key], 1e-12) for r in runs]
        lines.append(f"clusters: class PQ / {key.replace('_', ' ')} {_fmt(ratios)}")
    confusion = sum(
        r["clusters"]["errors"]["confusion"].reindex(index=list(CLASS_NAMES), columns=[-1, *CLASS_NAMES], fill_value=0)
        for r in runs
    )
    confusion.index = [CLASS_NAMES[c] for c in confusion.index]
    confusion.columns = ["background", *(CLASS_NAMES[c] for c in confusion.columns[1:])]
    lines.append("clusters: matched test segments, true class (rows) x predicted class, summed over seeds")
    lines.append(confusion.to_string())
    places = pd.DataFrame(
        {
            CLASS_NAMES[c]: [
                sum(r["clusters"]["errors"]["per_class"].get(c, {}).get(key, 0) for r in runs) for key in ERROR_KEYS
            ]
            for c in CLASS_NAMES
        },
        index=ERROR_KEYS,
    ).T
    lines.append("clusters: where each class's PQ goes (segments, summed over seeds)")
    lines.append(places.to_string())
    return "\n".join(lines)


def _fmt2(values, signed=False):
    """Mean +- 2 standard errors over seeds."""
    mean, se = _mean_se(values)
    text = f"{mean:+.3f}" if signed else f"{mean:.3f}"
    return text if math.isnan(se) else f"{text} ± {2 * se:.3f}"


def history_report(preset, runs):
    """``--history``: each option's scores, its paired differences to the single window, F1 by windows seen."""
    names = list(runs[0])
    bins = ["all", *(label for label, _, _ in SEEN_BINS)]
    lines = [f"\n{preset}: {len(runs)} seed(s), test half; mean ± 2 SE over seeds"]
    rows = []
    for name in names:
        cells = [name, _fmt2([r[name]["pq"] for r in runs]), _fmt2([r[name]["map"] for r in runs])]
        cells += [_fmt2([r[name]["objects"][b][0] for r in runs]) for b in bins]
        rows.append(cells)
    header = ["classifier", "class PQ", "mAP@0.5", *(f"object F1 {b}" for b in bins)]
    lines.append(pd.DataFrame(rows, columns=header).to_string(index=False))
    counts = {b: int(np.mean([r[SINGLE]["objects"][b][1] for r in runs])) for b in bins}
    lines.append(f"matched test segments per seed by windows seen (mean): {counts}")
    lines.append(f"paired differences to '{SINGLE}' (mean ± 2 SE over seeds):")
    rows = []
    for name in names[1:]:
        cells = [name]
        for key in ("pq", "map"):
            cells.append(_fmt2([r[name][key] - r[SINGLE][key] for r in runs], signed=True))
        for b in bins:
            cells.append(_fmt2([r[name]["objects"][b][0] - r[SINGLE]["objects"][b][0] for r in runs], signed=True))
        rows.append(cells)
    lines.append(pd.DataFrame(rows, columns=header).to_string(index=False))
    rows = [[name, *(_fmt2([r[name]["per_class"][c] for r in runs]) for c in CLASS_NAMES)] for name in names]
    lines.append("class PQ per class")
    lines.append(pd.DataFrame(rows, columns=["classifier", *CLASS_NAMES.values()]).to_string(index=False))
    rows = [[name, *(_fmt2([r[name]["ap"][c] for r in runs]) for c in CLASS_NAMES)] for name in names]
    lines.append("AP@0.5 per class")
    lines.append(pd.DataFrame(rows, columns=["classifier", *CLASS_NAMES.values()]).to_string(index=False))
    return "\n".join(lines)


def learned_report(preset, runs):
    """``--learned``: per class PQ and the targets of issue #43, F1 by windows seen, paired differences."""
    names = list(runs[0])
    bins = ["all", *(label for label, _, _ in SEEN_BINS)]
    lines = [f"\n{preset}: {len(runs)} seed(s), test half; mean ± 2 SE over seeds"]
    rows = []
    for name in names:
        ratio = [r[name]["pq"] / max(r[name]["clustering_pq"], 1e-12) for r in runs]
        cells = [name, _fmt2([r[name]["pq"] for r in runs]), _fmt2([r[name]["clustering_pq"] for r in runs])]
        cells += [_fmt2(ratio), *(_fmt2([r[name]["per_class"][c] for r in runs]) for c in CLASS_NAMES)]
        rows.append(cells)
    header = ["clusters, classifier", "class PQ", "clustering PQ", "ratio", *CLASS_NAMES.values()]
    lines.append(pd.DataFrame(rows, columns=header).to_string(index=False))
    rows = [[name, *(_fmt2([r[name]["objects"][b][0] for r in runs]) for b in bins)] for name in names]
    for name in names:
        for _, suffix in HISTORY_ROWS[1:]:
            other = f"{name}{suffix}"
            if other in names:
                differences = [[r[other]["objects"][b][0] - r[name]["objects"][b][0] for r in runs] for b in bins]
                rows.append([f"{other} - single", *(_fmt2(values, True) for values in differences)])
    lines.append("per-object macro-F1 by windows seen (differences paired over seeds)")
    lines.append(pd.DataFrame(rows, columns=["classifier", *bins]).to_string(index=False))
    counts = {b: int(np.mean([r[LEARNED]["objects"][b][1] for r in runs])) for b in bins}
    lines.append(f"{LEARNED}: matched test segments per seed by windows seen (mean): {counts}")
    lines.append("paired differences of class PQ (mean ± 2 SE over seeds)")
    for first, second in (
        (LEARNED, NEIGHBOURHOOD),
        (LEARNED, OBJECTS),
        (f"{LEARNED}, mean proba", f"{OBJECTS}, mean proba"),
        ("learned (in-sample)", LEARNED),
        ("learned (out-of-fold + true segments)", LEARNED),
        ("learned (out-of-fold + true segments), mean proba", f"{LEARNED}, mean proba"),
        ("learned (in-sample + true segments)", "learned (in-sample)"),
        ("learned (in-sample + true segments), mean proba", "learned (in-sample), mean proba"),
        ("learned (out-of-fold + true segments), cluster mean proba", "learned (out-of-fold + true segments)"),
        (
            "learned (out-of-fold + true segments), cluster mean proba",
            "learned (out-of-fold + true segments), mean proba",
        ),
        (OBJECTS, NEIGHBOURHOOD),
    ):
        for key in ("pq", "clustering_pq"):
            values = [r[first][key] - r[second][key] for r in runs]
            lines.append(f"  {key}: {first} - {second}: {_fmt2(values, signed=True)}")
    for name in (LEARNED, OBJECTS):
        confusion = sum(
            r[name]["errors"]["confusion"].reindex(index=list(CLASS_NAMES), columns=[-1, *CLASS_NAMES], fill_value=0)
            for r in runs
        )
        confusion.index = [CLASS_NAMES[c] for c in confusion.index]
        confusion.columns = ["background", *(CLASS_NAMES[c] for c in confusion.columns[1:])]
        lines.append(f"{name}: matched test segments, true class (rows) x predicted class, summed over seeds")
        lines.append(confusion.to_string())
        places = pd.DataFrame(
            {
                CLASS_NAMES[c]: [
                    sum(r[name]["errors"]["per_class"].get(c, {}).get(key, 0) for r in runs) for key in ERROR_KEYS
                ]
                for c in CLASS_NAMES
            },
            index=ERROR_KEYS,
        ).T
        lines.append(f"{name}: where each class's PQ goes (segments, summed over seeds)")
        lines.append(places.to_string())
    return "\n".join(lines)


def perfect_clusters(preset, options):
    """Per class F1 on perfect clusters (each object's detections per 0.5 s frame) by the size of the training data.

    The test segments are the test half's of each seed's data; the training segments those of ``n`` other
    simulated sequences (seed + 100) for each ``n`` of ``--training-sizes``; the learner is the default one.
    Also the median number of detections and range of the group segments called pedestrian and of those called
    group.  Returns the table as text.
    """
    lines = [f"\n{preset}: perfect clusters, F1 per class on the test half's segments; mean over seeds"]
    rows = []
    for n in options.training_sizes:
        f1, to_pedestrian, objects, sizes = [], [], [], []
        for seed in options.seeds:
            scenes = make_scenes(options.n_sequences, options.duration, difficulty=preset, random_state=seed)
            _, test = sequence_train_test_split(scenes.groups, test_size=0.5, random_state=seed)
            train = make_scenes(n, options.duration, difficulty=preset, random_state=seed + 100)
            train_table, test_table = _object_segments(train), _object_segments(scenes, test)
            names = [c for c in train_table.columns if c not in ("sequence", "cluster", "window", "class")]
            learner = default_classifier().fit(train_table[names], train_table["class"])
            predicted = learner.predict(test_table[names])
            f1.append(f1_score(test_table["class"], predicted, labels=list(CLASS_NAMES), average=None))
            group = test_table["class"].to_numpy() == 4
            to_pedestrian.append(float(np.mean(predicted[group] == 3)) if group.any() else float("nan"))
            sizes.append(test_table.loc[group, ["n_detections", "range_mean"]].assign(called=predicted[group]))
            objects.append(
                train_table.loc[train_table["class"] == 4, ["sequence", "cluster"]].drop_duplicates().shape[0]
            )
        row = {"training sequences": n, **dict(zip(CLASS_NAMES.values(), np.mean(f1, axis=0).round(3), strict=True))}
        row["group -> pedestrian"] = round(float(np.nanmean(to_pedestrian)), 3)
        row["group objects in training"] = objects
        sizes = pd.concat(sizes)
        for called, code in (("as pedestrian", 3), ("as group", 4)):
            mine = sizes[sizes["called"] == code]
            row[f"group {called}: median n, range m"] = (
                f"{mine['n_detections'].median():.0f}, {mine['range_mean'].median():.0f}" if len(mine) else "-"
            )
        rows.append(row)
    lines.append(pd.DataFrame(rows).to_string(index=False))
    return "\n".join(lines)


def _object_segments(scenes, rows=None):
    """The cluster features of every annotated object's 0.5 s segments (of ``rows``), with the object's class."""
    X = FrameTransform().fit_transform(scenes.data)
    target = np.asarray(scenes.target)
    classes = road_user_class(scenes.data["label_id"])
    labels = target if rows is None else np.where(np.isin(np.arange(len(X)), rows), target, -1)
    table = cluster_features(X, labels, window=0.5)
    class_of = pd.Series(classes[target >= 0], index=target[target >= 0]).groupby(level=0).first()
    return table.assign(**{"class": class_of.reindex(table["cluster"].to_numpy()).to_numpy()})


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument(
        "--data", nargs="+", default=["realistic", "easy"], choices=["realistic", "easy", "radarscenes"]
    )
    parser.add_argument("--n-sequences", type=int, default=4)
    parser.add_argument("--duration", type=float, default=20.0, help="s per sequence")
    parser.add_argument("--n-iter", type=int, default=10, help="iterations of each of the two PQ searches")
    parser.add_argument("--radius", type=float, default=1.5, help="neighbourhood radius of the point-wise rival, m")
    parser.add_argument("--time-window", type=float, default=0.25, help="its time window, +- s")
    parser.add_argument(
        "--class-weight", choices=["balanced"], help="class weights of the learner of all three (default: none)"
    )
    parser.add_argument(
        "--extra-training",
        type=int,
        default=0,
        help="simulated sequences (another seed) added to the classifiers' training data, not to the tuning",
    )
    parser.add_argument(
        "--perfect-clusters", action="store_true", help="only the F1 per class on perfect clusters by training size"
    )
    parser.add_argument("--training-sizes", type=int, nargs="+", default=[2, 4, 8])
    parser.add_argument("--tuned-dir", help="folder to keep and reuse the tuned settings in")
    parser.add_argument(
        "--online",
        action="store_true",
        help="classify the final object ids of OnlinePipeline's causal replay of the test half, not the offline "
        "clusters (the classifiers are trained on the offline clusters, as reproduce trains them)",
    )
    parser.add_argument(
        "--history",
        action="store_true",
        help="the clusters' classifier with each history option (and calibrated) instead of the three models",
    )
    parser.add_argument(
        "--learned",
        action="store_true",
        help="the learned grouping (LinkClustering) classified, against the object setting's clusters and the "
        "neighbourhood point-wise baseline",
    )
    parser.add_argument("--runs-file", help="keep the records of each preset in RUNS_FILE_<preset>.pkl as they come")
    options = parser.parse_args(argv)
    if options.history:  # the calibrated learners' folds are the training sequences, which routing hands them
        sklearn.set_config(enable_metadata_routing=True)
    with threadpool_limits(1):
        for preset in options.data:
            if options.perfect_clusters:
                print(perfect_clusters(preset, options), flush=True)
                continue
            runs = []
            for seed in options.seeds:
                runs.append(run_one(preset, seed, options))
                if options.runs_file:  # every record so far, to report a run that was stopped part way
                    Path(f"{options.runs_file}_{preset}.pkl").write_bytes(pickle.dumps(runs))
            chosen = learned_report if options.learned else history_report if options.history else report
            print(chosen(preset, runs), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
