"""``sklearn-radar cluster``: apply a tuned pipeline to a RadarScenes folder, write devkit predictions."""

from __future__ import annotations

import json
import os
from numbers import Integral
from pathlib import Path

import numpy as np
from sklearn.base import clone
from sklearn.utils._param_validation import validate_params

from .._executor import connect_executor
from .._files import atomic_write, check_ours_to_replace
from .._schema import LABELS, STATIC_LABEL
from ..classification import devkit_class_index
from ..classification._classes import CLASS_OF_LABEL, DEVKIT_CLASS_INDEX, DEVKIT_CLASS_NAMES, IGNORED
from ..datasets import load_radarscenes
from ..datasets._radarscenes_reader import _read_sensors_json, _read_sequences_json, _resolve_data_dir
from ..experiments._learned import LEARNED_EXPERIMENT
from ..experiments._saved import SAVED_EXPERIMENT, params_setting
from ._classifier_setting import classifier_setting, classify_sequence

#: Our two "classes" in the devkit's per-point prediction file: clustered or noise.
CLASS_NAMES = {0: "NOISE", 1: "CLUSTERED"}


@validate_params(
    {
        "data": [str, os.PathLike],
        "params": [str, os.PathLike, None],
        "out": [str, os.PathLike],
        "experiment": SAVED_EXPERIMENT,
        "classifier": [str, os.PathLike, None],
        "scheduler": [str, None],
        "workers": [Integral, None],
    },
    prefer_skip_nested_validation=True,
)
def cluster_radarscenes(data, params, out, experiment=None, *, classifier=None, scheduler=None, workers=None):
    """Cluster every detection of a RadarScenes folder with saved parameters, one sequence at a time.

    Writes the RadarScenes devkit's per-point predictions JSON (schema 2:
    ``{uuid: [class, instance]}``), class 1 for clustered detections and 0
    for noise, instance = cluster id (-1 for noise).  The pipeline never
    crosses sequences, so each sequence is loaded, clustered and written
    on its own (its cluster ids shifted past those of the sequences before
    it): the predictions are written sequence by sequence and the data set
    need not fit in memory.  The file is written atomically (a temporary sibling,
    renamed when complete).

    With ``classifier`` each sequence is also classified
    (:meth:`~sklearn_radar.classification.ClusterClassifier.predict_instances`):
    the class is the devkit's ``ClassificationLabel`` index of the
    predicted road-user class (CAR 0, PEDESTRIAN 1, PEDESTRIAN_GROUP 2,
    TWO_WHEELER 3, LARGE_VEHICLE 4; STATIC 5 for noise and for clusters
    classified as background), the instance the road user (-1 for
    STATIC), and the file's ``label_mapping`` is the devkit's
    ``ClassificationLabel.translation_dict``.

    Parameters
    ----------
    data : str or path-like
        RadarScenes data folder (or its parent).
    params : str or path-like or None
        ``params.json`` written by ``sklearn-radar reproduce``.  None only
        with a ``classifier`` that holds a whole pipeline (which fixes the
        clustering).
    out : str or path-like
        Predictions file to write.
    experiment : int, "objects" or "learned", default=None
        Which saved experiment (a number, the object experiment, or the
        learned grouping, whose fitted model the run saved beside
        ``params``: each sequence is labelled by its ``predict``, the model
        never refitted); None: the best (by the cross-validated training score).
    classifier : str or path-like, default=None
        File written by :func:`~sklearn_radar.classification.save_classifier`.
        A whole pipeline from raw detections ending in a ClusterClassifier
        needs no ``params``; if ``params`` is given too, its setting must
        cluster exactly as the classifier's pipeline.  A bare
        ClusterClassifier takes the steps before it from ``params``, whose
        clusterer must be the classifier's.  Loading runs pickle: only
        use files you trust.
    scheduler : str, default=None
        Address of a running dask scheduler: the sequences are loaded and
        clustered on its workers (which must see ``data`` at the same
        path), a few at a time, and sent back in order.
    workers : int, default=None
        Start a local dask cluster of this many worker processes instead.

    Returns
    -------
    summary : dict
        ``experiment`` (its number; None without ``params``), ``params``
        and ``stage1_params`` (the setting applied; None without
        ``params``), ``chosen`` (why the file names it its best, when
        ``experiment`` is None; else None), ``n_detections``, ``n_clusters`` (with
        ``classifier``: the road users), ``out``, and with ``classifier``
        ``classes`` (detections per devkit class name).

    Raises
    ------
    FileExistsError
        If ``out`` exists and is neither empty nor a predictions file that
        this package wrote (checked before the data are read and again
        before the file is replaced).
    ValueError
        If neither ``params`` nor ``classifier`` is given, or they disagree.
    """
    setting, pipeline, chosen = params_setting(params, experiment, classifier)
    if classifier is not None:
        model = classifier_setting(classifier, setting, params, pipeline)
        run, head, counted = classify_sequence, _CLASSES_HEAD, {name: 0 for name in DEVKIT_CLASS_NAMES.values()}
    else:
        learned = setting["experiment"] == LEARNED_EXPERIMENT
        run = predict_sequence if learned else cluster_sequence
        model, head, counted = pipeline, _PREDICTIONS_HEAD, None
    check_predictions_file(out)
    data_dir = _resolve_data_dir(Path(data))
    _read_sensors_json(data_dir / "sensors.json")  # a malformed folder fails here, before any worker starts
    numbers = sorted(_read_sequences_json(data_dir / "sequences.json"))
    counts = {"n_detections": 0, "n_clusters": 0}
    failed = []

    def write(handle):
        handle.write(head)
        try:
            for uuids, labels, *classes in executor.imap(run, tasks):
                shifted = np.where(labels >= 0, labels + counts["n_clusters"], -1)
                classes = classes[0] if classes else None
                _write_entries(handle, uuids, shifted, first=counts["n_detections"] == 0, classes=classes)
                counts["n_detections"] += len(labels)
                counts["n_clusters"] += int(labels.max()) + 1 if len(labels) else 0
                if counted is not None:
                    _count_classes(counted, classes)
        except OSError as error:  # reading a sequence failed: not a write error of ``out``
            failed.append(error)
            raise _ReadFailed from None
        handle.write(_PREDICTIONS_TAIL if counts["n_detections"] else _PREDICTIONS_EMPTY_TAIL)

    with connect_executor(scheduler, workers) as executor:
        tasks = [(str(data_dir), n, model) for n in numbers]
        try:
            atomic_write(Path(out), write, replaceable=check_predictions_file)
        except _ReadFailed:
            raise failed[0] from None
    applied = {
        "experiment": None if setting is None else setting["experiment"],
        "params": None if setting is None else setting["params"],
        "stage1_params": None if setting is None else setting.get("stage1_params"),
        "chosen": chosen,
    }
    summary = {**applied, **counts, "out": str(out)}
    if counted is not None:
        summary["classes"] = counted
    return summary


