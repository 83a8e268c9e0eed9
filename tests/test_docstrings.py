"""Every public class, function and estimator method has a numpydoc docstring that names its parameters.

For each object in the ``__all__`` of ``sklearn_radar`` and its subpackages,
and each public method that the package defines on those classes (``fit``,
``transform``, ``partial_fit``, ``update``, ``__call__``, ...), this runs
:func:`numpydoc.validate.validate` and fails on the codes of
:data:`CHECKED_CODES`.  For classes it also checks what numpydoc cannot see:
that every key of ``_parameter_constraints`` is in the Parameters section,
and, for estimators fitted on a few seconds of simulated detections, that
the Attributes section lists exactly the public attributes ``fit`` sets.

Objects in modules that are being rewritten carry their current failures
in :data:`KNOWN_GAPS`; the test fails when one of them gains a failure *or
loses one*, so that the dict only shrinks, and honestly.
"""

from __future__ import annotations

import inspect
from functools import cache
from importlib import import_module

import numpy as np
import pytest
from numpydoc.docscrape import NumpyDocString
from numpydoc.validate import validate
from sklearn.base import BaseEstimator

#: Subpackages first: an object exported twice is named after the most specific package.
PACKAGES = [
    "sklearn_radar.classification",
    "sklearn_radar.cluster",
    "sklearn_radar.datasets",
    "sklearn_radar.evaluation",
    "sklearn_radar.experiments",
    "sklearn_radar.metrics",
    "sklearn_radar.model_selection",
    "sklearn_radar.online",
    "sklearn_radar.preprocessing",
    "sklearn_radar.reproduce",
    "sklearn_radar",
]

#: The numpydoc codes that fail the test: those that catch an undocumented, undescribed or misnamed
#: parameter or return value.
#:
#: Not checked, deliberately: RT03 (a return value without a description).  The summary line already
#: says what a function returns, and an entry such as ``keep : ndarray of bool, shape (n_detections,)``
#: or ``self : DopplerDensityFilter`` names and types it; demanding a sentence under it would mostly
#: repeat the summary.  Likewise RT02 (named return values are this package's convention, as
#: scikit-learn's), PR04 (grouped entries such as ``min_spread, max_trials`` -- "as in
#: estimate_velocity" -- carry no type), and the style codes (capitals, full stops, line lengths),
#: See Also, Examples and extended-summary codes.
CHECKED_CODES = {
    "GL08": "the object has no docstring",
    "PR01": "a parameter of the signature is not documented",
    "PR02": "a documented parameter is not in the signature (misnamed or removed)",
    "PR03": "the parameters are documented in another order than the signature's",
    "PR07": "a documented parameter has no description",
    "PR10": "'name: type' without a space before the colon is read as one parameter name",
    "RT01": "the function returns a value but has no Returns section",
    "YD01": "the function yields but has no Yields section",
}

#: Checks of this test that numpydoc does not make.
CUSTOM_CODES = {
    "PC01": "a key of _parameter_constraints is not in the Parameters section",
    "AT01": "fit sets a public attribute (trailing underscore) that the Attributes section does not list",
    "AT02": "the Attributes section lists a fitted attribute (trailing underscore) that fit does not set",
}

#: Accepted failures, {dotted name: {codes}}: none today.  An entry must still fail with exactly those
#: codes -- the test insists -- so the table can only shrink honestly.
KNOWN_GAPS: dict[str, set[str]] = {}

#: Public methods checked besides those not starting with an underscore.
SPECIAL_METHODS = ("__call__",)


def _public_objects():
    """``{dotted name: object}`` of the classes and functions in the ``__all__`` lists, each once."""
    objects, seen = {}, set()
    for package in PACKAGES:
        module = import_module(package)
        for name in module.__all__:
            obj = getattr(module, name)
            if (inspect.isclass(obj) or inspect.isfunction(obj)) and id(obj) not in seen:
                seen.add(id(obj))
                objects[f"{package}.{name}"] = obj
    return objects


