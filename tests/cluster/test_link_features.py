"""Features of LinkClustering: pair enumeration, neighbourhoods, the local rigid velocity (Eq. 6), pair symmetry."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from sklearn_radar.cluster._link_features import (
    DETECTION_FEATURES,
    LOCAL_RADIUS,
    LOCAL_WINDOW,
    PAIR_FEATURES,
    RIDGE,
    V_MOVING,
    Detections,
    detection_features,
    pair_features,
    pairs_within,
    usable,
)


def _detections(x, y, t, v, los=None, rcs=None, rng=None):
    n = len(x)
    rng = rng or np.random.default_rng(0)
    return Detections(
        x=np.asarray(x, float),
        y=np.asarray(y, float),
        t=np.asarray(t, float),
        v=np.asarray(v, float),
        los=rng.uniform(-np.pi, np.pi, n) if los is None else np.asarray(los, float),
        rcs=rng.normal(0, 5, n) if rcs is None else np.asarray(rcs, float),
        range=rng.uniform(5, 80, n),
        sensor=rng.integers(1, 5, n).astype(float),
        ego=np.full(n, 8.0),
    )


def _brute_pairs(x, y, t, radius, window, subset):
    return {
        (i, j)
        for i in range(len(x))
        for j in range(i + 1, len(x))
        if subset[i] and subset[j] and np.hypot(x[i] - x[j], y[i] - y[j]) <= radius and abs(t[i] - t[j]) <= window
    }


coordinates = arrays(np.float64, st.integers(0, 40), elements=st.floats(-5, 5).map(lambda v: round(v, 1)))


@settings(max_examples=200, deadline=None)
@given(coordinates, st.data(), st.sampled_from([0.5, 1.0, 3.0]), st.sampled_from([0.0, 0.1, 0.25]))
def test_pairs_are_exactly_those_within_the_radius_and_window(x, data, radius, window):
    n = len(x)
    y = data.draw(arrays(np.float64, n, elements=st.floats(-5, 5).map(lambda v: round(v, 1))))
    t = data.draw(arrays(np.float64, n, elements=st.sampled_from([0.0, 0.05, 0.1, 0.2, 0.25, 0.3, 0.5])))
    subset = data.draw(arrays(np.bool_, n))
    i, j = pairs_within(x, y, t, radius, window, subset)
    assert set(zip(i.tolist(), j.tolist(), strict=True)) == _brute_pairs(x, y, t, radius, window, subset)
    assert np.all(i < j) and len(set(zip(i.tolist(), j.tolist(), strict=True))) == len(i)
    assert list(zip(i, j, strict=True)) == sorted(zip(i, j, strict=True))  # sorted by (i, j)


def test_neighbourhood_counts_worked_by_hand():
    # Four detections on the x axis at x = 0, 1, 2, 3 m; 2 is 0.1 s later than the others.  Within 2.5 m and
    # 0.15 s: every pair but 0-3 (3 m).  Within 1 m and 0.1 s: 0-1, 1-2 and 2-3.  Doppler 5, 5.2, 8, 0 m/s:
    # only 0-1 differ by less than 0.5 m/s, and 3 is static (not moving for the others).
    d = _detections(x=[0, 1, 2, 3], y=[0, 0, 0, 0], t=[0, 0, 0.1, 0], v=[5.0, 5.2, 8.0, 0.0])
    features, local = detection_features(d)
    column = {name: k for k, name in enumerate(DETECTION_FEATURES)}
    assert features[:, column["n_local"]].tolist() == [2, 3, 3, 2]
    assert features[:, column["n_near"]].tolist() == [1, 2, 2, 1]
    assert features[:, column["n_similar"]].tolist() == [1, 1, 0, 0]
    assert features[:, column["n_moving"]].tolist() == [2, 2, 2, 2]
    assert local.count.tolist() == [2, 3, 3, 2]
    np.testing.assert_allclose(local.spread[0], np.std([5.2, 8.0]))


def _ridge_velocity(d, k, src, dst):
    """Eq. 6's velocity of detection k by a direct solve of the ridge normal equations."""
    neighbours = [b for a, b in zip(src, dst, strict=True) if a == k and abs(d.v[b]) > V_MOVING]
    rows = [k, *neighbours]
    u = np.column_stack([np.cos(d.los[rows]), np.sin(d.los[rows])])
    own = np.array([np.cos(d.los[k]), np.sin(d.los[k])])
    system = u.T @ u + RIDGE * np.eye(2)
    right = u.T @ d.v[rows] + RIDGE * d.v[k] * own
    velocity = np.linalg.solve(system, right)
    residual = np.sqrt(np.sum((d.v[rows] - u @ velocity) ** 2) / len(rows))
    return velocity, residual


