"""``predict_instances`` of a road-user classifier, or of a scikit-learn Pipeline that ends in one."""

from __future__ import annotations

from sklearn.pipeline import Pipeline
from sklearn.utils._param_validation import HasMethods, validate_params

__all__ = ["predict_instances"]


@validate_params(
    {"model": [HasMethods(["predict_instances"]), Pipeline], "X": ["array-like"]},
    prefer_skip_nested_validation=False,
)
def predict_instances(model, X):
    """The road users in X of a fitted classifier or of a fitted pipeline that ends in one.

    A :class:`~sklearn.pipeline.Pipeline` passes on only its own methods
    (``predict``, ``predict_proba``, ``score``, ...), so
    ``pipeline.predict_instances(X)`` does not exist; this runs the
    pipeline's other steps' ``transform`` on X, then its last step's
    ``predict_instances``, which is what ``pipeline.predict(X)`` does for
    ``predict``.

    Read more in the :ref:`User Guide <user-guide-classification>`.

    Parameters
    ----------
    model : estimator with ``predict_instances``, or Pipeline
        A fitted :class:`ClusterClassifier` or :class:`PointClassifier` (any
        estimator with ``predict_instances``), or a fitted pipeline whose
        last step has it.
    X : DataFrame or array-like of shape (n_detections, n_columns)
        The detections the pipeline (or the classifier) takes.

    Returns
    -------
    instances : DataFrame of shape (n_detections, 3)
        ``class`` (road-user class code, -1 background), ``instance`` (-1
        where the class is background) and ``confidence`` (in [0, 1]) per
        detection, as :meth:`ClusterClassifier.predict_instances` returns
        them.

    Raises
    ------
    ValueError
        If ``model`` is a pipeline whose last step has no
        ``predict_instances``.

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn.pipeline import make_pipeline
    >>> from sklearn_radar import DopplerDensityFilter, FrameTransform, RadarDBSCAN
    >>> from sklearn_radar.classification import ClusterClassifier, predict_instances, road_user_class
    >>> from sklearn_radar.datasets import make_scenes
    >>> scenes = make_scenes(n_sequences=2, duration=6.0, random_state=0)
    >>> model = make_pipeline(
    ...     FrameTransform(), DopplerDensityFilter(), ClusterClassifier(RadarDBSCAN(metric="xyv", vr_min=-np.inf))
    ... ).fit(scenes.data, road_user_class(scenes.data["label_id"]))
    >>> predict_instances(model, scenes.data).columns.tolist()
    ['class', 'instance', 'confidence']
    """
    if hasattr(model, "predict_instances"):
        return model.predict_instances(X)
    last = model.steps[-1][1] if model.steps else None
    if not hasattr(last, "predict_instances"):
        raise ValueError(
            "predict_instances: the pipeline's last step must have predict_instances (a ClusterClassifier or a "
            f"PointClassifier), got {type(last).__name__}"
        )
    return last.predict_instances(model[:-1].transform(X) if len(model) > 1 else X)
