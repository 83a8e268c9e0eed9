"""Object-level metrics: hand-computed cases, a brute-force per-window matcher on random labelings, properties."""

import math
import pickle
from collections import defaultdict

import numpy as np
import pandas as pd
import pytest
from sklearn.model_selection import GridSearchCV

from sklearn_radar import RadarDBSCAN
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import experiment_pipeline
from sklearn_radar.metrics import (
    background_share,
    instance_coverage,
    instance_scores,
    make_instance_scorer,
    panoptic_quality,
    panoptic_quality_scorer,
)

FLOAT_KEYS = ("pq", "sq", "rq", "precision", "recall", "mcov", "mwcov")
SHARE_KEYS = ("background_segment_share", "background_cluster_share")
COUNT_KEYS = ("tp", "fp", "fn")
ALL_KEYS = FLOAT_KEYS + COUNT_KEYS + SHARE_KEYS

# ----------------------------------------------------------------------------------------------------------------
# Hand-computed case: one sequence starting at t = 10 s, two windows of 0.5 s, three objects.
#
# window 0, t in [10.0, 10.5):
#   rows 0-3  object 0 (|g0| = 4)   -> rows 0, 1, 2 in cluster 10, row 3 noise
#   rows 4-5  object 1 (|g1| = 2)   -> row 4 in cluster 11, row 5 in cluster 12: each IoU 1/2, exactly 0.5, no match
#   row 6     background            -> cluster 10:  g0 vs p10 = {0, 1, 2, 6}: 3 / (4 + 4 - 3) = 0.6, a match
#   row 7     background            -> cluster 13, background only
# window 1, t in [10.5, 11.0) (row 8 exactly at 10.5 s):
#   rows 8-9   object 0 (|g0'| = 2) -> cluster 10
#   rows 10-12 object 2 (|g2| = 3)  -> cluster 10, which merges both: p10' = {8..12}
#              g0' vs p10': 2 / 5 = 0.4, no match; g2 vs p10': 3 / 5 = 0.6, a match
#   row 13     background           -> cluster 13, background only again
#
# Ground-truth segments g0, g1, g0', g2: 4.  Predicted segments p10, p11, p12, p13, p10', p13': 6.
# TP = 2 (IoU 0.6 and 0.6), FP = 6 - 2 = 4, FN = 4 - 2 = 2.
# SQ = (0.6 + 0.6) / 2 = 0.6;  RQ = 2 / (2 + 4/2 + 2/2) = 0.4;  PQ = 0.24;  precision = 2/6;  recall = 2/4.
# Coverage: g0 0.6, g1 0.5, g0' 0.4, g2 0.6 -> mCov = 2.1 / 4 = 0.525;
#           mWCov = (4 * 0.6 + 2 * 0.5 + 2 * 0.4 + 3 * 0.6) / (4 + 2 + 2 + 3) = 6 / 11.
# Background: segments p13 and p13' of 6 -> 1/3;  clusters 10, 11, 12, 13: only 13 -> 1/4.
# ----------------------------------------------------------------------------------------------------------------
CASE_TRUE = np.array([0, 0, 0, 0, 1, 1, -1, -1, 0, 0, 2, 2, 2, -1])
CASE_PRED = np.array([10, 10, 10, -1, 11, 12, 10, 13, 10, 10, 10, 10, 10, 13])
CASE_TIMES = 10.0 + np.array([0.0, 0.1, 0.2, 0.3, 0.1, 0.4, 0.2, 0.49, 0.5, 0.6, 0.7, 0.8, 0.9, 0.99])
CASE_EXPECTED = {
    "pq": 0.24,
    "sq": 0.6,
    "rq": 0.4,
    "precision": 1 / 3,
    "recall": 0.5,
    "tp": 2,
    "fp": 4,
    "fn": 2,
    "mcov": 0.525,
    "mwcov": 6 / 11,
    "background_segment_share": 1 / 3,
    "background_cluster_share": 0.25,
}
# The same labels as one window (window=None):
#   g0 = rows 0-3, 8, 9 (6); g1 = {4, 5} (2); g2 = {10, 11, 12} (3).  T = 3.
#   p10 = {0, 1, 2, 6, 8, 9, 10, 11, 12} (9); p11 = {4}; p12 = {5}; p13 = {7, 13}.  P = 4.
#   g0 vs p10: 5 / (6 + 9 - 5) = 0.5, not a match; g2 vs p10: 3 / 9; g1: 1/2 with p11 and p12.  TP = 0.
#   SQ = 0 (0/0), RQ = PQ = precision = recall = 0.  FP = 4, FN = 3.
#   mCov = (1/2 + 1/2 + 1/3) / 3 = 4/9;  mWCov = (6/2 + 2/2 + 3/3) / 11 = 5/11.
#   Background: p13 of 4 segments, cluster 13 of 4 clusters -> 1/4 and 1/4.
CASE_EXPECTED_ONE_WINDOW = {
    "pq": 0.0,
    "sq": 0.0,
    "rq": 0.0,
    "precision": 0.0,
    "recall": 0.0,
    "tp": 0,
    "fp": 4,
    "fn": 3,
    "mcov": 4 / 9,
    "mwcov": 5 / 11,
    "background_segment_share": 0.25,
    "background_cluster_share": 0.25,
}


