"""The learned step: the learned grouping fitted on the training half, scored on the test half, its errors by cause.

Beside the offline model, the causal one (``link__causal=True``) is fitted on the same training half and scored
causally on the test half (its offline ``predict``, which equals the stream's final ids); it is saved as
:data:`LEARNED_CAUSAL_FILE` for ``sklearn-radar stream``.

The pipeline (:func:`~sklearn_radar.experiments._learned.learned_pipeline`) is fitted once, in this process (it
needs every training example at once), with the pre-clustered target that the object experiment's PQ is scored
against, and the run's seed; each test sequence is labelled where it lives by the fitted model's ``predict``.  The
error anatomy (:func:`~sklearn_radar.metrics.instance_errors`) is taken on the test half for it and, where they
ran, for the object experiment's and the strongest offline baseline's kept settings (re-labelled here, so that a
run without this step keeps its records as they were).  Why: :ref:`user-guide-objects`.
"""

from __future__ import annotations

import time

import numpy as np
import pandas as pd
from sklearn.base import clone

from ..experiments import baseline_pipeline, object_pipeline
from ..experiments._learned import learned_pipeline
from ..metrics import instance_errors
from ..metrics._parts import combine_instance_parts, combine_parts, instance_parts, score_parts
from ._classification import strongest_offline_baseline
from ._constants import BASELINES, OBJECTS, SCORE_WINDOW_S
from ._context import Outcome
from ._experiment_records import InstanceErrors, InstanceScores, LearnedCausalResult, LearnedResult
from ._tuning import native_params

#: The fitted learned pipeline's file in the run's folder (``params.json``'s ``"learned"`` entry points to it).
LEARNED_FILE = "learned.joblib"
#: The fitted causal learned pipeline's file (``"causal_model"`` of the entry): what ``stream`` runs.
LEARNED_CAUSAL_FILE = "learned_causal.joblib"
#: The learned grouping's parameters in the run beside the front's (LinkClustering's defaults otherwise).
LEARNED_PARAMS = {}
#: The causal model's, under LEARNED_PARAMS: fewer boosting iterations, at most 16 links per detection and trees at
#: most 6 levels deep, for the stream's time per scan (the measured PQ cost: :ref:`user-guide-learned`,
#: :ref:`online-learned`).  No cluster context: its gain did not hold on fresh seeds (:ref:`learned-cluster-context`).
LEARNED_CAUSAL_PARAMS = {"link__max_iter": 40, "link__max_links_per_detection": 16, "link__max_depth": 6}
#: The object-level scores kept (those of :class:`InstanceScores`).
_SCORES = tuple(name for name in InstanceScores.__dataclass_fields__ if name != "window_s")
#: The error anatomy's name of each setting.
LEARNED_NAME, OBJECTS_NAME = "learned grouping", "object experiment"


def run_learned(env, key, needed):
    """Fit the learned grouping on the training half, score it offline on the test half; the error anatomy."""
    start = time.perf_counter()
    params = {
        **LEARNED_PARAMS,
        "link__window": SCORE_WINDOW_S,
        "link__random_state": env.seed,
        "link__n_jobs": env.executor.threads if hasattr(env.executor, "threads") else 1,
    }
    model = learned_pipeline(params)
    tables = env.sequences.map(training_table, env.train, executor=env.executor)
    X_train = pd.concat([X for X, _ in tables], ignore_index=True)
    y_train = np.concatenate([y for _, y in tables])
    fields, parts = _fitted(env, model, X_train, y_train)
    errors = {LEARNED_NAME: _errors(parts)}
    for name, pipeline in _compared(needed):
        errors[name] = _errors(env.sequences.map(refitted_sequence, env.test, pipeline, executor=env.executor))
    causal, causal_model = _causal(env, params, X_train, y_train)
    result = LearnedResult(
        params=native_params({k: v for k, v in model.get_params().items() if _is_setting(k)}),
        model_file=LEARNED_FILE,
        n_training_pairs=model[-1].n_training_pairs_,
        errors=errors,
        wall_time_s=time.perf_counter() - start,
        causal=causal,
        **fields,
    )
    summary = (
        f"    learned: test PQ {result.instance_test.pq:.3f} offline, {causal.instance_test.pq:.3f} causal (fitted in "
        f"{result.fit_wall_time_s:.1f} s and {causal.fit_wall_time_s:.1f} s), "
        f"missed segments {errors[LEARNED_NAME].missed} of {errors[LEARNED_NAME].n_true} offline"
    )
    return Outcome(result, summary, models={LEARNED_FILE: model, LEARNED_CAUSAL_FILE: causal_model})


