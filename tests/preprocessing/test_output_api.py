"""The output API of the stage-0 transformers: set_output, get_feature_names_out, Pipeline, ColumnTransformer.

The behaviour table (input container x set_output setting -> output):

================  ==========================  ==============================================
input             set_output                  transform returns
================  ==========================  ==============================================
DataFrame         unset or "default"          DataFrame: input columns + added ones, input index
DataFrame         "pandas"                    the same DataFrame (columns = get_feature_names_out())
array             unset or "default"          ndarray in the working layout
array             "pandas"                    DataFrame of that array, get_feature_names_out() columns,
                                              RangeIndex
either            "polars"                    polars DataFrame; without polars, scikit-learn's ImportError
================  ==========================  ==============================================
"""

import importlib.util

import numpy as np
import pandas as pd
import pytest
from sklearn import clone, config_context
from sklearn.compose import ColumnTransformer
from sklearn.exceptions import NotFittedError
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.utils.estimator_checks import (
    check_get_feature_names_out_error,
    check_global_output_transform_pandas,
    check_set_output_transform,
    check_set_output_transform_pandas,
    check_transformer_get_feature_names_out,
    check_transformer_get_feature_names_out_pandas,
)

import sklearn_radar
from sklearn_radar import ClusterMerger, DopplerDensityFilter, FrameTransform, RadarDBSCAN
from sklearn_radar._schema import RAW_LAYOUT, WORK_LAYOUT
from sklearn_radar.cluster import SequenceDBSCAN, WindowedDBSCAN
from sklearn_radar.datasets import make_scenes

#: A stage-1 setting that finds clusters in a few seconds of simulated detections.
STAGE1 = dict(metric="xyv", eps_xyv=1.2, min_samples=3, vr_min=0.5)


@pytest.fixture(scope="module")
def raw_frame():
    """Raw detections as the detection table, under a shuffled, non-default index (a CV split's rows)."""
    data = make_scenes(n_sequences=2, duration=3.0, random_state=5).data
    order = np.random.default_rng(0).permutation(len(data))
    return data.iloc[order].set_axis([f"det{i}" for i in order])


@pytest.fixture(scope="module")
def raw_array(raw_frame):
    """The same detections as a plain array in the order of RAW_LAYOUT."""
    return raw_frame[list(RAW_LAYOUT.columns)].to_numpy(dtype=np.float64)


@pytest.fixture(scope="module")
def work_frame(raw_frame):
    return FrameTransform().fit_transform(raw_frame)


def _transformer_and_input(kind, raw_frame, raw_array, work_frame):
    """(transformer, its DataFrame input, its array input) for the stage named ``kind``."""
    if kind == "FrameTransform":
        return FrameTransform(), raw_frame, raw_array
    return DopplerDensityFilter(), work_frame, FrameTransform().fit_transform(raw_array)


STAGES = ["FrameTransform", "DopplerDensityFilter"]


# --- set_output exists and follows the behaviour table ---------------------------------------------------------


@pytest.mark.parametrize("transformer", [FrameTransform(), DopplerDensityFilter()], ids=repr)
def test_set_output_is_available_and_returns_the_transformer(transformer):
    # Before get_feature_names_out existed, scikit-learn's available_if hid set_output: AttributeError.
    assert transformer.set_output(transform="pandas") is transformer
    assert transformer.set_output(transform="default") is transformer


@pytest.mark.parametrize("kind", STAGES)
@pytest.mark.parametrize("setting", [None, "default", "pandas"])
def test_a_dataframe_comes_back_as_a_dataframe_under_every_setting(kind, setting, raw_frame, raw_array, work_frame):
    transformer, frame, _ = _transformer_and_input(kind, raw_frame, raw_array, work_frame)
    out = transformer.set_output(transform=setting).fit_transform(frame)
    assert isinstance(out, pd.DataFrame)
    assert out.columns.tolist() == transformer.get_feature_names_out().tolist()
    assert out.index.equals(frame.index)  # same rows, same order, same labels
    pd.testing.assert_frame_equal(out[frame.columns], frame)  # the input columns, unchanged and in place


@pytest.mark.parametrize("kind", STAGES)
@pytest.mark.parametrize("setting", [None, "default"])
def test_an_array_comes_back_as_an_array_under_the_default_setting(kind, setting, raw_frame, raw_array, work_frame):
    transformer, _, array = _transformer_and_input(kind, raw_frame, raw_array, work_frame)
    out = transformer.set_output(transform=setting).fit_transform(array)
    assert type(out) is np.ndarray
    assert out.shape == (len(array), len(transformer.get_feature_names_out()))


