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
    pairs = set(zip(a.tolist(), b.tolist(), strict=True))
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
    assert RadarDBSCAN(metric="xy", eps_xy=0.5, min_samples=2.01, **UNRESTRICTED).fit(
        X
    ).core_sample_indices_.tolist() == [1]
    assert RadarDBSCAN(metric="xy", eps_xy=0.5, min_samples=2.0, **UNRESTRICTED).fit(
        X
    ).core_sample_indices_.tolist() == [0, 1, 2]


def _frame(rows):
    return pd.DataFrame(rows, columns=["x", "y", "v_r", "t"])


def test_spatial_and_doppler_comparisons_are_strict_and_time_is_inclusive():
    def pair(x=0.0, y=0.0, v=0.0, t=0.0):
        return _frame([(0.0, 0.0, 2.0, 0.0), (x, y, 2.0 + v, t)])

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
    # dx = dy = 0.85: inside the 1 m box of the world axes (heading 0), but with the car heading 45 degrees
    # the gap along the car's x axis is (0.85 + 0.85) / sqrt(2) = 1.20 m, outside it.
    X = _frame([(0.0, 0.0, 2.0, 0.0), (0.85, 0.85, 2.0, 0.0)])
    params = dict(metric="box", eps_xy=1.0, min_samples=2, vr_min=-np.inf)
    assert RadarDBSCAN(**params).fit(X).labels_.tolist() == [0, 0]
    assert RadarDBSCAN(**params).fit(X.assign(heading=np.pi / 4)).labels_.tolist() == [-1, -1]


@pytest.mark.parametrize(
    "heading, linked",
    [
        # cos 0.3 = 0.95534, sin 0.3 = 0.29552; dx, dy = 0.9, 0.6.
        # along = cos * dx + sin * dy = 0.85980 + 0.17731 = 1.03711 >= 1: not neighbours.
        (0.3, False),
        # heading -0.3: along = 0.85980 - 0.17731 = 0.68249, across = cos * dy - sin * dx = 0.57320 + 0.26597
        # = 0.83917, both < 1: neighbours.  (At +-pi/4 a square box cannot tell the sign apart.)
        (-0.3, True),
    ],
)
def test_box_turns_with_the_heading_not_against_it(heading, linked):
    X = _frame([(0.0, 0.0, 2.0, 0.0), (0.9, 0.6, 2.0, 0.0)]).assign(heading=heading)
    labels = RadarDBSCAN(metric="box", eps_xy=1.0, min_samples=2, vr_min=-np.inf).fit(X).labels_
    assert labels.tolist() == ([0, 0] if linked else [-1, -1])


def test_rotated_box_is_strict():
    # Heading pi/2: the car's x axis is the world's y axis, so dy = 1.0 is a gap of exactly eps_xy along it
    # (cos(pi/2) * 0 + sin(pi/2) * 1.0 = 1.0): not < eps_xy.
    params = dict(metric="box", eps_xy=1.0, min_samples=2, vr_min=-np.inf)
    at_eps = _frame([(0.0, 0.0, 2.0, 0.0), (0.0, 1.0, 2.0, 0.0)]).assign(heading=np.pi / 2)
    inside = _frame([(0.0, 0.0, 2.0, 0.0), (0.0, 0.999, 2.0, 0.0)]).assign(heading=np.pi / 2)
    assert RadarDBSCAN(**params).fit(at_eps).labels_.tolist() == [-1, -1]
    assert RadarDBSCAN(**params).fit(inside).labels_.tolist() == [0, 0]


@pytest.mark.parametrize("later_heading, linked", [(np.pi / 4, False), (0.0, True)])
def test_box_takes_the_axes_of_the_later_detection(later_heading, linked):
    # (0, 0) at t = 0 and (0.85, 0.85) at t = 0.1 s.  Axes of heading 0: |dx| = |dy| = 0.85 < 1, neighbours;
    # of heading pi/4: along = 1.70 / sqrt(2) = 1.20 >= 1, not.  The later detection's heading decides.
    earlier_heading = np.pi / 4 - later_heading
    X = _frame([(0.0, 0.0, 2.0, 0.0), (0.85, 0.85, 2.0, 0.1)]).assign(heading=[earlier_heading, later_heading])
    labels = RadarDBSCAN(metric="box", eps_xy=1.0, min_samples=2, vr_min=-np.inf).fit(X).labels_
    assert labels.tolist() == ([0, 0] if linked else [-1, -1])


