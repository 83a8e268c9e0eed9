"""Mergeable per-sequence parts: combined, they give the score of the concatenated sequences (issue 14)."""

import pickle

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sklearn_radar import RadarDBSCAN
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import experiment_pipeline
from sklearn_radar.metrics import (
    instance_scores,
    panoptic_quality,
    panoptic_quality_scorer,
    radar_v_measure,
    radar_v_measure_scorer,
)
from sklearn_radar.metrics._parts import (
    FailedPart,
    InstanceParts,
    PanopticParts,
    VMeasureParts,
    combine_instance_parts,
    combine_parts,
    instance_parts,
    score_parts,
    sequence_parts,
)

TOL = dict(rel=1e-12, abs=1e-12)


def _sequence(n):
    labels = st.lists(st.integers(-1, 3), min_size=n, max_size=n)
    clusters = st.lists(st.integers(-1, 4), min_size=n, max_size=n)
    times = st.lists(st.floats(0.0, 3.0, allow_nan=False), min_size=n, max_size=n)
    shape = st.sampled_from(["random", "all background", "all noise", "one object", "one cluster"])
    return st.tuples(labels, clusters, times, shape).map(_shaped)


def _shaped(case):
    truth, pred, times, shape = case
    truth, pred, times = np.array(truth, dtype=np.int64), np.array(pred, dtype=np.int64), np.array(times)
    if shape == "all background":
        truth[:] = -1
    elif shape == "all noise":
        pred[:] = -1
    elif shape == "one object":
        truth[:] = 2
    elif shape == "one cluster":
        pred[:] = 0
    return truth, pred, times


#: 1 to 5 sequences of 0 to 25 detections; label ids overlap between sequences (they are small integers).
sequences = st.lists(st.integers(0, 25).flatmap(_sequence), min_size=1, max_size=5)


def _concatenate(seqs):
    truth = np.concatenate([s[0] for s in seqs])
    pred = np.concatenate([s[1] for s in seqs])
    times = np.concatenate([s[2] for s in seqs])
    groups = np.concatenate([np.full(len(s[0]), f"seq{i}") for i, s in enumerate(seqs)])
    return truth, pred, times, groups


@settings(max_examples=200, deadline=None)
@given(sequences, st.sampled_from([0.5, 1.0, 2.0]))
def test_v1_parts_combine_to_the_radar_v_measure_of_the_concatenation(seqs, beta):
    truth, pred, _, groups = _concatenate(seqs)
    parts = [score_parts("v1", t, p) for t, p, _ in seqs]
    assert combine_parts("v1", parts, beta=beta) == pytest.approx(
        radar_v_measure(truth, pred, groups=groups, beta=beta), **TOL
    )


@settings(max_examples=200, deadline=None)
@given(sequences, st.sampled_from([0.5, 0.25, None]))
def test_pq_parts_combine_to_the_panoptic_quality_of_the_concatenation(seqs, window):
    truth, pred, times, groups = _concatenate(seqs)
    parts = [score_parts("pq", t, p, s, window=window) for t, p, s in seqs]
    expected = panoptic_quality(truth, pred, times=times, groups=groups, window=window)
    assert combine_parts("pq", parts) == pytest.approx(expected.pq, **TOL)
    assert sum(part.tp for part in parts) == expected.tp
    assert sum(part.fp for part in parts) == expected.fp
    assert sum(part.fn for part in parts) == expected.fn


@settings(max_examples=100, deadline=None)
@given(sequences, st.sampled_from(["v1", "pq"]), st.randoms(use_true_random=False))
def test_the_order_of_the_parts_does_not_matter(seqs, objective, random):
    parts = [score_parts(objective, t, p, s) for t, p, s in seqs]
    shuffled = list(parts)
    random.shuffle(shuffled)
    assert combine_parts(objective, shuffled) == pytest.approx(combine_parts(objective, parts), **TOL)