@pytest.mark.parametrize("kind", STAGES)
def test_an_array_comes_back_as_a_named_dataframe_under_pandas(kind, raw_frame, raw_array, work_frame):
    transformer, _, array = _transformer_and_input(kind, raw_frame, raw_array, work_frame)
    default = transformer.fit_transform(array)
    out = transformer.set_output(transform="pandas").fit_transform(array)
    assert isinstance(out, pd.DataFrame)
    assert out.columns.tolist() == list(WORK_LAYOUT.columns)
    assert out.index.equals(pd.RangeIndex(len(array)))  # an array has no index; rows in input order
    np.testing.assert_array_equal(out.to_numpy(), default)


@pytest.mark.parametrize("kind", STAGES)
def test_the_global_pandas_setting_equals_the_local_one(kind, raw_frame, raw_array, work_frame):
    transformer, _, array = _transformer_and_input(kind, raw_frame, raw_array, work_frame)
    local = transformer.set_output(transform="pandas").fit_transform(array)
    with config_context(transform_output="pandas"):
        from_global = type(transformer)().fit_transform(array)
    pd.testing.assert_frame_equal(from_global, local)


@pytest.mark.parametrize("kind", STAGES)
@pytest.mark.parametrize("use", ["frame", "array"])
def test_pandas_output_equals_the_default_output_put_in_a_dataframe(kind, use, raw_frame, raw_array, work_frame):
    # scikit-learn's check_set_output_transform_pandas on inputs these transformers can read: fit and transform
    # (separately and as fit_transform) with the default and the pandas setting, then compare.
    transformer, frame, array = _transformer_and_input(kind, raw_frame, raw_array, work_frame)
    X = frame if use == "frame" else array
    for method in ("fit.transform", "fit_transform"):
        outputs = {}
        for setting in ("default", "pandas"):
            fitted = type(transformer)().set_output(transform=setting)
            out = fitted.fit(X).transform(X) if method == "fit.transform" else fitted.fit_transform(X)
            outputs[setting] = out, fitted.get_feature_names_out()
        (default, _), (pandas_out, names) = outputs["default"], outputs["pandas"]
        index = frame.index if use == "frame" else None
        pd.testing.assert_frame_equal(pandas_out, pd.DataFrame(default, columns=names, index=index))


@pytest.mark.skipif(importlib.util.find_spec("polars") is not None, reason="polars is installed")
def test_polars_without_polars_raises_scikit_learns_import_error(raw_array):
    transformer = FrameTransform().set_output(transform="polars")
    with pytest.raises(ImportError, match="requires polars to be installed"):
        transformer.fit_transform(raw_array)


@pytest.mark.skipif(importlib.util.find_spec("polars") is None, reason="polars is not installed")
def test_polars_output_is_a_polars_dataframe_with_the_feature_names(raw_array):
    import polars as pl

    transformer = FrameTransform().set_output(transform="polars")
    out = transformer.fit_transform(raw_array)
    assert isinstance(out, pl.DataFrame) and out.columns == list(WORK_LAYOUT.columns)


def test_the_input_dataframe_is_not_renamed_or_modified(raw_frame):
    before = raw_frame.copy()
    FrameTransform().set_output(transform="pandas").fit_transform(raw_frame)
    pd.testing.assert_frame_equal(raw_frame, before)


# --- get_feature_names_out -------------------------------------------------------------------------------------


def test_frame_transform_appends_only_the_working_columns_it_did_not_find(raw_frame):
    # A table that already holds x and t (from an earlier run): they are overwritten in place, not appended.
    X = raw_frame.assign(t=0.0, x=0.0)
    transformer = FrameTransform().fit(X)
    names = transformer.get_feature_names_out().tolist()
    assert names == [*raw_frame.columns, "t", "x", "y", "v_r", "heading"]
    assert transformer.transform(X).columns.tolist() == names


def test_the_filter_appends_keep_unless_present(work_frame):
    assert DopplerDensityFilter().fit(work_frame).get_feature_names_out()[-1] == "keep"
    with_keep = work_frame.assign(keep=True)
    assert DopplerDensityFilter().fit(with_keep).get_feature_names_out().tolist() == with_keep.columns.tolist()


