"""``sklearn-radar cluster``: apply a tuned pipeline to a RadarScenes folder, write devkit predictions."""

from __future__ import annotations

import functools
import json
import os
from numbers import Integral
from pathlib import Path

import numpy as np
from sklearn.base import BaseEstimator, clone
from sklearn.utils._param_validation import Interval, StrOptions, validate_params

from ._executor import connect_executor
from ._files import atomic_write, check_ours_to_replace
from ._schema import LABELS, STATIC_LABEL
from .classification._classes import CLASS_OF_LABEL, DEVKIT_CLASS_INDEX, DEVKIT_CLASS_NAMES, IGNORED
from .datasets import load_radarscenes
from .datasets._radarscenes import _read_sensors_json, _read_sequences_json, _resolve_data_dir
from .experiments import OBJECT_EXPERIMENT, experiment_pipeline, get_experiment, object_pipeline

#: Our two "classes" in the devkit's per-point prediction file: clustered or noise.
CLASS_NAMES = {0: "NOISE", 1: "CLUSTERED"}


_EXPERIMENT = [Interval(Integral, 1, None, closed="left"), StrOptions({OBJECT_EXPERIMENT}), None]


@validate_params({"path": [str, os.PathLike], "experiment": _EXPERIMENT}, prefer_skip_nested_validation=True)
def load_params(path, experiment=None):
    """The saved setting of ``experiment`` (default: the best) from a reproduce run's ``params.json``.

    Parameters
    ----------
    path : str or path-like
        ``params.json`` written by ``sklearn-radar reproduce``.
    experiment : int or "objects", default=None
        Experiment number, or the object experiment; None: the run's best
        (the highest cross-validated training score of the run's objective,
        see :ref:`user-guide-command-line`).

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
    return _checked_setting(_read_params(path), path, experiment)


def _read_params(path):
    """The parsed ``params.json`` at ``path``; FileNotFoundError, ValueError or OSError name it."""
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise FileNotFoundError(f"parameter file not found: {path}") from None
    except (json.JSONDecodeError, UnicodeDecodeError):
        raise ValueError(f"{path}: not a JSON parameter file written by 'sklearn-radar reproduce'") from None
    except OSError as error:
        raise OSError(f"cannot read the parameter file {path}: {error.strerror or error}") from None


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
    reason = saved.get("best_reason", _ABSENT)
    if reason is not _ABSENT and not isinstance(reason, str):
        raise bad("the key 'best_reason'", f"must be a string, got {_json_type(reason)}")
    if experiment is None:
        chosen = saved.get("best")
        if chosen is None and isinstance(reason, str):  # the run chose none, and says why
            raise ValueError(f"{path}: names no best setting ({reason}); choose one by its experiment number")
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
    if chosen == OBJECT_EXPERIMENT:
        if number != OBJECT_EXPERIMENT:
            raise bad(f"the key 'experiment' of {where}", f"must be {OBJECT_EXPERIMENT!r}, got {number!r}")
        stage = 2  # the object experiment merges its own stage 1
    else:
        if isinstance(number, bool) or not isinstance(number, int) or str(number) != chosen:
            raise bad(f"the key 'experiment' of {where}", f"must be the number {chosen}, got {number!r}")
        try:
            stage = get_experiment(number).stage
        except ValueError:
            problem = f"must be one of the paper's experiments, got {number}"
            raise bad(f"the key 'experiment' of {where}", problem) from None
    if not isinstance(setting["params"], dict):
        got = _json_type(setting["params"])
        raise bad(f"the key 'params' of {where}", f"must be an object of parameters, got {got}")
    _check_stage1_params(setting.get("stage1_params", _ABSENT), stage, f"{path}: {where}")
    return setting


_ABSENT = object()
#: Why a ``params.json`` without ``best_reason`` names its ``best`` (files of versions before issue 46).
_UNEXPLAINED_BEST = "the file's 'best', which it does not explain (older versions chose it by the test score)"


def _check_stage1_params(value, stage, where):
    """A stage-2 setting fixes its stage 1 (an object); a stage-1 setting has none (null).

    A stage-2 experiment without it would fall back to the paper's #8
    setting: another clustering than the one tuned, so it is refused.
    """
    if stage == 2 and not isinstance(value, dict):
        got = "lacks it" if value is _ABSENT else f"got {_json_type(value)}"
        raise ValueError(
            f"{where}: the key 'stage1_params' must be an object of stage-1 parameters for a stage-2 experiment "
            f"(without them the pipeline would fall back to the paper's stage 1), {got}"
        )
    if stage == 1 and value not in (None, _ABSENT):
        raise ValueError(
            f"{where}: the key 'stage1_params' must be null for a stage-1 experiment, got {_json_type(value)}"
        )


def _json_type(value):
    """The JSON name of a parsed value's type: null, object, array, ..."""
    names = {type(None): "null", dict: "an object", list: "an array", str: "a string", bool: "a boolean"}
    return names.get(type(value), "a number" if isinstance(value, (int, float)) else type(value).__name__)


