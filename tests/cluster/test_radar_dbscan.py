"""RadarDBSCAN against scikit-learn's DBSCAN, hand-computed cases and property tests."""

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.cluster import DBSCAN

from sklearn_radar import RadarDBSCAN
from sklearn_radar.cluster import min_points_at_range

UNRESTRICTED = dict(eps_t=None, alpha_r=0.0, vr_min=-np.inf)


def _same_partition(a, b):
    """True when two labelings of the same rows group them identically (ids may differ)."""
    pairs = set(zip(a.tolist(), b.tolist()))
    return len(pairs) == len(set(a.tolist())) == len(set(b.tolist()))


def _assert_like_sklearn(ours, reference, X, radius_ok):
    """Core points equal, core partition equal, noise equal, borders in an adjacent core's cluster."""
    core = reference.core_sample_indices_
    np.testing.assert_array_equal(np.sort(ours.core_sample_indices_), np.sort(core))
    assert _same_partition(ours.labels_[core], reference.labels_[core])
    np.testing.assert_array_equal(ours.labels_ == -1, reference.labels_ == -1)
    is_core = np.zeros(len(X), dtype=bool)
    is_core[core] = True
    for border in np.flatnonzero(~is_core & (ours.labels_ >= 0)):
        adjacent = core[radius_ok(X[border], X[core])]
        assert ours.labels_[border] in set(ours.labels_[adjacent].tolist())


@pytest.mark.parametrize("seed", range(25))
def test_xy_criterion_equals_sklearn_dbscan_on_xy(seed):
    rng = np.random.default_rng(seed)
    X = rng.uniform(0, 10, (int(rng.integers(50, 500)), 2))
    eps, min_samples = rng.uniform(0.2, 1.5), int(rng.integers(1, 8))
    reference = DBSCAN(eps=eps, min_samples=min_samples).fit(X)
    ours = RadarDBSCAN(metric="xy", eps_xy=eps, eps_vr=1e12, min_samples=min_samples, **UNRESTRICTED).fit(X)
    _assert_like_sklearn(ours, reference, X, lambda p, Q: np.hypot(*(Q - p).T) <= eps)


@pytest.mark.parametrize("seed", range(25))
def test_xyv_criterion_equals_sklearn_dbscan_on_scaled_doppler(seed):
    rng = np.random.default_rng(100 + seed)
    X = np.c_[rng.uniform(0, 10, (300, 2)), rng.normal(0, 3, 300)]
    eps, scale, min_samples = rng.uniform(0.3, 1.5), rng.uniform(0.5, 5.0), int(rng.integers(2, 7))
    scaled = X * [1.0, 1.0, 1.0 / scale]
    reference = DBSCAN(eps=eps, min_samples=min_samples).fit(scaled)
    ours = RadarDBSCAN(metric="xyv", eps_xyv=eps, vr_scale=scale, min_samples=min_samples, **UNRESTRICTED).fit(X)
    _assert_like_sklearn(ours, reference, scaled, lambda p, Q: np.linalg.norm(Q - p, axis=1) <= eps)


@pytest.mark.parametrize("seed", range(25))
def test_box_criterion_equals_sklearn_chebyshev_dbscan_on_scaled_doppler(seed):
    rng = np.random.default_rng(200 + seed)
    X = np.c_[rng.uniform(0, 10, (300, 2)), rng.normal(0, 3, 300)]
    eps, eps_vr, min_samples = rng.uniform(0.3, 1.5), rng.uniform(0.5, 5.0), int(rng.integers(2, 7))
    scaled = X * [1.0, 1.0, eps / eps_vr]
    reference = DBSCAN(eps=eps, min_samples=min_samples, metric="chebyshev").fit(scaled)
    ours = RadarDBSCAN(metric="box", eps_xy=eps, eps_vr=eps_vr, min_samples=min_samples, **UNRESTRICTED).fit(X)
    _assert_like_sklearn(ours, reference, scaled, lambda p, Q: np.abs(Q - p).max(axis=1) <= eps)


def test_a_point_counts_itself_toward_min_samples():
    X = np.array([[0.0, 0.0], [0.5, 0.0]])
    two = RadarDBSCAN(metric="xy", eps_xy=1.0, min_samples=2, **UNRESTRICTED).fit(X)
    three = RadarDBSCAN(metric="xy", eps_xy=1.0, min_samples=3, **UNRESTRICTED).fit(X)
    assert two.labels_.tolist() == [0, 0]  # one neighbour + itself = 2
    assert three.labels_.tolist() == [-1, -1]
    lone = RadarDBSCAN(metric="xy", min_samples=1, **UNRESTRICTED).fit(np.array([[0.0, 0.0], [5.0, 5.0]]))
    assert lone.labels_.tolist() == [0, 1]  # min_samples = 1: every point is its own core


