"""The compiled velocity fit: kept apart from the public functions, and equal to numpy's least squares."""

import numba
import numpy as np
import pytest

from sklearn_radar.cluster import _velocity
from sklearn_radar.cluster._velocity_kernels import axial_spread, masked_lstsq


def test_the_estimator_module_defines_no_numba_kernel():
    defined = [
        name
        for name, value in vars(_velocity).items()
        if isinstance(value, numba.core.dispatcher.Dispatcher) and value.py_func.__module__ == _velocity.__name__
    ]
    assert defined == []


@pytest.mark.parametrize("seed", range(20))
def test_masked_least_squares_is_numpy_lstsq_on_the_masked_rows(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 30))
    theta = rng.uniform(-np.pi, np.pi, n) * rng.choice([1.0, 1e-4])  # well and badly conditioned
    v_r = rng.normal(0.0, 5.0, n)
    mask = rng.random(n) < 0.7
    mask[:2] = True
    vx, vy = masked_lstsq(np.cos(theta), np.sin(theta), v_r, mask)
    design = np.column_stack((np.cos(theta), np.sin(theta)))[mask]
    expected = np.linalg.lstsq(design, v_r[mask], rcond=None)[0]
    np.testing.assert_allclose([vx, vy], expected, rtol=1e-9, atol=1e-9 * np.abs(v_r).max())


def test_masked_least_squares_of_one_line_of_sight_is_the_minimum_norm_solution():
    theta = np.full(4, 0.3)  # a rank-1 design: lstsq's minimum-norm answer lies along the line of sight
    v_r = np.array([1.0, 1.2, 0.8, 1.0])
    vx, vy = masked_lstsq(np.cos(theta), np.sin(theta), v_r, np.ones(4, dtype=bool))
    expected = np.linalg.lstsq(np.column_stack((np.cos(theta), np.sin(theta))), v_r, rcond=None)[0]
    np.testing.assert_allclose([vx, vy], expected, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize(
    "theta, mask, expected",
    [
        ([0.1, 0.3, 0.2], [True, True, True], 0.2),
        ([np.pi - 0.05, -np.pi + 0.05], [True, True], 0.1),  # across the branch cut at +-pi
        ([0.2, 0.2 + np.pi], [True, True], 0.0),  # opposite directions: one line
        ([0.0, 0.5, 2.0], [True, True, False], 0.5),  # a row outside the mask does not count
    ],
)
def test_axial_spread_is_the_spread_of_the_lines_modulo_pi(theta, mask, expected):
    assert axial_spread(np.array(theta), np.array(mask)) == pytest.approx(expected, abs=1e-12)