def _assert_scores(scores, expected):
    assert set(scores) == set(expected)
    for key, value in expected.items():
        if key in COUNT_KEYS:
            assert scores[key] == value and isinstance(scores[key], int), key
        else:
            assert scores[key] == pytest.approx(value, abs=1e-12), key
            assert isinstance(scores[key], float), key


def test_hand_computed_case_per_window():
    scores = instance_scores(CASE_TRUE, CASE_PRED, times=CASE_TIMES)
    _assert_scores(scores, CASE_EXPECTED)


def test_hand_computed_case_as_one_window():
    _assert_scores(instance_scores(CASE_TRUE, CASE_PRED, times=CASE_TIMES, window=None), CASE_EXPECTED_ONE_WINDOW)
    _assert_scores(instance_scores(CASE_TRUE, CASE_PRED, times=None), CASE_EXPECTED_ONE_WINDOW)


def test_the_three_functions_are_parts_of_instance_scores():
    pq = panoptic_quality(CASE_TRUE, CASE_PRED, times=CASE_TIMES)
    coverage = instance_coverage(CASE_TRUE, CASE_PRED, times=CASE_TIMES)
    share = background_share(CASE_TRUE, CASE_PRED, times=CASE_TIMES)
    assert set(pq) == {"pq", "sq", "rq", "precision", "recall", "tp", "fp", "fn"}
    assert set(coverage) == {"mcov", "mwcov"}
    assert set(share) == set(SHARE_KEYS)
    _assert_scores({**pq, **coverage, **share}, CASE_EXPECTED)


def test_background_share_without_times_is_per_sequence():
    # One window per sequence: p13 is one of the 4 clusters (and of the 4 segments).
    share = background_share(CASE_TRUE, CASE_PRED)
    assert share.background_segment_share == share.background_cluster_share == 0.25


def test_iou_exactly_one_half_is_not_a_match():
    # g = {0, 1}, p = {0}: IoU = 1/2 -> no match: TP 0, FP 1 (cluster 5), FN 1; coverage 1/2.
    scores = instance_scores([0, 0], [5, -1], times=[0.0, 0.1])
    assert (scores.tp, scores.fp, scores.fn, scores.pq) == (0, 1, 1, 0.0)
    assert scores.mcov == 0.5
    # One more detection of g in p: IoU = 2/3 > 1/2 -> a match, PQ = SQ * RQ = 2/3 * 1.
    scores = instance_scores([0, 0, 0], [5, 5, -1], times=[0.0, 0.1, 0.2])
    assert (scores.tp, scores.fp, scores.fn) == (1, 0, 0)
    assert scores.pq == pytest.approx(2 / 3)


