"""Labels do not depend on the row order (issue 15, item 2) and tiny scan intervals do not crash (item 3)."""

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sklearn_radar import ClusterMerger, RadarDBSCAN
from sklearn_radar.cluster._radar_dbscan_kernels import _pair_distance, _spatial_neighbor, points_of


def _same_partition(a, b):
    """Equal up to renaming (noise, -1, is a label like any other)."""
    a, b = np.asarray(a), np.asarray(b)
    return len(set(zip(a.tolist(), b.tolist(), strict=True))) == len(set(a.tolist())) == len(set(b.tolist()))


def _labels_of_permuted(model, X, permutation):
    """Labels of ``X.iloc[permutation]``, put back in the order of X."""
    labels = np.empty(len(X), dtype=np.int64)
    labels[permutation] = model.fit_predict(X.iloc[permutation])
    return labels


def test_box_is_symmetric_for_equal_times_with_different_headings():
    # The example: the rows reversed gave [0 0 1 1] against [0 0 0 0].
    X = pd.DataFrame(
        {"x": [0, 0.2, 0.9, 1.1], "y": [0, 0, 0.9, 1.1], "v_r": 5.0, "t": 0.0, "heading": [0, 0, np.pi / 4, np.pi / 4]}
    )
    forward = RadarDBSCAN(min_samples=2).fit_predict(X)
    backward = RadarDBSCAN(min_samples=2).fit_predict(X.iloc[::-1])[::-1]
    assert _same_partition(forward, backward)
    # (0.2, 0) and (0.9, 0.9) are in the box of heading 0 but not in that of heading pi/4: not neighbours.
    assert forward[1] != forward[2]


def test_box_pair_distance_agrees_with_the_criterion_and_is_symmetric():
    rng = np.random.default_rng(0)
    n = 400
    points = points_of(
        x=rng.uniform(-2, 2, n),
        y=rng.uniform(-2, 2, n),
        v=rng.uniform(-1, 1, n),
        t=rng.choice([0.0, 0.05], n),
        heading=rng.choice([0.0, 0.3, 1.2, -2.0], n),
    )
    crit = RadarDBSCAN(metric="box", eps_xy=1.0, eps_vr=1.5)._kernel_criterion()
    for _ in range(3000):
        i, j = rng.integers(0, n, 2)
        neighbor = _spatial_neighbor(i, j, points, crit)
        assert neighbor == _spatial_neighbor(j, i, points, crit)
        assert _pair_distance(i, j, points, crit) == _pair_distance(j, i, points, crit)
        assert neighbor == (_pair_distance(i, j, points, crit) < 1.0)


# Two 12-row tables whose merged clusters depended on the row order: clusters starting in the same scan were
# paired (A older, B newer) by their stage-1 label ids, which follow the rows.
_TIED_STARTS = [
    (
        "velocity",
        {
            "x": [4.0, 3.1, 2.7, 1.1, 0.8, 0.4, 2.2, 0.8, 1.7, 3.0, 2.4, 1.3],
            "y": [0.2, 0.6, 0.4, 1.1, 0.8, 0.7, 0.8, 0.8, 0.9, 0.7, 1.5, 1.1],
            "t": [0.2, 0.0, 0.0, 0.0, 0.3, 0.3, 0.1, 0.3, 0.2, 0.1, 0.2, 0.0],
            "azimuth_sc": [-0.98, -0.18, -0.55, 0.19, 0.68, 0.49, -0.75, 0.0, -0.07, -0.12, -0.26, 0.37],
        },
        [11, 4, 7, 8, 9, 0, 6, 2, 5, 1, 3, 10],
    ),
    (
        "continuation",
        {
            "x": [1.2, 2.9, 2.4, 3.0, 2.5, 2.4, 2.2, 3.1, 2.7, 2.7, 1.4, 0.9],
            "y": [1.6, 1.3, 1.5, 0.6, 0.0, 1.6, 0.3, 1.5, 0.1, 0.2, 0.2, 0.3],
            "t": [0.1, 0.3, 0.0, 0.2, 0.0, 0.0, 0.0, 0.2, 0.0, 0.1, 0.3, 0.0],
            "azimuth_sc": [0.62, -0.95, -0.39, 0.1, 0.07, 0.36, 0.07, -0.73, -0.84, 0.55, -0.43, -0.7],
        },
        [5, 8, 2, 7, 1, 3, 0, 9, 10, 4, 6, 11],
    ),
]