def _causal(env, params, X_train, y_train):
    """The causal learned pipeline (its filter causal too) fitted on the training half, and its record with the causal
    test scores: its ``predict``, which the stream's final ids equal."""
    model = learned_pipeline({**LEARNED_CAUSAL_PARAMS, **params, "link__causal": True, "filter__causal": True})
    fields, _ = _fitted(env, model, X_train, y_train)
    settings = native_params({k: v for k, v in model.get_params().items() if _is_setting(k)})
    return LearnedCausalResult(model_file=LEARNED_CAUSAL_FILE, params=settings, **fields), model


def _fitted(env, model, X_train, y_train):
    """Fit ``model`` on the training half and label the test half: the fields both records share, and the parts."""
    fit_start = time.perf_counter()
    model.fit(X_train, y_train)
    fit_s = time.perf_counter() - fit_start
    parts = env.sequences.map(predicted_sequence, env.test, model, executor=env.executor)
    scores = combine_instance_parts([p["instance"] for p in parts])
    link = model[-1]
    fields = {
        "link_threshold": link.link_threshold_,
        "objectness_threshold": link.objectness_threshold_,
        "min_cluster_size": link.min_cluster_size_,
        "cv_pq": link.cv_score_,
        "fit_wall_time_s": fit_s,
        "v1_test": combine_parts("v1", [p["v1"] for p in parts]),
        "n_clusters_test": int(sum(p["n_clusters"] for p in parts)),
        "instance_test": InstanceScores(window_s=SCORE_WINDOW_S, **{k: float(scores[k]) for k in _SCORES}),
        "model": model,
    }
    return fields, parts


def _is_setting(name):
    """Whether a deep parameter of the learned pipeline is a step's setting (not a step, not the pipeline's)."""
    return "__" in name and name.split("__")[0] in ("frame", "filter", "link")


def _compared(needed):
    """``(name, unfitted pipeline)`` of the object experiment's and the strongest offline baseline's kept settings."""
    found = []
    objects = needed.get(OBJECTS)
    if objects is not None:
        kept = objects.kept
        found.append((OBJECTS_NAME, object_pipeline(2, stage1_params=kept.stage1_params, params=kept.params)))
    strongest = strongest_offline_baseline(needed.get(BASELINES))
    if strongest is not None:
        name, result = strongest
        found.append((name, baseline_pipeline(name).set_params(**result.params)))
    return found


def training_table(sequence):
    """One training sequence: the estimators' input and its pre-clustered target."""
    return sequence.X, np.asarray(sequence.target, dtype=np.int64)


def predicted_sequence(sequence, model):
    """One test sequence labelled by the fitted ``model``: its scores' parts and what the error anatomy needs."""
    return _labelled(sequence, np.asarray(model.predict(sequence.X), dtype=np.int64))


def refitted_sequence(sequence, pipeline):
    """One test sequence labelled by an unsupervised ``pipeline`` (fitted on it, as the run scores it)."""
    return _labelled(sequence, np.asarray(clone(pipeline).fit_predict(sequence.X), dtype=np.int64))


def _labelled(sequence, labels):
    times = sequence.scenes.data["timestamp"].to_numpy(dtype=np.float64) * 1e-6
    target = np.asarray(sequence.target, dtype=np.int64)
    return {
        "id": sequence.id,
        "v1": score_parts("v1", target, labels),
        "instance": instance_parts(target, labels, times=times, window=SCORE_WINDOW_S),
        "n_clusters": len(np.unique(labels[labels >= 0])),
        "target": target,
        "predicted": labels,
        "times": times,
    }


def _errors(parts):
    """The error anatomy of the test half from its sequences' labels (pooled, each sequence its own group)."""
    found = instance_errors(
        np.concatenate([p["target"] for p in parts]),
        np.concatenate([p["predicted"] for p in parts]),
        times=np.concatenate([p["times"] for p in parts]),
        groups=np.concatenate([np.full(len(p["times"]), p["id"]) for p in parts]),
        window=SCORE_WINDOW_S,
    )
    return InstanceErrors(**{k: found[k] for k in InstanceErrors.__dataclass_fields__})
