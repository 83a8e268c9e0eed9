"""Saving and loading a fitted ClusterClassifier: joblib, with the versions it was made with, written atomically.

The same file layout holds other fitted models of the package (:func:`save_model`, :func:`load_model`: the
learned grouping of ``sklearn-radar reproduce``).  A classifier file is a header of two text lines, then the
joblib pickle:

1. ``sklearn-radar classifier`` (how a file is recognised as ours);
2. one JSON object: ``format`` (1), ``sklearn_radar`` and ``sklearn``
   (the versions that wrote it), ``type`` (``ClusterClassifier`` or
   ``Pipeline``; another model's class name), ``payload_bytes`` and ``payload_sha256`` (of the pickle).

The header is read and checked before anything is unpickled, so a foreign,
truncated or damaged file and a file of another scikit-learn are refused
without running any of their code.  Loading then runs pickle (joblib):
**only load files you trust**, as for any pickle (scikit-learn's model
persistence guide says the same).
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import warnings
from pathlib import Path

import joblib
import sklearn
from sklearn.base import BaseEstimator
from sklearn.exceptions import InconsistentVersionWarning, NotFittedError
from sklearn.pipeline import Pipeline
from sklearn.utils._param_validation import validate_params
from sklearn.utils.validation import check_is_fitted

from .. import __version__
from .._files import atomic_write, check_ours_to_replace
from ._cluster_classifier import ClusterClassifier

__all__ = ["ClassifierVersionWarning", "load_classifier", "load_model", "save_classifier", "save_model"]

#: The first line of a classifier file: how a file is recognised as written by :func:`save_classifier`.
CLASSIFIER_MAGIC = b"sklearn-radar classifier\n"
#: The layout of the header and payload; a file of another format is refused.
CLASSIFIER_FORMAT = 1
#: The longest header line read (a larger one is not ours).
_MAX_HEADER = 4096


class ClassifierVersionWarning(UserWarning):
    """A classifier file was written by another version of sklearn-radar (it is loaded)."""


@validate_params({"classifier": [BaseEstimator], "path": [str, os.PathLike]}, prefer_skip_nested_validation=True)
def save_classifier(classifier, path):
    """Save a fitted :class:`ClusterClassifier` (or a pipeline ending in one) to a file, atomically.

    The file holds the joblib pickle of ``classifier`` behind a header with
    the sklearn-radar and scikit-learn versions (:func:`load_classifier`
    checks them).  It is written to a temporary sibling and renamed into
    place when complete, so ``path`` holds either the old file or the whole
    new one.  An existing ``path`` is replaced only if it is empty or a
    classifier file written by this function (:func:`check_classifier_file`).

    For ``sklearn-radar cluster --classifier`` and ``stream --classifier``,
    save the whole pipeline from raw detections (for example
    ``make_pipeline(FrameTransform(), DopplerDensityFilter(),
    ClusterClassifier(...))``): a bare ClusterClassifier reads working
    detections and needs ``--params`` for the steps before it.

    Read more in the :ref:`User Guide <user-guide-classification>`.

    Parameters
    ----------
    classifier : ClusterClassifier or Pipeline
        Fitted; a :class:`~sklearn.pipeline.Pipeline` must end in a fitted
        ClusterClassifier.
    path : str or path-like
        File to write.

    Raises
    ------
    ValueError
        If ``classifier`` is not such an estimator, or not fitted.
    FileExistsError
        If ``path`` is another file (it is kept).
    """
    save_model(classifier, path, (ClusterClassifier,), "classifier")


def save_model(model, path, finals, noun):
    """Save a fitted model whose last step is one of ``finals`` behind the checked header, atomically.

    :func:`save_classifier` for another kind of model (``noun`` names it in the errors).

    Parameters
    ----------
    model : estimator or Pipeline
        Fitted; a :class:`~sklearn.pipeline.Pipeline` must end in a fitted instance of ``finals``.
    path : str or path-like
        File to write; an existing one is replaced only if it is empty or a file of this layout.
    finals : tuple of type
        The estimator classes the model (or its pipeline's last step) may be.
    noun : str
        What the model is, for the messages (``"classifier"``).
    """
    kind = _checked_model(model, noun, finals)
    check_classifier_file(path)
    buffer = io.BytesIO()
    joblib.dump(model, buffer)
    payload = buffer.getvalue()
    header = {
        "format": CLASSIFIER_FORMAT,
        "sklearn_radar": __version__,
        "sklearn": sklearn.__version__,
        "type": kind,
        "payload_bytes": len(payload),
        "payload_sha256": hashlib.sha256(payload).hexdigest(),
    }

    def write(stream):
        stream.write(CLASSIFIER_MAGIC)
        stream.write(json.dumps(header, sort_keys=True).encode("ascii") + b"\n")
        stream.write(payload)

    atomic_write(Path(path), write, replaceable=check_classifier_file)


@validate_params({"path": [str, os.PathLike]}, prefer_skip_nested_validation=True)
def load_classifier(path):
    """Load a classifier saved by :func:`save_classifier`; the file is checked before it is unpickled.

    **Loading runs pickle: only load files you trust.**  A pickle can run
    any code when it is loaded; the checks below (made before unpickling)
    refuse files this package did not write, not files made to look like
    them.

    Version policy:

    * another **scikit-learn** version than the one that wrote the file:
      refused (ValueError).  scikit-learn does not support unpickling an
      estimator in another version than it was pickled with: the result
      may break or, worse, predict differently without any error.
      Retrain (or install the scikit-learn version the error names).
    * another **sklearn-radar** version: loaded, with a
      :class:`ClassifierVersionWarning`.  The package's own estimators are
      plain Python over the stored parameters and fitted attributes; the
      loaded object is still checked to be a fitted ClusterClassifier, but
      its predictions may differ where the package changed its features.

    Read more in the :ref:`User Guide <user-guide-classification>`.

    Parameters
    ----------
    path : str or path-like
        A file written by :func:`save_classifier`.

    Returns
    -------
    classifier : ClusterClassifier or Pipeline
        As saved: fitted, a ClusterClassifier or a Pipeline ending in one.

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    ValueError
        Naming the file: it was not written by :func:`save_classifier`
        (foreign), is truncated or damaged, was written by another
        scikit-learn, or does not hold a fitted ClusterClassifier.

    Warns
    -----
    ClassifierVersionWarning
        If it was written by another sklearn-radar version.
    """
    return load_model(path, (ClusterClassifier,), "classifier")


def load_model(path, finals, noun):
    """Load a model saved by :func:`save_model` whose last step is one of ``finals``; checked before unpickling.

    :func:`load_classifier` for another kind of model, with its checks and version policy.  **Loading runs pickle:
    only load files you trust.**

    Parameters
    ----------
    path : str or path-like
        A file written by :func:`save_model` (or :func:`save_classifier`).
    finals : tuple of type
        The estimator classes the model (or its pipeline's last step) must be.
    noun : str
        What the model is, for the messages (``"classifier"``).

    Returns
    -------
    model : estimator or Pipeline
        As saved.
    """
    path = Path(path)
    try:
        with open(path, "rb") as stream:
            header = _read_header(stream, path, noun)
            payload = stream.read(header["payload_bytes"] + 1)
    except FileNotFoundError:
        raise FileNotFoundError(f"{noun} file not found: {path}") from None
    except IsADirectoryError:
        raise ValueError(f"{path}: is a folder, not a {noun} file") from None
    except OSError as error:
        raise OSError(f"cannot read the {noun} file {path}: {error.strerror or error}") from None
    if len(payload) != header["payload_bytes"] or hashlib.sha256(payload).hexdigest() != header["payload_sha256"]:
        problem = "truncated" if len(payload) < header["payload_bytes"] else "damaged"
        raise ValueError(
            f"{path}: the {noun} file is {problem} ({len(payload)} of {header['payload_bytes']} bytes after the "
            "header, or another checksum); save it again"
        )
    _check_versions(header, path, noun)
    try:
        with warnings.catch_warnings():
            # The versions were compared above; scikit-learn's own warning would only repeat it.
            warnings.simplefilter("ignore", InconsistentVersionWarning)
            model = joblib.load(io.BytesIO(payload))
    except Exception as error:  # a pickle can raise anything: each becomes one message naming the file
        raise ValueError(f"{path}: cannot unpickle the {noun}: {type(error).__name__}: {error}") from None
    _checked_model(model, str(path), finals)
    try:  # an estimator pickled before a parameter was renamed lacks the new attribute
        model.get_params(deep=True)
    except AttributeError as error:
        raise ValueError(
            f"{path}: the {noun} was saved with other parameters than this sklearn-radar's ({error}); a parameter "
            "was renamed since (see the changelog): fit and save it again"
        ) from None
    return model


def check_classifier_file(path):
    """Refuse to replace ``path`` unless it is absent, empty, or a classifier file this package wrote.

    A classifier file is recognised by its first line
    (:data:`CLASSIFIER_MAGIC`); any other file (a plain joblib dump,
    ``params.json``, a typo) is another's work and is kept.

    Parameters
    ----------
    path : str or path-like
        The classifier file to write.

    Raises
    ------
    FileExistsError
        Naming ``path``.
    """
    check_ours_to_replace(path, (CLASSIFIER_MAGIC,), "a classifier file")


def final_classifier(model):
    """The ClusterClassifier of a loaded model: itself, or the last step of its pipeline."""
    return model.steps[-1][1] if isinstance(model, Pipeline) else model


def _read_header(stream, path, noun):
    """The parsed, checked header of an open model file; ValueError names the file and the problem."""
    saver = "save_classifier" if noun == "classifier" else "save_model"
    foreign = f"{path}: not a {noun} file written by sklearn-radar's {saver}"
    if stream.read(len(CLASSIFIER_MAGIC)) != CLASSIFIER_MAGIC:
        raise ValueError(f"{foreign} (a plain joblib or pickle file is not loaded: save it with {saver})")
    line = stream.readline(_MAX_HEADER)
    try:
        header = json.loads(line.decode("ascii"))
    except (UnicodeDecodeError, json.JSONDecodeError):
        raise ValueError(f"{foreign}: its header line is not JSON (truncated or damaged?)") from None
    if not isinstance(header, dict) or header.get("format") != CLASSIFIER_FORMAT:
        got = header.get("format") if isinstance(header, dict) else header
        raise ValueError(f"{path}: {noun} file format {got!r}; this sklearn-radar reads format {CLASSIFIER_FORMAT}")
    for key, kind in (("sklearn_radar", str), ("sklearn", str), ("payload_bytes", int), ("payload_sha256", str)):
        if not isinstance(header.get(key), kind) or isinstance(header.get(key), bool):
            raise ValueError(f"{foreign}: its header lacks {key!r} (damaged?)")
    return header


def _check_versions(header, path, noun):
    """Refuse another scikit-learn; warn about another sklearn-radar (see :func:`load_classifier`)."""
    if header["sklearn"] != sklearn.__version__:
        raise ValueError(
            f"{path}: the {noun} was saved with scikit-learn {header['sklearn']}, this is "
            f"{sklearn.__version__}; scikit-learn does not support unpickling across versions (the model may "
            f"predict differently without an error): retrain it, or use scikit-learn {header['sklearn']}"
        )
    if header["sklearn_radar"] != __version__:
        warnings.warn(
            f"{path}: the {noun} was saved with sklearn-radar {header['sklearn_radar']}, this is {__version__}; "
            "it is loaded, but its predictions may differ where the package changed: retrain it to be sure",
            ClassifierVersionWarning,
            stacklevel=3,
        )


def _checked_model(model, where, finals=(ClusterClassifier,)):
    """``type`` of the header (the final class's name or ``"Pipeline"``) of a fitted such model; else a ValueError.

    The error names ``where``.
    """
    final = final_classifier(model) if isinstance(model, Pipeline) and model.steps else model
    name = " or ".join(cls.__name__ for cls in finals)
    if not isinstance(final, finals):
        got = type(model).__name__ if final is model else f"a Pipeline ending in {type(final).__name__}"
        raise ValueError(f"{where}: must hold a fitted {name} or a Pipeline ending in one, got {got}")
    try:
        check_is_fitted(final)
        if final is not model:
            check_is_fitted(model)
    except NotFittedError:
        raise ValueError(f"{where}: the {type(final).__name__} is not fitted (fit it before saving)") from None
    return "Pipeline" if final is not model else type(final).__name__