def _count_classes(counted, classes):
    """Add the detections of each devkit class index in ``classes`` to ``counted`` (by class name)."""
    indices, numbers = np.unique(classes, return_counts=True)
    name_of = {int(devkit_class_index([code])[0]): name for code, name in DEVKIT_CLASS_NAMES.items()}
    for index, number in zip(indices.tolist(), numbers.tolist(), strict=True):
        counted[name_of[index]] += number


def check_predictions_file(out):
    """Refuse to replace ``out`` unless it is absent, empty, or a predictions file this package wrote.

    A predictions file is recognised by its first bytes, a document head
    that :func:`write_predictions` writes (schema 2 with this package's
    ``NOISE``/``CLUSTERED`` classes, or with the devkit's classes of
    ``--classifier``): any other file (``params.json``, a devkit file, a
    typo) is another's work and is kept.

    Parameters
    ----------
    out : str or path-like
        The predictions file to write.

    Raises
    ------
    FileExistsError
        Naming ``out``.
    """
    check_ours_to_replace(out, (_PREDICTIONS_HEAD, _CLASSES_HEAD), "a predictions file", "output file")


class _ReadFailed(Exception):
    """A sequence could not be read while the predictions were being written (the OSError is re-raised)."""


def cluster_sequence(task):
    """Load one sequence and cluster it: ``(data folder, sequence number, pipeline)`` -> ``(uuids, labels)``.

    Runs on a dask worker with ``--scheduler``/``--workers`` (so the worker
    reads the sequence itself), else in this process.
    """
    data_dir, number, pipeline = task
    scenes = load_radarscenes(data_dir, sequences=number)
    labels = clone(pipeline).fit_predict(scenes.data)
    return scenes.data["uuid"].to_numpy(), np.asarray(labels, dtype=np.int64)


def predict_sequence(task):
    """Load one sequence, label it with a fitted model: ``(data folder, sequence number, model)`` -> (uuids, labels).

    The learned grouping's :func:`cluster_sequence`: the model, fitted on a run's training half, is applied as it is,
    to the columns it was fitted on (a ValueError names those the folder lacks).
    """
    data_dir, number, model = task
    scenes = load_radarscenes(data_dir, sequences=number)
    columns = list(getattr(model, "feature_names_in_", scenes.data.columns))
    missing = [c for c in columns if c not in scenes.data.columns]
    if missing:
        raise ValueError(f"{data_dir}: sequence {number} lacks the columns {missing} the learned model was fitted on")
    labels = model.predict(scenes.data[columns])
    return scenes.data["uuid"].to_numpy(), np.asarray(labels, dtype=np.int64)