@pytest.mark.parametrize("seed, heading", [(0, 0.3), (1, -0.3), (2, 1.1), (3, -2.5), (4, 2.0)])
def test_rotated_box_equals_sklearn_chebyshev_dbscan_in_the_car_frame(seed, heading):
    # Points drawn in the car frame and carried into the world by rotating by +heading (x_world = R(h) x_car):
    # the box criterion with that heading must cluster them as the plain Chebyshev DBSCAN clusters the
    # car-frame coordinates (with Doppler scaled so that eps_vr counts like eps_xy).
    rng = np.random.default_rng(300 + seed)
    car = np.c_[rng.uniform(0, 8, (250, 2)), rng.normal(0, 3, 250)]
    eps, eps_vr, min_samples = 0.8, 2.0, 4
    c, s = np.cos(heading), np.sin(heading)
    world = _frame(
        np.c_[5.0 + c * car[:, 0] - s * car[:, 1], -3.0 + s * car[:, 0] + c * car[:, 1], car[:, 2], np.zeros(250)]
    ).assign(heading=heading)
    scaled = car * [1.0, 1.0, eps / eps_vr]
    reference = DBSCAN(eps=eps, min_samples=min_samples, metric="chebyshev").fit(scaled)
    assert len(set(reference.labels_.tolist()) - {-1}) >= 3  # a case with several clusters and noise
    ours = RadarDBSCAN(metric="box", eps_xy=eps, eps_vr=eps_vr, min_samples=min_samples, **UNRESTRICTED).fit(world)
    _assert_like_sklearn(ours, reference, scaled, lambda p, Q: np.abs(Q - p).max(axis=1) <= eps)


@pytest.mark.parametrize("dv, linked", [(4.9, True), (5.0, False), (6.0, False)])
def test_eq_4_needs_the_doppler_condition_too(dv, linked):
    # 0.5 m apart (< eps_xy = 1), Doppler apart by dv: neighbours only when |dv| < eps_vr = 5.
    X = _frame([(0.0, 0.0, 2.0, 0.0), (0.5, 0.0, 2.0 + dv, 0.0)])
    labels = RadarDBSCAN(metric="xy", eps_xy=1.0, eps_vr=5.0, min_samples=2, vr_min=-np.inf).fit(X).labels_
    assert labels.tolist() == ([0, 0] if linked else [-1, -1])


@pytest.mark.parametrize("v_r, core", [(0.4, False), (-0.4, False), (0.41, True), (-0.41, True)])
def test_vr_min_is_a_strict_bound_on_the_absolute_doppler(v_r, core):
    # Three detections within 0.3 m; each has 2 neighbours + itself >= min_samples = 3, so core exactly
    # when |v_r| > vr_min = 0.4: |0.4| is not > 0.4.
    X = _frame([(0.0, 0.0, v_r, 0.0), (0.3, 0.0, v_r, 0.0), (0.0, 0.3, v_r, 0.0)])
    model = RadarDBSCAN(metric="xy", eps_xy=0.5, min_samples=3, vr_min=0.4).fit(X)
    assert model.core_sample_indices_.tolist() == ([0, 1, 2] if core else [])


@pytest.mark.parametrize("border_x, expected", [(0.0, [0, 0, 1, 1, 1]), (-0.1, [0, 0, 0, 1, 1])])
def test_a_border_point_joins_its_closest_core_point(border_x, expected):
    # Cores at x = -0.4 (cluster A, with -0.9) and 0.3 (cluster B, with 0.8), 0.7 m apart: not linked
    # (eps_xy = 0.6).  The slow middle detection (|v_r| = 0.1 < vr_min) cannot be core; it reaches both cores.
    # At x = 0: 0.4 m to A's core, 0.3 m to B's -> B.  At x = -0.1: 0.3 m to A's, 0.4 m to B's -> A.
    # (Doppler differs by 2.9 m/s, 2.9 / eps_vr = 0.058 of the normalised distance: it does not decide.)
    X = _frame(
        [
            (-0.9, 0.0, 3.0, 0.0),
            (-0.4, 0.0, 3.0, 0.0),
            (border_x, 0.0, 0.1, 0.0),
            (0.3, 0.0, 3.0, 0.0),
            (0.8, 0.0, 3.0, 0.0),
        ]
    )
    model = RadarDBSCAN(metric="xy", eps_xy=0.6, eps_vr=50.0, min_samples=3, vr_min=0.4).fit(X)
    assert model.core_sample_indices_.tolist() == [1, 3]
    assert model.labels_.tolist() == expected