@settings(max_examples=100, deadline=None)
@given(sequences, st.sampled_from(["v1", "pq"]))
def test_a_part_of_several_sequences_with_groups_is_their_merge(seqs, objective):
    truth, pred, times, groups = _concatenate(seqs)
    merged = score_parts(objective, truth, pred, times, groups=groups)
    separate = [score_parts(objective, t, p, s) for t, p, s in seqs]
    assert combine_parts(objective, [merged]) == pytest.approx(combine_parts(objective, separate), **TOL)


def test_background_pools_over_sequences_by_hand():
    # Each sequence: one background and one object detection, both in one cluster.
    # Per sequence h = 0 (one cluster: no information), c = 1, so V = 0 and the naive mean is 0.
    # Pooled background (2), objects A0 (1) and B0 (1), clusters A7 = {bg, A0} and B7 = {bg, B0}:
    # H(C) = 1.5 ln 2, H(C|K) = ln 2, h = 0.5 / 1.5 = 1/3; completeness over the objects is 1; V = 2 h / (h + 1) = 1/2.
    # (Background kept apart per sequence would give H(C) = 2 ln 2, h = 1/2 and V = 2/3.)
    seq = (np.array([-1, 0]), np.array([7, 7]))
    assert combine_parts("v1", [score_parts("v1", *seq)]) == 0.0
    assert combine_parts("v1", [score_parts("v1", *seq), score_parts("v1", *seq)]) == pytest.approx(0.5, **TOL)
    assert radar_v_measure([-1, 0, -1, 0], [7, 7, 7, 7], groups=[1, 1, 2, 2]) == pytest.approx(0.5, **TOL)


def test_noise_is_one_cluster_over_sequences_by_hand():
    # Each sequence: one object lost to noise.  Alone: one class and one cluster, h = c = V = 1.
    # Together: objects A0 and B0 (H(C) = ln 2) in the one pooled noise cluster: MI = 0, h = 0, c = 1, V = 0.
    seq = (np.array([0, 0]), np.array([-1, -1]))
    assert combine_parts("v1", [score_parts("v1", *seq)]) == 1.0
    assert combine_parts("v1", [score_parts("v1", *seq)] * 2) == 0.0


def test_pq_pools_the_counts_not_the_scores_by_hand():
    # A: the cluster takes 3 of the object's 4 detections and 1 background detection: TP 1, IoU 3/5, PQ 0.6.
    # B: two objects lost to noise (FN 2) and a background-only cluster (FP 1): PQ 0.  Naive mean 0.3.
    # Together: SQ = 0.6 / 1, RQ = 1 / (1 + 1/2 + 2/2) = 0.4, PQ = 0.24.
    a = score_parts("pq", [0, 0, 0, 0, -1], [7, 7, 7, -1, 7], [0.0, 0.1, 0.2, 0.3, 0.4])
    b = score_parts("pq", [0, 0, 1, 1, -1, -1], [-1, -1, -1, -1, 3, 3], [0.0, 0.1, 0.1, 0.2, 0.2, 0.3])
    assert (a.tp, a.fp, a.fn, b.tp, b.fp, b.fn) == (1, 0, 0, 0, 1, 2)
    assert a.iou_sum == pytest.approx(0.6, **TOL)
    assert combine_parts("pq", [a]) == pytest.approx(0.6, **TOL)
    assert combine_parts("pq", [b]) == 0.0
    assert combine_parts("pq", [a, b]) == pytest.approx(0.24, **TOL)


def test_an_empty_sequence_contributes_nothing():
    empty = np.array([], dtype=np.int64)
    seq = (np.array([-1, 0, 0, 1]), np.array([7, 7, 7, 8]), np.array([0.0, 0.1, 0.6, 0.7]))
    for objective in ("v1", "pq"):
        alone = combine_parts(objective, [score_parts(objective, *seq)])
        with_empty = combine_parts(
            objective, [score_parts(objective, empty, empty, empty), score_parts(objective, *seq)]
        )
        assert with_empty == pytest.approx(alone, **TOL)
    # Nothing at all: radar_v_measure of no detection is 1.0 (scikit-learn's convention), PQ 0.0 (0/0).
    assert combine_parts("v1", [score_parts("v1", empty, empty)]) == radar_v_measure(empty, empty) == 1.0
    assert combine_parts("pq", [score_parts("pq", empty, empty, empty)]) == 0.0