def test_segments_never_cross_sequences():
    # Object 0 in sequences 1 and 2, one cluster id per half: per sequence each half is the whole object.
    truth, pred, times = [0, 0, 0, 0], [1, 1, 2, 2], [0.0, 0.1, 0.0, 0.1]
    per_sequence = instance_scores(truth, pred, times=times, groups=[1, 1, 2, 2])
    assert (per_sequence.pq, per_sequence.tp) == (1.0, 2)
    # Without sequences, object 0 is one segment of 4 and each cluster covers half of it: IoU 1/2, no match.
    one_sequence = instance_scores(truth, pred, times=times)
    assert (one_sequence.pq, one_sequence.tp, one_sequence.fp, one_sequence.fn) == (0.0, 0, 2, 1)
    # Equal cluster ids in two sequences are two clusters (and two segments).
    scores = instance_scores([0, 0, 1, 1], [7, 7, 7, 7], times=times, groups=["a", "a", "b", "b"])
    assert (scores.tp, scores.fp, scores.fn, scores.pq) == (2, 0, 0, 1.0)
    share = background_share([0, 0, -1, -1], [7, 7, 7, 7], groups=["a", "a", "b", "b"])
    assert share.background_cluster_share == 0.5


def test_windows_start_at_each_sequences_first_detection():
    # Sequence 1 starts at 0 s, sequence 2 at 100.3 s: with window 0.5, rows at 100.3 and 100.7 share window 0.
    scores = instance_scores([0, 0, 1, 1], [4, 4, 4, 4], times=[0.0, 0.4, 100.3, 100.7], groups=[1, 1, 2, 2])
    assert (scores.tp, scores.fp, scores.fn) == (2, 0, 0)
    # A sequence starting at 0.4 s: rows at 0.4 and 0.5 s both lie in its window 0, one segment of each kind.
    scores = instance_scores([0, 0], [4, 4], times=[0.4, 0.5], window=0.5, groups=[1, 1])
    assert (scores.tp, scores.fp, scores.fn) == (1, 0, 0)
    # Starting at 0 s: 0.4 s is in window 0 and 0.5 s in window 1, two segments of each kind, two matches.
    scores = instance_scores([0, 0, 0], [4, 4, 4], times=[0.0, 0.4, 0.5], window=0.5)
    assert (scores.tp, scores.fp, scores.fn) == (2, 0, 0)


@pytest.mark.parametrize(
    ("truth", "pred"),
    [
        ([], []),  # nothing at all
        ([-1, -1, -1], [-1, -1, -1]),  # no object, no cluster
        ([0, 0, 1], [-1, -1, -1]),  # all noise
        ([-1, -1, -1], [0, 0, 1]),  # background clustered only
    ],
    ids=["empty", "nothing", "all-noise", "background-only"],
)
def test_degenerate_input_scores_zero_and_never_nan(truth, pred):
    scores = instance_scores(truth, pred, times=np.zeros(len(truth)))
    for key in FLOAT_KEYS:
        assert scores[key] == 0.0, key
    all_background = len(pred) > 0 and max(pred) >= 0
    assert scores.background_segment_share == scores.background_cluster_share == (1.0 if all_background else 0.0)
    assert scores.fn == len(set(truth) - {-1}) and scores.fp == len(set(pred) - {-1})


def test_invalid_arrays_raise():
    with pytest.raises(ValueError, match="equal length"):
        instance_scores([0, 0], [0], times=[0.0, 0.1])
    with pytest.raises(ValueError, match="equal length"):
        instance_scores([0, 0], [0, 0], times=[0.0])
    with pytest.raises(ValueError, match="equal length"):
        instance_scores([0, 0], [0, 0], times=None, groups=[1])
    with pytest.raises(ValueError, match="finite"):
        instance_scores([0, 0], [0, 0], times=[0.0, np.nan])


