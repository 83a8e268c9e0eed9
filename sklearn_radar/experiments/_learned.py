"""Beyond the paper: the learned grouping, fitted on labelled sequences and applied to new ones.

The learned experiment is the object experiment's front (:func:`object_pipeline`'s ``frame`` and ``filter``:
FCS and the Doppler-density filter at the paper's chosen setting, which the object experiment does not tune)
followed by :class:`~sklearn_radar.cluster.LinkClustering` (``link``), whose thresholds are tuned for panoptic
quality inside its ``fit``.  Unlike every other setting of ``sklearn-radar reproduce`` it is a fitted model, not a
parameter setting: the run saves it as a file (:func:`save_learned`) and ``params.json`` points to it; its causal
twin (``link__causal=True``), saved beside it, is what ``sklearn-radar stream`` runs.  Read more in the
:ref:`User Guide <user-guide-objects>`.
"""

from __future__ import annotations

from sklearn.pipeline import Pipeline
from sklearn.utils._param_validation import validate_params

from ..classification._persist import load_model, save_model
from ..cluster import LinkClustering
from ._objects import object_pipeline

__all__ = ["LEARNED_EXPERIMENT", "learned_pipeline", "load_learned", "save_learned"]

#: The step key and name of the learned experiment in ``reproduce`` and ``params.json``.
LEARNED_EXPERIMENT = "learned"
#: What the errors of a learned model file call it.
_NOUN = "learned grouping"


@validate_params({"params": [dict, None]}, prefer_skip_nested_validation=True)
def learned_pipeline(params=None):
    """The learned experiment's pipeline, unfitted: ``frame``, ``filter`` (the object experiment's), ``link``.

    Parameters
    ----------
    params : dict, default=None
        Pipeline parameters set after construction (``link__max_iter``, ``filter__d_xy``, ...).

    Returns
    -------
    pipeline : sklearn.pipeline.Pipeline
        Fit it with the ground-truth instance of each detection as ``y``.

    Examples
    --------
    >>> from sklearn_radar.experiments._learned import learned_pipeline
    >>> [name for name, _ in learned_pipeline().steps]
    ['frame', 'filter', 'link']
    """
    front = object_pipeline(1).steps[:2]
    pipeline = Pipeline([*front, ("link", LinkClustering())])
    if params:
        pipeline.set_params(**params)
    return pipeline


def save_learned(model, path):
    """Save a fitted learned pipeline behind the classifier files' checked header (:func:`save_model`).

    Parameters
    ----------
    model : Pipeline
        Fitted, ending in a :class:`~sklearn_radar.cluster.LinkClustering`.
    path : str or path-like
        File to write (atomically).
    """
    save_model(model, path, (LinkClustering,), _NOUN)


def load_learned(path):
    """The fitted learned pipeline saved by :func:`save_learned`; the file is checked before it is unpickled.

    **Loading runs pickle: only load files you trust.**  A file of another scikit-learn is refused, of another
    sklearn-radar loaded with a warning (:func:`~sklearn_radar.classification.load_classifier`'s policy).

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    model : Pipeline or LinkClustering

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    ValueError
        Naming the file: foreign, truncated, damaged, of another scikit-learn, or not a fitted LinkClustering.
    """
    return load_model(path, (LinkClustering,), _NOUN)
