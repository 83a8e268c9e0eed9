"""tracking_scores against hand-computed cases and against py-motmetrics on the same per-window matches."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sklearn_radar.metrics import tracking_scores

motmetrics = pytest.importorskip("motmetrics")


def test_a_perfect_track():
    scores = tracking_scores([0, 0, 1, 1], [3, 3, 4, 4], times=[0.0, 0.6, 0.0, 0.6])
    assert scores["mota"] == 1.0 and scores["idf1"] == 1.0 and scores["id_switches"] == 0
    assert scores["n_objects"] == 4 and scores["n_windows"] == 2


def test_a_switch_a_miss_and_a_false_positive_by_hand():
    # Windows of 0.5 s: object 0 is tracked as 5, then as 6 (a switch), then missed (its detections are noise);
    # a cluster 9 of background detections is a false positive in window 0.
    truth = [0, 0, 0, 0, 0, 0, -1, -1]
    pred = [5, 5, 6, 6, -1, -1, 9, 9]
    times = [0.0, 0.1, 0.6, 0.7, 1.1, 1.2, 0.0, 0.1]
    scores = tracking_scores(truth, pred, times=times)
    assert (scores["id_switches"], scores["misses"], scores["false_positives"]) == (1, 1, 1)
    assert scores["mota"] == pytest.approx(1 - 3 / 3)
    # IDF1: track 0 (3 windows) against 5 (1), 6 (1), 9 (1): the best assignment keeps one window.
    assert (scores["idtp"], scores["idfn"], scores["idfp"]) == (1, 2, 2)
    assert scores["idf1"] == pytest.approx(2 / (2 + 2 + 2))


def test_iou_at_one_half_is_not_a_match():
    # Two of four detections: IoU 2 / 4 = 0.5, which does not exceed the threshold.
    scores = tracking_scores([0, 0, 0, 0], [1, 1, -1, -1], times=[0.0] * 4)
    assert scores["n_matches"] == 0 and scores["misses"] == 1 and scores["false_positives"] == 1


def test_sequences_are_separate_tracks():
    # The same ids in two sequences: no switch, two tracks each side.
    scores = tracking_scores([0, 0], [1, 1], times=[0.0, 0.0], groups=[1, 2])
    assert scores["n_objects"] == 2 and scores["idtp"] == 2 and scores["id_switches"] == 0


def motmetrics_scores(labels_true, labels_pred, times, groups, window):
    """The reference: py-motmetrics fed, window by window, 1 - IoU where IoU > 0.5 (else no match)."""
    labels_true, labels_pred = np.asarray(labels_true), np.asarray(labels_pred)
    times, groups = np.asarray(times, dtype=float), np.asarray(groups)
    accumulator = motmetrics.MOTAccumulator(auto_id=False)
    window_id = 0
    for sequence in np.unique(groups):
        mine = groups == sequence
        index = np.floor((times - times[mine].min()) / window).astype(int)
        for f in np.unique(index[mine]):
            rows = mine & (index == f)
            gt = sorted(set(labels_true[rows][labels_true[rows] >= 0].tolist()))
            hyp = sorted(set(labels_pred[rows][labels_pred[rows] >= 0].tolist()))
            distance = np.full((len(gt), len(hyp)), np.nan)
            for i, g in enumerate(gt):
                for j, h in enumerate(hyp):
                    a, b = rows & (labels_true == g), rows & (labels_pred == h)
                    iou = (a & b).sum() / (a | b).sum()
                    if iou > 0.5:
                        distance[i, j] = 1.0 - iou
            accumulator.update(
                [int(sequence) * 100_000 + g for g in gt],
                [int(sequence) * 100_000 + h for h in hyp],
                distance,
                window_id,
            )
            window_id += 1
    summary = motmetrics.metrics.create().compute(
        accumulator, metrics=["mota", "idf1", "num_switches", "num_misses", "num_false_positives"]
    )
    return summary.iloc[0].to_dict()


def assert_like_motmetrics(truth, pred, times, groups, window=0.5):
    ours = tracking_scores(truth, pred, times=times, groups=groups, window=window)
    reference = motmetrics_scores(truth, pred, times, groups, window)
    assert ours["id_switches"] == reference["num_switches"]
    assert ours["misses"] == reference["num_misses"]
    assert ours["false_positives"] == reference["num_false_positives"]
    np.testing.assert_allclose(ours["mota"], reference["mota"], rtol=1e-12)
    np.testing.assert_allclose(ours["idf1"], reference["idf1"], rtol=1e-12)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.tuples(st.integers(-1, 3), st.integers(-1, 4), st.integers(0, 5), st.integers(0, 1)),
        min_size=1,
        max_size=60,
    )
)
def test_equals_motmetrics_on_random_tables(rows):
    truth, pred, tenth, groups = (np.array(column) for column in zip(*rows, strict=True))
    if not (truth >= 0).any():
        return  # MOTA is undefined without a ground-truth object
    assert_like_motmetrics(truth, pred, tenth * 0.2, groups)


def test_equals_motmetrics_on_the_online_ids_of_a_simulated_recording():
    from sklearn_radar.datasets import make_scenes
    from sklearn_radar.experiments import experiment_pipeline
    from sklearn_radar.online import OnlinePipeline
    from sklearn_radar.online._replay import replay

    scenes = make_scenes(n_sequences=2, duration=4.0, random_state=1)
    ids = replay(OnlinePipeline(experiment_pipeline(13)), scenes.data)["object_ids"]
    times = scenes.data["timestamp"].to_numpy() * 1e-6
    assert_like_motmetrics(scenes.target, ids, times, scenes.data["sequence"].to_numpy())