# ----------------------------------------------------------------------------------------------------------------
# Brute force: segments as Python sets, a double loop over the segments of each window.
# ----------------------------------------------------------------------------------------------------------------
def _brute_force(truth, pred, times, groups, window):
    n = len(truth)
    groups = [0] * n if groups is None else list(groups)
    start = {}
    for i in range(n):
        start[groups[i]] = min(start.get(groups[i], math.inf), times[i])
    cell = [(groups[i], 0 if window is None else math.floor((times[i] - start[groups[i]]) / window)) for i in range(n)]
    true_segments, pred_segments = defaultdict(set), defaultdict(set)
    clusters = defaultdict(set)
    for i in range(n):
        if truth[i] != -1:
            true_segments[cell[i], truth[i]].add(i)
        if pred[i] != -1:
            pred_segments[cell[i], pred[i]].add(i)
            clusters[groups[i], pred[i]].add(i)
    tp_iou, cover = [], {}
    matched_true, matched_pred = set(), set()
    for g_key, g in true_segments.items():
        cover[g_key] = 0.0
        for p_key, p in pred_segments.items():
            if g_key[0] != p_key[0]:  # another window or sequence
                continue
            iou = len(g & p) / len(g | p)
            cover[g_key] = max(cover[g_key], iou)
            if iou > 0.5:
                assert g_key not in matched_true and p_key not in matched_pred  # matches are unique
                matched_true.add(g_key)
                matched_pred.add(p_key)
                tp_iou.append(iou)
    tp, n_true, n_pred = len(tp_iou), len(true_segments), len(pred_segments)
    sq = sum(tp_iou) / tp if tp else 0.0
    rq = tp / (tp + (n_pred - tp) / 2 + (n_true - tp) / 2) if n_true + n_pred else 0.0
    total = sum(len(g) for g in true_segments.values())
    background_segments = sum(all(truth[i] == -1 for i in p) for p in pred_segments.values())
    background_clusters = sum(all(truth[i] == -1 for i in c) for c in clusters.values())
    return {
        "pq": sq * rq,
        "sq": sq,
        "rq": rq,
        "precision": tp / n_pred if n_pred else 0.0,
        "recall": tp / n_true if n_true else 0.0,
        "tp": tp,
        "fp": n_pred - tp,
        "fn": n_true - tp,
        "mcov": sum(cover.values()) / n_true if n_true else 0.0,
        "mwcov": sum(len(g) * cover[k] for k, g in true_segments.items()) / total if total else 0.0,
        "background_segment_share": background_segments / n_pred if n_pred else 0.0,
        "background_cluster_share": background_clusters / len(clusters) if clusters else 0.0,
    }


def _random_case(rng):
    n = int(rng.integers(0, 70))
    n_groups = int(rng.integers(1, 4))
    truth = rng.integers(-1, rng.integers(1, 6), n)
    # Predictions: often a noisy copy of the truth (so that matches occur), sometimes independent.
    if rng.random() < 0.6:
        pred = np.where(rng.random(n) < 0.2, rng.integers(-1, 8, n), truth + 1)
        pred[(truth == -1) & (rng.random(n) < 0.5)] = -1
    else:
        pred = rng.integers(-1, rng.integers(1, 8), n)
    times = rng.uniform(0.0, 2.0, n).round(2) + rng.choice([0.0, 5.0, 1e5], n_groups)[rng.integers(0, n_groups, n)]
    groups = rng.choice(np.array([3, 7, 11]), n) if n_groups > 1 else None
    window = rng.choice(np.array([0.1, 0.25, 0.5, 1.0, np.nan]))
    return truth, pred, times, groups, None if np.isnan(window) else float(window)


def test_against_a_brute_force_matcher_on_random_labelings():
    rng = np.random.default_rng(12)
    n_matches = 0
    for _ in range(400):
        truth, pred, times, groups, window = _random_case(rng)
        scores = instance_scores(truth, pred, times=times, groups=groups, window=window)
        expected = _brute_force(truth.tolist(), pred.tolist(), times.tolist(), groups, window)
        assert set(scores) == set(expected)
        for key, value in expected.items():
            assert np.isfinite(scores[key])
            assert scores[key] == pytest.approx(value, abs=1e-12), (key, truth, pred, times, groups, window)
        n_matches += scores.tp
    assert n_matches > 500  # the cases exercise matching, not only misses


def test_random_labelings_are_invariant_to_renaming_labels_and_permuting_rows():
    rng = np.random.default_rng(3)
    for _ in range(100):
        truth, pred, times, groups, window = _random_case(rng)
        scores = instance_scores(truth, pred, times=times, groups=groups, window=window)
        # Rename: an injective map of the labels, -1 kept; strings for the clusters.
        rename_true = np.where(truth == -1, -1, 1000 - 3 * truth)
        rename_pred = np.array([-1 if p == -1 else f"cluster-{p}" for p in pred], dtype=object)
        renamed = instance_scores(rename_true, rename_pred, times=times, groups=groups, window=window)
        order = rng.permutation(len(truth))
        permuted = instance_scores(
            truth[order],
            pred[order],
            times=times[order],
            groups=None if groups is None else groups[order],
            window=window,
        )
        for key in ALL_KEYS:
            assert renamed[key] == pytest.approx(scores[key], abs=1e-12), key
            assert permuted[key] == pytest.approx(scores[key], abs=1e-12), key


