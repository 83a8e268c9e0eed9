"""OnlinePipeline: scan by scan, the offline causal pipeline's labels exactly; persistent ids; the object list."""

import json

import numpy as np
import pandas as pd
import pytest
from sklearn.pipeline import Pipeline, make_pipeline

from sklearn_radar import ClusterMerger, DopplerDensityFilter, FrameTransform, RadarDBSCAN
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import experiment_pipeline, paper_params
from sklearn_radar.experiments._saved import load_params
from sklearn_radar.online import OnlinePipeline, Tracker


def scans_in_time_order(data):
    """Row positions of each scan (a time of a sequence, any sensors), all sequences interleaved by timestamp."""
    order = np.lexsort((data["sequence"].to_numpy(), data["timestamp"].to_numpy()))
    keys = data[["timestamp", "sequence"]].to_numpy()[order]
    cut = np.flatnonzero(np.any(np.diff(keys, axis=0) != 0, axis=1)) + 1
    return np.split(order, cut)


def replay(online, data):
    """Stage-1 labels, keep flags, object ids as reported, every alias and every stage-2 merge of a replay."""
    columns = {name: data[name].to_numpy() for name in data.columns if name not in ("uuid", "track_id")}
    labels = np.full(len(data), -2)
    object_ids = np.full(len(data), -2)
    keep = np.zeros(len(data), dtype=bool)
    aliases, merges = [], []
    for rows in scans_in_time_order(data):
        result = online.update({name: values[rows] for name, values in columns.items()}, objects=False)
        labels[rows], object_ids[rows], keep[rows] = result.labels, result.object_ids, result.keep
        aliases += result.aliases
        merges += result.joins
    end = online.finish()
    return labels, object_ids, keep, aliases + end.aliases, merges + end.joins


def stage2_resolution(labels, merges):
    """Each stage-1 label's cluster after the stage-2 merges (a union-find written for the test)."""
    parent = {}

    def find(label):
        while parent.get(label, label) != label:
            label = parent[label]
        return label

    for a, b in merges:
        parent[find(b)] = find(a)
    return np.array([find(label) if label >= 0 else -1 for label in labels.tolist()])


def assert_same_partition(a, b):
    """Equal noise and a one-to-one map between the cluster ids of a and b."""
    a, b = np.asarray(a), np.asarray(b)
    np.testing.assert_array_equal(a < 0, b < 0)
    clustered = a >= 0
    pairs = set(zip(a[clustered].tolist(), b[clustered].tolist(), strict=True))
    assert len(pairs) == len(set(a[clustered].tolist())) == len(set(b[clustered].tolist()))


def assert_online_equals_offline(online, data):
    """Replay ``data``: keep flags, stage-1 labels and stage-2 clusters equal the offline causal pipeline's.

    Returns the stage-2 joins of the replay.
    """
    labels, _, keep, _, joins = replay(online, data)
    offline_keep, offline_stage1, offline_final = offline_causal(online, data)
    np.testing.assert_array_equal(keep, offline_keep)
    assert_same_partition(labels, offline_stage1)
    assert_same_partition(stage2_resolution(labels, joins), offline_final)
    return labels, joins, offline_final


def offline_causal(online, data):
    """(keep, stage-1 labels, final labels) of the offline causal pipeline."""
    pipeline = online.causal_pipeline()
    final_labels = pipeline.fit_predict(data)
    final = pipeline.steps[-1][1]
    steps = [step for _, step in pipeline.steps[:-1] if step != "passthrough"]
    keep = np.ones(len(data), dtype=bool)
    if len(steps) == 2:
        keep = make_pipeline(*steps).fit_transform(data)["keep"].to_numpy()
    return keep, getattr(final, "stage1_labels_", final.labels_), final_labels


TUNED = {  # settings that merge often, so that the comparison sees many decisions
    12: {"merge__eps_d": 2.0, "merge__eps_phi": 0.8, "merge__eps_v": 2.5, "merge__unknown_velocity": "accept"},
    13: {"merge__eps_d": 2.5, "merge__eps_v": 4.0, "merge__unknown_velocity": "accept"},
}


