"""Per-sequence parts of the filter evaluation: combined, they give Tables I and II of the whole data set (issue 14)."""

import pickle

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sklearn_radar import DopplerDensityFilter, FrameTransform
from sklearn_radar.datasets import make_scenes
from sklearn_radar.evaluation import FilterEvaluationOptions, filter_error_windows, filter_grid, filter_settings_table
from sklearn_radar.evaluation._filter_parts import (
    FilterGridPart,
    combine_error_windows,
    combine_filter_grid,
    combine_filter_settings_table,
    filter_error_windows_parts,
    filter_grid_parts,
    filter_settings_table_parts,
)

GRID = {"vr_thresholds": (0.0, 0.1, 0.35), "d_xys": (0.8, 1.4)}


def _options(**options):
    return FilterEvaluationOptions(**GRID | options)


@pytest.fixture(scope="module")
def scenes():
    return make_scenes(n_sequences=3, duration=5.0, random_state=0)


def _variants(scenes):
    """(X, target): as simulated, with sequence 2 without objects, with sequence 3 without background."""
    sequence = scenes.data["sequence"].to_numpy()
    keep = ~((sequence == 3) & (scenes.target == -1))
    return {
        "as simulated": (scenes.data, scenes.target),
        "a sequence without objects": (scenes.data, np.where(sequence == 2, -1, scenes.target)),
        "a sequence without background": (scenes.data[keep], scenes.target[keep]),
    }


def _pieces(X, target, blocks=None):
    """(X, target) of each sequence (or block of sequence numbers)."""
    sequence = X["sequence"].to_numpy()
    blocks = blocks if blocks is not None else [[value] for value in np.unique(sequence)]
    return [(X[np.isin(sequence, block)], target[np.isin(sequence, block)]) for block in blocks]


def _assert_same_grid(whole, combined):
    assert set(combined) == set(whole)
    for name in ("errors", "background_removed", "objects_removed"):
        pd.testing.assert_frame_equal(combined[name], whole[name], check_exact=True)
    assert combined.errors.dtypes.eq(np.int64).all()
    for name in ("frame", "n_background", "n_objects"):
        assert combined[name] == whole[name] and type(combined[name]) is type(whole[name]), name
    assert combined.elapsed_s > 0


@pytest.mark.parametrize("variant", ["as simulated", "a sequence without objects", "a sequence without background"])
@pytest.mark.parametrize("frame", ["frame", "car"])
def test_grid_parts_combine_to_the_whole_grid(scenes, variant, frame):
    X, target = _variants(scenes)[variant]
    whole = filter_grid(X, target, _options(frame=frame))
    parts = [filter_grid_parts(Xs, ts, _options(frame=frame)) for Xs, ts in _pieces(X, target)]
    _assert_same_grid(whole, combine_filter_grid(parts[::-1]))
    assert whole.errors.to_numpy().sum() > 0 or variant != "as simulated"  # the comparison covers errors


def test_grid_parts_with_the_default_grid_and_blocks(scenes):
    whole = filter_grid(scenes.data, scenes.target)
    parts = [
        filter_grid_parts(X, t, FilterEvaluationOptions(n_jobs=2))
        for X, t in _pieces(scenes.data, scenes.target, [[2], [1, 3]])
    ]
    _assert_same_grid(whole, combine_filter_grid(parts))


def test_parts_need_the_same_options_but_not_the_same_parallelism(scenes):
    pieces = _pieces(scenes.data, scenes.target)
    parts = [filter_grid_parts(X, t, _options(n_jobs=k + 1, verbose=k)) for k, (X, t) in enumerate(pieces)]
    _assert_same_grid(filter_grid(scenes.data, scenes.target, _options()), combine_filter_grid(parts))
    with pytest.raises(ValueError, match="different options"):
        combine_filter_grid([parts[0], filter_grid_parts(*pieces[1], _options(min_kept=0.5))])


@pytest.mark.parametrize("variant", ["as simulated", "a sequence without objects", "a sequence without background"])
def test_settings_parts_combine_to_the_whole_table(scenes, variant):
    X, target = _variants(scenes)[variant]
    whole = filter_settings_table(X, target)
    parts = [filter_settings_table_parts(Xs, ts) for Xs, ts in _pieces(X, target)]
    pd.testing.assert_frame_equal(combine_filter_settings_table(parts), whole, check_exact=True)