def test_counts_of_sequences_add_up():
    rng = np.random.default_rng(5)
    for _ in range(50):
        truth, pred, times, _, window = _random_case(rng)
        groups = rng.integers(0, 3, len(truth))
        together = instance_scores(truth, pred, times=times, groups=groups, window=window)
        apart = [
            instance_scores(truth[groups == s], pred[groups == s], times=times[groups == s], window=window)
            for s in range(3)
        ]
        for key in COUNT_KEYS:
            assert together[key] == sum(scores[key] for scores in apart)


def test_window_none_is_one_window_per_sequence():
    rng = np.random.default_rng(8)
    for _ in range(50):
        truth, pred, times, groups, _ = _random_case(rng)
        one_window = instance_scores(truth, pred, times=times, groups=groups, window=None)
        huge_window = instance_scores(truth, pred, times=times, groups=groups, window=1e9)
        no_times = instance_scores(truth, pred, times=None, groups=groups)
        for key in ALL_KEYS:
            assert one_window[key] == pytest.approx(huge_window[key], abs=1e-12) == no_times[key]


# ----------------------------------------------------------------------------------------------------------------
# Properties on simulated scenes.
# ----------------------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def scenes():
    return make_scenes(n_sequences=2, duration=4, random_state=0)


def _times(data):
    return (data["timestamp"].to_numpy() - data["timestamp"].min()) * 1e-6


def test_a_perfect_labelling_scores_one(scenes):
    truth = scenes.target
    pred = np.where(truth == -1, -1, 3 * truth + 17)  # renamed, background left as noise
    for window in (0.5, 0.1, None):
        scores = instance_scores(truth, pred, times=_times(scenes.data), groups=scenes.groups, window=window)
        assert scores.tp > 0 and scores.fp == scores.fn == 0
        for key in FLOAT_KEYS:
            assert scores[key] == 1.0, (key, window)
        assert scores.background_segment_share == scores.background_cluster_share == 0.0


def test_clustering_background_lowers_pq_and_raises_the_background_share(scenes):
    truth, times = scenes.target, _times(scenes.data)
    perfect = np.where(truth == -1, -1, truth)
    before = instance_scores(truth, perfect, times=times, groups=scenes.groups)
    background = np.flatnonzero(truth == -1)[:5]
    pred = perfect.copy()
    pred[background] = truth.max() + 1  # one cluster of background only
    after = instance_scores(truth, pred, times=times, groups=scenes.groups)
    assert after.pq < before.pq == 1.0
    assert after.fp > before.fp == 0
    assert after.background_cluster_share > before.background_cluster_share == 0.0
    assert after.background_segment_share > before.background_segment_share == 0.0
    # Coverage ignores extra clusters.
    assert after.mcov == before.mcov == 1.0


def test_adding_a_background_cluster_never_raises_pq():
    rng = np.random.default_rng(21)
    for _ in range(100):
        truth, pred, times, groups, window = _random_case(rng)
        free = np.flatnonzero((truth == -1) & (pred == -1))
        if len(free) == 0:
            continue
        before = instance_scores(truth, pred, times=times, groups=groups, window=window)
        pred = pred.copy()
        pred[free[: rng.integers(1, len(free) + 1)]] = 99
        after = instance_scores(truth, pred, times=times, groups=groups, window=window)
        assert after.pq <= before.pq
        assert after.pq < before.pq or before.pq == 0.0
        assert after.background_cluster_share >= before.background_cluster_share
        assert after.background_cluster_share > 0.0


# ----------------------------------------------------------------------------------------------------------------
# Scorers.
# ----------------------------------------------------------------------------------------------------------------
class _AllNoise(RadarDBSCAN):
    def fit_predict(self, X, y=None):
        return np.full(len(X), -1)


