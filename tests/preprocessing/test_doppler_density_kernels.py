"""Eq. 1 written once: the online filter's compiled loop decides as doppler_density_keep, thresholds included."""

import numba
import numpy as np
import pandas as pd
import pytest

from sklearn_radar import DopplerDensityFilter
from sklearn_radar.online import _filter
from sklearn_radar.preprocessing import _doppler_density_filter, doppler_density_keep
from sklearn_radar.preprocessing._doppler_density_kernels import (
    _removed_by_eq1,
    keep_new,
    removed_by_eq1,
    speed_limits,
)

RULE = {"vr_threshold": 0.3, "threshold_ratios": (1, 3, 7), "min_neighbors": (2, 4, 6)}


def _boundary_speeds(rng, n):
    """Speeds at, just below and just above each threshold 0.3 / ratio, and random ones, either sign."""
    limits = 0.3 / np.array([1.0, 3.0, 7.0])
    speeds = np.r_[limits, np.nextafter(limits, 0), np.nextafter(limits, 1), rng.uniform(0, 1, 20)]
    return rng.choice(speeds, n) * rng.choice([-1.0, 1.0], n)


@pytest.mark.parametrize("seed", range(5))
def test_the_compiled_loop_is_doppler_density_keep(seed):
    rng = np.random.default_rng(seed)
    n_old, n_new = 200, 60
    x, y = rng.uniform(0, 15, n_old + n_new), rng.uniform(0, 15, n_old + n_new)  # about 3 neighbours each
    t = np.r_[np.sort(rng.uniform(0, 0.2, n_old)), np.full(n_new, 0.2)]
    v_r = _boundary_speeds(rng, n_new)
    limits = speed_limits(RULE["vr_threshold"], np.array(RULE["threshold_ratios"], dtype=float))
    keep = keep_new(x, y, t, v_r, n_old, 1.0, 0.25, limits, np.array(RULE["min_neighbors"], dtype=np.int64))
    # The reference: the counts by brute force, the rule by the public function.
    d2 = (x[n_old:, None] - x[None, :]) ** 2 + (y[n_old:, None] - y[None, :]) ** 2
    counts = (d2 <= 1.0).sum(axis=1) - 1
    np.testing.assert_array_equal(keep, doppler_density_keep(v_r, counts, **RULE))
    assert 0 < keep.sum() < n_new  # both decisions occur


def test_the_rule_compiled_and_on_numpy_arrays_decide_alike():
    rng = np.random.default_rng(0)
    speed = np.abs(_boundary_speeds(rng, 500))
    counts = rng.integers(0, 8, 500)
    limits = speed_limits(RULE["vr_threshold"], RULE["threshold_ratios"])
    min_neighbors = np.array(RULE["min_neighbors"], dtype=np.int64)
    compiled = [_removed_by_eq1(s, n, limits, min_neighbors) for s, n in zip(speed, counts, strict=True)]
    np.testing.assert_array_equal(compiled, removed_by_eq1(speed, counts, limits, min_neighbors))
    assert _removed_by_eq1.py_func is removed_by_eq1  # one source


def test_the_online_filter_module_compiles_no_rule_of_its_own():
    defined = [
        name
        for name, value in vars(_filter).items()
        if isinstance(value, numba.core.dispatcher.Dispatcher) and value.py_func.__module__ == _filter.__name__
    ]
    assert defined == []


def test_the_batch_filter_decides_by_the_shared_rule(monkeypatch):
    calls = []

    def spy(speed, n_neighbors, limits, min_neighbors):
        calls.append(limits)
        return removed_by_eq1(speed, n_neighbors, limits, min_neighbors)

    monkeypatch.setattr(_doppler_density_filter, "removed_by_eq1", spy)
    X = pd.DataFrame({"x": [0.0, 0.5, 9.0], "y": 0.0, "v_r": [0.2, 0.5, 0.5], "t": 0.0})
    keep = DopplerDensityFilter(**RULE).fit_transform(X)["keep"]
    assert keep.tolist() == [False, True, False]  # one neighbour: fast enough only at 0.5 m/s; none: removed
    np.testing.assert_array_equal(calls, [speed_limits(0.3, (1, 3, 7))])


def test_a_rule_of_unequal_lengths_is_refused():
    with pytest.raises(ValueError, match="equal length"):
        _doppler_density_filter._doppler_density_keep([0.0], [1], 0.1, np.array([1.0, 5.0]), np.array([2]))