def _own_methods(klass):
    """Names of the public methods that the package itself defines on ``klass`` or its bases."""
    names = []
    for base in klass.__mro__:
        if not base.__module__.startswith("sklearn_radar"):
            continue
        for name, member in vars(base).items():
            public = not name.startswith("_") or name in SPECIAL_METHODS
            if public and inspect.isfunction(member) and name not in names:
                names.append(name)
    return names


def _checked_names():
    names = []
    for name, obj in _public_objects().items():
        names.append(name)
        if inspect.isclass(obj):
            names += [f"{name}.{method}" for method in _own_methods(obj)]
    return names


CHECKED_NAMES = _checked_names()


def _resolve(dotted):
    module_name, _, rest = dotted.partition(".")
    obj = import_module(module_name)
    for part in rest.split("."):
        try:
            obj = getattr(obj, part)
        except AttributeError:
            obj = import_module(f"{obj.__name__}.{part}")
    return obj


def _documented(obj, section):
    """Names listed in a numpydoc section; ``a, b : type`` lists both."""
    doc = NumpyDocString(inspect.getdoc(obj) or "")
    names = set()
    for entry in doc[section]:
        names.update(part.strip().lstrip("*") for part in entry.name.split(","))
    return names


@cache
def _detections():
    """A few seconds of simulated raw detections and their FrameTransform output."""
    from sklearn_radar.datasets import make_scenes
    from sklearn_radar.preprocessing import FrameTransform

    raw = make_scenes(n_sequences=1, duration=3.0, random_state=0).data
    return raw, FrameTransform().fit_transform(raw)


def _fit_progress_bayes_search(klass):
    """One random candidate of experiment #3's search, on the one simulated sequence."""
    from sklearn_radar import instance_target
    from sklearn_radar.experiments import experiment_pipeline, search_space
    from sklearn_radar.metrics import precluster_target, radar_v_measure_scorer

    raw, _ = _detections()
    target = precluster_target(raw, instance_target(raw["track_id"], raw["sequence"]))
    rows = np.arange(len(raw))
    search = klass(
        experiment_pipeline(3),
        search_space(3),
        n_iter=1,
        optimizer_kwargs={"n_initial_points": 1},
        scoring=radar_v_measure_scorer,
        cv=[(rows, rows)],  # one sequence: one fold, scored on the data it is fitted on (a clusterer)
        random_state=0,
    )
    return search.fit(raw, target)


def _fit_sequence_search(klass):
    """Two random candidates of experiment #3's search, two folds of one simulated sequence each."""
    from sklearn_radar import instance_target
    from sklearn_radar.datasets import make_scenes
    from sklearn_radar.experiments import experiment_pipeline, search_space
    from sklearn_radar.metrics import precluster_target

    raw = make_scenes(n_sequences=2, duration=2.0, random_state=0).data
    target = precluster_target(raw, instance_target(raw["track_id"], raw["sequence"]))
    search = klass(experiment_pipeline(3), search_space(3), n_iter=2, n_initial_points=2, cv=2, random_state=0)
    return search.fit(raw, target, raw["sequence"])


def _fit_classifier(klass):
    """A road-user classifier on the FrameTransform output, with the classes of its label_id."""
    from sklearn_radar.classification import road_user_class

    raw, work = _detections()
    return klass().fit(work, road_user_class(raw["label_id"]))


def _fit_link_clustering(klass):
    """The learned grouping on the FrameTransform output, with the instances of its track ids (few iterations)."""
    from sklearn_radar import instance_target

    raw, work = _detections()
    return klass(max_iter=10).fit(work, instance_target(raw["track_id"], raw["sequence"]))