@pytest.mark.parametrize("objective", ["v1", "pq"])
def test_a_part_is_small_and_pickles(objective):
    rng = np.random.default_rng(0)
    n = 10_000
    truth = rng.integers(-1, 4, n)  # background and 4 objects
    pred = rng.integers(-1, 4, n)  # noise and 4 clusters
    times = np.sort(rng.uniform(0.0, 100.0, n))
    part = score_parts(objective, truth, pred, times, window=None)
    assert part.size <= 3 * 5 * 5  # at most one cell per (class, cluster) pair: independent of n
    data = pickle.dumps(part)
    assert len(data) < 2_000 < truth.nbytes
    again = pickle.loads(data)
    assert combine_parts(objective, [again, part]) == combine_parts(objective, [part, part])


def test_the_v1_part_holds_the_contingency_cells():
    part = score_parts("v1", [-1, -1, 0, 0, 0, 5], [3, -1, 3, 3, -1, -1])
    assert isinstance(part, VMeasureParts)
    cells = sorted(zip(part.true.tolist(), part.pred.tolist(), part.count.tolist(), strict=True))
    # Background row -1, noise column -1; the objects 0 and 5 and the cluster 3 get the local codes 0, 1 and 0.
    assert cells == [(-1, -1, 1), (-1, 0, 1), (0, -1, 1), (0, 0, 2), (1, -1, 1)]


def test_iou_sum_stays_out_of_the_public_scores():
    scores = instance_scores([0, 0], [1, 1], times=[0.0, 0.1])
    assert "iou_sum" not in scores
    assert isinstance(score_parts("pq", [0, 0], [1, 1], [0.0, 0.1]), PanopticParts)


class _Failing(RadarDBSCAN):
    def fit(self, X, y=None):
        raise RuntimeError("boom")


def _two_sequences():
    windows = []
    for sequence, x0 in ((1, 0.0), (2, 40.0)):
        windows.append(
            pd.DataFrame(
                {
                    "x": x0 + np.array([0.0, 0.3, 0.6, 5.0, 5.3, 20.0, 20.2]),
                    "y": 0.0,
                    "v_r": 3.0,
                    "t": [0.0, 0.1, 0.2, 0.3, 0.6, 0.7, 0.8],
                    "sequence": sequence,
                }
            )
        )
    X = pd.concat(windows, ignore_index=True)
    y = np.array([0, 0, 0, 1, 1, -1, -1] * 2)
    return X, y


@pytest.mark.parametrize(("objective", "scorer"), [("v1", radar_v_measure_scorer), ("pq", panoptic_quality_scorer)])
def test_sequence_parts_combine_to_the_scorer_of_the_whole_fold(objective, scorer):
    X, y = _two_sequences()
    estimator = RadarDBSCAN(min_samples=2)
    parts = [
        sequence_parts(estimator, X[X["sequence"] == s], y[(X["sequence"] == s).to_numpy()], objective) for s in (1, 2)
    ]
    assert not any(isinstance(part, FailedPart) for part in parts)
    expected = scorer(estimator, X, y)
    assert 0.0 < expected < 1.0
    assert combine_parts(objective, parts) == pytest.approx(expected, **TOL)


class _Fixed(RadarDBSCAN):
    """Returns the labels it was made with, whatever X."""

    def __init__(self, labels=None):
        self.labels = labels

    def fit_predict(self, X, y=None):
        return self.labels