def test_real_valued_min_samples_rounds_up():
    X = np.array([[0.0, 0.0], [0.3, 0.0], [0.6, 0.0]])
    assert RadarDBSCAN(metric="xy", eps_xy=0.5, min_samples=2.01, **UNRESTRICTED).fit(X).core_sample_indices_.tolist() == [1]
    assert RadarDBSCAN(metric="xy", eps_xy=0.5, min_samples=2.0, **UNRESTRICTED).fit(X).core_sample_indices_.tolist() == [0, 1, 2]


def _frame(rows):
    return pd.DataFrame(rows, columns=["x", "y", "v_r", "t"])


def test_spatial_and_doppler_comparisons_are_strict_and_time_is_inclusive():
    pair = lambda **d: _frame([(0.0, 0.0, 2.0, 0.0), (d.get("x", 0.0), d.get("y", 0.0), 2.0 + d.get("v", 0.0), d.get("t", 0.0))])
    def linked(X, **params):
        return RadarDBSCAN(min_samples=2, vr_min=-np.inf, **params).fit(X).labels_[0] >= 0

    assert not linked(pair(x=1.0), metric="box", eps_xy=1.0)  # |dx| = eps_xy: not < eps_xy
    assert linked(pair(x=0.999), metric="box", eps_xy=1.0)
    assert not linked(pair(v=5.0), metric="box", eps_vr=5.0)
    assert not linked(pair(x=0.6, y=0.8), metric="xy", eps_xy=1.0)  # distance exactly 1
    assert not linked(pair(x=0.6, y=0.8), metric="xyv", eps_xyv=1.0)
    assert linked(pair(t=0.25), metric="xy")  # |dt| = eps_t counts
    assert not linked(pair(t=0.2501), metric="xy")


def test_box_is_aligned_with_the_car_heading():
    # Two detections 1.2 m apart along a car heading of 45 degrees: outside a 1 m world-aligned box
    # diagonal? No: dx = dy = 0.85 fits the world box, but along the car axis the gap is 1.2 m.
    X = _frame([(0.0, 0.0, 2.0, 0.0), (0.85, 0.85, 2.0, 0.0)])
    params = dict(metric="box", eps_xy=1.0, min_samples=2, vr_min=-np.inf)
    assert RadarDBSCAN(**params).fit(X).labels_.tolist() == [0, 0]
    assert RadarDBSCAN(**params).fit(X.assign(heading=np.pi / 4)).labels_.tolist() == [-1, -1]


def test_only_fast_enough_detections_become_core_points():
    X = _frame([(0.0, 0.0, 0.3, 0.0), (0.5, 0.0, 0.3, 0.0), (1.0, 0.0, 0.5, 0.0)])
    model = RadarDBSCAN(metric="xy", eps_xy=0.6, eps_vr=5.0, min_samples=2, vr_min=0.4).fit(X)
    assert model.core_sample_indices_.tolist() == [2]
    assert model.labels_.tolist() == [-1, 0, 0]  # point 1 is a border of core 2; point 0 reaches no core
    negative = RadarDBSCAN(metric="xy", eps_xy=0.6, min_samples=2, vr_min=0.4).fit(X.assign(v_r=-X["v_r"]))
    assert negative.core_sample_indices_.tolist() == [2]  # |v_r| is compared


def test_removed_rows_are_noise_and_bridge_nothing():
    X = _frame([(0.0, 0.0, 3.0, 0.0), (0.5, 0.0, 3.0, 0.0), (1.0, 0.0, 3.0, 0.0), (1.5, 0.0, 3.0, 0.0), (2.0, 0.0, 3.0, 0.0)])
    params = dict(metric="xy", eps_xy=0.6, min_samples=2, vr_min=0.0)
    assert RadarDBSCAN(**params).fit(X).labels_.tolist() == [0, 0, 0, 0, 0]
    split = RadarDBSCAN(**params).fit(X.assign(keep=[True, True, False, True, True]))
    assert split.labels_.tolist() == [0, 0, -1, 1, 1]
    assert 2 not in split.core_sample_indices_


def test_sequences_never_connect():
    X = _frame([(0.0, 0.0, 3.0, 0.0), (0.1, 0.0, 3.0, 0.0)]).assign(sequence=[1, 2])
    assert RadarDBSCAN(min_samples=2, vr_min=0.0).fit(X).labels_.tolist() == [-1, -1]
    assert RadarDBSCAN(min_samples=2, vr_min=0.0).fit(X.assign(sequence=1)).labels_.tolist() == [0, 0]


def test_an_object_tracked_for_20_s_forms_one_cluster():
    t = np.arange(0, 20, 0.06)
    X = _frame(np.c_[10 * t, np.zeros_like(t), np.full_like(t, 10.0), t])
    X = pd.concat([X, X.assign(y=0.3)], ignore_index=True)
    labels = RadarDBSCAN(metric="xy", eps_xy=1.0, min_samples=3).fit(X).labels_
    assert set(labels.tolist()) == {0}