@pytest.mark.parametrize(
    "n_columns, expected",
    [
        (1, list(WORK_LAYOUT.columns[:6])),  # widened to keep, position 5
        (8, list(WORK_LAYOUT.columns[:8])),
        (12, [*WORK_LAYOUT.columns, "x10", "x11"]),  # columns beyond the layout keep their input names
    ],
)
def test_the_filter_names_every_column_of_an_array_result(n_columns, expected):
    X = np.random.default_rng(0).uniform(size=(15, n_columns))
    filter_ = DopplerDensityFilter().fit(X)
    assert filter_.get_feature_names_out().tolist() == expected
    assert filter_.transform(X).shape[1] == len(expected)


def test_explicit_input_features_must_match_those_seen_in_fit(raw_frame, raw_array):
    on_frame = FrameTransform().fit(raw_frame)
    assert on_frame.get_feature_names_out(raw_frame.columns).tolist() == on_frame.get_feature_names_out().tolist()
    with pytest.raises(ValueError, match="input_features is not equal to feature_names_in_"):
        on_frame.get_feature_names_out([f"c{i}" for i in range(raw_frame.shape[1])])
    on_array = FrameTransform().fit(raw_array)
    with pytest.raises(ValueError, match="input_features should have length equal"):
        on_array.get_feature_names_out(["a", "b"])
    # The working layout is what an array result holds, whatever the raw columns are called.
    assert on_array.get_feature_names_out(list(RAW_LAYOUT.columns)).tolist() == list(WORK_LAYOUT.columns)


@pytest.mark.parametrize("transformer", [FrameTransform(), DopplerDensityFilter()], ids=repr)
def test_feature_names_before_fit_raise_not_fitted(transformer):
    with pytest.raises(NotFittedError):
        transformer.get_feature_names_out()


# --- scikit-learn's own checks ---------------------------------------------------------------------------------
# scikit-learn 1.9.1's parametrize_with_checks does not yield the set_output and get_feature_names_out checks (only
# scikit-learn's own test suite runs them), so tests/test_common.py does not see them: they run here.

_NAMED_COLUMNS = (
    "the check's DataFrame has columns col0, col1, ...; these transformers read a DataFrame by column name "
    "(the detection table) and raise a ValueError naming the missing columns, by design (a DataFrame is never "
    "read by position). The same comparison on DataFrames with the right names passes: "
    "test_pandas_output_equals_the_default_output_put_in_a_dataframe."
)
SKLEARN_CHECKS = [
    pytest.param(check_set_output_transform, id="check_set_output_transform"),
    pytest.param(check_transformer_get_feature_names_out, id="check_transformer_get_feature_names_out"),
    pytest.param(check_get_feature_names_out_error, id="check_get_feature_names_out_error"),
    *(
        pytest.param(
            check, id=check.__name__, marks=pytest.mark.xfail(raises=ValueError, strict=True, reason=_NAMED_COLUMNS)
        )
        for check in (
            check_set_output_transform_pandas,
            check_global_output_transform_pandas,
            check_transformer_get_feature_names_out_pandas,
        )
    ),
]


@pytest.mark.parametrize("check", SKLEARN_CHECKS)
@pytest.mark.parametrize(
    "transformer", [FrameTransform(), FrameTransform(frame="car"), DopplerDensityFilter()], ids=repr
)
def test_scikit_learn_output_checks(transformer, check):
    # As the common checks (tests/test_common.py, PLAUSIBILITY_OFF): FrameTransform's random raw columns (negative
    # ranges, azimuths beyond +-pi) are no radar data, so its checks run with the plausibility checks off.
    with sklearn_radar.config_context(check_plausibility=not isinstance(transformer, FrameTransform)):
        check(type(transformer).__name__, transformer)


# --- inside a Pipeline ---------------------------------------------------------------------------------------------


def _stage0_and(last):
    return make_pipeline(FrameTransform(), DopplerDensityFilter(), last)


@pytest.mark.parametrize(
    "last",
    [RadarDBSCAN(**STAGE1), ClusterMerger(stage1=RadarDBSCAN(**STAGE1), unknown_velocity="accept")],
    ids=lambda estimator: type(estimator).__name__,
)
def test_a_pandas_pipeline_labels_as_the_default_one(last, raw_frame, raw_array):
    expected = _stage0_and(last).fit_predict(raw_frame)
    assert expected.max() >= 3  # there are clusters to compare
    pandas_pipeline = _stage0_and(last).set_output(transform="pandas")
    # From an array, the stages after FrameTransform get the working columns as a DataFrame without raw columns.
    np.testing.assert_array_equal(pandas_pipeline.fit_predict(raw_array), expected)
    np.testing.assert_array_equal(pandas_pipeline.fit_predict(raw_frame), expected)