def test_sequence_parts_reads_timestamps_in_microseconds():
    y = np.array([0, 0, 0, 0, -1, -1])
    labels = np.array([5, 5, 5, 5, 5, -1])
    t = np.array([0.0, 0.1, 0.4, 0.6, 0.7, 0.9])  # windows [0, 0.5) and [0.5, 1.0): 3 + 1 object detections
    stamps = pd.DataFrame({"timestamp": 7_000_000 + np.round(t * 1e6).astype(np.int64)})
    by_t = sequence_parts(_Fixed(labels), pd.DataFrame({"t": t}), y, "pq")
    by_stamp = sequence_parts(_Fixed(labels), stamps, y, "pq")
    expected = panoptic_quality(y, labels, times=t)
    for part in (by_t, by_stamp):
        # Window 0: {0, 1, 2} vs {0, 1, 2}; window 1: object {3}, cluster {3, 4}: IoU 1/2, not a match.
        assert (part.tp, part.fp, part.fn) == (expected.tp, expected.fp, expected.fn) == (1, 1, 1)
        assert part.iou_sum == pytest.approx(1.0, **TOL)
    # "v1" needs no time column.
    assert isinstance(sequence_parts(_Fixed(labels), pd.DataFrame({"x": t}), y, "v1"), VMeasureParts)


@pytest.mark.parametrize("objective", ["v1", "pq"])
def test_a_failing_fit_gives_a_failed_part_and_the_fold_scores_zero(objective):
    X, y = _two_sequences()
    one = X["sequence"] == 1
    good = sequence_parts(RadarDBSCAN(min_samples=2), X[one], y[one.to_numpy()], objective)
    failed = sequence_parts(_Failing(), X[~one], y[~one.to_numpy()], objective)
    assert not isinstance(good, FailedPart) and combine_parts(objective, [good]) > 0.0
    assert failed == FailedPart("RuntimeError: boom")
    assert combine_parts(objective, [good, failed]) == 0.0
    assert combine_parts(objective, [failed, good]) == 0.0


def test_bad_objective_and_empty_parts_raise():
    part = score_parts("v1", [0], [0])
    with pytest.raises(ValueError, match="objective"):
        score_parts("v2", [0], [0])
    with pytest.raises(ValueError, match="objective"):
        combine_parts("V1", [part])
    with pytest.raises(ValueError, match="objective"):
        sequence_parts(RadarDBSCAN(), *_two_sequences(), "accuracy")
    with pytest.raises(ValueError, match="parts"):
        combine_parts("v1", [])
    with pytest.raises(ValueError, match="PanopticParts"):
        combine_parts("pq", [part])
    with pytest.raises(ValueError, match="equal length"):
        score_parts("v1", [0, 1], [0])
    with pytest.raises(ValueError, match="'t'"):  # a set-up mistake: raised before any fit
        sequence_parts(_Failing(), pd.DataFrame({"x": [0.0]}), [0], "pq")


def test_beta_zero_with_zero_completeness_scores_zero():
    # One object split over two clusters: completeness 0 over the objects; the background makes h > 0.
    part = score_parts("v1", [0, 0, -1, -1], [1, 2, -1, -1])
    assert combine_parts("v1", [part], beta=0.0) == 0.0
    assert combine_parts("v1", [part], beta=1.0) == pytest.approx(radar_v_measure([0, 0, -1, -1], [1, 2, -1, -1]))


# ----------------------------------------------------------------------------------------------------------------
# Every object-level score at once: instance_parts / combine_instance_parts.
# ----------------------------------------------------------------------------------------------------------------
INSTANCE_KEYS = set(instance_scores([0], [0], times=[0.0]))


def _renumbered(seq):
    """The sequence with its objects and its clusters numbered 0, 1, ... (-1 kept): ids collide across sequences."""
    truth, pred, times = seq
    renumbered = []
    for labels in (truth, pred):
        codes = np.full(labels.shape[0], -1, dtype=np.int64)
        codes[labels != -1] = pd.factorize(labels[labels != -1])[0]
        renumbered.append(codes)
    return (*renumbered, times)


def _assert_same_scores(got, expected):
    assert set(got) == set(expected) == INSTANCE_KEYS
    for key, value in expected.items():
        if key in ("tp", "fp", "fn"):
            assert got[key] == value and isinstance(got[key], int), key
        else:
            assert got[key] == pytest.approx(value, **TOL), key


