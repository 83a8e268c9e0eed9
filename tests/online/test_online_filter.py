"""The online filter's compiled rule: Eq. 1 exactly as doppler_density_keep decides it, thresholds included."""

import numpy as np
import pytest

from sklearn_radar import DopplerDensityFilter
from sklearn_radar.online._filter import FilterWindow, _keep_new
from sklearn_radar.preprocessing import doppler_density_keep


@pytest.mark.parametrize("seed", range(5))
def test_the_compiled_rule_is_doppler_density_keep(seed):
    rng = np.random.default_rng(seed)
    window = FilterWindow(DopplerDensityFilter(vr_threshold=0.3, threshold_ratios=(1, 3, 7), min_neighbors=(2, 4, 6)))
    n_old, n_new = 200, 60
    x, y = rng.uniform(0, 15, n_old + n_new), rng.uniform(0, 15, n_old + n_new)  # about 3 neighbours each
    t = np.r_[np.sort(rng.uniform(0, 0.2, n_old)), np.full(n_new, 0.2)]
    # Speeds at, just below and just above each threshold 0.3 / ratio, and random ones.
    limits = 0.3 / np.array([1.0, 3.0, 7.0])
    v_r = rng.choice(np.r_[limits, np.nextafter(limits, 0), np.nextafter(limits, 1), rng.uniform(-1, 1, 20)], n_new)
    keep = _keep_new(x, y, t, v_r, n_old, 1.0, 0.25, window.speed_limits, window.min_neighbors)
    # The reference: the counts by brute force, the rule by the public function.
    d2 = (x[n_old:, None] - x[None, :]) ** 2 + (y[n_old:, None] - y[None, :]) ** 2
    counts = (d2 <= 1.0).sum(axis=1) - 1
    expected = doppler_density_keep(v_r, counts, vr_threshold=0.3, threshold_ratios=(1, 3, 7), min_neighbors=(2, 4, 6))
    np.testing.assert_array_equal(keep, expected)
    assert 0 < keep.sum() < n_new  # both decisions occur