@pytest.mark.parametrize("difficulty", ["realistic", "easy"])
@pytest.mark.parametrize(
    "number, params",
    [(1, None), (8, None), (12, None), (13, None), (12, TUNED[12]), (13, TUNED[13])],
    ids=["1", "8", "12-velocity", "13-continuation", "12-tuned", "13-tuned"],
)
def test_online_equals_offline_causal(difficulty, number, params):
    data = make_scenes(n_sequences=3, duration=5.0, random_state=number, difficulty=difficulty).data
    _, merges, _ = assert_online_equals_offline(OnlinePipeline(experiment_pipeline(number, params=params)), data)
    if number in (12, 13) and params is not None:
        assert len(merges) > 0  # the comparison covered merges


@pytest.mark.parametrize("min_samples", [3, 4])  # 2 is 1: a cluster with a partner is core
@pytest.mark.parametrize("number", [12, 13], ids=["velocity", "continuation"])
def test_stage2_min_samples_above_one_equals_offline_causal(number, min_samples):
    """The DBSCAN over clusters with N_min > 1: the joins, made once certain, give the offline causal clusters.

    Three sequences interleaved scan by scan, four sensors out of phase (the simulator's default).
    """
    data = make_scenes(n_sequences=3, duration=6.0, random_state=number, difficulty="realistic").data
    params = {**TUNED[number], "merge__min_samples": min_samples}
    labels, _, offline_final = assert_online_equals_offline(
        OnlinePipeline(experiment_pipeline(number, params=params)), data
    )
    # The case is one where N_min matters: the offline clusters differ from those of every accepted pair joined.
    paper = OnlinePipeline(experiment_pipeline(number, params=TUNED[number]))
    _, _, _, _, all_pairs = replay(paper, data)
    assert len(set(stage2_resolution(labels, all_pairs).tolist())) < len(set(offline_final.tolist()))


def targets_scan(t_s, ys):
    """One scan of several targets at the heights ``ys`` (m), each as :func:`target_scan` moving along x at 5 m/s."""
    parts = [target_scan(t_s, 5.0 * t_s, y=y) for y in ys]
    return {name: np.concatenate([part[name] for part in parts]) for name in parts[0]}


def test_a_non_core_cluster_joins_its_first_core_partner():
    """min_samples 3: A (y = 10 m) then, 0.3 s later, B (10 m) and C (11.2 m); 0.3 s after them D (12 m).

    A, B, C are partners of each other (within eps_d = 1.5 m): cores.  D continues C only (B's
    continuation is 2 m away): not core, it joins C's object.  Stage 1 (eps_xy 1 m) keeps them apart.
    """
    stage1 = RadarDBSCAN(metric="xy", eps_xy=1.0, min_samples=2, vr_min=0.1)
    merger = ClusterMerger(stage1=stage1, eps_d=1.5, eps_t2=0.35, min_samples=3, unknown_velocity="accept")
    online = OnlinePipeline(make_pipeline(FrameTransform(), merger))
    times = np.round(np.arange(0.0, 3.2, 0.05), 2)
    heights = {0: [10.0], 1: [10.0, 11.2], 2: [12.0]}
    phase = np.select([times < 1.0, (times > 1.22) & (times < 2.0), times > 2.22], [0, 1, 2], -1)  # gaps 0.3 s
    scans = [targets_scan(t, heights[k]) for t, k in zip(times, phase, strict=True) if k >= 0]
    data = pd.DataFrame({name: np.concatenate([scan[name] for scan in scans]) for name in scans[0]}).assign(sequence=0)
    offline = online.causal_pipeline().fit_predict(data)
    labels, _, _, _, joins = replay(online, data)
    assert_same_partition(stage2_resolution(labels, joins), offline)
    assert len(np.unique(labels)) == 4 and len(np.unique(offline)) == 1  # four stage-1 clusters, one object
    work = online.causal_pipeline()[:-1].fit_transform(data)
    alone = online.causal_pipeline()[-1].set_params(min_samples=5).fit(work)  # no cluster has 4 partners
    assert len(np.unique(alone.labels_)) == 4  # so the one object above needed the cores and D's join


