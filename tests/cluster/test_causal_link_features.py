"""Causal features of LinkClustering: the offline features of the data cut at each time, the same pairs."""

import math

import numba
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from sklearn_radar.cluster._causal_link_features import (
    _within,
    causal_detection_features,
    causal_pair_features,
    causal_pairs,
)
from sklearn_radar.cluster._link_features import Detections, detection_features, pair_features, pairs_within


def _random_detections(n, rng, times=12):
    t = np.sort(rng.integers(0, times, n) * 0.04)
    return Detections(
        x=rng.uniform(0, 8, n),
        y=rng.uniform(0, 8, n),
        t=t,
        v=rng.normal(0, 3, n),
        los=rng.uniform(-np.pi, np.pi, n),
        rcs=rng.normal(0, 5, n),
        range=rng.uniform(5, 80, n),
        sensor=rng.integers(1, 5, n).astype(float),
        ego=np.full(n, 8.0),
    )


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**16), st.integers(1, 120))
def test_causal_features_are_the_offline_features_of_the_data_truncated_at_each_time(seed, n):
    # The reference: the offline (past and future) features computed on the detections up to each time; for the
    # detections of that last time, their whole neighbourhood is then the past.
    d = _random_detections(n, np.random.default_rng(seed))
    features, local = causal_detection_features(d)
    for time in np.unique(d.t):
        upto = d.t <= time
        truncated = Detections(*(values[upto] for values in d))
        expected, expected_local = detection_features(truncated)
        last = truncated.t == time
        np.testing.assert_allclose(features[upto][last], expected[last], rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(local.vx[upto][last], expected_local.vx[last], rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(local.count[upto][last], expected_local.count[last])


def test_features_from_a_start_are_those_of_the_whole_run():
    # The online path computes the new scan's features against a window of the past: the same numbers.
    d = _random_detections(200, np.random.default_rng(3), times=40)
    whole, whole_local = causal_detection_features(d)
    start = int(np.searchsorted(d.t, d.t[120]))
    tail, tail_local = causal_detection_features(d, start)
    np.testing.assert_array_equal(tail, whole[start:])
    np.testing.assert_array_equal(tail_local.vx, whole_local.vx[start:])


@settings(max_examples=50, deadline=None)
@given(st.integers(0, 2**16), st.integers(0, 80), st.sampled_from([0.0, 0.04, 0.25]), st.sampled_from([1.0, 3.0]))
def test_causal_pairs_are_the_offline_pairs_in_arrival_order(seed, n, window, radius):
    rng = np.random.default_rng(seed)
    d = _random_detections(n, rng)
    node = rng.random(n) < 0.7
    i, j = causal_pairs(d.x, d.y, d.t, node, 0, radius, window)
    ref_i, ref_j = pairs_within(d.x, d.y, d.t, radius, window, node)
    assert set(zip(i.tolist(), j.tolist(), strict=True)) == set(zip(ref_i.tolist(), ref_j.tolist(), strict=True))
    assert len(i) == len(ref_i)
    assert np.all(np.diff(j * (n + 1) + i) > 0)  # in the order of j, then i
    start = n // 2
    later = j >= start
    tail_i, tail_j = causal_pairs(d.x, d.y, d.t, node, start, radius, window)
    np.testing.assert_array_equal(tail_i, i[later])
    np.testing.assert_array_equal(tail_j, j[later])


@settings(max_examples=50, deadline=None)
@given(
    st.integers(0, 2**16),
    st.integers(0, 80),
    st.sampled_from([0.0, 0.04, 0.25]),
    st.sampled_from([1.0, 3.0]),
    st.integers(1, 6),
)
def test_max_links_keeps_each_detections_nearest_earlier_candidates(seed, n, window, radius, max_links):
    # The reference: every candidate pair by brute force, each later detection's sorted by the scaled distance.
    rng = np.random.default_rng(seed)
    d = _random_detections(n, rng)
    if n > 4:
        d = d._replace(x=np.round(d.x), y=np.round(d.y))  # ties of the distance, broken by the earlier detection
    node = rng.random(n) < 0.7
    i, j = causal_pairs(d.x, d.y, d.t, node, 0, radius, window, max_links)
    expected = []
    for b in range(n):
        found = [
            (((d.x[a] - d.x[b]) ** 2 + (d.y[a] - d.y[b]) ** 2) / radius**2 + ((d.t[b] - d.t[a]) / window) ** 2, a)
            if window > 0
            else (((d.x[a] - d.x[b]) ** 2 + (d.y[a] - d.y[b]) ** 2) / radius**2, a)
            for a in range(b)
            if node[a]
            and node[b]
            and d.t[b] - d.t[a] <= window
            and np.hypot(d.x[a] - d.x[b], d.y[a] - d.y[b]) <= radius
        ]
        expected += [(a, b) for a in sorted(a for _, a in sorted(found)[:max_links])]
    assert list(zip(i.tolist(), j.tolist(), strict=True)) == expected
    start = n // 2
    tail_i, tail_j = causal_pairs(d.x, d.y, d.t, node, start, radius, window, max_links)
    np.testing.assert_array_equal(tail_i, i[j >= start])
    np.testing.assert_array_equal(tail_j, j[j >= start])


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**16), st.integers(2, 80), st.booleans())
def test_compiled_pair_features_equal_the_numpy_ones(seed, n, measured):
    # The reference: the offline (numpy) pair features, on the same detections and pairs.

    rng = np.random.default_rng(seed)
    d = _random_detections(n, rng)
    if not measured:  # absent measurements are NaN, and so are the features that need them
        d = d._replace(los=np.full(n, np.nan), rcs=np.full(n, np.nan), sensor=np.full(n, np.nan))
    _, local = causal_detection_features(d)
    objectness = rng.random(n)
    i, j = causal_pairs(d.x, d.y, d.t, np.ones(n, dtype=bool), 0, 3.0, 0.25)
    np.testing.assert_allclose(
        causal_pair_features(d, local, objectness, i, j),
        pair_features(d, local, objectness, i, j),
        rtol=1e-9,
        atol=1e-9,
    )


@settings(max_examples=300, deadline=None)
@given(
    st.floats(-50, 50, allow_nan=False),
    st.floats(-50, 50, allow_nan=False),
    st.integers(-4, 4),
    st.sampled_from([0.0, 1e-300, 1.0, 2.5]),
)
def test_the_circle_test_is_hypots_even_on_the_circle(dx, dy, ulps, scale):
    # The kernels decide "within the radius" from the squares away from the circle and from math.hypot near it:
    # radii a few ulps either side of the distance, and arbitrary ones, give hypot's answer (compiled, numba's
    # hypot, which can differ from Python's in the last bit).
    distance = math.hypot(dx, dy)
    radius = distance
    for _ in range(abs(ulps)):
        radius = np.nextafter(radius, np.inf if ulps > 0 else -np.inf)
    for r in (radius, scale, distance * 0.5, distance * 2):
        assert _within.py_func(dx, dy, r) == (math.hypot(dx, dy) <= r)
        assert _within(dx, dy, r) == _hypot_within(dx, dy, r)


@numba.njit
def _hypot_within(dx, dy, radius):
    return math.hypot(dx, dy) <= radius