@settings(max_examples=300, deadline=None)
@given(sequences, st.sampled_from([0.5, 0.25, 2.0, None]), st.booleans())
def test_instance_parts_combine_to_the_instance_scores_of_the_concatenation(seqs, window, with_times):
    seqs = [_renumbered(seq) for seq in seqs]
    truth, pred, times, groups = _concatenate(seqs)
    parts = [instance_parts(t, p, times=s if with_times else None, window=window) for t, p, s in seqs]
    expected = instance_scores(truth, pred, times=times if with_times else None, groups=groups, window=window)
    _assert_same_scores(combine_instance_parts(parts), expected)
    # The counts of panoptic quality are those of its own part, and combine_parts("pq") takes the richer part.
    assert combine_parts("pq", parts) == pytest.approx(expected.pq, **TOL)


@settings(max_examples=100, deadline=None)
@given(sequences, st.sampled_from([0.5, None]), st.randoms(use_true_random=False))
def test_instance_parts_merge_in_any_order_and_a_part_with_groups_is_their_merge(seqs, window, random):
    seqs = [_renumbered(seq) for seq in seqs]
    truth, pred, times, groups = _concatenate(seqs)
    parts = [instance_parts(t, p, times=s, window=window) for t, p, s in seqs]
    shuffled = list(parts)
    random.shuffle(shuffled)
    merged = instance_parts(truth, pred, times=times, window=window, groups=groups)
    expected = combine_instance_parts(parts)
    _assert_same_scores(combine_instance_parts(shuffled), expected)
    _assert_same_scores(combine_instance_parts([merged]), expected)


def test_instance_parts_pool_objects_and_clusters_not_the_scores_by_hand():
    # All detections in one 0.5 s window, so segments are clusters.  Labels restart at 0 in each sequence.
    # A: object 0 (4 detections) split 2 + 2 over clusters 1 and 2: IoU 2/4 each, cover 1/2, no match (IoU > 1/2
    #    needed); object 1 (2 detections) lost to noise: cover 0.  TP 0, FP 2, FN 2; mCov 1/4, mWCov 2/6.
    # B: object 0 (2 detections) is cluster 1 exactly: TP 1, IoU 1; clusters 2 and 3 hold background only: FP 2.
    #    mCov = mWCov = 1; background shares 2/3.
    a = (np.array([0, 0, 0, 0, 1, 1]), np.array([1, 1, 2, 2, -1, -1]), np.zeros(6))
    b = (np.array([0, 0, -1, -1, -1]), np.array([1, 1, 2, 2, 3]), np.full(5, 0.1))
    part_a, part_b = instance_parts(*a[:2], times=a[2]), instance_parts(*b[:2], times=b[2])
    assert (part_a.tp, part_a.fp, part_a.fn, part_b.tp, part_b.fp, part_b.fn) == (0, 2, 2, 1, 2, 0)
    assert combine_instance_parts([part_a])["mcov"] == pytest.approx(1 / 4, **TOL)
    assert combine_instance_parts([part_a])["mwcov"] == pytest.approx(1 / 3, **TOL)
    assert combine_instance_parts([part_b])["background_cluster_share"] == pytest.approx(2 / 3, **TOL)
    # Together: three objects with covers 1/2, 0, 1 (sizes 4, 2, 2): mCov = 1.5 / 3 = 1/2 (the mean of the
    # sequences' mCov would be 5/8), mWCov = (2 + 0 + 2) / 8 = 1/2 (not 2/3).  TP 1, FP 4, FN 2: SQ 1,
    # RQ = 1 / (1 + 2 + 1) = 1/4, precision 1/5, recall 1/3.  Clusters: 2 of 5 hold background only.
    hand = dict(
        pq=0.25,
        sq=1.0,
        rq=0.25,
        precision=0.2,
        recall=1 / 3,
        tp=1,
        fp=4,
        fn=2,
        mcov=0.5,
        mwcov=0.5,
        background_segment_share=0.4,
        background_cluster_share=0.4,
    )
    _assert_same_scores(combine_instance_parts([part_a, part_b]), hand)
    _assert_same_scores(combine_instance_parts([part_b, part_a]), hand)