@pytest.mark.parametrize(
    "r, linear, reciprocal",
    [(10.0, 0.5, 2.0), (25.0, 0.5, 2.0), (50.0, 1.0, 1.0), (100.0, 2.0, 0.5), (200.0, 2.5, 0.4)],
)
def test_eq_2_by_hand_with_alpha_1(r, linear, reciprocal):
    assert min_points_at_range([r], 4.0, 1.0, "linear")[0] == pytest.approx(4.0 * linear)
    assert min_points_at_range([r], 4.0, 1.0, "reciprocal")[0] == pytest.approx(4.0 * reciprocal)


def test_range_adaptive_min_points_decide_core_points():
    # Three detections close together; 3 needed at 50 m. Reciprocal: far (100 m) needs 1.5 -> core;
    # near (25 m) needs 4.5 -> not core.
    X = _frame([(0.0, 0.0, 3.0, 0.0), (0.3, 0.0, 3.0, 0.0), (0.6, 0.0, 3.0, 0.0)])
    params = dict(metric="xy", eps_xy=0.5, min_samples=3.0, alpha_r=1.0, vr_min=0.0)
    far = RadarDBSCAN(range_scaling="reciprocal", **params).fit(X.assign(range_sc=100.0))
    near = RadarDBSCAN(range_scaling="reciprocal", **params).fit(X.assign(range_sc=25.0))
    assert far.core_sample_indices_.tolist() == [0, 1, 2]
    assert near.core_sample_indices_.tolist() == []
    linear_far = RadarDBSCAN(range_scaling="linear", **params).fit(X.assign(range_sc=100.0))
    assert linear_far.core_sample_indices_.tolist() == []
    with pytest.raises(ValueError, match="range_sc"):
        RadarDBSCAN(alpha_r=0.5).fit(X)


def test_labels_are_consecutive_in_order_of_first_row():
    X = _frame([(5.0, 0.0, 3.0, 0.0), (0.0, 0.0, 3.0, 0.0), (5.2, 0.0, 3.0, 0.0), (0.2, 0.0, 3.0, 0.0)])
    assert RadarDBSCAN(min_samples=2).fit(X).labels_.tolist() == [0, 1, 0, 1]


def test_n_jobs_gives_the_same_labels():
    rng = np.random.default_rng(3)
    X = _frame(np.c_[rng.uniform(0, 20, (2000, 2)), rng.normal(0, 4, 2000), rng.uniform(0, 2, 2000)]).assign(sequence=rng.integers(0, 5, 2000))
    params = dict(metric="xyv", eps_xyv=1.0, vr_scale=2.0, min_samples=3, vr_min=0.5)
    np.testing.assert_array_equal(RadarDBSCAN(n_jobs=2, **params).fit(X).labels_, RadarDBSCAN(**params).fit(X).labels_)


_points = st.integers(2, 80).flatmap(
    lambda n: st.tuples(
        st.just(n),
        st.integers(0, 2**16),
        st.sampled_from(["box", "xy", "xyv"]),
        st.floats(0.3, 2.0),
        st.floats(1.0, 4.0),
    )
)


@settings(max_examples=60, deadline=None)
@given(case=_points)
def test_invariants(case):
    n, seed, metric, eps, min_samples = case
    rng = np.random.default_rng(seed)
    X = _frame(np.c_[rng.uniform(0, 6, (n, 2)).round(2), rng.normal(0, 2, n).round(1), rng.integers(0, 12, n) * 0.0625])
    X["sequence"] = rng.integers(0, 3, n)
    X["heading"] = rng.uniform(-np.pi, np.pi, n)
    model = RadarDBSCAN(metric=metric, eps_xy=eps, eps_xyv=eps, eps_vr=1.5, vr_scale=1.5, min_samples=min_samples, vr_min=0.3)
    labels = model.fit(X).labels_
    assert labels.shape == (n,)
    core = np.zeros(n, dtype=bool)
    core[model.core_sample_indices_] = True

    # No cluster spans two sequences; no core link spans more than eps_t.
    for label in set(labels.tolist()) - {-1}:
        members = labels == label
        assert X.loc[members, "sequence"].nunique() == 1
    # Every clustered core point has a same-cluster core neighbour within eps_t, unless it is alone.
    for i in np.flatnonzero(core):
        mates = np.flatnonzero(core & (labels == labels[i]))
        if len(mates) > 1:
            assert np.min(np.abs(X["t"].to_numpy()[mates[mates != i]] - X["t"].iloc[i])) <= 0.25

    # Row order does not matter, except which cluster a border point joins on an exact tie.
    order = rng.permutation(n)
    shuffled = model.fit(X.iloc[order].reset_index(drop=True))
    back = np.empty(n, dtype=np.int64)
    back[order] = shuffled.labels_
    assert _same_partition(labels[core], back[core])
    np.testing.assert_array_equal(labels == -1, back == -1)
