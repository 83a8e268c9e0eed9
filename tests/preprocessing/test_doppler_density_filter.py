"""DopplerDensityFilter: every branch of Eq. 1 on hand-made cases, the neighbour count against brute force."""

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.pipeline import make_pipeline

from sklearn_radar import DopplerDensityFilter, FrameTransform
from sklearn_radar.datasets import make_scenes
from sklearn_radar.preprocessing import doppler_density_keep, neighbor_counts


@pytest.mark.parametrize(
    "speed, n, kept, branch",
    [
        (9.0, 0, False, "N < 1 removes even a fast detection"),
        (9.0, 1, True, "fast with one neighbour stays"),
        (0.09, 1, False, "|v| < eta_1 = 0.1 and N < 2"),
        (0.09, 2, True, "|v| < eta_1 but N = 2, and |v| >= eta_2 = 0.02"),
        (0.019, 2, False, "|v| < eta_2 = 0.02 and N < 3"),
        (0.019, 3, True, "|v| < eta_2 but N = 3, and |v| >= eta_3 = 0.01"),
        (0.009, 3, False, "|v| < eta_3 = 0.01 and N < 4"),
        (0.009, 4, True, "|v| < eta_3 but N = 4, and |v| >= eta_4 = 0.002"),
        (0.0019, 9, False, "|v| < eta_4 = 0.002 and N < 10"),
        (0.0019, 10, True, "N = 10 keeps even a static detection"),
        (0.1, 1, True, "|v| = eta_1 is not below it (strict)"),
    ],
)
def test_each_branch_of_eq_1_decides_a_row(speed, n, kept, branch):
    for sign in (1.0, -1.0):  # the rule uses |v_r|
        assert doppler_density_keep([sign * speed], [n], vr_threshold=0.1)[0] == kept, branch


def test_ratios_and_neighbour_thresholds_are_configurable():
    keep = doppler_density_keep([0.5, 0.5], [2, 3], vr_threshold=1.0, threshold_ratios=(1,), min_neighbors=(3,))
    assert keep.tolist() == [False, True]


def _frame(points):
    """Detections with working columns: (x, y, v_r, t, sequence) per row."""
    return pd.DataFrame(points, columns=["x", "y", "v_r", "t", "sequence"])


def test_neighbours_are_counted_inclusively_in_space_and_time_and_within_the_sequence():
    X = _frame(
        [
            (0.0, 0.0, 0.0, 0.00, 1),  # the probe, static
            (1.4, 0.0, 0.0, 0.00, 1),  # exactly d_xy away: counts
            (0.0, 0.0, 0.0, 0.25, 1),  # exactly dt later: counts
            (1.5, 0.0, 0.0, 0.00, 1),  # too far
            (0.0, 0.0, 0.0, 0.30, 1),  # too late
            (0.1, 0.0, 0.0, 0.00, 2),  # other sequence
        ]
    )
    counts = neighbor_counts(*(X[c].to_numpy(float) for c in ("x", "y", "t", "sequence")), d_xy=1.4, dt=0.25, cap=100)
    assert counts[0] == 2
    assert counts[5] == 0


def test_causal_mode_ignores_future_neighbours():
    X = _frame([(0.0, 0.0, 0.05, 0.0, 1), (0.5, 0.0, 0.05, 0.1, 1), (0.2, 0.0, 0.05, 0.2, 1)])
    both = DopplerDensityFilter(vr_threshold=0.1).fit_transform(X)["keep"].tolist()
    causal = DopplerDensityFilter(vr_threshold=0.1, causal=True).fit_transform(X)["keep"].tolist()
    # |v| = 0.05 < eta_1 needs N >= 2: with look-ahead all have two neighbours;
    # causally the first has none and the second only one.
    assert both == [True, True, True]
    assert causal == [False, False, True]


