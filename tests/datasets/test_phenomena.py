"""Tests of the background detections of the simulator's realistic phenomena."""

import numpy as np

from sklearn_radar.datasets._phenomena import _second_bounce


def test_second_bounce_ghosts_sit_at_twice_the_range_with_twice_the_radial_velocity():
    objects = {
        "scan": np.array([0, 1, 2]),
        "range": np.array([10.0, 20.0, 60.0]),
        "azimuth": np.array([0.1, -0.2, 0.0]),
        "vr": np.array([3.0, -1.5, 2.0]),
        "rcs": np.array([5.0, 5.0, 5.0]),
    }
    ghost = _second_bounce(objects, 1.0, np.random.default_rng(0))
    assert len(ghost["scan"]) == 2  # 120 m is beyond the sensors' range
    np.testing.assert_allclose(ghost["range"], [20.0, 40.0], atol=0.5)
    np.testing.assert_array_equal(ghost["vr"], [6.0, -3.0])
    np.testing.assert_array_equal(ghost["azimuth"], [0.1, -0.2])
