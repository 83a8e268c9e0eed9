"""``sklearn-radar cluster``: apply a tuned pipeline to a RadarScenes folder, write devkit predictions."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .._schema import LABELS, STATIC_LABEL
from ..datasets import load_radarscenes
from ..experiments import experiment_pipeline, get_experiment
from ._io import atomic_write_text

#: Our two "classes" in the devkit's per-point prediction file: clustered or noise.
CLASS_NAMES = {0: "NOISE", 1: "CLUSTERED"}


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
        chosen = str(experiment) if experiment is not None else saved["best"]
        setting = saved["experiments"][chosen]
    except FileNotFoundError:
        raise FileNotFoundError(f"parameter file not found: {path}") from None
    except (json.JSONDecodeError, UnicodeDecodeError):
        raise ValueError(f"{path}: not a JSON parameter file written by 'sklearn-radar reproduce'") from None
    except (KeyError, TypeError):
        raise ValueError(f"{path}: has no saved setting for experiment {experiment or 'best'!r}") from None
    return setting


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
    scenes = load_radarscenes(data)
    pipeline = experiment_pipeline(
        number,
        params={k: v for k, v in setting["params"].items() if k.split("__")[0] in ("cluster", "merge", "filter")},
        stage1_params=setting.get("stage1_params") if get_experiment(number).stage == 2 else None,
    )
    labels = pipeline.fit_predict(scenes.data)
    write_predictions(scenes.data["uuid"].to_numpy(), labels, out)
    return {"experiment": number, "n_detections": len(labels), "n_clusters": int(labels.max() + 1), "out": str(out)}


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
