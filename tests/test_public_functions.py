"""Every public function validates its parameters with scikit-learn's ``validate_params``.

Modelled on ``sklearn/tests/test_public_functions.py`` and
``imblearn/tests/test_public_functions.py``: for each function the
constraints must name exactly its parameters, and an object of no valid
type, as well as a value generated to violate each constraint, must raise
:class:`~sklearn.utils._param_validation.InvalidParameterError` (a
ValueError) naming the parameter and the function.

The public functions are those in the ``__all__`` of ``sklearn_radar`` and
of its subpackages; :func:`test_every_public_function_is_listed` keeps the
lists below complete.
"""

import inspect
from importlib import import_module
from inspect import signature
from numbers import Integral, Real

import pytest
from sklearn.utils._param_validation import (
    Interval,
    InvalidParameterError,
    generate_invalid_param_val,
    generate_valid_param,
    make_constraint,
)

PACKAGES = [
    "sklearn_radar",
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
]

PARAM_VALIDATION_FUNCTION_LIST = [
    "sklearn_radar.config_context",
    "sklearn_radar.describe_columns",
    "sklearn_radar.get_config",
    "sklearn_radar.instance_target",
    "sklearn_radar.set_config",
    "sklearn_radar.classification.cluster_features",
    "sklearn_radar.classification.devkit_class_index",
    "sklearn_radar.classification.load_classifier",
    "sklearn_radar.classification.predict_instances",
    "sklearn_radar.classification.road_user_class",
    "sklearn_radar.classification.save_classifier",
    "sklearn_radar.cluster.estimate_velocities",
    "sklearn_radar.cluster.estimate_velocity",
    "sklearn_radar.cluster.min_points_at_range",
    "sklearn_radar.datasets.format_statistics",
    "sklearn_radar.datasets.load_radarscenes",
    "sklearn_radar.datasets.make_scenes",
    "sklearn_radar.datasets.scene_statistics",
    "sklearn_radar.datasets.write_radarscenes",
    "sklearn_radar.evaluation.filter_error_windows",
    "sklearn_radar.evaluation.filter_errors",
    "sklearn_radar.evaluation.filter_grid",
    "sklearn_radar.evaluation.filter_removal_rates",
    "sklearn_radar.evaluation.filter_settings_table",
    "sklearn_radar.evaluation.plot_filter_errors",
    "sklearn_radar.experiments.derived_params",
    "sklearn_radar.experiments.baseline_pipeline",
    "sklearn_radar.experiments.experiment_pipeline",
    "sklearn_radar.experiments.get_experiment",
    "sklearn_radar.experiments.paper_experiments",
    "sklearn_radar.experiments.paper_params",
    "sklearn_radar.experiments.search_space",
    "sklearn_radar.experiments.object_pipeline",
    "sklearn_radar.experiments.object_search_space",
    "sklearn_radar.metrics.background_share",
    "sklearn_radar.metrics.class_errors",
    "sklearn_radar.metrics.class_panoptic_quality",
    "sklearn_radar.metrics.hota_scores",
    "sklearn_radar.metrics.instance_coverage",
    "sklearn_radar.metrics.instance_errors",
    "sklearn_radar.metrics.instance_scores",
    "sklearn_radar.metrics.make_instance_scorer",
    "sklearn_radar.metrics.make_semantic_scorer",
    "sklearn_radar.metrics.mean_average_precision",
    "sklearn_radar.metrics.panoptic_quality",
    "sklearn_radar.metrics.panoptic_quality_scorer",
    "sklearn_radar.metrics.pointwise_macro_f1",
    "sklearn_radar.metrics.precluster_target",
    "sklearn_radar.metrics.radar_homogeneity_completeness_v_measure",
    "sklearn_radar.metrics.radar_v_measure",
    "sklearn_radar.metrics.radar_v_measure_scorer",
    "sklearn_radar.metrics.semantic_scores",
    "sklearn_radar.metrics.tracking_scores",
    "sklearn_radar.model_selection.make_bayes_search",
    "sklearn_radar.model_selection.sequence_train_test_split",
    "sklearn_radar.online.iter_scans",
    "sklearn_radar.preprocessing.doppler_density_keep",
    "sklearn_radar.preprocessing.neighbor_counts",
    "sklearn_radar.reproduce.cluster_radarscenes",
    "sklearn_radar.reproduce.load_params",
    "sklearn_radar.reproduce.parse_experiments",
    "sklearn_radar.reproduce.reproduce",
    "sklearn_radar.reproduce.write_predictions",
]

