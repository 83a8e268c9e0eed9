"""``--classifier`` of ``sklearn-radar cluster`` and ``stream``: the saved classifier, its clustering, the classes.

A classifier file (:func:`~sklearn_radar.classification.save_classifier`)
holds either a whole pipeline from raw detections ending in a
:class:`~sklearn_radar.classification.ClusterClassifier`, or a bare
ClusterClassifier.  A whole pipeline is complete: it fixes the frame
transform, the filter and the clusterer, so ``--params`` is not needed.  A
bare one reads working detections, so the steps before it come from
``--params``.  When both are given, they must cluster alike (same steps,
same parameters), else the classifier would classify clusters of another
setting than the one named: a ValueError names the first difference.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from sklearn.base import clone
from sklearn.pipeline import Pipeline

from ..classification import devkit_class_index, load_classifier
from ..classification._persist import final_classifier
from ..cluster import RadarDBSCAN
from ..datasets import load_radarscenes

#: Our class code -> the devkit's ClassificationLabel value, as a lookup indexed by ``code + 1``.


@dataclass
class ClassifierSetting:
    """What ``--classifier`` (with or without ``--params``) applies.

    Parameters
    ----------
    preprocessing : Pipeline
        The steps from raw detections to working detections (frame transform, filter).
    fitted : bool
        Whether ``preprocessing`` is fitted (from a saved pipeline) or is to be fitted on each sequence (from
        ``--params``; its steps learn nothing).
    classifier : ClusterClassifier
        The fitted classifier.
    clustering : Pipeline
        The clustering it classifies, unfitted: ``preprocessing`` then its clusterer (what ``stream`` replays).
    """

    preprocessing: Pipeline
    fitted: bool
    classifier: object
    clustering: Pipeline

    def working(self, raw):
        """The working detections of a raw detection table.

        A saved pipeline gets the columns it was fitted with, in that order (a pipeline fitted without the
        ``uuid`` or the ground truth, as ``reproduce`` fits its classifiers, reads none of them).
        """
        if self.fitted:
            return self.preprocessing.transform(_fitted_columns(self.preprocessing, raw))
        return clone(self.preprocessing).fit_transform(raw)


def _fitted_columns(preprocessing, raw):
    """``raw`` reduced to the columns ``preprocessing`` was fitted with; ValueError names those it lacks."""
    names = getattr(preprocessing, "feature_names_in_", None)
    if names is None or not hasattr(raw, "columns"):
        return raw
    missing = [str(name) for name in names if name not in raw.columns]
    if missing:
        raise ValueError(f"the classifier was fitted with the column(s) {missing}, which the detections lack")
    return raw[list(names)]


def classifier_setting(classifier_path, setting=None, params_path=None, pipeline=None):
    """The classifier of ``classifier_path`` with its preprocessing; checked against ``--params`` if given.

    Parameters
    ----------
    classifier_path : str or path-like
        File written by :func:`~sklearn_radar.classification.save_classifier`.
    setting : dict, default=None
        The checked setting of ``--params`` (:func:`~sklearn_radar.reproduce.load_params`), or None.
    params_path : str or path-like, default=None
        Its file, for the messages.
    pipeline : Pipeline, default=None
        The setting's pipeline (:func:`~sklearn_radar.experiments._saved.setting_pipeline`).

    Returns
    -------
    setting : ClassifierSetting

    Raises
    ------
    ValueError
        Naming the files: a bare ClusterClassifier without ``--params``, or a classifier that clusters otherwise
        than ``--params``.
    """
    model = load_classifier(classifier_path)
    classifier = final_classifier(model)
    clusterer = RadarDBSCAN() if classifier.clusterer is None else classifier.clusterer
    if isinstance(model, Pipeline):
        preprocessing = Pipeline(model.steps[:-1])
        fitted = True
    elif pipeline is None:
        raise ValueError(
            f"--classifier {classifier_path} holds a bare ClusterClassifier, which reads working detections: give "
            "--params for the frame transform and filter before it (or save the whole pipeline from raw detections)"
        )
    else:
        preprocessing = Pipeline(clone(pipeline).steps[:-1])
        fitted = False
    clustering = Pipeline([*clone(preprocessing).steps, ("cluster", clone(clusterer))])
    if pipeline is not None:
        difference = first_difference(clustering, pipeline)
        if difference is not None:
            number = setting["experiment"]
            named = f"#{number}" if isinstance(number, int) else repr(number)
            raise ValueError(
                f"--classifier {classifier_path} and experiment {named} of --params {params_path} cluster "
                f"differently ({difference}): give the setting the classifier was trained on, or leave out --params"
            )
    return ClassifierSetting(preprocessing, fitted, classifier, clustering)


def first_difference(ours, theirs):
    """The first difference of two pipelines' steps (type or parameter, by position) as text; None if alike."""
    steps, other_steps = ours.steps, theirs.steps
    if len(steps) != len(other_steps):
        return f"{len(steps)} steps against {len(other_steps)}"
    for position, ((name, step), (_, other)) in enumerate(zip(steps, other_steps, strict=True)):
        where = f"step {position + 1} ({name})"
        if type(step) is not type(other):
            return f"{where}: {_kind(step)} against {_kind(other)}"
        if isinstance(step, str):
            continue
        mine, yours = _leaves(step), _leaves(other)
        for key in sorted(set(mine) | set(yours)):
            if not _same(mine.get(key, _MISSING), yours.get(key, _MISSING)):
                return f"{where}: {key}={mine.get(key)!r} against {yours.get(key)!r}"
    return None


_MISSING = object()


def _kind(step):
    return repr(step) if isinstance(step, str) else type(step).__name__


def _leaves(estimator):
    """The parameters of an estimator that are not estimators themselves (those of nested ones included)."""
    return {key: value for key, value in estimator.get_params(deep=True).items() if not hasattr(value, "get_params")}


def _same(a, b):
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    try:
        return bool(a == b)
    except (TypeError, ValueError):  # arrays: element-wise
        return np.array_equal(a, b)


def classify_sequence(task):
    """Load one sequence, cluster and classify it: ``(folder, number, setting)`` -> ``(uuids, instances, classes)``.

    ``instances`` are those of
    :meth:`~sklearn_radar.classification.ClusterClassifier.predict_instances`
    (-1 for noise and background), ``classes`` the devkit's class indices.
    Runs on a dask worker with ``--scheduler``/``--workers``, else here.
    """
    data_dir, number, setting = task
    scenes = load_radarscenes(data_dir, sequences=number)
    predicted = setting.classifier.predict_instances(setting.working(scenes.data))
    uuids = scenes.data["uuid"].to_numpy()
    return uuids, predicted["instance"].to_numpy(np.int64), devkit_class_index(predicted["class"].to_numpy())