@validate_params(
    {
        "data": [str, os.PathLike],
        "params": [str, os.PathLike, None],
        "out": [str, os.PathLike],
        "experiment": _EXPERIMENT,
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
    it): the predictions are written as a stream and the data set need not
    fit in memory.  The file is written atomically (a temporary sibling,
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
    experiment : int or "objects", default=None
        Which saved experiment (a number, or the object experiment); None:
        the best (by the cross-validated training score).
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
        path), a few at a time, and streamed back in order.
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
    setting, pipeline, chosen = _params_setting(params, experiment, classifier)
    if classifier is not None:
        from ._classifier_setting import classifier_setting, classify_sequence

        model = classifier_setting(classifier, setting, params, pipeline)
        run, head, counted = classify_sequence, _CLASSES_HEAD, {name: 0 for name in DEVKIT_CLASS_NAMES.values()}
    else:
        model, run, head, counted = pipeline, cluster_sequence, _PREDICTIONS_HEAD, None
    check_predictions_file(out)
    data_dir = _resolve_data_dir(Path(data))
    _read_sensors_json(data_dir / "sensors.json")  # a malformed folder fails here, before any worker starts
    numbers = sorted(_read_sequences_json(data_dir / "sequences.json"))
    counts = {"n_detections": 0, "n_clusters": 0}
    failed = []

    def write(stream):
        stream.write(head)
        try:
            for uuids, labels, *classes in executor.stream(run, tasks):
                shifted = np.where(labels >= 0, labels + counts["n_clusters"], -1)
                classes = classes[0] if classes else None
                _write_entries(stream, uuids, shifted, first=counts["n_detections"] == 0, classes=classes)
                counts["n_detections"] += len(labels)
                counts["n_clusters"] += int(labels.max()) + 1 if len(labels) else 0
                if counted is not None:
                    _count_classes(counted, classes)
        except OSError as error:  # reading a sequence failed: not a write error of ``out``
            failed.append(error)
            raise _ReadFailed from None
        stream.write(_PREDICTIONS_TAIL if counts["n_detections"] else _PREDICTIONS_EMPTY_TAIL)

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


def _params_setting(params, experiment, classifier):
    """``(setting, pipeline, chosen)`` of ``params`` (all None without it); ValueError when neither file is given.

    ``chosen`` says why the file names the setting its best (None when ``experiment`` chose it).
    """
    if params is None:
        if classifier is None:
            raise ValueError("give --params (a params.json of 'sklearn-radar reproduce'), --classifier, or both")
        if experiment is not None:
            raise ValueError("--experiment chooses a setting of --params: give --params with it")
        return None, None, None
    path = Path(params)
    saved = _read_params(path)
    setting = _checked_setting(saved, path, experiment)
    chosen = None if experiment is not None else saved.get("best_reason", _UNEXPLAINED_BEST)
    return setting, setting_pipeline(setting, params), chosen


def _count_classes(counted, classes):
    """Add the detections of each devkit class index in ``classes`` to ``counted`` (by class name)."""
    from ._classifier_setting import devkit_class_index

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


def setting_pipeline(setting, path):
    """The pipeline of a checked setting; ValueError names the file and the parameter it cannot set."""
    number = setting["experiment"]
    where = f"{path}: experiments['{number}']"
    named = f"#{number}" if number != OBJECT_EXPERIMENT else repr(number)
    params = {k: v for k, v in setting["params"].items() if k.split("__")[0] in ("cluster", "merge", "filter")}
    if number == OBJECT_EXPERIMENT:
        build = functools.partial(object_pipeline, 2, stage1_params=setting["stage1_params"])
    else:
        stage1_params = setting.get("stage1_params") if get_experiment(number).stage == 2 else None
        build = functools.partial(experiment_pipeline, number, stage1_params=stage1_params)
    known = build().get_params()
    unknown = sorted(key for key in params if key not in known)
    if unknown:
        raise ValueError(f"{where}: key 'params' holds parameters that experiment {named} does not have: {unknown}")
    try:
        pipeline = build(params=params)
        # Check every value now, before the data are loaded, rather than when the pipeline is fitted.
        for estimator in [pipeline, *pipeline.get_params(deep=True).values()]:
            if isinstance(estimator, BaseEstimator) and hasattr(estimator, "_validate_params"):
                estimator._validate_params()
    except (ValueError, TypeError) as error:
        first_line = str(error).splitlines()[0] if str(error) else type(error).__name__
        raise ValueError(f"{where}: cannot build experiment {named}'s pipeline: {first_line}") from None
    return pipeline


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

    def write(stream):
        stream.write(head)
        _write_entries(stream, uuids, labels, first=True, classes=classes)
        stream.write(_PREDICTIONS_TAIL if len(labels) else _PREDICTIONS_EMPTY_TAIL)

    check_predictions_file(out)
    atomic_write(Path(out), write, replaceable=check_predictions_file)


def _devkit_classes(classes, n):
    """The devkit's class index of each road-user class code; ValueError for another length or code."""
    from ._classifier_setting import devkit_class_index

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


def _write_entries(stream, uuids, labels, first, classes=None):
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
    stream.write("".join(lines).encode("ascii"))
