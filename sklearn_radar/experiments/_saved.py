"""Settings saved by ``sklearn-radar reproduce`` in ``params.json``: read, checked and built into pipelines.

The command line's ``cluster`` and ``stream``, and
:meth:`sklearn_radar.online.OnlinePipeline.from_params`, apply a saved
setting through this module (:ref:`user-guide-command-line`).
"""

from __future__ import annotations

import functools
import json
import os
from numbers import Integral
from pathlib import Path

from sklearn.base import BaseEstimator
from sklearn.utils._param_validation import Interval, StrOptions, validate_params

from ._learned import LEARNED_EXPERIMENT, load_learned
from ._objects import OBJECT_EXPERIMENT, object_pipeline
from ._paper import experiment_pipeline, get_experiment

#: The ``experiment`` argument: a paper experiment's number, the object experiment, the learned grouping, or None
#: (the run's best).
SAVED_EXPERIMENT = [
    Interval(Integral, 1, None, closed="left"),
    StrOptions({OBJECT_EXPERIMENT, LEARNED_EXPERIMENT}),
    None,
]
#: Why a learned entry of an older run does not stream.
NO_CAUSAL_MODEL = (
    f"experiment {LEARNED_EXPERIMENT!r} names no causal model (key 'causal_model'; runs of older versions fitted "
    f"the offline one only): rerun 'sklearn-radar reproduce --experiments {LEARNED_EXPERIMENT}', or apply it "
    f"offline with 'sklearn-radar cluster --experiment {LEARNED_EXPERIMENT}'"
)


@validate_params({"path": [str, os.PathLike], "experiment": SAVED_EXPERIMENT}, prefer_skip_nested_validation=True)
def load_params(path, experiment=None):
    """The saved setting of ``experiment`` (default: the best) from a reproduce run's ``params.json``.

    Parameters
    ----------
    path : str or path-like
        ``params.json`` written by ``sklearn-radar reproduce``.
    experiment : int, "objects" or "learned", default=None
        Experiment number, the object experiment, or the learned grouping
        (whose setting points to its fitted model); None: the run's best
        (the highest cross-validated training score of the run's objective,
        see :ref:`user-guide-command-line`).

    Returns
    -------
    setting : dict
        ``experiment`` (its number), ``v1_test``, ``params`` (pipeline
        parameters) and ``stage1_params`` (stage 2: the fixed stage-1
        setting; otherwise None); the learned grouping's also ``model``,
        its file.

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
    if chosen in (OBJECT_EXPERIMENT, LEARNED_EXPERIMENT):
        if number != chosen:
            raise bad(f"the key 'experiment' of {where}", f"must be {chosen!r}, got {number!r}")
        stage = 2 if chosen == OBJECT_EXPERIMENT else 1  # the object experiment merges its own stage 1
        model = setting.get("model")
        if chosen == LEARNED_EXPERIMENT and (not isinstance(model, str) or not model):
            raise bad(where, f"must name its fitted model's file in the key 'model', got {_json_type(model)}")
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
#: Why a ``params.json`` without ``best_reason`` names its ``best`` (files of older versions, which chose it by the
#: test score).
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


def setting_pipeline(setting, path):
    """The pipeline of a checked setting; ValueError names the file and the parameter it cannot set.

    The learned grouping has no pipeline to build: it is a fitted model, and the one that runs online (what
    :class:`~sklearn_radar.online.OnlinePipeline` takes from here) is its causal one (:func:`learned_model` with
    ``causal=True``).
    """
    number = setting["experiment"]
    if number == LEARNED_EXPERIMENT:
        return learned_model(setting, path, causal=True)
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


def learned_model(setting, path, causal=False):
    """The fitted pipeline of the learned grouping's checked setting, from the file its ``model`` names.

    With ``causal``, the causal model (the file its ``causal_model`` names, a LinkClustering with
    ``causal=True``): what runs online.

    The file is read relative to the folder of ``params.json`` (``path``), checked before it is unpickled
    (:func:`~sklearn_radar.experiments._learned.load_learned`: **only load files you trust**), and its front must
    have the setting's ``params``.

    Raises
    ------
    FileNotFoundError
        Naming the model file, if it is missing.
    ValueError
        Naming the file: not a learned model written by a run, or with another front than ``params``.
    """
    key = "causal_model" if causal else "model"
    if causal and (not isinstance(setting.get(key), str) or not setting.get(key)):
        raise ValueError(f"{path}: {NO_CAUSAL_MODEL}")
    file = Path(path).parent / setting[key]
    model = load_learned(file)
    if not hasattr(model, "steps"):
        raise ValueError(f"{file}: holds a bare LinkClustering; the run saves the whole pipeline from raw detections")
    front = model.get_params()
    expected = dict(setting["params"])
    if causal and "filter__causal" in expected:  # the causal model's filter is causal, the entry's the offline one's
        expected["filter__causal"] = True
    # As params.json holds them (a tuple is a JSON array).
    differ = sorted(k for k, v in expected.items() if k not in front or json.loads(json.dumps(front[k])) != v)
    if differ:
        raise ValueError(
            f"{path}: experiments['{LEARNED_EXPERIMENT}'] does not describe the model in {file}: its params "
            f"{differ} differ from the model's (a model file of another run?)"
        )
    if bool(model[-1].causal) != causal:
        raise ValueError(f"{file}: holds a model with causal={model[-1].causal}, its entry's '{key}' needs {causal}")
    return model


def saved_tracker(path):
    """The tracker's parameters that a reproduce run's ``params.json`` saves under ``"tracker"``, or None.

    The tracking step tunes :class:`~sklearn_radar.online.Tracker`'s parameters on the training half and saves
    them there (``sklearn-radar stream --track``).

    Raises
    ------
    FileNotFoundError, OSError
        Naming the file, if it cannot be read.
    ValueError
        Naming the file and the key, if it is not JSON or its ``"tracker"`` is not an object with an object
        ``"params"``.
    """
    path = Path(path)
    saved = _read_params(path)
    tracker = saved.get("tracker") if isinstance(saved, dict) else None
    if tracker is None:
        return None
    params = tracker.get("params") if isinstance(tracker, dict) else None
    if not isinstance(params, dict):
        raise ValueError(
            f"{path}: the key 'tracker' must be an object with the object 'params' (not a parameter file written by "
            f"'sklearn-radar reproduce'), got {_json_type(params if isinstance(tracker, dict) else tracker)}"
        )
    return params


def params_setting(params, experiment, classifier):
    """``(setting, pipeline, chosen)`` of the ``params.json`` at ``params`` (all None without it).

    ValueError when neither ``params`` nor ``classifier`` is given.

    ``chosen`` says why the file names the setting its best (None when ``experiment`` chose it).  For the learned
    grouping ``pipeline`` is its fitted model (:func:`learned_model`), which takes no ``classifier``.
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
    if setting["experiment"] == LEARNED_EXPERIMENT:
        if classifier is not None:
            raise ValueError(
                f"--classifier does not go with experiment {LEARNED_EXPERIMENT!r} of {path}: the classifiers are "
                "trained on the clusters of a parameter setting, not on the learned grouping's"
            )
        return setting, learned_model(setting, path), chosen
    return setting, setting_pipeline(setting, params), chosen