def test_sensors_in_phase_and_scans_sharing_a_time():
    """Several sensors' scans at the same timestamp (in phase) give the offline labels too."""
    data = make_scenes(n_sequences=2, duration=5.0, random_state=5, difficulty="realistic").data.copy()
    data["timestamp"] = data["timestamp"] // 40_000 * 40_000  # 40 ms grid: sensors share scan times
    assert data.groupby(["sequence", "timestamp"])["sensor_id"].nunique().max() > 1
    assert_online_equals_offline(OnlinePipeline(experiment_pipeline(13, params=TUNED[13])), data)


def test_ids_never_reused_and_the_older_survives():
    data = make_scenes(n_sequences=2, duration=6.0, random_state=2, difficulty="realistic").data
    online = OnlinePipeline(experiment_pipeline(13, params=TUNED[13]))
    labels, object_ids, _, aliases, _ = replay(online, data)
    assert aliases and all(kept < merged for _, kept, merged, _ in aliases)
    assert {reason for *_, reason in aliases} == {"stage1", "stage2"}
    retired_at = {merged: us for us, _, merged, _ in aliases}
    timestamps = data["timestamp"].to_numpy()
    for merged, us in retired_at.items():  # a merged id is never reported after its merge
        assert not np.any((object_ids == merged) & (timestamps > us))
    # A new object's id is a stage-1 id never seen before: each scan's new ids exceed every earlier id.
    seen = {-1}
    for rows in scans_in_time_order(data):
        new = set(labels[rows].tolist()) - seen
        assert not new or min(new) > max(seen)
        seen |= new


def test_a_scan_older_than_its_sensor_raises():
    data = make_scenes(n_sequences=1, duration=1.0, random_state=0).data
    scans = [data.iloc[rows] for rows in scans_in_time_order(data)]
    online = OnlinePipeline(experiment_pipeline(8))
    online.update(scans[0])
    online.update(scans[5])
    with pytest.raises(ValueError, match="older than"):
        online.update(scans[1])
    with pytest.raises(ValueError, match="has the time of"):
        online.update(scans[5])
    with pytest.raises(ValueError, match="not one scan"):
        online.update(pd.concat([scans[6], scans[7]]))
    with pytest.raises(ValueError, match="lacks the column"):
        online.update(scans[6].drop(columns="vr"))


@pytest.mark.parametrize(
    "pipeline, match",
    [
        (make_pipeline(FrameTransform(), RadarDBSCAN(eps_t=None)), "eps_t"),
        (make_pipeline(FrameTransform(), RadarDBSCAN(cluster_vr_min=0.2)), "cluster_vr_min"),
        (make_pipeline(FrameTransform(), ClusterMerger(cluster_vr_min=0.2)), "cluster_vr_min"),
        (make_pipeline(DopplerDensityFilter(), RadarDBSCAN()), "FrameTransform"),
    ],
)
def test_pipelines_that_cannot_stream_are_refused(pipeline, match):
    with pytest.raises(ValueError, match=match):
        OnlinePipeline(pipeline)


def test_the_repr_shows_the_pipeline_and_rebuilds_it():
    pipeline = experiment_pipeline(13, params=TUNED[13])
    text = repr(OnlinePipeline(pipeline))
    assert text.startswith("OnlinePipeline(pipeline=Pipeline(steps=[('frame', FrameTransform()),")
    assert "eps_d=2.5" in text and "unknown_velocity='accept'" in text  # the parameters set
    namespace = {
        "OnlinePipeline": OnlinePipeline,
        "Pipeline": Pipeline,
        "FrameTransform": FrameTransform,
        "DopplerDensityFilter": DopplerDensityFilter,
        "ClusterMerger": ClusterMerger,
        "RadarDBSCAN": RadarDBSCAN,
    }
    rebuilt = eval(text, namespace)  # the repr is Python that rebuilds it
    assert repr(rebuilt.pipeline.get_params(deep=True)) == repr(pipeline.get_params(deep=True))


