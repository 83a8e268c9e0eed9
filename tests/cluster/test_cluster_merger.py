"""ClusterMerger (stage 2): merges what stage 1 split, keeps different road users apart, never looks ahead."""

import importlib.util
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from sklearn_radar import ClusterMerger, RadarDBSCAN


def _load_reference():
    """The plain per-pair implementation next to this file (tests run with --import-mode=importlib)."""
    spec = importlib.util.spec_from_file_location("_merger_reference", Path(__file__).with_name("_merger_reference.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


reference = _load_reference()
STAGE1 = RadarDBSCAN(metric="xy", eps_xy=1.0, eps_vr=5.0, min_samples=2, vr_min=0.0)


def _car(times, start, velocity, sequence=1, length=4.5, width=1.8, sensor=(0.0, 0.0)):
    """Detections every 0.6 m around the outline of a car driving straight, with consistent Doppler."""
    rows = []
    along = np.linspace(-length / 2, length / 2, int(np.ceil(length / 0.6)) + 1)
    across = np.linspace(-width / 2, width / 2, int(np.ceil(width / 0.6)) + 1)
    outline = [(a, -width / 2) for a in along] + [(a, width / 2) for a in along]
    outline += [(-length / 2, c) for c in across[1:-1]] + [(length / 2, c) for c in across[1:-1]]
    for t in times:
        cx, cy = start[0] + velocity[0] * t, start[1] + velocity[1] * t
        for dx, dy in outline:
            x, y = cx + dx, cy + dy
            los = np.arctan2(y - sensor[1], x - sensor[0])
            v_r = velocity[0] * np.cos(los) + velocity[1] * np.sin(los)
            rows.append((x, y, v_r, t, sequence, los, 0.0))
    return pd.DataFrame(rows, columns=["x", "y", "v_r", "t", "sequence", "azimuth_sc", "sensor_yaw"])


SCANS = np.round(np.arange(0.0, 1.0, 0.06), 3)
AFTER_GAP = np.round(np.arange(1.3, 2.0, 0.06), 3)


def _split_by_a_gap(velocity=(10.0, 0.0)):
    return pd.concat([_car(SCANS, (20.0, 5.0), velocity), _car(AFTER_GAP, (20.0, 5.0), velocity)], ignore_index=True)


@pytest.mark.parametrize("mode", ["continuation", "velocity"])
def test_an_object_split_by_a_gap_of_300_ms_is_merged(mode):
    X = _split_by_a_gap()
    model = ClusterMerger(mode=mode, eps_d=1.0, eps_phi=0.4, eps_v=1.0, eps_t2=0.35, stage1=STAGE1).fit(X)
    assert len(set(model.stage1_labels_.tolist())) == 2  # stage 1 split it (gap > eps_t = 0.25 s)
    assert set(model.labels_.tolist()) == {0}


@pytest.mark.parametrize("eps_phi, merged", [(0.4, True), (0.25, False)])
def test_eq_6_compares_direction_and_speed_not_the_velocity_vector(eps_phi, merged):
    # After the gap the car drives on at the same speed, 10 m/s, turned by 0.3 rad: (10, 0) -> (9.553, 2.955).
    # Eq. 6: dphi = 0.3 and dv = | |v_A| - |v_B| | = 0 < eps_v = 1.0, so it merges when dphi < eps_phi.
    # (The norm of the velocity difference, 2 * 10 * sin(0.15) = 2.99 m/s, would refuse it.)
    turned = 10.0 * np.array([np.cos(0.3), np.sin(0.3)])
    start = np.array([20.0 + 10.0 * 1.3, 5.0]) - turned * 1.3  # where the first part would be at t = 1.3 s
    X = pd.concat(
        [_car(SCANS, (20.0, 5.0), (10.0, 0.0)), _car(AFTER_GAP, tuple(start), tuple(turned))], ignore_index=True
    )
    model = ClusterMerger(mode="velocity", eps_d=1.0, eps_phi=eps_phi, eps_v=1.0, eps_t2=0.35, stage1=STAGE1).fit(X)
    assert len(set(model.stage1_labels_.tolist())) == 2
    assert len(set(model.labels_.tolist())) == (1 if merged else 2)


@pytest.mark.parametrize("min_samples, merged", [(1, True), (2, True), (3, False)])
def test_min_samples_of_the_second_dbscan_counts_the_cluster_itself(min_samples, merged):
    # Two stage-1 clusters and one merge edge: each has 1 partner + itself = 2 clusters, so both are core
    # (and merge) for min_samples <= 2; for 3 neither is core and the edge merges nothing.
    X = _split_by_a_gap()
    model = ClusterMerger(
        mode="continuation", eps_d=1.0, eps_v=1.0, eps_t2=0.35, min_samples=min_samples, stage1=STAGE1
    ).fit(X)
    assert len(model.merges_) == 1
    assert len(set(model.labels_.tolist())) == (1 if merged else 2)


def test_a_long_truck_split_along_its_length_is_merged_by_velocity():
    # 3.5 m between the halves: more than the 1 m + 8 m/s x 0.25 s stage 1 can bridge over time.
    front = _car(SCANS, (27.5, 5.0), (8.0, 0.0), length=4.0)
    rear = _car(SCANS, (20.0, 5.0), (8.0, 0.0), length=4.0)
    X = pd.concat([front, rear], ignore_index=True)
    model = ClusterMerger(mode="velocity", eps_d=2.5, eps_phi=0.2, eps_v=0.5, stage1=STAGE1).fit(X)
    assert len(set(model.stage1_labels_.tolist())) == 2
    assert set(model.labels_.tolist()) == {0}


@pytest.mark.parametrize("mode", ["continuation", "velocity"])
def test_road_users_passing_within_1_5_m_at_different_velocities_stay_apart(mode):
    # The westbound car appears right beside the eastbound one at t = 0.6 s: centres 3.3 m apart,
    # 1.5 m between the cars, so distance and time allow a merge and only the velocity can refuse it.
    east = _car(SCANS, (10.0, 5.0), (10.0, 0.0))
    west = _car(SCANS[10:], (22.0, 8.3), (-10.0, 0.0))
    X = pd.concat([east, west], ignore_index=True)
    model = ClusterMerger(mode=mode, eps_d=3.5, eps_phi=0.4, eps_v=2.0, eps_t2=0.35, stage1=STAGE1).fit(X)
    assert len(set(model.labels_[: len(east)].tolist())) == 1
    assert set(model.labels_[: len(east)].tolist()).isdisjoint(model.labels_[len(east) :].tolist())


@pytest.mark.parametrize("mode", ["continuation", "velocity"])
def test_a_merge_never_uses_data_after_its_decision_time(mode):
    X = _split_by_a_gap()
    params = dict(mode=mode, eps_d=1.0, eps_phi=0.4, eps_v=1.0, eps_t2=0.35, stage1=STAGE1)
    tau = 1.3 + 0.35  # the second part starts at 1.3 s: decided with data up to tau
    before = (X["t"] <= tau).to_numpy()
    first, second = (X["t"] < 1.0).to_numpy(), ((X["t"] > 1.0) & (X["t"] <= tau)).to_numpy()
    # After tau the second part swerves away and its Doppler jumps: that must not matter.
    swerved = X.copy()
    late = ~before
    swerved.loc[late, "y"] += 20.0 * (X.loc[late, "t"] - tau)
    swerved.loc[late, "v_r"] = -15.0
    for data in (X, swerved):
        labels = ClusterMerger(**params).fit(data).labels_
        assert len(set(labels[first | second].tolist())) == 1
    without_future = ClusterMerger(**params).fit(X[before]).labels_
    assert len(set(without_future[first[before] | second[before]].tolist())) == 1


def test_unknown_velocities_are_rejected_or_accepted_as_asked():
    # The second part is a single scan: its continuation has no velocity.
    X = pd.concat([_car(SCANS, (20.0, 5.0), (10.0, 0.0)), _car([1.25], (20.0, 5.0), (10.0, 0.0))], ignore_index=True)
    params = dict(mode="continuation", eps_d=1.5, eps_v=1.0, eps_t2=0.35, stage1=STAGE1)
    rejected = ClusterMerger(unknown_velocity="reject", **params).fit(X).labels_
    accepted = ClusterMerger(unknown_velocity="accept", **params).fit(X).labels_
    assert len(set(rejected.tolist())) == 2
    assert len(set(accepted.tolist())) == 1


def test_noise_stays_noise_and_rows_stay_in_order():
    X = pd.concat(
        [
            _split_by_a_gap(),
            pd.DataFrame([(90.0, 90.0, 0.0, 0.5, 1, 0.0, 0.0)], columns=_car([0], (0, 0), (0, 0)).columns),
        ],
        ignore_index=True,
    )
    model = ClusterMerger(eps_d=1.0, eps_v=1.0, stage1=STAGE1).fit(X)
    assert model.labels_.shape == (len(X),)
    assert model.stage1_labels_[-1] == -1 and model.labels_[-1] == -1


def test_sequences_are_never_merged():
    first = _car(SCANS, (20.0, 5.0), (10.0, 0.0), sequence=1)
    second = _car(AFTER_GAP - 1.0, (20.0, 5.0), (10.0, 0.0), sequence=2)
    model = ClusterMerger(eps_d=50.0, eps_v=50.0, eps_t2=5.0, unknown_velocity="accept", stage1=STAGE1)
    labels = model.fit(pd.concat([first, second], ignore_index=True)).labels_
    assert set(labels[: len(first)].tolist()).isdisjoint(labels[len(first) :].tolist())


class _CountingDBSCAN(RadarDBSCAN):
    calls = 0

    def fit(self, X, y=None):
        type(self).calls += 1
        return super().fit(X, y)


def test_memory_runs_stage_1_once_for_many_stage_2_settings(tmp_path):
    X = _split_by_a_gap()
    stage1 = _CountingDBSCAN(metric="xy", eps_xy=1.0, eps_vr=5.0, min_samples=2, vr_min=0.0)
    _CountingDBSCAN.calls = 0
    for eps_d in (0.5, 1.0, 1.5, 2.0):
        ClusterMerger(eps_d=eps_d, stage1=stage1, memory=str(tmp_path)).fit(X)
    assert _CountingDBSCAN.calls == 1
    ClusterMerger(eps_d=1.0, stage1=stage1).fit(X)
    assert _CountingDBSCAN.calls == 2  # no memory: computed again


def test_velocity_mode_needs_the_line_of_sight_columns():
    with pytest.raises(ValueError, match="azimuth_sc"):
        ClusterMerger(mode="velocity", stage1=STAGE1).fit(_split_by_a_gap().drop(columns="azimuth_sc"))


@pytest.fixture(scope="module", params=["easy", "realistic"])
def simulated_stage1(request):
    """Two simulated sequences through frame transform, filter and a loose stage 1 (many small clusters).

    On the realistic preset stage-1 clusters start in the same scan, which checks the order of such ties.
    """
    from sklearn_radar import DopplerDensityFilter, FrameTransform
    from sklearn_radar.datasets import make_scenes

    scenes = make_scenes(n_sequences=2, duration=6.0, random_state=3, difficulty=request.param)
    X = DopplerDensityFilter().fit_transform(FrameTransform().fit_transform(scenes.data))
    stage1 = RadarDBSCAN(metric="xyv", eps_xyv=0.9, vr_scale=1.0, min_samples=2, vr_min=0.2)
    return X, stage1


@pytest.mark.parametrize("mode", ["continuation", "velocity"])
@pytest.mark.parametrize(
    "params",
    [
        dict(eps_d=0.94, eps_phi=0.403, eps_v=2.72, eps_t2=0.35, unknown_velocity="reject"),
        dict(eps_d=2.5, eps_phi=0.8, eps_v=4.0, eps_t2=1.0, unknown_velocity="accept"),
        dict(eps_d=2.0, eps_phi=0.2, eps_v=2.0, eps_t2=0.25, unknown_velocity="reject"),
    ],
)
def test_merges_equal_a_plain_per_pair_implementation(simulated_stage1, mode, params):
    X, stage1 = simulated_stage1
    model = ClusterMerger(mode=mode, stage1=stage1, **params).fit(X)
    found = {(int(s), int(a), int(b)) for s, a, b in model.merges_}
    expected = set()
    los = (X["azimuth_sc"] + X["sensor_yaw"] + X["heading"]).to_numpy()
    for sequence in np.unique(X["sequence"]):
        rows = (X["sequence"] == sequence).to_numpy()
        columns = [X[name].to_numpy()[rows] for name in ("x", "y", "t", "v_r")]
        pairs = reference.reference_merges(model.stage1_labels_[rows], *columns, los[rows], mode=mode, **params)
        expected |= {(int(sequence), a, b) for a, b in pairs}
    assert len(expected) > 0  # the comparison is not vacuous
    assert found == expected


def test_track_continuation_equals_the_numpy_cubic_and_line(simulated_stage1):
    from sklearn_radar.cluster._merge_kernels import cluster_runs, track_continuation

    X, stage1 = simulated_stage1
    rows = (X["sequence"] == X["sequence"].iloc[0]).to_numpy()
    x, y, t = (X[name].to_numpy()[rows] for name in ("x", "y", "t"))
    labels = stage1.fit(X[rows]).labels_
    runs = cluster_runs(labels, x, y, t)
    n_checked = 0
    for k, label in enumerate(runs.ids):
        member = np.flatnonzero(labels == label)
        for tau in np.unique(t[member])[:8]:  # every prefix length from 1 to 8 scans
            end, centre, velocity = track_continuation(runs, k, tau)
            ref_end, ref_centre, ref_velocity = reference.reference_continuation(member[t[member] <= tau], x, y, t)
            assert end == ref_end
            np.testing.assert_allclose(centre, ref_centre, rtol=0, atol=1e-9)
            np.testing.assert_allclose(velocity, ref_velocity, rtol=1e-7, atol=1e-7)
            n_checked += 1
    assert n_checked > 100
