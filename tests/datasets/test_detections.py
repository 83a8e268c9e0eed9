"""Tests of the simulator's true detections: wheel reflections and angle glint."""

import numpy as np
import pytest

from sklearn_radar.datasets._detections import WHEEL_RADIUS, _glint, _wheel_reflections
from sklearn_radar.datasets._scenario import RoadUser

from .test_radarscenes_preset import _straight_road


class _Car:
    kind, length, width = "car", 4.5, 1.8


def _broadside_car(n, sin_aspect, share=1.0):
    """A car at the origin heading along x at 10 m/s, no yaw; ``n`` detections at its centre, all in scan 0."""
    motion = (np.zeros(1), np.zeros(1), np.full(1, 10.0), np.zeros(1), np.zeros(1), np.zeros(1))
    points = (np.zeros(n), np.zeros(n), np.full(n, 10.0), np.zeros(n))
    knobs = {"wheel_micro_doppler": share}
    return _wheel_reflections(
        _Car, np.zeros(n, int), motion, points, np.full(n, sin_aspect), knobs, np.random.default_rng(0)
    )


def test_wheel_points_move_between_zero_and_twice_the_car_speed():
    n = 20_000
    x, y, vx, vy = _broadside_car(n, sin_aspect=1.0)
    assert vx.min() >= 0.0 and vx.max() <= 20.0 and np.all(vy == 0.0)
    # Rim point at angle phi: 1 + sin(phi); uniform phi gives mean v and half the points above it.
    assert np.mean(vx) == pytest.approx(10.0, abs=0.15)
    assert np.mean(vx > 10.0) == pytest.approx(0.5, abs=0.02)
    assert np.mean(vx > 19.0) == pytest.approx(np.arccos(0.9) / np.pi, abs=0.02)  # sin(phi) > 0.9
    # On the visible (left, +y) side, within a wheel radius of the axles at +-0.6 of the half-length.
    np.testing.assert_array_equal(y, 0.9)
    assert np.all(np.abs(np.abs(x) - 0.6 * 2.25) <= WHEEL_RADIUS + 1e-12)


def test_wheels_are_hidden_head_on_and_a_share_shows_at_an_angle():
    n = 20_000
    _, _, vx, _ = _broadside_car(n, sin_aspect=0.0)
    np.testing.assert_array_equal(vx, 10.0)
    _, _, vx, _ = _broadside_car(n, sin_aspect=-0.5, share=0.4)  # the right side: 0.4 * 0.5 on the wheels
    assert np.mean(vx != 10.0) == pytest.approx(0.2, abs=0.015)


@pytest.mark.parametrize("share", [0.3, 1.0])
def test_glint_moves_a_share_of_the_azimuths_by_half_the_angular_extent(share):
    user = RoadUser(kind="car", length=4.0, width=3.0, road=_straight_road(), s0=0.0, speed=10.0, d0=0.0)
    azimuth, r = np.full(40_000, 0.1), np.full(40_000, 10.0)
    moved = _glint(azimuth, r, user, share, np.random.default_rng(0)) - azimuth
    assert (moved != 0).mean() == pytest.approx(share, abs=0.01)
    # Extent hypot(4, 3) / 10 m = 0.5 rad, so a standard deviation of 0.25 rad: hand-computed.
    assert moved[moved != 0].std() == pytest.approx(0.25, rel=0.03)
    assert abs(moved[moved != 0].mean()) < 0.01
    np.testing.assert_array_equal(azimuth, 0.1)  # the input is left alone