def _tied_model(mode):
    stage1 = RadarDBSCAN(metric="xy", eps_xy=0.8, min_samples=2, vr_min=-np.inf, eps_t=0.1)
    return ClusterMerger(mode=mode, unknown_velocity="accept", eps_d=1.0, stage1=stage1)


@pytest.mark.parametrize("mode, columns, permutation", _TIED_STARTS, ids=["velocity", "continuation"])
def test_merger_tie_between_clusters_starting_in_one_scan_does_not_follow_the_rows(mode, columns, permutation):
    X = pd.DataFrame({**columns, "v_r": 5.0, "sensor_yaw": 0.0})
    model = _tied_model(mode)
    labels = model.fit_predict(X)
    for order in (permutation, np.arange(len(X))[::-1]):
        assert _same_partition(labels, _labels_of_permuted(model, X, np.asarray(order)))


_MODELS = {
    "box": lambda: RadarDBSCAN(metric="box", eps_xy=0.8, min_samples=2, vr_min=-np.inf, eps_t=0.1),
    "xy": lambda: RadarDBSCAN(metric="xy", eps_xy=0.8, min_samples=2, vr_min=-np.inf, eps_t=0.1),
    "xyv": lambda: RadarDBSCAN(metric="xyv", eps_xyv=0.8, vr_scale=2.0, min_samples=2, vr_min=-np.inf, eps_t=0.1),
}


@st.composite
def _small_tables(draw):
    n = draw(st.integers(1, 14))
    coordinate = st.integers(0, 30).map(lambda k: k / 10)
    column = lambda values: draw(st.lists(values, min_size=n, max_size=n))  # noqa: E731
    return pd.DataFrame(
        {
            "x": column(coordinate),
            "y": column(coordinate),
            "v_r": column(st.sampled_from([-3.0, 4.0, 5.0, 5.5])),
            "t": column(st.sampled_from([0.0, 0.1, 0.2, 0.3])),
            "sequence": column(st.sampled_from([1, 2])),
            "heading": column(st.sampled_from([0.0, 0.0, 0.7])),
            "azimuth_sc": column(st.sampled_from([-0.6, -0.1, 0.2, 0.9])),
            "sensor_yaw": 0.0,
        }
    )


@pytest.mark.parametrize("metric", sorted(_MODELS))
@pytest.mark.parametrize("stage", ["RadarDBSCAN", "continuation", "velocity"])
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(X=_small_tables(), seed=st.integers(0, 2**32 - 1))
def test_permuting_the_rows_permutes_the_labels(metric, stage, X, seed):
    stage1 = _MODELS[metric]()
    model = stage1 if stage == "RadarDBSCAN" else ClusterMerger(mode=stage, unknown_velocity="accept", stage1=stage1)
    labels = model.fit_predict(X)
    permutation = np.random.default_rng(seed).permutation(len(X))
    assert _same_partition(labels, _labels_of_permuted(model, X, permutation))


@pytest.mark.parametrize("n_scans", [2, 3, 4, 5])
@pytest.mark.parametrize("dt", [1e-160, 1e-300, 5e-324])
def test_scans_closer_than_1e_154_s_give_an_unknown_velocity_not_a_crash(n_scans, dt):
    # Issue 15, item 3: the squared lags underflowed to 0 and the line fit divided by it (ZeroDivisionError).
    t = np.repeat(np.arange(n_scans) * dt, 3)
    X = pd.DataFrame({"x": np.tile([0.0, 0.1, 0.2], n_scans), "y": 0.0, "v_r": 5.0, "t": t})
    X = pd.concat([X, X.assign(x=X["x"] + 0.5, t=X["t"] + 0.05)], ignore_index=True)
    stage1 = RadarDBSCAN(metric="xy", eps_xy=0.15, min_samples=2, vr_min=-np.inf, eps_t=0.01)
    for unknown in ("reject", "accept"):
        labels = ClusterMerger(stage1=stage1, unknown_velocity=unknown).fit_predict(X)
        assert len(labels) == len(X)


def test_track_continuation_of_scans_closer_than_1e_154_s_is_unknown():
    from sklearn_radar.cluster._merge_kernels import cluster_runs, track_continuation

    t = np.array([0.0, 1e-160, 2e-160])
    runs = cluster_runs(np.zeros(3, dtype=np.int64), np.array([0.0, 1.0, 2.0]), np.zeros(3), t)
    _, centre, velocity = track_continuation(runs, 0, 1.0)
    np.testing.assert_array_equal(centre, [2.0, 0.0])
    assert not np.isfinite(velocity).all()