def test_transform_marks_rows_and_never_drops_or_reorders():
    scenes = make_scenes(n_sequences=2, duration=5.0, random_state=2)
    X = FrameTransform().fit_transform(scenes.data).iloc[::-1]
    before = X.copy()
    Xt = DopplerDensityFilter().fit_transform(X)
    pd.testing.assert_frame_equal(X, before)
    assert Xt.index.equals(X.index) and Xt["keep"].dtype == bool
    pd.testing.assert_frame_equal(Xt.drop(columns="keep"), X)
    assert 0 < (~Xt["keep"]).sum() < len(Xt)


def test_filter_removes_mostly_background_on_simulated_data():
    scenes = make_scenes(n_sequences=3, duration=20.0, random_state=4)
    keep = make_pipeline(FrameTransform(), DopplerDensityFilter()).fit_transform(scenes.data)["keep"].to_numpy()
    background = scenes.target == -1
    assert (~keep[background]).mean() > 0.15
    assert (~keep[~background]).mean() < 0.02


def test_plain_array_gets_keep_at_position_5():
    X = np.array([[0.0, 0.0], [0.5, 0.0], [10.0, 0.0]])
    Xt = DopplerDensityFilter().fit_transform(X)
    assert Xt.shape == (3, 6)
    np.testing.assert_array_equal(Xt[:, :2], X)
    # v_r = 0 everywhere: the two close points have one neighbour each (< 2) and go, like the isolated one.
    assert Xt[:, 5].tolist() == [0.0, 0.0, 0.0]


def test_n_jobs_gives_the_same_result():
    scenes = make_scenes(n_sequences=3, duration=4.0, random_state=6)
    X = FrameTransform().fit_transform(scenes.data)
    np.testing.assert_array_equal(
        DopplerDensityFilter(n_jobs=2).fit_transform(X)["keep"], DopplerDensityFilter().fit_transform(X)["keep"]
    )


@pytest.mark.parametrize(
    "params, match",
    [
        (dict(threshold_ratios=(1, 5), min_neighbors=(2,)), "equal length"),
        (dict(threshold_ratios=(1, 0), min_neighbors=(2, 3)), "threshold_ratios must be positive"),
        (dict(min_neighbors=(2, 3, 4, 0)), "min_neighbors must be integers >= 1"),
        (dict(d_xy=-1.0), "d_xy"),
        (dict(vr_threshold=-0.1), "vr_threshold"),
    ],
)
def test_bad_parameters_are_named(params, match):
    with pytest.raises(ValueError, match=match):
        DopplerDensityFilter(**params).fit(_frame([(0, 0, 0, 0, 1)]))


def test_missing_working_columns_are_named():
    with pytest.raises(ValueError, match=r"missing the column\(s\) \['x', 'y', 'v_r', 't'\]"):
        DopplerDensityFilter().fit(make_scenes(n_sequences=1, duration=1.0, random_state=0).data)


@settings(max_examples=40, deadline=None)
@given(
    n=st.integers(1, 60),
    seed=st.integers(0, 2**16),
    d_xy=st.floats(0.3, 3.0),
    dt=st.floats(0.0, 0.5),
    causal=st.booleans(),
    cap=st.integers(1, 12),
)
def test_neighbour_count_equals_brute_force(n, seed, d_xy, dt, causal, cap):
    rng = np.random.default_rng(seed)
    x, y = rng.uniform(0, 5, n).round(1), rng.uniform(0, 5, n).round(1)  # rounding makes ties likely
    t = rng.integers(0, 8, n) * 0.0625  # exact binary fractions: window edges are exact
    sequence = rng.integers(0, 2, n)
    squared_distance = (x[:, None] - x[None, :]) ** 2 + (y[:, None] - y[None, :]) ** 2
    lag = t[None, :] - t[:, None]
    in_time = (lag <= (0.0 if causal else dt)) & (lag >= -dt)
    neighbour = (
        (squared_distance <= d_xy**2) & in_time & (sequence[:, None] == sequence[None, :]) & ~np.eye(n, dtype=bool)
    )
    expected = np.minimum(neighbour.sum(axis=1), cap)
    np.testing.assert_array_equal(neighbor_counts(x, y, t, sequence, d_xy, dt, causal=causal, cap=cap), expected)