class _Failing(RadarDBSCAN):
    def fit(self, X, y=None):
        raise RuntimeError("boom")


@pytest.fixture(scope="module")
def pipeline_labels(scenes):
    return experiment_pipeline(1).fit_predict(scenes.data)


def test_scorer_equals_the_function_on_fit_predict_labels(scenes, pipeline_labels):
    expected = instance_scores(
        scenes.target, pipeline_labels, times=_times(scenes.data), groups=scenes.data["sequence"].to_numpy()
    )
    assert 0.0 < expected.pq < 1.0
    assert panoptic_quality_scorer(experiment_pipeline(1), scenes.data, scenes.target) == pytest.approx(expected.pq)
    for metric, key, sign in [
        ("sq", "sq", 1),
        ("f1", "rq", 1),
        ("mwcov", "mwcov", 1),
        ("neg_background_segment_share", "background_segment_share", -1),
    ]:
        scorer = make_instance_scorer(metric)
        assert scorer(experiment_pipeline(1), scenes.data, scenes.target) == pytest.approx(sign * expected[key])


def test_scorer_reads_t_in_seconds_and_window_none_needs_no_time(scenes, pipeline_labels):
    expected = instance_scores(scenes.target, pipeline_labels, times=None, groups=scenes.groups)
    data = scenes.data.drop(columns="timestamp").assign(t=0.0)
    scorer = make_instance_scorer("recall", window=None)
    assert scorer(experiment_pipeline(1), scenes.data, scenes.target) == pytest.approx(expected.recall)
    # A 't' column is read in s: all detections at t = 0 are one window, as window=None.
    assert panoptic_quality_scorer(_Fixed(pipeline_labels), data, scenes.target) == pytest.approx(expected.pq)


class _Fixed(RadarDBSCAN):
    """Returns the labels it was made with, whatever X."""

    def __init__(self, labels=None):
        self.labels = labels

    def fit_predict(self, X, y=None):
        return self.labels


def test_scorer_never_raises_on_degenerate_output_or_failure(scenes):
    X, y = scenes.data, scenes.target
    assert panoptic_quality_scorer(_AllNoise(), X, y) == 0.0
    assert panoptic_quality_scorer(_Failing(), X, y) == 0.0
    assert panoptic_quality_scorer(_Fixed(np.zeros(3)), X, y) == 0.0  # wrong length
    assert make_instance_scorer("mcov")(_Failing(), X, y) == 0.0
    # A negated share: all noise has no background cluster (0/0 -> 0.0), a failure scores the worst value, -1.
    assert make_instance_scorer("neg_background_cluster_share")(_AllNoise(), X, y) == 0.0
    assert make_instance_scorer("neg_background_cluster_share")(_Failing(), X, y) == -1.0


def test_scorer_without_a_time_column_is_a_setup_error():
    X = pd.DataFrame({"x": [0.0, 0.3], "y": 0.0, "v_r": 3.0, "sequence": 1})
    with pytest.raises(ValueError, match=r"'t' .* or 'timestamp'"):
        panoptic_quality_scorer(_AllNoise(), X, [0, 0])
    assert make_instance_scorer(window=None)(_Fixed(np.array([4, 4])), X, [0, 0]) == 1.0


def test_scorer_pickles_and_works_in_a_search():
    X = pd.DataFrame(
        {"x": [0.0, 0.3, 5.0, 5.3, 20.0], "y": 0.0, "v_r": 3.0, "t": [0.0, 0.1, 0.0, 0.1, 0.2], "sequence": 1}
    )
    y = np.array([0, 0, 1, 1, -1])
    scorer = pickle.loads(pickle.dumps(make_instance_scorer("pq", window=0.5)))
    assert repr(scorer) == "make_instance_scorer(metric='pq', window=0.5)"
    everything = np.arange(len(X))
    search = GridSearchCV(
        RadarDBSCAN(), {"min_samples": [2, 10]}, scoring=scorer, cv=[(everything, everything)], error_score="raise"
    ).fit(X, y)
    assert search.best_params_ == {"min_samples": 2}
    assert search.best_score_ == pytest.approx(1.0)
