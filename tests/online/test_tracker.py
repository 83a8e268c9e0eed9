"""Tracker: hand-computed tracking cases, the Kalman step against a numpy reference, input checks, the pipeline hook."""

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from sklearn_radar import FrameTransform
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import object_pipeline
from sklearn_radar.online import OnlinePipeline, Tracker, iter_scans
from sklearn_radar.online import _tracker_kernels as kernels
from sklearn_radar.online._tracker import sequence_frame

SENSOR = np.array([0.0, -30.0])  # where every detection is seen from in the hand-made scenes


def detections(centre, velocity, offsets=((-0.5, 0.0), (0.5, 0.0), (0.0, 0.5))):
    """Detections of a rigid object at ``centre`` moving at ``velocity``: x, y, Doppler and line of sight."""
    points = np.asarray(centre, dtype=float) + np.asarray(offsets, dtype=float)
    sight = points - SENSOR
    los = np.arctan2(sight[:, 1], sight[:, 0])
    v_r = velocity[0] * np.cos(los) + velocity[1] * np.sin(los)
    return points[:, 0], points[:, 1], v_r, los


def feed(tracker, t, objects):
    """One scan of several objects, each ``(centre, velocity, cluster id)``; the track id of each object's rows."""
    parts = [detections(centre, velocity) for centre, velocity, _ in objects]
    x, y, v_r, los = (np.concatenate(column) for column in zip(*parts, strict=True))
    clusters = np.concatenate([np.full(3, cluster) for _, _, cluster in objects])
    ids = tracker.update(x, y, v_r, los, t, clusters)
    return [ids[3 * k : 3 * k + 3] for k in range(len(objects))]


def one_id(ids):
    """The single id the rows of one object carry (an assertion otherwise)."""
    assert len(set(ids.tolist())) == 1, ids
    return int(ids[0])