@validate_params(
    {"uuids": ["array-like"], "labels": ["array-like"], "out": [str, os.PathLike], "classes": ["array-like", None]},
    prefer_skip_nested_validation=True,
)
def write_predictions(uuids, labels, out, classes=None):
    """Write cluster labels in the devkit's ``per_point_predictions_to_json`` layout, schema 2 (label and instance).

    Without ``classes`` the class of a detection is 1 (``CLUSTERED``) for
    a clustered detection and 0 (``NOISE``) for noise, with the
    ``label_mapping`` STATIC -> 0, every other label -> 1.  With
    ``classes`` (road-user class codes of
    :class:`~sklearn_radar.classification.ClusterClassifier`) it is the
    devkit's ``ClassificationLabel`` index of the class
    (:data:`~sklearn_radar.classification.DEVKIT_CLASS_INDEX`: background
    and noise are STATIC, 5), with the devkit's own
    ``ClassificationLabel.translation_dict`` as ``label_mapping``: the
    file the devkit writes for those predictions, byte for byte.

    Parameters
    ----------
    uuids : array-like of str
        Detection uuids.
    labels : array-like of int
        Cluster (or instance) per detection, -1 for noise.
    out : str or path-like
        File to write (atomically).  An existing file is replaced only if it
        is empty or a predictions file written by this package
        (:func:`check_predictions_file`).
    classes : array-like of int, default=None
        Road-user class code per detection (0 car ... 4 pedestrian group,
        -1 background), or None.

    Raises
    ------
    FileExistsError
        If ``out`` is another file.
    """
    labels = np.asarray(labels)
    uuids = np.asarray(uuids)
    if len(uuids) != len(labels):
        raise ValueError(f"uuids and labels differ in length: {len(uuids)} != {len(labels)}")
    if classes is not None:
        classes = _devkit_classes(classes, len(labels))
    head = _PREDICTIONS_HEAD if classes is None else _CLASSES_HEAD

    def write(handle):
        handle.write(head)
        _write_entries(handle, uuids, labels, first=True, classes=classes)
        handle.write(_PREDICTIONS_TAIL if len(labels) else _PREDICTIONS_EMPTY_TAIL)

    check_predictions_file(out)
    atomic_write(Path(out), write, replaceable=check_predictions_file)


def _devkit_classes(classes, n):
    """The devkit's class index of each road-user class code; ValueError for another length or code."""
    classes = np.asarray(classes)
    if len(classes) != n:
        raise ValueError(f"classes and labels differ in length: {len(classes)} != {n}")
    if classes.dtype.kind not in "iu" or not np.isin(classes, list(DEVKIT_CLASS_INDEX)).all():
        raise ValueError(f"classes must be road-user class codes {sorted(DEVKIT_CLASS_INDEX)}")
    return devkit_class_index(classes)


def _predictions_frame(mapping, names):
    """The document around the predictions, split where they go: ``(head, tail, tail without predictions)``.

    ``mapping`` is the devkit's ``label_mapping`` (RadarScenes label id ->
    class index or None), ``names`` its ``new_label_names``.  The pieces
    and :func:`_write_entries` make the same bytes as
    ``json.dumps(document, ensure_ascii=True, indent=2)`` (the devkit's
    ``per_point_predictions_to_json``), written a sequence at a time.
    """
    document = {
        "schema": 2,
        "label_mapping": {str(k): v for k, v in mapping.items()},
        "new_label_names": {str(k): v for k, v in names.items()},
        "predictions": {},
    }
    text = json.dumps(document, ensure_ascii=True, indent=2)
    empty = '"predictions": {}\n}'
    assert text.endswith(empty)
    head = text[: -len(empty)] + '"predictions": {'
    return head.encode("ascii"), b"\n  }\n}", b"}\n}"


def _class_frame():
    """The frame of classified predictions: the devkit's ``ClassificationLabel.translation_dict``, in its order."""
    mapping, names = {}, {}
    for label in sorted(LABELS):
        code = CLASS_OF_LABEL[label]
        mapping[label] = None if code == IGNORED else DEVKIT_CLASS_INDEX[code]
        if code != IGNORED:
            names.setdefault(DEVKIT_CLASS_INDEX[code], DEVKIT_CLASS_NAMES[code])
    return _predictions_frame(mapping, names)


_PREDICTIONS_HEAD, _PREDICTIONS_TAIL, _PREDICTIONS_EMPTY_TAIL = _predictions_frame(
    {label: (0 if label == STATIC_LABEL else 1) for label in LABELS}, CLASS_NAMES
)
#: The head of a predictions file with the classifier's classes (``--classifier``); the tails are the same.
_CLASSES_HEAD = _class_frame()[0]


def _write_entries(handle, uuids, labels, first, classes=None):
    """``"uuid": [class, instance]`` lines (indent 2, as json.dumps), comma-separated across calls.

    The class is ``classes`` when given (the devkit's class indices), else 1 for a clustered detection, 0 for noise.
    """
    labels = np.asarray(labels)
    classes = (labels >= 0).astype(np.int64) if classes is None else np.asarray(classes)
    lines = [
        f"{'' if first and i == 0 else ','}\n    {json.dumps(str(u), ensure_ascii=True)}: [\n"
        f"      {int(kind)},\n      {int(label)}\n    ]"
        for i, (u, kind, label) in enumerate(zip(uuids, classes.tolist(), labels.tolist(), strict=True))
    ]
    handle.write("".join(lines).encode("ascii"))
