"""OnlinePipeline with the learned grouping (a fitted causal LinkClustering): offline causal labels, scan by scan."""

import numpy as np
import pandas as pd
import pytest
from sklearn.pipeline import Pipeline

from sklearn_radar import DopplerDensityFilter, FrameTransform, instance_target
from sklearn_radar.cluster import LinkClustering
from sklearn_radar.cluster._causal_agglomeration import live_clusters
from sklearn_radar.datasets import make_scenes
from sklearn_radar.online import OnlinePipeline, Tracker
from sklearn_radar.online._replay import replay

#: Fixed thresholds: a cheap fit.
LINK = {"link_threshold": 0.5, "objectness_threshold": 0.3, "min_cluster_size": 3, "max_iter": 15, "causal": True}


def _pipeline(**link):
    return Pipeline(
        [("frame", FrameTransform()), ("filter", DopplerDensityFilter()), ("link", LinkClustering(**{**LINK, **link}))]
    )


@pytest.fixture(scope="module")
def fitted():
    scenes = make_scenes(n_sequences=2, duration=3.0, difficulty="realistic", random_state=0)
    y = instance_target(scenes.data["track_id"], scenes.data["sequence"])
    return _pipeline().fit(scenes.data, y)


@pytest.fixture(scope="module")
def recording():
    """Three sequences of four unsynchronised sensors, their scans interleaved when replayed."""
    scenes = make_scenes(n_sequences=3, duration=2.5, difficulty="realistic", random_state=7)
    assert scenes.data["sensor_id"].nunique() > 1
    return scenes.data


def _same_partition(a, b):
    a, b = np.asarray(a), np.asarray(b)
    np.testing.assert_array_equal(a < 0, b < 0)
    clustered = a >= 0
    pairs = set(zip(a[clustered].tolist(), b[clustered].tolist(), strict=True))
    assert len(pairs) == len(set(a[clustered].tolist())) == len(set(b[clustered].tolist()))


def test_online_ids_resolved_through_the_aliases_equal_offline_causal_predict(fitted, recording):
    online = OnlinePipeline(fitted)
    replayed = replay(online, recording)
    offline = online.causal_pipeline()
    expected = offline.predict(recording)
    keep = offline[:-1].transform(recording)["keep"].to_numpy()
    np.testing.assert_array_equal(replayed["keep"], keep)
    assert (expected >= 0).sum() > 100
    assert replayed["aliases"]  # older clusters merged while streaming
    _same_partition(replayed["object_ids"], expected)


@pytest.mark.parametrize(
    "limit",
    [
        {"max_links_per_detection": 2},  # leaves links out
        {"max_extent": 4.0},  # refuses merges
        {"cluster_window": 0.5},  # links from the clusters so far (a window longer than the pair window)
        {"cluster_window": 0.1, "max_extent": 4.0},  # (shorter)
    ],
)
def test_a_limited_model_streams_as_offline_predict(recording, limit):
    scenes = make_scenes(n_sequences=2, duration=3.0, difficulty="realistic", random_state=0)
    y = instance_target(scenes.data["track_id"], scenes.data["sequence"])
    limited = _pipeline(**limit).fit(scenes.data, y)
    online = OnlinePipeline(limited)
    replayed = replay(online, recording)
    expected = online.causal_pipeline().predict(recording)
    assert (expected >= 0).sum() > 100
    _same_partition(replayed["object_ids"], expected)
    unlimited = _pipeline().fit(scenes.data, y).predict(recording)
    assert not np.array_equal(expected, unlimited)  # the limit changes the clusters


def test_ids_are_unique_across_sequences_and_the_older_survives(fitted, recording):
    replayed = replay(OnlinePipeline(fitted), recording)
    ids, sequence = replayed["reported"], recording["sequence"].to_numpy()
    clustered = ids >= 0
    assert len(set(zip(ids[clustered].tolist(), sequence[clustered].tolist(), strict=True))) == len(
        set(ids[clustered].tolist())
    )
    assert all(kept < merged for _, kept, merged, reason in replayed["aliases"])
    assert {reason for *_, reason in replayed["aliases"]} == {"learned"}
    retired_at = {merged: us for us, _, merged, _ in replayed["aliases"]}
    stamps = recording["timestamp"].to_numpy()
    for merged, us in retired_at.items():  # an alias is never given again
        assert not np.any((ids == merged) & (stamps > us))