def test_causal_time_window_is_inclusive_too():
    # Causal: the later detection sees the earlier one when the lag is <= eps_t = 0.25 s and becomes core
    # (1 neighbour + itself = 2); the earlier one had no past and stays noise.
    params = dict(metric="xy", causal=True, min_samples=2, vr_min=-np.inf)
    assert RadarDBSCAN(**params).fit(_frame([(0.0, 0.0, 2.0, 0.0), (0.0, 0.0, 2.0, 0.25)])).labels_.tolist() == [-1, 0]
    assert RadarDBSCAN(**params).fit(_frame([(0.0, 0.0, 2.0, 0.0), (0.0, 0.0, 2.0, 0.2501)])).labels_.tolist() == [
        -1,
        -1,
    ]


def test_only_fast_enough_detections_become_core_points():
    X = _frame([(0.0, 0.0, 0.3, 0.0), (0.5, 0.0, 0.3, 0.0), (1.0, 0.0, 0.5, 0.0)])
    model = RadarDBSCAN(metric="xy", eps_xy=0.6, eps_vr=5.0, min_samples=2, vr_min=0.4).fit(X)
    assert model.core_sample_indices_.tolist() == [2]
    assert model.labels_.tolist() == [-1, 0, 0]  # point 1 is a border of core 2; point 0 reaches no core
    negative = RadarDBSCAN(metric="xy", eps_xy=0.6, min_samples=2, vr_min=0.4).fit(X.assign(v_r=-X["v_r"]))
    assert negative.core_sample_indices_.tolist() == [2]  # |v_r| is compared


def test_removed_rows_are_noise_and_bridge_nothing():
    X = _frame(
        [(0.0, 0.0, 3.0, 0.0), (0.5, 0.0, 3.0, 0.0), (1.0, 0.0, 3.0, 0.0), (1.5, 0.0, 3.0, 0.0), (2.0, 0.0, 3.0, 0.0)]
    )
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


@pytest.mark.parametrize(
    "r, linear, reciprocal",
    [
        # N_min(r) = 4 * (1 + 0.5 * rel), rel = clip(r) / 50 - 1 (linear) or 50 / clip(r) - 1 (reciprocal).
        (25.0, 4 * (1 + 0.5 * -0.5), 4 * (1 + 0.5 * 1.0)),  # 3.0, 6.0
        (40.0, 4 * (1 + 0.5 * -0.2), 4 * (1 + 0.5 * 0.25)),  # 3.6, 4.5
        (100.0, 4 * (1 + 0.5 * 1.0), 4 * (1 + 0.5 * -0.5)),  # 6.0, 3.0
        (125.0, 4 * (1 + 0.5 * 1.5), 4 * (1 + 0.5 * -0.6)),  # 7.0, 2.8
    ],
)
def test_eq_2_by_hand_with_alpha_one_half(r, linear, reciprocal):
    # At alpha_r = 0.5 the slope shows: alpha_r**2 (0.25) or no alpha_r (1) would give other values.
    assert min_points_at_range([r], 4.0, 0.5, "linear")[0] == pytest.approx(linear)
    assert min_points_at_range([r], 4.0, 0.5, "reciprocal")[0] == pytest.approx(reciprocal)


def test_range_adaptive_min_points_with_alpha_one_half_decide_core_points():
    # Three detections within 0.3 m at 100 m, N_min,50 = 4, alpha_r = 0.5 (reciprocal):
    # N_min = 4 * (1 + 0.5 * (50 / 100 - 1)) = 3.0 -> 2 neighbours + itself = 3 suffice.  At 40 m:
    # 4 * (1 + 0.5 * 0.25) = 4.5 -> 5 needed, not core.
    X = _frame([(0.0, 0.0, 3.0, 0.0), (0.3, 0.0, 3.0, 0.0), (0.0, 0.3, 3.0, 0.0)])
    params = dict(metric="xy", eps_xy=0.5, min_samples=4.0, alpha_r=0.5, vr_min=0.0)
    assert RadarDBSCAN(**params).fit(X.assign(range_sc=100.0)).core_sample_indices_.tolist() == [0, 1, 2]
    assert RadarDBSCAN(**params).fit(X.assign(range_sc=40.0)).core_sample_indices_.tolist() == []


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
    X = _frame(np.c_[rng.uniform(0, 20, (2000, 2)), rng.normal(0, 4, 2000), rng.uniform(0, 2, 2000)]).assign(
        sequence=rng.integers(0, 5, 2000)
    )
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
    model = RadarDBSCAN(
        metric=metric, eps_xy=eps, eps_xyv=eps, eps_vr=1.5, vr_scale=1.5, min_samples=min_samples, vr_min=0.3
    )
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