def test_straight_line_keeps_one_id_through_changing_cluster_ids():
    # 10 m/s along x, a scan every 50 ms; the clustering gives a new id every 4 scans (as after a gap in stage 1)
    tracker = Tracker(min_hits=3)
    seen = []
    for k in range(40):
        t = 0.05 * k
        (ids,) = feed(tracker, t, [((5.0 + 10.0 * t, 0.0), (10.0, 0.0), 100 + k // 4)])
        seen.append(one_id(ids))
    assert seen[:2] == [-1, -1]  # confirmed at the third hit
    assert set(seen[2:]) == {0}
    track = tracker.tracks()
    np.testing.assert_allclose([track["vx"][0], track["vy"][0]], [10.0, 0.0], atol=0.05)


def test_confirmation_after_min_hits():
    for min_hits in (1, 2, 5):
        tracker = Tracker(min_hits=min_hits)
        seen = [one_id(feed(tracker, 0.05 * k, [((10.0, 0.0), (0.0, 0.0), 3)])[0]) for k in range(7)]
        assert seen == [-1] * (min_hits - 1) + [0] * (7 - min_hits + 1)


def test_two_crossing_objects_keep_their_ids():
    # A along x at y = 0, B along y at x = 10; both at (10, 0) at t = 1 s.  No cluster id lasts (a new id every
    # scan), so the motion model and the Doppler decide; from the sensor at (0, -30) their Doppler differs by 9 m/s.
    tracker = Tracker(min_hits=2)
    a_ids, b_ids = [], []
    for k in range(41):
        t = 0.05 * k
        a, b = feed(
            tracker, t, [((10.0 * t, 0.0), (10.0, 0.0), 2 * k), ((10.0, 10.0 * t - 10.0), (0.0, 10.0), 2 * k + 1)]
        )
        a_ids.append(one_id(a))
        b_ids.append(one_id(b))
    assert set(a_ids[1:]) == {0} and set(b_ids[1:]) == {1}


def test_occlusion_shorter_than_max_age_keeps_the_id_and_longer_ends_it():
    for gap, expected in ((8, 0), (12, 1)):  # 0.4 s and 0.6 s without the object; max_age 0.5 s
        tracker = Tracker(min_hits=1, max_age=0.5)
        ids = []
        for k in range(30):
            if 10 <= k < 10 + gap:
                tracker.update(np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0), 0.05 * k, np.zeros(0, dtype=int))
                continue
            t = 0.05 * k
            (found,) = feed(tracker, t, [((5.0 + 10.0 * t, 0.0), (10.0, 0.0), 1 if k < 10 else 2)])
            ids.append(one_id(found))
        assert set(ids[:10]) == {0}
        assert set(ids[10:]) == {expected}


def test_many_tracks_and_cluster_ids_keep_their_ids_as_the_tracker_grows():
    # 20 still objects 10 m apart with lasting cluster ids, then 20 more with a new cluster id every scan: more
    # tracks and links than a new Tracker has room for, so its arrays grow while tracks are live
    tracker = Tracker(min_hits=1)
    first = [(10.0 * k, 0.0) for k in range(20)]
    second = [(10.0 * k, 50.0) for k in range(20)]
    for scan in range(8):
        centres = first + (second if scan >= 4 else [])
        objects = [(centre, (0.0, 0.0), k if k < 20 else 1000 * scan + k) for k, centre in enumerate(centres)]
        ids = [one_id(found) for found in feed(tracker, 0.05 * scan, objects)]
        assert ids == list(range(len(centres)))
    assert tracker.n_tracks == 40
    track = tracker.tracks()
    np.testing.assert_array_equal(track["track_id"], np.arange(40))
    np.testing.assert_allclose(track["x"], [x for x, _ in first + second], atol=1e-9)
    np.testing.assert_allclose(track["y"], [y + 1 / 6 for _, y in first + second], atol=1e-9)  # the centroid
    np.testing.assert_array_equal(track["hits"], [8] * 20 + [4] * 20)


def test_split_cluster_joins_its_track():
    tracker = Tracker(min_hits=2)
    for k in range(6):
        feed(tracker, 0.05 * k, [((20.0 + 0.25 * k, 0.0), (5.0, 0.0), 4)])
    t = 0.3
    centre = 20.0 + 5.0 * t
    front = ((centre + 0.8, 0.0), (5.0, 0.0), 4)
    rear = ((centre - 0.8, 0.0), (5.0, 0.0), 9)  # the same object as a second cluster for one scan
    kept, split = feed(tracker, t, [front, rear])
    assert one_id(kept) == 0 and one_id(split) == 0
    assert tracker.n_tracks == 1


def test_a_far_cluster_starts_its_own_track():
    tracker = Tracker(min_hits=1)
    for k in range(4):
        near, far = feed(tracker, 0.05 * k, [((20.0, 0.0), (0.0, 0.0), 1), ((40.0, 0.0), (0.0, 0.0), 2 + k)])
        assert one_id(near) == 0 and one_id(far) == 1


def test_noise_within_the_radius_with_agreeing_doppler_takes_the_track_id():
    tracker = Tracker(min_hits=1, noise_radius=2.0, doppler_gate=0.5)
    for k in range(5):
        feed(tracker, 0.05 * k, [((20.0 + 0.5 * k, 0.0), (10.0, 0.0), 1)])
    t = 0.25
    x, y, v_r, los = detections((22.5 + 1.0, 0.0), (10.0, 0.0), offsets=((0.0, 0.0), (0.0, 0.0), (10.0, 0.0)))
    v_r = v_r + np.array([0.0, 3.0, 0.0])  # the second disagrees in Doppler; the third is 10 m away
    ids = tracker.update(x, y, v_r, los, t, np.array([-1, -1, -1]))
    np.testing.assert_array_equal(ids, [0, -1, -1])
    assert (Tracker(min_hits=1).update(x, y, v_r, los, 0.0, np.array([-1, -1, -1])) == -1).all()


def reference_predict(state, cov, dt, q):
    """F x and F P F^T + Q of the constant-velocity model, written with numpy matrices."""
    f = np.eye(4)
    f[0, 2] = f[1, 3] = dt
    block = q * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
    noise = np.zeros((4, 4))
    noise[np.ix_([0, 2], [0, 2])] = block
    noise[np.ix_([1, 3], [1, 3])] = block
    return f @ state, f @ cov @ f.T + noise


def reference_update(state, cov, x, y, v_r, los, r_pos, r_vr):
    """The batch Kalman update with the centroid and every Doppler stacked: x + K (z - H x), (I - K H) P."""
    h = [[1, 0, 0, 0], [0, 1, 0, 0]] + [[0, 0, np.cos(a), np.sin(a)] for a in los]
    h = np.array(h, dtype=float)
    z = np.r_[x.mean(), y.mean(), v_r]
    r = np.diag(np.r_[r_pos, r_pos, np.full(len(v_r), r_vr)])
    gain = cov @ h.T @ np.linalg.inv(h @ cov @ h.T + r)
    return state + gain @ (z - h @ state), (np.eye(4) - gain @ h) @ cov


def random_track(rng):
    state = rng.normal(0, 5, 4)
    root = rng.normal(0, 1, (4, 4))
    return state, root @ root.T + 0.5 * np.eye(4)


def test_predict_equals_the_matrix_form():
    rng = np.random.default_rng(0)
    tracks = [random_track(rng) for _ in range(3)]
    state = np.array([s for s, _ in tracks])
    cov = np.array([c for _, c in tracks])
    kernels.predict(state, cov, 3, 0.07, 4.0)
    for k, (s, c) in enumerate(tracks):
        expected_state, expected_cov = reference_predict(s, c, 0.07, 4.0)
        np.testing.assert_allclose(state[k], expected_state, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(cov[k], expected_cov, rtol=1e-10, atol=1e-12)


def test_update_equals_the_batch_kalman_update():
    rng = np.random.default_rng(1)
    tracks = [random_track(rng) for _ in range(2)]
    state = np.array([s for s, _ in tracks])
    cov = np.array([c for _, c in tracks])
    n = 7
    x, y, v_r = rng.normal(0, 5, n), rng.normal(0, 5, n), rng.normal(0, 3, n)
    los = rng.uniform(-np.pi, np.pi, n)
    track = np.array([0, 1, 0, -1, 1, 0, 1])
    count = kernels.update(state, cov, track, x, y, v_r, los, 0.8, 0.09, np.inf)
    np.testing.assert_array_equal(count, [3, 3])
    for k, (s, c) in enumerate(tracks):
        mine = track == k
        expected_state, expected_cov = reference_update(s, c, x[mine], y[mine], v_r[mine], los[mine], 0.8, 0.09)
        np.testing.assert_allclose(state[k], expected_state, rtol=1e-9, atol=1e-5)  # the transform writes float32
        np.testing.assert_allclose(cov[k], expected_cov, rtol=1e-9, atol=1e-5)  # the transform writes float32


def test_update_leaves_out_a_doppler_outlier():
    state = np.array([[0.0, 0.0, 5.0, 0.0]])
    cov = np.eye(4)[None] * 0.01
    x, y, los = np.zeros(2), np.zeros(2), np.zeros(2)
    v_r = np.array([5.0, 15.0])  # the second is 10 m/s off, far beyond 3 standard deviations
    kept = state.copy(), cov.copy()
    kernels.update(kept[0], kept[1], np.array([0, -1]), x, y, v_r, los, 1.0, 0.09, 3.0)
    both = state.copy(), cov.copy()
    kernels.update(both[0], both[1], np.array([0, 0]), x, y, v_r, los, 1.0, 0.09, 3.0)
    np.testing.assert_allclose(both[0][0, 2:], kept[0][0, 2:])  # the outlier changed nothing of the velocity


@settings(max_examples=30, deadline=None)
@given(st.lists(st.integers(0, 6), min_size=1, max_size=12), st.integers(0, 2**31 - 1))
@example([2, 3, 4, 4, 5, 5, 6, 1, 3, 2, 6], 432)  # summed in row order, a noise detection's gate test flipped
def test_rows_in_rows_out_and_row_order_does_not_matter(sizes, seed):
    rng = np.random.default_rng(seed)
    tracker, shuffled = Tracker(min_hits=1, noise_radius=2.0), Tracker(min_hits=1, noise_radius=2.0)
    for k, n in enumerate(sizes):
        x, y = rng.uniform(0, 30, n), rng.uniform(0, 30, n)
        v_r, los = rng.normal(0, 3, n), rng.uniform(-np.pi, np.pi, n)
        clusters = rng.integers(-1, 3, n)
        ids = tracker.update(x, y, v_r, los, 0.05 * k, clusters)
        assert ids.shape == (n,) and ids.dtype == np.int64
        order = rng.permutation(n)
        permuted = shuffled.update(x[order], y[order], v_r[order], los[order], 0.05 * k, clusters[order])
        np.testing.assert_array_equal(permuted, ids[order])


@pytest.mark.parametrize(
    ("params", "name"),
    [
        ({"gate": 0.0}, "gate"),
        ({"min_hits": 0}, "min_hits"),
        ({"min_hits": 2.5}, "min_hits"),
        ({"max_age": -1.0}, "max_age"),
        ({"max_age": np.inf}, "max_age"),
        ({"position_noise": 0.0}, "position_noise"),
        ({"doppler_noise": "0.3"}, "doppler_noise"),
        ({"acceleration": np.nan}, "acceleration"),
        ({"doppler_gate": -0.1}, "doppler_gate"),
        ({"noise_radius": -1.0}, "noise_radius"),
    ],
)
def test_bad_parameters_are_a_value_error_naming_them(params, name):
    with pytest.raises(ValueError, match=name):
        Tracker(**params)


def test_bad_scans_are_a_value_error():
    tracker = Tracker()
    one = np.zeros(1)
    with pytest.raises(ValueError, match="'y' has 2 values"):
        tracker.update(one, np.zeros(2), one, one, 0.0, [0])
    with pytest.raises(ValueError, match="'v_r' holds values that are not finite"):
        tracker.update(one, one, [np.nan], one, 0.0, [0])
    with pytest.raises(ValueError, match="'clusters' must hold integer"):
        tracker.update(one, one, one, one, 0.0, [0.5])
    tracker.update(one, one, one, one, 1.0, [0])
    with pytest.raises(ValueError, match="not later"):
        tracker.update(one, one, one, one, 1.0, [0])
    with pytest.raises(ValueError, match="tracker must be a Tracker"):
        OnlinePipeline(object_pipeline(causal=True), tracker="kalman")


def test_sequence_frame_equals_the_frame_transform():
    data = make_scenes(n_sequences=1, duration=1.0, random_state=3).data
    c = {
        name: data[name].to_numpy(dtype=float)
        for name in ("ego_x_seq", "ego_y_seq", "ego_yaw_seq", "azimuth_sc", "sensor_yaw")
    }
    car = FrameTransform(frame="car").fit_transform(data)
    fixed = FrameTransform(frame="frame").fit_transform(data)
    x, y, los = sequence_frame(c, car["x"].to_numpy(), car["y"].to_numpy(), "car")
    np.testing.assert_allclose(x, fixed["x"], atol=1e-5)  # the transform writes float32
    np.testing.assert_allclose(y, fixed["y"], atol=1e-5)  # the transform writes float32
    np.testing.assert_allclose(los, fixed["azimuth_sc"] + fixed["sensor_yaw"] + fixed["heading"], atol=1e-5)


def test_pipeline_without_tracker_is_unchanged_and_with_one_reports_track_ids():
    data = make_scenes(n_sequences=2, duration=3.0, random_state=0).data
    pipeline = object_pipeline(causal=True, params={"merge__min_cluster_size": 5})
    plain, tracked = OnlinePipeline(pipeline), OnlinePipeline(pipeline, tracker=Tracker(min_hits=2))
    assert plain.tracker is None
    n_tracked = 0
    for scan in iter_scans(data):
        a, b = plain.update(scan), tracked.update(scan)
        assert a.track_id is None
        for name in ("labels", "object_ids", "confirmed", "keep"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        assert a.aliases == b.aliases
        assert b.track_id.shape == (len(scan),)
        n_tracked += int((b.track_id >= 0).sum())
    assert n_tracked > 0
    assert repr(tracked).endswith("tracker=Tracker(min_hits=2))")