def test_from_params_records_the_experiment_it_took(tmp_path):
    stage1 = {key.split("__", 1)[1]: value for key, value in paper_params(8).items()}
    saved = {
        "best": "13",
        "experiments": {
            "8": {"experiment": 8, "v1_test": 0.4, "params": paper_params(8), "stage1_params": None},
            "13": {"experiment": 13, "v1_test": 0.5, "params": paper_params(13), "stage1_params": stage1},
        },
    }
    path = tmp_path / "params.json"
    path.write_text(json.dumps(saved))
    assert OnlinePipeline.from_params(path, experiment=8).experiment == 8
    assert OnlinePipeline.from_params(path, experiment=13).experiment == 13
    assert OnlinePipeline.from_params(path).experiment == load_params(path)["experiment"]  # the run's choice
    assert OnlinePipeline(experiment_pipeline(8)).experiment is None
    assert OnlinePipeline.from_params(path).tracker is None
    tracked = OnlinePipeline.from_params(path, experiment=8, tracker=Tracker(min_hits=2))
    assert tracked.tracker.min_hits == 2 and tracked.experiment == 8


def target_scan(t_s, x_centre, speed=5.0, y=10.0):
    """Three detections of a target at (x_centre, y) moving along x at ``speed`` m/s; sensor and car at rest."""
    x = x_centre + np.array([-0.4, 0.0, 0.4])
    yy = np.full(3, y)
    los = np.arctan2(yy, x)
    zeros = np.zeros(3)
    return {
        "range_sc": np.hypot(x, yy),
        "azimuth_sc": los,
        "vr": speed * np.cos(los),
        "timestamp": np.full(3, round(t_s * 1e6)),
        **{name: zeros for name in ("sensor_x", "sensor_y", "sensor_yaw", "ego_x_seq", "ego_y_seq")},
        **{name: zeros for name in ("ego_yaw_seq", "ego_vx", "ego_yaw_rate")},
    }


def occluded_track(gap_s):
    """Object ids of a target seen for 1 s, unseen for ``gap_s`` s between two scans, then seen for 1 s (50 ms)."""
    stage1 = RadarDBSCAN(metric="xy", eps_xy=1.0, min_samples=2, vr_min=0.1)
    online = OnlinePipeline(make_pipeline(FrameTransform(), ClusterMerger(stage1=stage1, eps_d=1.5)))
    times = np.r_[np.arange(0.0, 0.96, 0.05), np.arange(0.95 + gap_s, 1.95 + gap_s, 0.05)]
    ids = [online.update(target_scan(t, 5.0 * t)).object_ids for t in times]
    return times, np.array(ids)


def test_occlusion_shorter_than_eps_t2_keeps_the_id():
    """A gap of 0.3 s (> eps_t, < eps_t2 = 0.35 s): a new stage-1 cluster, aliased to the old id by stage 2."""
    times, ids = occluded_track(0.3)
    before, after = ids[times < 1.0], ids[times > 1.0]
    assert len(np.unique(before)) == 1
    assert after[0, 0] != before[0, 0]  # the new cluster starts as a new object ...
    assert np.all(after[-1] == before[0, 0])  # ... and becomes the old one when stage 2 decides the pair


def test_occlusion_longer_than_eps_t2_gives_a_new_id():
    times, ids = occluded_track(0.6)
    before, after = ids[times < 1.0], ids[times > 1.0]
    assert len(np.unique(before)) == 1 and len(np.unique(after)) == 1
    assert after[0, 0] > before[0, 0]  # a new id, never an old one reused


