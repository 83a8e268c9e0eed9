"""The input contract of sklearn_radar._schema: named columns, positional arrays and missing columns."""

import numpy as np
import pandas as pd
import pytest

from sklearn_radar import ClusterMerger, DopplerDensityFilter, FrameTransform, RadarDBSCAN, config_context
from sklearn_radar._schema import (
    FILTER_READS,
    FRAME_TRANSFORM_READS,
    MERGER_READS,
    RAW_LAYOUT,
    STAGE1_READS,
    WINDOWED_READS,
    WORK_LAYOUT,
    ColumnsRead,
)
from sklearn_radar._validation import read_columns, write_columns
from sklearn_radar.datasets import make_scenes

ALL_READS = [FRAME_TRANSFORM_READS, FILTER_READS, STAGE1_READS, MERGER_READS, WINDOWED_READS]


@pytest.mark.parametrize("reads", ALL_READS)
def test_every_column_read_has_a_position_in_its_layout(reads):
    positions = [reads.layout.position(name) for name in reads.names]
    assert len(set(positions)) == len(positions)
    assert set(reads.layout.neutral) <= set(reads.layout.columns)


def test_measured_quantities_have_no_neutral_value():
    # A range or an angle made up for a missing column would be a silent wrong answer.
    for name in ("range_sc", "azimuth_sc", "sensor_yaw"):
        assert name not in WORK_LAYOUT.neutral
    assert "range_sc" not in RAW_LAYOUT.neutral


def test_frame_transform_writes_the_working_layout():
    raw = np.c_[[10.0, 20.0], [0.1, -0.2], [1.0, 2.0], [0.0, 60_000.0]]
    Xt = FrameTransform(frame="car").fit_transform(raw)
    assert Xt.shape == (2, len(WORK_LAYOUT.columns))
    np.testing.assert_allclose(Xt[:, WORK_LAYOUT.position("range_sc")], [10.0, 20.0])
    np.testing.assert_allclose(Xt[:, WORK_LAYOUT.position("azimuth_sc")], [0.1, -0.2])
    np.testing.assert_allclose(Xt[:, WORK_LAYOUT.position("t")], [0.0, 0.06])
    np.testing.assert_allclose(Xt[:, WORK_LAYOUT.position("keep")], [1.0, 1.0])


def test_range_adaptive_min_points_on_an_array_without_range_is_refused():
    X = np.c_[[0.0, 0.5, 1.0], [0.0, 0.0, 0.0], [5.0, 5.0, 5.0], [0.0, 0.0, 0.0]]
    with pytest.raises(ValueError, match="range_sc"):
        RadarDBSCAN(alpha_r=0.5).fit(X)
    RadarDBSCAN(alpha_r=0.0).fit(X)  # alpha_r = 0 does not need it


def test_velocity_merging_on_an_array_without_line_of_sight_is_refused():
    X = np.c_[[0.0, 0.5, 1.0], [0.0, 0.0, 0.0], [5.0, 5.0, 5.0], [0.0, 0.0, 0.0]]
    with pytest.raises(ValueError, match="azimuth_sc"):
        ClusterMerger(mode="velocity").fit(X)
    ClusterMerger(mode="continuation").fit(X)


def test_a_required_column_without_neutral_value_is_named():
    reads = ColumnsRead(required=("x", "range_sc"), optional=(), layout=WORK_LAYOUT)
    with pytest.raises(ValueError, match=r"'range_sc' \(position 6\) is required"):
        read_columns(DopplerDensityFilter(), np.zeros((3, 4)), reads, reset=True)
    _, columns = read_columns(DopplerDensityFilter(), np.ones((3, 7)), reads, reset=True)
    np.testing.assert_array_equal(columns["range_sc"], [1.0, 1.0, 1.0])


def test_widening_an_array_over_a_column_without_neutral_value_is_refused():
    with pytest.raises(ValueError, match="range_sc"):
        write_columns(np.zeros((2, 4)), {"heading": np.zeros(2)})
    widened = write_columns(np.zeros((2, 4)), {"keep": np.array([0.0, 1.0])})
    np.testing.assert_array_equal(widened[:, 4:], [[0.0, 0.0], [0.0, 1.0]])  # sequence 0, then keep


def test_an_array_pipeline_equals_the_dataframe_pipeline_in_both_merging_modes():
    data = make_scenes(n_sequences=2, duration=4.0, random_state=3).data
    raw = data[list(RAW_LAYOUT.columns)].to_numpy(dtype=np.float64)
    stage1 = RadarDBSCAN(metric="xyv", eps_xyv=1.2, min_samples=3, alpha_r=0.5, vr_min=0.5)
    for mode in ("velocity", "continuation"):
        merger = ClusterMerger(stage1=stage1, mode=mode, unknown_velocity="accept")
        from_frame = merger.fit(
            DopplerDensityFilter().fit_transform(FrameTransform().fit_transform(data))
        ).labels_.copy()
        from_array = merger.fit(DopplerDensityFilter().fit_transform(FrameTransform().fit_transform(raw))).labels_
        assert from_frame.max() > 3
        np.testing.assert_array_equal(from_array, from_frame)


def test_a_dataframe_without_a_required_column_is_named():
    X = pd.DataFrame({"x": [0.0], "y": [0.0], "v_r": [1.0]})
    with pytest.raises(ValueError, match="'t'"):
        RadarDBSCAN().fit(X)


def test_a_raw_value_that_makes_a_working_column_overflow_is_named():
    raw = np.c_[[10.0, 10.0], [0.1, 0.1], [1.0, 1.0], [0.0, 0.0], [3.6, 3.6], [0.7, 0.7], [0.0, 0.0]]
    raw = np.c_[raw, np.zeros((2, 4)), [0.1, 1.7e308]]  # ego_yaw_rate: 1.7e308 rad/s times sensor_x overflows v_r
    with pytest.raises(ValueError, match=r"column 'ego_yaw_rate' holds 1.7e\+308 rad/s \(row 1\), above the plausible"):
        FrameTransform().fit_transform(raw)
    with config_context(check_plausibility=False):  # what is left when the data is declared right
        with pytest.raises(ValueError, match=r"column 'ego_yaw_rate' holds 1.7e\+308 at row 1.*'v_r' overflow"):
            FrameTransform().fit_transform(raw)


class _OtherFrame:
    """A table that is not pandas (as a polars DataFrame): named columns, convertible to an array by position."""

    def __init__(self, frame):
        self.frame = frame
        self.columns = list(frame.columns)

    def to_pandas(self):
        return self.frame

    def __array__(self, dtype=None, copy=None):
        return self.frame.to_numpy(dtype=dtype)


@pytest.mark.parametrize("estimator", [DopplerDensityFilter(), RadarDBSCAN()], ids=lambda e: type(e).__name__)
def test_a_table_other_than_pandas_is_refused_rather_than_read_by_position(estimator):
    # Its columns hold the working layout in another order: read by position, y would be taken for x.
    rng = np.random.default_rng(0)
    frame = pd.DataFrame({"t": np.repeat(np.arange(20) * 0.06, 5), "y": rng.normal(size=100)})
    frame["x"] = rng.normal(size=100)
    frame["v_r"] = 1.0
    with pytest.raises(ValueError, match=r"_OtherFrame, whose columns would be read by position.*to_pandas"):
        estimator.fit(_OtherFrame(frame))
    estimator.fit(_OtherFrame(frame).to_pandas())  # the same table as pandas is read by name