#: How each estimator class of the public API is fitted: on the raw table or on FrameTransform's output.
FIT = {
    "sklearn_radar.preprocessing.FrameTransform": lambda klass: klass().fit(_detections()[0]),
    "sklearn_radar.preprocessing.DopplerDensityFilter": lambda klass: klass().fit(_detections()[1]),
    "sklearn_radar.cluster.RadarDBSCAN": lambda klass: klass().fit(_detections()[1]),
    "sklearn_radar.cluster.ClusterMerger": lambda klass: klass().fit(_detections()[1]),
    "sklearn_radar.cluster.WindowedDBSCAN": lambda klass: klass().fit(_detections()[1]),
    "sklearn_radar.cluster.WindowedHDBSCAN": lambda klass: klass().fit(_detections()[1]),
    "sklearn_radar.cluster.SequenceDBSCAN": lambda klass: klass().fit(_detections()[1]),
    "sklearn_radar.cluster.SequenceHDBSCAN": lambda klass: klass().fit(_detections()[1]),
    "sklearn_radar.cluster.SlidingDBSCAN": lambda klass: klass().fit(_detections()[1]),
    "sklearn_radar.cluster.LinkClustering": _fit_link_clustering,
    "sklearn_radar.classification.ClusterClassifier": _fit_classifier,
    "sklearn_radar.classification.PointClassifier": _fit_classifier,
    "sklearn_radar.model_selection.ProgressBayesSearchCV": _fit_progress_bayes_search,
    "sklearn_radar.model_selection.SequenceSearchCV": _fit_sequence_search,
}


def _custom_failures(name, klass):
    """The CUSTOM_CODES failures of a class, as ``{code: message}``."""
    failures = {}
    parameters = _documented(klass, "Parameters")
    undocumented = sorted(set(getattr(klass, "_parameter_constraints", {})) - parameters)
    if undocumented:
        failures["PC01"] = f"constrained but not in Parameters: {undocumented}"
    if issubclass(klass, BaseEstimator):
        estimator = FIT[name](klass)
        fitted = {attr for attr in vars(estimator) if attr.endswith("_") and not attr.startswith("_")}
        listed = _documented(klass, "Attributes")
        missing = sorted(fitted - listed)
        if missing:
            failures["AT01"] = f"set by fit but not in Attributes: {missing}"
        absent = sorted(attr for attr in listed if attr.endswith("_") and not hasattr(estimator, attr))
        if absent:
            failures["AT02"] = f"in Attributes but not set by fit: {absent}"
    return failures


def _failures(name):
    """``{code: message}`` of every checked problem of the object ``name``."""
    result = validate(name)
    failures = {}
    for code, message in result["errors"]:
        if code in CHECKED_CODES:
            failures[code] = f"{failures[code]}; {message}" if code in failures else message
    obj = _resolve(name)
    if inspect.isclass(obj):
        failures.update(_custom_failures(name, obj))
    return failures


def test_every_estimator_is_fitted_by_the_attribute_check():
    estimators = {
        name for name, obj in _public_objects().items() if inspect.isclass(obj) and issubclass(obj, BaseEstimator)
    }
    assert estimators == set(FIT)


def test_known_gaps_name_checked_objects_and_codes():
    assert set(KNOWN_GAPS) <= set(CHECKED_NAMES), "a KNOWN_GAPS entry names no public object: remove it"
    for name, codes in KNOWN_GAPS.items():
        assert codes, f"KNOWN_GAPS[{name!r}] is empty: remove the entry"
        assert set(codes) <= set(CHECKED_CODES) | set(CUSTOM_CODES), f"KNOWN_GAPS[{name!r}] has unknown codes"


@pytest.mark.parametrize("name", CHECKED_NAMES)
def test_docstring(name):
    failures = _failures(name)
    known = KNOWN_GAPS.get(name, set())
    new = {code: message for code, message in failures.items() if code not in known}
    described = {**CHECKED_CODES, **CUSTOM_CODES}
    assert not new, f"{name}:\n" + "\n".join(f"  {code} ({described[code]}): {new[code]}" for code in sorted(new))
    fixed = sorted(known - set(failures))
    assert not fixed, f"{name} no longer fails {fixed}: remove them from KNOWN_GAPS"