def test_object_list_of_a_hand_made_target():
    stage1 = RadarDBSCAN(metric="xy", eps_xy=1.0, min_samples=2, vr_min=0.1)
    online = OnlinePipeline(make_pipeline(FrameTransform(), stage1))
    for t in np.arange(0.0, 0.5, 0.05):
        result = online.update(target_scan(t, 2.0 + 5.0 * t, y=5.0))  # near: the lines of sight spread
    objects = result.objects
    assert len(objects) == 1
    # The window holds the scans of the last eps_t = 0.25 s: 0.20 .. 0.45 s, six scans of three detections.
    window_times = np.arange(0.20, 0.46, 0.05)
    assert objects.n_detections[0] == 3 * len(window_times)
    np.testing.assert_allclose(objects.x[0], np.mean(2.0 + 5.0 * window_times), rtol=1e-9)
    np.testing.assert_allclose(objects.y[0], 5.0)
    np.testing.assert_allclose(objects.extent_x[0], 5.0 * (0.45 - 0.20) + 0.8, rtol=1e-9)
    assert objects.velocity_known[0]
    np.testing.assert_allclose([objects.vx[0], objects.vy[0]], [5.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(objects.age[0], 0.45)
    assert objects.last_update[0] == 450_000
    frame = objects.to_frame()
    assert list(frame.columns)[:3] == ["object_id", "sequence", "x"] and len(frame) == 1


def test_the_windows_keep_a_bounded_span_of_time():
    """Memory stays flat: no window keeps detections older than its span, however long the stream runs."""
    data = make_scenes(n_sequences=1, duration=12.0, random_state=7, difficulty="realistic").data
    online = OnlinePipeline(experiment_pipeline(13))
    eps_t, eps_t2 = 0.25, float(online._merger.eps_t2)
    # The oldest undecided cluster is at most eps_t2 + eps_t (+ one scan gap) old; before it, stage 2 keeps the
    # rows of eps_t (the object list) and the scan centres of eps_t2 + 4 eps_t (the continuation's five last
    # scans), each + 0.05 s: bounds that do not grow with the recording.
    pending = eps_t2 + eps_t + 0.1
    bounds = {
        "rows": eps_t + 0.05 + pending,
        "tracks": eps_t2 + 4 * eps_t + 0.05 + pending,
        "stage 1": eps_t + 0.05,
    }  # stage 1 prunes at scans with active rows
    columns = {name: data[name].to_numpy() for name in data.columns if name not in ("uuid", "track_id")}
    spans = {name: [] for name in bounds}
    for rows in scans_in_time_order(data):
        online.update({name: values[rows] for name, values in columns.items()}, objects=False)
        now = columns["timestamp"][rows[0]] * 1e-6
        state = online._sequences[int(columns["sequence"][rows[0]])]
        kept = {
            "rows": state.merge.rows["t"],
            "tracks": state.merge.tracks["t"],
            "stage 1": online._stage1._windows[float(columns["sequence"][rows[0]])].points.t,
        }
        for name, times in kept.items():
            spans[name].append(now - times.min() if len(times) else 0.0)
        assert len(online._ids.root) <= len(state.merge.clusters) + len(online._stage1._windows)
    for name, bound in bounds.items():
        assert max(spans[name]) <= bound + 1e-9, name
        assert max(spans[name]) > 0.5 * bound, name  # the check sees windows that do fill


def test_confirmation_rule_equals_offline_causal():
    """min_cluster_size 10: the stage-2 clusters with the rule applied are the causal pipeline's labels."""
    from sklearn_radar._labels import drop_small_clusters

    data = make_scenes(n_sequences=3, duration=5.0, random_state=12, difficulty="realistic").data
    online = OnlinePipeline(experiment_pipeline(12, params={**TUNED[12], "merge__min_cluster_size": 10}))
    assert online.min_cluster_size == 10
    labels, _, _, _, joins = replay(online, data)
    offline = online.causal_pipeline().fit_predict(data)
    confirmed = drop_small_clusters(stage2_resolution(labels, joins), 10, data["timestamp"].to_numpy())
    assert_same_partition(confirmed, offline)
    assert 0 < np.sum(offline >= 0) < np.sum(labels >= 0)  # the rule removed detections, not all


def test_a_track_is_confirmed_at_its_min_cluster_size_th_detection():
    """Three detections per scan, min_cluster_size 7: the third scan confirms it, and only then is it listed."""
    stage1 = RadarDBSCAN(metric="xy", eps_xy=1.0, min_samples=2, vr_min=0.1)
    online = OnlinePipeline(make_pipeline(FrameTransform(), ClusterMerger(stage1=stage1, min_cluster_size=7)))
    results = [online.update(target_scan(t, 2.0 + 5.0 * t, y=5.0)) for t in (0.0, 0.05, 0.1, 0.15)]
    assert [r.confirmed.tolist() for r in results] == [[False] * 3, [False] * 3, [True] * 3, [True] * 3]
    assert [len(r.objects) for r in results] == [0, 0, 1, 1]
    assert all(np.all(r.object_ids == results[0].object_ids[0]) for r in results)  # the id is given at once