def test_instance_parts_count_segments_per_window_and_clusters_per_sequence_by_hand():
    # One cluster 4 over two windows: with object 0 in window 0 (a match), background only in window 1.
    part = instance_parts([0, 0, -1, -1], [4, 4, 4, 4], times=[0.0, 0.2, 0.6, 0.7])
    assert (part.n_clusters, part.n_background_clusters, part.n_background_segments) == (1, 0, 1)
    assert (part.tp, part.fp, part.fn, part.n_object_detections) == (1, 1, 0, 2)
    # The same sequence twice: 2 of the 4 segments are background-only, no cluster is.
    scores = combine_instance_parts([part, part])
    assert scores["background_segment_share"] == 0.5 and scores["background_cluster_share"] == 0.0
    assert scores["precision"] == 0.5 and scores["recall"] == 1.0


def test_instance_parts_of_nothing_and_without_objects():
    empty = np.array([], dtype=np.int64)
    nothing = instance_scores(empty, empty, times=np.array([]))
    _assert_same_scores(combine_instance_parts([]), nothing)
    _assert_same_scores(combine_instance_parts([instance_parts(empty, empty, times=np.array([]))]), nothing)
    # Background and clusters only: no ratio with an object in it can be formed (0.0), every cluster is background.
    part = instance_parts([-1, -1, -1], [0, 0, 1], times=None)
    scores = combine_instance_parts([part, part])
    assert (scores["tp"], scores["fp"], scores["fn"]) == (0, 4, 0)
    assert scores["pq"] == scores["mcov"] == scores["mwcov"] == scores["recall"] == 0.0
    assert scores["background_segment_share"] == scores["background_cluster_share"] == 1.0
    _assert_same_scores(scores, instance_scores([-1] * 6, [0, 0, 1] * 2, times=None, groups=[1, 1, 1, 2, 2, 2]))


def test_an_instance_part_is_small_and_pickles():
    rng = np.random.default_rng(0)
    n = 10_000
    truth = rng.integers(-1, 40, n)
    pred = rng.integers(-1, 60, n)
    times = np.sort(rng.uniform(0.0, 100.0, n))
    part = instance_parts(truth, pred, times=times)
    assert isinstance(part, InstanceParts) and isinstance(part, PanopticParts)
    assert part.size == 10 and part.tp + part.fn > 1_000  # ten numbers for thousands of segments
    data = pickle.dumps(part)
    assert len(data) < 500
    again = pickle.loads(data)
    assert again == part
    _assert_same_scores(combine_instance_parts([again]), instance_scores(truth, pred, times=times))


def test_combine_instance_parts_refuses_other_parts():
    with pytest.raises(ValueError, match="InstanceParts, got FailedPart: RuntimeError: boom"):
        combine_instance_parts([instance_parts([0], [0], times=None), FailedPart("RuntimeError: boom")])
    with pytest.raises(ValueError, match="PanopticParts"):
        combine_instance_parts([score_parts("pq", [0], [0])])
    with pytest.raises(ValueError, match="window"):
        instance_parts([0], [0], times=[0.0], window=0.0)
    with pytest.raises(ValueError, match="equal length"):
        instance_parts([0, 1], [0], times=None)


@pytest.fixture(scope="module")
def simulated():
    scenes = make_scenes(n_sequences=3, duration=5, random_state=0)
    X = scenes.data[[c for c in scenes.data.columns if c not in ("uuid", "track_id", "label_id")]]
    return scenes, X, X["timestamp"].to_numpy(dtype=np.float64) * 1e-6


def test_instance_parts_of_a_pipeline_fitted_per_sequence_combine_to_the_scores_of_the_whole(simulated):
    scenes, X, times = simulated
    whole = experiment_pipeline(8).fit_predict(X)
    expected = instance_scores(scenes.target, whole, times=times, groups=scenes.groups)
    parts = []
    for sequence in np.unique(scenes.groups):
        rows = scenes.groups == sequence
        labels = experiment_pipeline(8).fit_predict(X[rows])
        parts.append(instance_parts(scenes.target[rows], labels, times=times[rows]))
    assert len(parts) == 3
    assert 0.0 < expected.pq < 1.0 and 0.0 < expected.mcov < 1.0 and expected.fp > 0
    _assert_same_scores(combine_instance_parts(parts), expected)
