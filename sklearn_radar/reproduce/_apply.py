"""``sklearn-radar cluster``: apply a tuned pipeline to a RadarScenes folder, write devkit predictions."""

from __future__ import annotations

import json
import os
from numbers import Integral
from pathlib import Path

import numpy as np
from sklearn.base import BaseEstimator
from sklearn.utils._param_validation import Interval, validate_params

from .._schema import LABELS, STATIC_LABEL
from ..datasets import load_radarscenes
from ..experiments import experiment_pipeline, get_experiment
from ._io import atomic_write_text

#: Our two "classes" in the devkit's per-point prediction file: clustered or noise.
CLASS_NAMES = {0: "NOISE", 1: "CLUSTERED"}


_EXPERIMENT = [Interval(Integral, 1, None, closed="left"), None]


@validate_params({"path": [str, os.PathLike], "experiment": _EXPERIMENT}, prefer_skip_nested_validation=True)
def load_params(path, experiment=None):
    """The saved setting of ``experiment`` (default: the best) from a reproduce run's ``params.json``.

    Parameters
    ----------
    path : str or path-like
        ``params.json`` written by ``sklearn-radar reproduce``.
    experiment : int, default=None
        Experiment number; None: the run's best (highest test V1).

    Returns
    -------
    setting : dict
        ``experiment`` (its number), ``v1_test``, ``params`` (pipeline
        parameters) and ``stage1_params`` (stage 2: the fixed stage-1
        setting; otherwise None).

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    ValueError
        If it is not such a file or has no setting for ``experiment``.
    """
    path = Path(path)
    try:
        saved = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise FileNotFoundError(f"parameter file not found: {path}") from None
    except (json.JSONDecodeError, UnicodeDecodeError):
        raise ValueError(f"{path}: not a JSON parameter file written by 'sklearn-radar reproduce'") from None
    except OSError as error:
        raise OSError(f"cannot read the parameter file {path}: {error.strerror or error}") from None
    return _checked_setting(saved, path, experiment)


def _checked_setting(saved, path, experiment):
    """The setting of ``experiment`` in a parsed ``params.json``; ValueError names the file and the bad key."""

    def bad(where, problem):
        return ValueError(f"{path}: {where} {problem} (not a parameter file written by 'sklearn-radar reproduce')")

    if not isinstance(saved, dict):
        raise bad("the top level", f"must be a JSON object, got {type(saved).__name__}")
    experiments = saved.get("experiments")
    if not isinstance(experiments, dict):
        problem = "is missing" if experiments is None else f"must be an object, got {type(experiments).__name__}"
        raise bad("the key 'experiments'", problem)
    if experiment is None:
        chosen = saved.get("best")
        if not isinstance(chosen, str) or chosen not in experiments:
            problem = "is missing" if chosen is None else f"names no saved experiment: {chosen!r}"
            raise bad("the key 'best'", problem)
    else:
        chosen = str(experiment)
        if chosen not in experiments:
            saved_keys = ", ".join(sorted(experiments, key=lambda k: (len(k), k))) or "none"
            raise ValueError(f"{path}: has no saved setting for experiment {experiment} (saved: {saved_keys})")
    setting = experiments[chosen]
    where = f"experiments[{chosen!r}]"
    if not isinstance(setting, dict):
        raise bad(where, f"must be an object, got {type(setting).__name__}")
    for key in ("experiment", "params"):
        if key not in setting:
            raise bad(where, f"lacks the key {key!r}")
    number = setting["experiment"]
    if isinstance(number, bool) or not isinstance(number, int) or str(number) != chosen:
        raise bad(f"the key 'experiment' of {where}", f"must be the number {chosen}, got {number!r}")
    try:
        get_experiment(number)
    except ValueError:
        raise bad(f"the key 'experiment' of {where}", f"must be one of the paper's experiments, got {number}") from None
    for key in ("params", "stage1_params"):
        value = setting.get(key)
        if key == "stage1_params" and value is None:
            continue
        if not isinstance(value, dict):
            raise bad(f"the key {key!r} of {where}", f"must be an object of parameters, got {type(value).__name__}")
    return setting