#: Public functions whose validation lands with the rework of ``sklearn_radar.reproduce``;
#: they move into PARAM_VALIDATION_FUNCTION_LIST then.


def _public_functions():
    """Dotted names of the functions in the ``__all__`` of every package, under the package that exports them."""
    names = set()
    for package in PACKAGES:
        module = import_module(package)
        for name in module.__all__:
            if inspect.isfunction(getattr(module, name)):
                names.add(f"{package}.{name}")
    return names


def test_every_public_function_is_listed():
    listed = PARAM_VALIDATION_FUNCTION_LIST
    assert len(set(listed)) == len(listed), "a function is listed twice"
    assert set(listed) == _public_functions()


def _get_func_info(func_module):
    module_name, func_name = func_module.rsplit(".", 1)
    module = import_module(module_name)
    func = getattr(module, func_name)

    func_sig = signature(func)
    func_params = [p.name for p in func_sig.parameters.values() if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]

    # The parameters `*args` and `**kwargs` are ignored since we cannot generate constraints.
    required_params = [
        p.name
        for p in func_sig.parameters.values()
        if p.default is p.empty and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)
    ]
    return func, func_name, func_params, required_params


def _check_function_param_validation(func, func_name, func_params, required_params, parameter_constraints):
    """An informative error for a value of no valid type, and for an invalid value of a valid type."""
    # Valid values for the required parameters.
    valid_required_params = {}
    for param_name in required_params:
        if parameter_constraints[param_name] == "no_validation":
            valid_required_params[param_name] = 1
        else:
            valid_required_params[param_name] = generate_valid_param(
                make_constraint(parameter_constraints[param_name][0])
            )

    # One constraint per parameter, and none for a parameter the function does not have.
    validation_params = parameter_constraints.keys()
    unexpected_params = set(validation_params) - set(func_params)
    missing_params = set(func_params) - set(validation_params)
    assert set(validation_params) == set(func_params), (
        f"Mismatch between the parameter constraints and the parameters of {func_name}.\n"
        f"Unexpected parameters {unexpected_params}, expected but missing parameters {missing_params}."
    )

    # An object of a type no constraint accepts.
    param_with_bad_type = type("BadType", (), {})()

    for param_name in func_params:
        constraints = parameter_constraints[param_name]
        if constraints == "no_validation":
            continue

        # An interval of reals and one of integers cannot be mixed (use RealNotInt instead of Real).
        assert not (
            any(isinstance(c, Interval) and c.type == Integral for c in constraints)
            and any(isinstance(c, Interval) and c.type == Real for c in constraints)
        ), f"{func_name}: the constraints of {param_name} mix Integral and Real intervals"

        match = rf"The '{param_name}' parameter of {func_name} must be .* Got .* instead."

        # First: a value of no valid type.
        with pytest.raises(InvalidParameterError, match=match):
            func(**{**valid_required_params, param_name: param_with_bad_type})

        # Then: for constraints on more than the type, a value of a valid type outside every valid value.
        # The constraints must be disjoint (not e.g. [StrOptions({"a"}), str]) for this to raise.
        for constraint in (make_constraint(c) for c in constraints):
            try:
                bad_value = generate_invalid_param_val(constraint)
            except NotImplementedError:
                continue
            with pytest.raises(InvalidParameterError, match=match):
                func(**{**valid_required_params, param_name: bad_value})


@pytest.mark.parametrize("func_module", PARAM_VALIDATION_FUNCTION_LIST)
def test_function_param_validation(func_module):
    func, func_name, func_params, required_params = _get_func_info(func_module)
    assert hasattr(func, "__wrapped__"), f"{func_module} is not decorated with validate_params"
    parameter_constraints = getattr(func, "_skl_parameter_constraints", None)
    assert parameter_constraints is not None, f"{func_module} has no validate_params constraints"
    _check_function_param_validation(func, func_name, func_params, required_params, parameter_constraints)