def test_the_local_velocity_is_the_ridge_least_squares_fit_of_eq_6():
    rng = np.random.default_rng(1)
    n = 60
    x, y = rng.uniform(0, 4, n), rng.uniform(0, 4, n)
    t = rng.choice([0.0, 0.05, 0.1], n)
    los = rng.uniform(-1.5, 1.5, n)
    truth = np.array([6.0, -2.0])
    v = np.cos(los) * truth[0] + np.sin(los) * truth[1] + rng.normal(0, 0.3, n)
    v[:5] = 0.05  # a few static detections: not in the fit of the others
    d = _detections(x, y, t, v, los=los, rng=rng)
    features, local = detection_features(d)
    i, j = pairs_within(d.x, d.y, d.t, LOCAL_RADIUS, LOCAL_WINDOW)
    src, dst = np.r_[i, j], np.r_[j, i]
    column = {name: k for k, name in enumerate(DETECTION_FEATURES)}
    for k in range(n):
        velocity, residual = _ridge_velocity(d, k, src, dst)
        np.testing.assert_allclose([local.vx[k], local.vy[k]], velocity, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(features[k, column["residual"]], residual, rtol=1e-7, atol=1e-9)
    # With many consistent neighbours the fit finds the object's velocity.
    np.testing.assert_allclose(np.median(local.vx[5:]), truth[0], atol=0.5)
    np.testing.assert_allclose(np.median(local.vy[5:]), truth[1], atol=0.5)


def test_pair_features_are_symmetric():
    rng = np.random.default_rng(2)
    n = 50
    d = _detections(rng.uniform(0, 5, n), rng.uniform(0, 5, n), rng.choice([0, 0.05, 0.1], n), rng.normal(0, 5, n))
    _, local = detection_features(d)
    objectness = rng.random(n)
    i, j = pairs_within(d.x, d.y, d.t, 3.0, 0.25)
    forward = pair_features(d, local, objectness, i, j)
    backward = pair_features(d, local, objectness, j, i)
    assert forward.shape == (len(i), len(PAIR_FEATURES))
    np.testing.assert_allclose(forward, backward, rtol=1e-12, atol=1e-12)


def test_without_a_line_of_sight_only_its_features_are_nan_and_left_out():
    n = 10
    rng = np.random.default_rng(3)
    d = _detections(
        rng.uniform(0, 3, n), rng.uniform(0, 3, n), np.zeros(n), rng.normal(0, 5, n), los=np.full(n, np.nan)
    )
    features, local = detection_features(d)
    needs_los = ~usable(DETECTION_FEATURES, {"rcs", "range", "sensor", "ego"})
    assert np.all(np.isnan(features[:, needs_los])) and not np.any(np.isnan(features[:, ~needs_los]))
    i, j = pairs_within(d.x, d.y, d.t, 3.0, 0.25)
    pairs = pair_features(d, local, rng.random(n), i, j)
    pair_needs_los = ~usable(PAIR_FEATURES, {"rcs", "range", "sensor", "ego"})
    assert len(i) and np.all(np.isnan(pairs[:, pair_needs_los])) and not np.any(np.isnan(pairs[:, ~pair_needs_los]))
    assert usable(DETECTION_FEATURES, {"los", "rcs", "range", "sensor", "ego"}).all()
