"""``sklearn-radar stream``: replay a RadarScenes folder scan by scan through the online pipeline."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from .._files import atomic_write
from ..classification import DEVKIT_CLASS_NAMES
from ..datasets import load_radarscenes
from ..experiments._learned import LEARNED_EXPERIMENT
from ..experiments._saved import learned_model, params_setting, saved_tracker
from ..online import OnlinePipeline, Tracker
from ..online._objects import ObjectList
from ..online._replay import replay
from ._classifier_setting import classifier_setting
from ._cluster import check_predictions_file, write_predictions

#: The first line of an object-list CSV this package writes: how a file is recognised as ours.
OBJECTS_HEADER = ",".join(["timestamp", *ObjectList.__dataclass_fields__])


def check_objects_file(out):
    """Refuse to replace ``out`` unless it is absent, empty, or an object list this package wrote.

    Raises
    ------
    FileExistsError
        Naming ``out``.
    """
    problem = _why_not_replaceable(Path(out))
    if problem is not None:
        raise FileExistsError(f"{out} {problem}; it is not replaced: choose another output file")


def _why_not_replaceable(out):
    """None when ``out`` may be replaced (absent, empty, or starting with our header), else why not."""
    if out.is_symlink():
        return "is a symbolic link"
    if not out.is_file() or out.stat().st_size == 0:
        return None
    head = (OBJECTS_HEADER + "\n").encode("ascii")
    with open(out, "rb") as handle:
        ours = handle.read(len(head)) == head
    return None if ours else "exists and is not an object list written by sklearn-radar"


def recording_seconds(data):
    """s of recording: the sum over sequences of last minus first timestamp."""
    span = data.groupby("sequence")["timestamp"].agg(["min", "max"])
    return float((span["max"] - span["min"]).sum()) * 1e-6


def stream_radarscenes(data, params, out, objects=None, experiment=None, classifier=None, track=False, history=None):
    """Replay a RadarScenes folder through the online pipeline of a saved setting; write devkit predictions.

    The scans of all sequences are fed in timestamp order (the sensors of a
    sequence interleaved, those measuring at the same time together); the
    predictions file holds each detection's final object id (every alias
    resolved to the surviving id), as ``sklearn-radar cluster`` writes
    cluster ids.  Nothing is written before every argument is checked, and
    no file that this package did not write is replaced.

    With ``track``, the pipeline runs the :class:`~sklearn_radar.online.Tracker`
    that the reproduce run tuned and saved in ``params`` (its key ``tracker``)
    and the predictions file holds each detection's track id as given at its
    scan (-1, noise, for a detection of no confirmed track): the ids a car
    would use, causal and lasting (:ref:`online-tracking`).

    With ``classifier``, the final objects are classified after the replay
    (:meth:`~sklearn_radar.classification.ClusterClassifier.predict_instances_of`
    on the final object ids, per time window as in training: a window's
    class uses the whole window, and with the classifier's ``history`` the
    object's earlier windows too, never later ones): the class is the devkit's
    ``ClassificationLabel`` index (STATIC 5 for noise and for objects
    classified as background), the instance the final object id where
    the class is a road user, -1 where it is STATIC.

    Parameters
    ----------
    data : str or path-like
        The RadarScenes folder to replay (or its parent).
    params : str or path-like or None
        The setting: a ``params.json`` of ``sklearn-radar reproduce``.  None
        only with a ``classifier`` that holds a whole pipeline (its
        clustering is replayed).
    out : str or path-like
        Predictions file to write.
    objects : str or path-like, default=None
        Object-list CSV to write (one row per live object per scan); None: none.
    experiment : int or "objects", default=None
        Which saved experiment; None: the best (by the cross-validated training score).  The learned grouping
        (``"learned"``) streams its causal model (the entry's ``causal_model``).
    classifier : str or path-like, default=None
        File written by :func:`~sklearn_radar.classification.save_classifier`,
        with the same rules as for ``sklearn-radar cluster``
        (:func:`~sklearn_radar.reproduce.cluster_radarscenes`).  Loading
        runs pickle: only use files you trust.
    track : bool, default=False
        Run the saved Tracker and write its track ids (not with ``classifier``).
    history : {"none", "mean_proba"} or None, default=None
        With ``classifier``: how each object's window is classified, in place of the classifier's own ``history``
        (:class:`~sklearn_radar.classification.ClusterClassifier`): ``"mean_proba"`` from the object's windows so
        far, ``"none"`` from that window alone; None: as the classifier was saved.  A classifier trained with
        ``history="features"`` reads them: it cannot be changed (ValueError).

    Returns
    -------
    summary : dict
        ``experiment``, ``params`` (None without ``params``), ``chosen`` (why the file names it its best, when
        ``experiment`` is None; else None), ``n_detections``, ``n_scans``, ``n_objects``,
        ``n_aliases``, ``latency`` and ``cpu`` (wall and thread CPU time per scan, s), ``recording`` (s),
        ``out`` and ``objects``; with ``classifier`` also ``classes`` (detections per devkit class name) and
        ``n_road_users`` (objects classified as a road user in some window); with ``track`` also
        ``tracker`` (its parameters as saved) and ``n_tracks`` (confirmed tracks).
    """
    setting, pipeline, chosen = params_setting(params, experiment, classifier)
    if setting is not None and setting["experiment"] == LEARNED_EXPERIMENT:  # the causal model runs online
        pipeline = learned_model(setting, params, causal=True)
    model = None
    if classifier is not None:
        model = classifier_setting(classifier, setting, params, pipeline)
        pipeline = model.clustering
        if history is not None:
            with_history(model.classifier, None if history == "none" else history, classifier)
    tracker, tracker_params = _saved_tracker(params, classifier) if track else (None, None)
    online = OnlinePipeline(pipeline, tracker=tracker)
    check_predictions_file(out)
    if objects is not None:
        if Path(objects).resolve() == Path(out).resolve():
            raise ValueError(f"--objects and --out name the same file: {out}")
        check_objects_file(objects)
    scenes = load_radarscenes(data)
    replayed = replay(online, scenes.data, objects=objects is not None)
    final = replayed["object_ids"]
    summary = {}
    if tracker is not None:
        tracks = replayed["track_id"]
        write_predictions(scenes.data["uuid"].to_numpy(), tracks, out)
        # Track ids are unique within a sequence: a track is a (sequence, id) pair.
        pairs = np.unique(np.c_[scenes.data["sequence"].to_numpy()[tracks >= 0], tracks[tracks >= 0]], axis=0)
        summary.update(tracker=tracker_params, n_tracks=len(pairs))
    elif model is None:
        write_predictions(scenes.data["uuid"].to_numpy(), final, out)
    else:
        classes, instances = classify_objects(model, scenes.data, final)
        write_predictions(scenes.data["uuid"].to_numpy(), instances, out, classes=classes)
        summary["classes"] = _class_counts(classes)
        summary["n_road_users"] = len(np.unique(instances[instances >= 0]))
    if objects is not None:
        table = replayed["objects"]
        if table is None:
            table = pd.DataFrame(columns=OBJECTS_HEADER.split(","))

        def write(handle):
            handle.write(table.to_csv(index=False, lineterminator="\n").encode("ascii"))

        atomic_write(Path(objects), write, replaceable=check_objects_file)
    return {
        "experiment": None if setting is None else setting["experiment"],
        "params": None if setting is None else setting["params"],
        "chosen": chosen,
        "n_detections": len(final),
        "n_scans": len(replayed["latency"]),
        "n_objects": len(np.unique(final[final >= 0])),
        "n_aliases": len(replayed["aliases"]),
        "latency": replayed["latency"],
        "cpu": replayed["cpu"],
        "recording": recording_seconds(scenes.data),
        "out": str(out),
        "objects": None if objects is None else str(objects),
        **summary,
    }


def with_history(classifier, history, path):
    """Set the ``history`` of a loaded ClusterClassifier; ValueError (naming ``path``) for one trained on features."""
    if "features" in (classifier.history, history) and classifier.history != history:
        raise ValueError(
            f"--history: the classifier of {path} was trained with history={classifier.history!r}; its history "
            "features cannot be switched on or off at prediction (mean_proba and none can)"
        )
    classifier.set_params(history=history)


def _saved_tracker(params, classifier):
    """The Tracker saved in ``params`` and its saved parameters; ValueError naming the file when it has none."""
    if classifier is not None:
        raise ValueError("--track does not go with --classifier: the classifiers label the final object ids")
    if params is None:
        raise ValueError("--track runs the Tracker saved in --params: give --params")
    found = saved_tracker(params)
    if found is None:
        raise ValueError(
            f"{params}: saves no tuned tracker (the key 'tracker'); a reproduce run with the objects and tracking "
            "steps (the default run) saves one"
        )
    try:
        return Tracker(**found), found
    except (TypeError, ValueError) as error:
        raise ValueError(f"{params}: the key 'tracker' holds parameters the Tracker does not take: {error}") from None


def classify_objects(model, data, object_ids):
    """Class code and instance of each detection of ``data`` for the final ``object_ids`` of a replay.

    Returns
    -------
    classes : ndarray of int64
        Road-user class code (-1 background and noise).
    instances : ndarray of int64
        The object id where the class is a road user, else -1.
    """
    predicted = model.classifier.predict_instances_of(model.working(data), object_ids)
    classes = predicted["class"].to_numpy(np.int64)
    return classes, np.where(classes >= 0, object_ids, -1).astype(np.int64)


def _class_counts(classes):
    """Detections per devkit class name, for every class."""
    return {name: int(np.count_nonzero(classes == code)) for code, name in DEVKIT_CLASS_NAMES.items()}