def test_confirmed_detections_have_a_cluster_of_min_cluster_size(fitted, recording):
    replayed = replay(OnlinePipeline(fitted), recording)
    assert np.all(replayed["reported"][replayed["confirmed"]] >= 0)
    assert (replayed["reported"] >= 0).sum() > replayed["confirmed"].sum()  # the first detections wait


def test_object_list_and_tracker(fitted, recording):
    one = recording[recording["sequence"] == recording["sequence"].iloc[0]]
    replayed = replay(OnlinePipeline(fitted), one, objects=True)
    table = replayed["objects"]
    assert table is not None and len(table)
    assert set(table["object_id"]) <= set(replayed["reported"][replayed["reported"] >= 0].tolist()) | set(
        kept for _, kept, _, _ in replayed["aliases"]
    )
    online = OnlinePipeline(fitted, tracker=Tracker())
    columns = {name: one[name].to_numpy() for name in one.columns if name not in ("uuid", "track_id")}
    tracked = unconfirmed = 0
    for stamp in np.unique(columns["timestamp"]):
        rows = columns["timestamp"] == stamp
        result = online.update({name: values[rows] for name, values in columns.items()}, objects=False)
        tracked += int((result.track_id >= 0).sum())
        unconfirmed += int(((result.object_ids >= 0) & ~result.confirmed).sum())
        # The Tracker follows the confirmed clusters only (the offline predict's): no track on the others.
        assert not np.any((result.track_id >= 0) & ~result.confirmed)
    assert tracked > 0 and unconfirmed > 0


def test_memory_stays_bounded(fitted):
    scenes = make_scenes(n_sequences=1, duration=6.0, difficulty="realistic", random_state=3)
    online = OnlinePipeline(fitted)
    columns = {name: scenes.data[name].to_numpy() for name in scenes.data.columns if name not in ("uuid", "track_id")}
    sequence = int(scenes.data["sequence"].iloc[0])
    held = []
    for stamp in np.unique(columns["timestamp"]):
        rows = columns["timestamp"] == stamp
        online.update({name: values[rows] for name, values in columns.items()}, objects=False)
        held.append((online._learned.retained_rows(), len(online._learned_ids.of_sequence[sequence])))
    late = np.array(held[len(held) // 2 :])
    spread = late[:, 0].max() - late[:, 0].min()
    assert late[:, 0].max() < 4 * max(np.median(late[:, 0]), 1) and spread < len(scenes.data) / 4
    live, _ = live_clusters(online._learned._windows[sequence].state)
    assert 0 < len(live) <= late[:, 1].max() + 1  # live clusters of the agglomeration: the recent ones


@pytest.mark.parametrize(
    "link, match",
    [(LinkClustering(causal=False), "causal=True"), (LinkClustering(causal=True), "not fitted")],
    ids=["not-causal", "unfitted"],
)
def test_a_non_causal_or_unfitted_model_is_refused(link, match):
    with pytest.raises(ValueError, match=match):
        OnlinePipeline(Pipeline([("frame", FrameTransform()), ("link", link)]))


def test_a_non_causal_fitted_model_is_refused_naming_causal(fitted, recording):
    y = instance_target(recording["track_id"], recording["sequence"])
    offline = _pipeline(causal=False).fit(recording, y)
    with pytest.raises(ValueError, match="causal"):
        OnlinePipeline(offline)


def test_a_scan_without_rcs_is_refused_when_the_model_reads_it(fitted, recording):
    scan = recording[recording["timestamp"] == recording["timestamp"].iloc[0]].drop(columns=["rcs"])
    with pytest.raises(ValueError, match="rcs"):
        OnlinePipeline(fitted).update(pd.DataFrame(scan))