@pytest.mark.parametrize("baseline", [WindowedDBSCAN(), SequenceDBSCAN(vr_min=-np.inf)], ids=repr)
def test_the_baselines_read_the_working_columns_as_a_dataframe(baseline, raw_array):
    stage0 = make_pipeline(FrameTransform(), DopplerDensityFilter())
    as_array = stage0.fit_transform(raw_array)
    as_frame = stage0.set_output(transform="pandas").fit_transform(raw_array)
    assert isinstance(as_frame, pd.DataFrame) and "range_sc" in as_frame and "vr" not in as_frame
    np.testing.assert_array_equal(baseline.fit_predict(as_frame), baseline.fit_predict(as_array))


def test_a_cloned_pipeline_keeps_its_pandas_output(raw_array):
    # Search objects and cross-validation fit clones: the setting must survive clone (scikit-learn copies it).
    pipeline = clone(make_pipeline(FrameTransform(), DopplerDensityFilter()).set_output(transform="pandas"))
    assert isinstance(pipeline.fit_transform(raw_array), pd.DataFrame)


def test_a_pipeline_transforms_to_the_named_working_columns(raw_array):
    pipeline = make_pipeline(FrameTransform(), DopplerDensityFilter()).set_output(transform="pandas")
    out = pipeline.fit_transform(raw_array)
    assert out.columns.tolist() == pipeline.get_feature_names_out().tolist() == list(WORK_LAYOUT.columns)
    assert out["keep"].dtype == bool  # the filter read a DataFrame and wrote a boolean column


# --- inside a ColumnTransformer --------------------------------------------------------------------------------


def _frame_beside_scaled_rcs(verbose_feature_names_out=False):
    return ColumnTransformer(
        [("frame", FrameTransform(), list(RAW_LAYOUT.columns)), ("rcs", StandardScaler(), ["rcs"])],
        verbose_feature_names_out=verbose_feature_names_out,
    )


def test_a_column_transformer_gives_raw_working_and_scaled_columns_under_pandas(raw_frame):
    columns = _frame_beside_scaled_rcs().set_output(transform="pandas")
    out = columns.fit_transform(raw_frame)
    assert out.columns.tolist() == [*RAW_LAYOUT.columns, "x", "y", "v_r", "t", "heading", "rcs"]
    assert out.index.equals(raw_frame.index)
    rcs = raw_frame["rcs"].to_numpy(dtype=np.float64)
    np.testing.assert_allclose(out["rcs"], (rcs - rcs.mean()) / rcs.std(), rtol=1e-5, atol=1e-6)
    np.testing.assert_array_equal(out["x"], FrameTransform().fit_transform(raw_frame)["x"])
    # The later stages read its result by name.
    labels = make_pipeline(columns, DopplerDensityFilter(), RadarDBSCAN(**STAGE1)).fit_predict(raw_frame)
    np.testing.assert_array_equal(labels, _stage0_and(RadarDBSCAN(**STAGE1)).fit_predict(raw_frame))


def test_a_column_transformer_limitations_default_output_and_prefixed_names(raw_frame):
    # Documented limitations (docs/user_guide/data.rst): under "default" the ColumnTransformer stacks its parts
    # into one ndarray whose columns are not in the working layout, and its default verbose names carry prefixes
    # ("frame__x"), which the later stages do not find.
    stacked = _frame_beside_scaled_rcs().fit_transform(raw_frame)
    assert type(stacked) is np.ndarray and stacked.shape[1] == len(RAW_LAYOUT.columns) + 6
    prefixed = _frame_beside_scaled_rcs(verbose_feature_names_out=True).set_output(transform="pandas")
    assert "frame__x" in prefixed.fit_transform(raw_frame)
    with pytest.raises(ValueError, match="missing the column"):
        make_pipeline(prefixed, DopplerDensityFilter()).fit_transform(raw_frame)


def test_fitting_and_transforming_different_containers_never_mislabels_columns(raw_frame, raw_array):
    # Documented: the names describe the container seen in fit.  A different one at transform (scikit-learn warns)
    # gives a result of another width, which the pandas wrapper refuses to rename rather than mislabel.
    fitted_on_frame = FrameTransform().set_output(transform="pandas").fit(raw_frame[list(RAW_LAYOUT.columns)])
    with pytest.warns(UserWarning, match="feature names"), pytest.raises(ValueError):
        fitted_on_frame.transform(raw_array)
    fitted_on_array = FrameTransform().set_output(transform="pandas").fit(raw_array)
    with pytest.warns(UserWarning, match="feature names"), pytest.raises(ValueError):
        fitted_on_array.transform(raw_frame)