def test_settings_parts_with_custom_settings(scenes):
    settings = pd.DataFrame({"vr_threshold": [0.2, 0.05, 0.2], "d_xy": [1.0, 1.0, 1.8], "note": ["a", "b", "c"]})
    options = FilterEvaluationOptions(frame="car", min_kept=0.5)
    whole = filter_settings_table(scenes.data, scenes.target, settings, options)
    parts = [filter_settings_table_parts(X, t, settings, options) for X, t in _pieces(scenes.data, scenes.target)]
    pd.testing.assert_frame_equal(combine_filter_settings_table(parts), whole, check_exact=True)


def _keep(X):
    prepared = DopplerDensityFilter(vr_threshold=0.10, d_xy=1.4).fit_transform(FrameTransform().fit_transform(X))
    return prepared["keep"].to_numpy(dtype=bool), prepared["t"].to_numpy()


@pytest.mark.parametrize("variant", ["as simulated", "a sequence without objects", "a sequence without background"])
def test_error_windows_parts_combine_to_the_whole_table(scenes, variant):
    X, target = _variants(scenes)[variant]
    keep, t = _keep(X)
    whole = filter_error_windows(keep, target, t)
    parts = []
    for Xs, ts in _pieces(X, target):
        keep_s, t_s = _keep(Xs)  # the filter of one sequence keeps what it keeps in the whole table
        parts.append(filter_error_windows_parts(keep_s, ts, t_s))
    combined = combine_error_windows(parts[::-1])
    pd.testing.assert_frame_equal(combined, whole, check_exact=True)
    assert whole["error"].any()
    # Plain concatenation in sequence order gives the same rows here (ids grow with the sequence) ...
    in_order = pd.concat([part.windows for part in parts], ignore_index=True)
    pd.testing.assert_frame_equal(in_order, whole, check_exact=True)
    # ... but not in another order: the combination sorts by object.
    assert not pd.concat([part.windows for part in parts[::-1]], ignore_index=True).equals(whole)


@st.composite
def _window_cases(draw):
    """Random detections of 1-3 sequences, object ids unique across sequences, in any id order."""
    n = draw(st.integers(1, 60))
    sequence = np.array(draw(st.lists(st.integers(0, 2), min_size=n, max_size=n)))
    local = np.array(draw(st.lists(st.integers(-1, 3), min_size=n, max_size=n)))
    t = np.array(draw(st.lists(st.integers(0, 40).map(lambda k: 0.025 * k), min_size=n, max_size=n)))
    keep = np.array(draw(st.lists(st.booleans(), min_size=n, max_size=n)))
    shift = draw(st.permutations([0, 1, 2]))  # object ids of later sequences may be smaller
    target = np.where(local < 0, -1, 10 * np.array(shift)[sequence] + local)
    return keep, target, t + 1000.0 * sequence, sequence


@settings(max_examples=150, deadline=None)
@given(_window_cases(), st.sampled_from([0.05, 0.15]), st.sampled_from([0.5, 0.75]))
def test_error_windows_parts_on_random_data(case, window, min_kept):
    keep, target, t, sequence = case
    whole = filter_error_windows(keep, target, t, window, min_kept)
    parts = [
        filter_error_windows_parts(keep[sequence == s], target[sequence == s], t[sequence == s], window, min_kept)
        for s in np.unique(sequence)
    ]
    pd.testing.assert_frame_equal(combine_error_windows(parts), whole, check_exact=True)


def test_time_tolerance_must_be_the_whole_data_sets():
    # One object in a sequence at about 3e6 s (the tolerance grows to 8 float64 spacings, 3.7 ns), one at 1000 s
    # (1 ns).  A detection 2 ns before the end of the second object's first window moves to the next window under
    # the whole data set's tolerance.
    window = 0.15
    t = np.array([3e6, 3e6 + 0.3, 1000.0, 1000.0 + window - 2e-9, 1000.0 + 2 * window])
    target = np.array([0, 0, 1, 1, 1])
    keep = np.array([True, True, True, False, True])
    whole = filter_error_windows(keep, target, t, window)
    default = [filter_error_windows_parts(keep[rows], target[rows], t[rows], window) for rows in ([0, 1], [2, 3, 4])]
    naive = pd.concat([part.windows for part in default], ignore_index=True)
    assert not naive.equals(whole)  # the per-sequence default tolerance really differs here
    with pytest.raises(ValueError, match=r"time_eps=3\.7"):
        combine_error_windows(default)
    needed = default[0].time_eps
    parts = [
        filter_error_windows_parts(keep[rows], target[rows], t[rows], window, time_eps=needed)
        for rows in ([0, 1], [2, 3, 4])
    ]
    pd.testing.assert_frame_equal(combine_error_windows(parts), whole, check_exact=True)


