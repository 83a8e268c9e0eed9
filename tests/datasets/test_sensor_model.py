"""Tests of the simulator's sensor model: the noise of the measured azimuth."""

import numpy as np
import pandas as pd
import pytest

from sklearn_radar.datasets._sensor_model import AZIMUTH_NOISE_GROWTH, _measure


def _azimuth_errors(rng, r, azimuth, n=4000, **kwargs):
    """Measured minus true azimuth (rad) of ``n`` detections at range ``r`` (m) and ``azimuth`` of sensor 3."""
    scans = {"timestamp": np.array([0]), "sensor_id": np.array([3]), "odometry_index": np.array([0])}
    odometry = pd.DataFrame(
        {"timestamp": [0], "x_seq": [0.0], "y_seq": [0.0], "yaw_seq": [0.0], "vx": [0.0], "yaw_rate": [0.0]}
    )
    truth = {
        "scan": np.zeros(n, int),
        "range": np.full(n, r),
        "azimuth": np.full(n, azimuth),
        "vr": np.zeros(n),
        "rcs": np.zeros(n),
    }
    measured = _measure(truth, scans, odometry, rng, **kwargs)
    return measured["azimuth_sc"].astype(float) - azimuth


def test_azimuth_noise_grows_towards_the_edge_of_the_field_of_view():
    rng = np.random.default_rng(0)
    boresight, edge = (np.std(_azimuth_errors(rng, 20.0, azimuth)) for azimuth in (0.0, np.deg2rad(55.0)))
    assert np.deg2rad(0.1) < boresight < np.deg2rad(0.5)
    assert edge > 2.5 * boresight


def test_angular_noise_grows_with_range_up_to_a_bound():
    rng = np.random.default_rng(0)
    spread = [np.std(_azimuth_errors(rng, r, 0.0, angular_noise_range=40.0)) for r in (20.0, 40.0, 60.0, 95.0)]
    assert spread[0] == pytest.approx(spread[1], rel=0.1)
    assert spread[2] == pytest.approx(spread[0] * (60 / 40) ** 2, rel=0.1)
    assert spread[3] == pytest.approx(spread[0] * AZIMUTH_NOISE_GROWTH, rel=0.1)