@validate_params(
    {"data": [str, os.PathLike], "params": [str, os.PathLike], "out": [str, os.PathLike], "experiment": _EXPERIMENT},
    prefer_skip_nested_validation=True,
)
def cluster_radarscenes(data, params, out, experiment=None):
    """Cluster every detection of a RadarScenes folder with saved parameters.

    Writes the RadarScenes devkit's per-point predictions JSON (schema 2:
    ``{uuid: [class, instance]}``), class 1 for clustered detections and 0
    for noise, instance = cluster id (-1 for noise).  The file is written
    atomically.

    Parameters
    ----------
    data : str or path-like
        RadarScenes data folder (or its parent).
    params : str or path-like
        ``params.json`` written by ``sklearn-radar reproduce``.
    out : str or path-like
        Predictions file to write.
    experiment : int, default=None
        Which saved experiment; None: the best.

    Returns
    -------
    summary : dict
        Experiment, detections, clusters and the output path.
    """
    setting = load_params(params, experiment)
    number = setting["experiment"]
    pipeline = _pipeline(setting, params)
    scenes = load_radarscenes(data)
    labels = pipeline.fit_predict(scenes.data)
    write_predictions(scenes.data["uuid"].to_numpy(), labels, out)
    return {"experiment": number, "n_detections": len(labels), "n_clusters": int(labels.max() + 1), "out": str(out)}


def _pipeline(setting, path):
    """The pipeline of a checked setting; ValueError names the file and the parameter it cannot set."""
    number = setting["experiment"]
    where = f"{path}: experiments['{number}']"
    params = {k: v for k, v in setting["params"].items() if k.split("__")[0] in ("cluster", "merge", "filter")}
    stage1_params = setting.get("stage1_params") if get_experiment(number).stage == 2 else None
    known = experiment_pipeline(number).get_params()
    unknown = sorted(key for key in params if key not in known)
    if unknown:
        raise ValueError(f"{where}: key 'params' holds parameters that experiment #{number} does not have: {unknown}")
    try:
        pipeline = experiment_pipeline(number, params=params, stage1_params=stage1_params)
        # Check every value now, before the data are loaded, rather than when the pipeline is fitted.
        for estimator in [pipeline, *pipeline.get_params(deep=True).values()]:
            if isinstance(estimator, BaseEstimator) and hasattr(estimator, "_validate_params"):
                estimator._validate_params()
    except (ValueError, TypeError) as error:
        first_line = str(error).splitlines()[0] if str(error) else type(error).__name__
        raise ValueError(f"{where}: cannot build experiment #{number}'s pipeline: {first_line}") from None
    return pipeline


@validate_params(
    {"uuids": ["array-like"], "labels": ["array-like"], "out": [str, os.PathLike]}, prefer_skip_nested_validation=True
)
def write_predictions(uuids, labels, out):
    """Write cluster labels in the devkit's ``per_point_predictions_to_json`` layout, schema 2 (label and instance).

    Parameters
    ----------
    uuids : array-like of str
        Detection uuids.
    labels : array-like of int
        Cluster per detection, -1 for noise.
    out : str or path-like
        File to write (atomically).
    """
    labels = np.asarray(labels)
    mapping = {label: (0 if label == STATIC_LABEL else 1) for label in LABELS}
    document = {
        "schema": 2,
        "label_mapping": {str(k): v for k, v in mapping.items()},
        "new_label_names": {str(k): v for k, v in CLASS_NAMES.items()},
        "predictions": {str(u): [int(label >= 0), int(label)] for u, label in zip(uuids, labels, strict=True)},
    }
    atomic_write_text(Path(out), json.dumps(document, ensure_ascii=True, indent=2))