def test_parts_are_small_and_picklable(scenes):
    part = filter_grid_parts(scenes.data, scenes.target, _options())
    again = pickle.loads(pickle.dumps(part))
    assert isinstance(again, FilterGridPart)
    _assert_same_grid(combine_filter_grid([part]), combine_filter_grid([again]))
    assert len(pickle.dumps(part)) < 5_000  # counts per cell, not per detection


def test_bad_parts(scenes):
    pieces = _pieces(scenes.data, scenes.target)
    grid = [filter_grid_parts(X, t, _options()) for X, t in pieces]
    table = [filter_settings_table_parts(X, t) for X, t in pieces]
    for combine in (combine_filter_grid, combine_filter_settings_table, combine_error_windows):
        with pytest.raises(ValueError, match="parts must not be empty"):
            combine([])
    with pytest.raises(ValueError, match="filter_grid_parts"):
        combine_filter_grid([grid[0], table[1]])
    with pytest.raises(ValueError, match=r"sequence\(s\) \[1\.0\]"):
        combine_filter_grid([grid[0], grid[0]])
    with pytest.raises(ValueError, match="different options"):
        combine_filter_grid([grid[0], filter_grid_parts(*pieces[1], _options(frame="car"))])
    with pytest.raises(ValueError, match="different options"):
        combine_filter_grid([grid[0], filter_grid_parts(*pieces[1], _options(vr_thresholds=(0.1,), d_xys=(1.4,)))])
    with pytest.raises(ValueError, match="different settings"):
        settings = pd.DataFrame({"vr_threshold": [0.1], "d_xy": [1.4]})
        combine_filter_settings_table([table[0], filter_settings_table_parts(*pieces[1], settings)])
    without = [filter_grid_parts(X.drop(columns="sequence"), t, _options()) for X, t in pieces[:2]]
    with pytest.raises(ValueError, match="no column 'sequence'"):
        combine_filter_grid(without)
    windows = [filter_error_windows_parts([True, True], [4, 4], [0.0, 0.2]) for _ in range(2)]
    with pytest.raises(ValueError, match=r"object id\(s\) \[4\]"):
        combine_error_windows(windows)
    with pytest.raises(ValueError, match="time_eps"):
        filter_grid_parts(*pieces[0], time_eps=0.0)


@pytest.fixture(scope="module")
def small():
    return make_scenes(n_sequences=4, duration=1.0, random_state=5)


@settings(max_examples=20, deadline=None)
@given(
    st.lists(st.integers(0, 2), min_size=4, max_size=4),
    st.lists(st.booleans(), min_size=4, max_size=4),
    st.sampled_from(["frame", "car"]),
    st.booleans(),
)
def test_grid_and_settings_parts_on_random_blocks(small, blocks, wiped, frame, causal):
    """Any grouping of whole sequences into parts, some sequences without objects, either frame, causal or not."""
    X = small.data
    sequence = X["sequence"].to_numpy()
    target = np.where(np.isin(sequence, [s + 1 for s in range(4) if wiped[s]]), -1, small.target)
    grouping = [[s + 1 for s in range(4) if blocks[s] == b] for b in range(3)]
    pieces = _pieces(X, target, [block for block in grouping if block])
    options = _options(frame=frame, causal=causal, dt=0.1)
    whole = filter_grid(X, target, options)
    _assert_same_grid(whole, combine_filter_grid([filter_grid_parts(Xs, ts, options) for Xs, ts in pieces]))
    table = filter_settings_table(X, target, options=options)
    parts = [filter_settings_table_parts(Xs, ts, options=options) for Xs, ts in pieces]
    pd.testing.assert_frame_equal(combine_filter_settings_table(parts), table, check_exact=True)
