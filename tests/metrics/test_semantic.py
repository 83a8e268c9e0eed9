"""Semantic metrics: hand-computed cases, brute-force references on random data, invariants, the scorer."""

import math
import pickle
from collections import Counter, defaultdict

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.metrics import f1_score
from sklearn.model_selection import GroupKFold, cross_val_score
from sklearn.pipeline import make_pipeline

from sklearn_radar import DopplerDensityFilter, FrameTransform, RadarDBSCAN
from sklearn_radar.classification import ClusterClassifier, road_user_class
from sklearn_radar.datasets import make_scenes
from sklearn_radar.metrics import (
    class_panoptic_quality,
    instance_coverage,
    make_semantic_scorer,
    mean_average_precision,
    pointwise_macro_f1,
    semantic_scores,
)

# ----------------------------------------------------------------------------------------------------------------
# Hand-computed case.  Classes: car 0, large vehicle 1, two-wheeler 2, pedestrian 3, group 4, background -1,
# ignored -2.  Sequence A (rows 0-12), windows of 0.5 s from t = 0; sequence B (rows 13-15), from t = 0.1.
#
# A, window 0:
#   rows 0-3   true car instance 0 (|g| = 4); rows 0-2 predicted instance 10, class car (conf 0.9); row 3 noise
#              -> TP car, IoU 3/4
#   rows 4-5   true pedestrian instance 1; predicted instance 11 = rows 4, 5, 6 with classes 3, 3, 0 (a mixed
#              segment: majority pedestrian; row 6 is background), conf 0.8, 0.8, 0.5 -> TP pedestrian, IoU 2/3
#   row 7      ignored (-2) in truth, predicted instance 12 (car): left out, so instance 12 has no segment
# A, window 1 (t >= 0.5):
#   rows 8-10  true car instance 0 again; predicted instance 10 with class group (4), conf 0.4: IoU 1, but the
#              wrong class -> FN car, FP group
#   rows 11-12 true two-wheeler instance 3; predicted instance 13 with classes 1, 2: a tie, confidence 0.6, 0.7
#              -> class 2 (the higher summed confidence), TP two-wheeler, IoU 1.  Without confidence: class 1
#              (the smaller code) -> FP large vehicle and FN two-wheeler.
# B, window 0:
#   rows 13-14 true car instance 0 (another sequence: another object), noise in the prediction -> FN car
#   row 15     background, predicted instance 10 (car, conf 0.95): instance 10 of sequence A is never compared
#              -> FP car
#
# PQ per class: car TP 1, FP 1 (B's 10), FN 2 (A window 1, B): SQ 3/4, RQ 1 / (1 + 1/2 + 1) = 0.4, PQ 0.3;
#   two-wheeler: PQ = SQ = RQ = 1; pedestrian: SQ 2/3, RQ 1, PQ 2/3; group: TP 0, FP 1 -> 0.
#   Classes present: 0, 2, 3, 4.  PQ = (0.3 + 1 + 2/3 + 0) / 4, SQ = (0.75 + 1 + 2/3 + 0) / 4, RQ = 2.4 / 4.
# AP (classes in truth: 0, 2, 3): car ranks B's 10 (0.95, FP) before A's 10 (0.9, TP) of 3 true segments:
#   points (recall 0, precision 0), (1/3, 1/2); interpolated 1/2 at the 34 recall points 0 .. 0.33 -> 17/101.
#   Two-wheeler 1, pedestrian 1.  mAP = (17/101 + 2) / 3.
# mCov (any class): car A0 3/4, pedestrian 2/3, car A1 1 (the group segment covers it), two-wheeler 1, car B 0.
# Point-wise F1 (row 7 left out): -1: 0 (rows 6, 15 predicted car; rows 3, 13, 14 predicted -1);
#   car: 3 of 9 true and 5 predicted -> 6/14; large vehicle 0; two-wheeler 2 * 1 / (2 + 1) = 2/3; pedestrian 1;
#   group 0.  Mean over 6 classes: (3/7 + 2/3 + 1) / 6; without background over 5.
# ----------------------------------------------------------------------------------------------------------------
CASE = {
    "classes_true": [0, 0, 0, 0, 3, 3, -1, -2, 0, 0, 0, 2, 2, 0, 0, -1],
    "instances_true": [0, 0, 0, 0, 1, 1, -1, 2, 0, 0, 0, 3, 3, 0, 0, -1],
    "classes_pred": [0, 0, 0, -1, 3, 3, 0, 0, 4, 4, 4, 1, 2, -1, -1, 0],
    "instances_pred": [10, 10, 10, -1, 11, 11, 11, 12, 10, 10, 10, 13, 13, -1, -1, 10],
}
CASE_CONFIDENCE = [0.9, 0.9, 0.9, 1.0, 0.8, 0.8, 0.5, 0.7, 0.4, 0.4, 0.4, 0.6, 0.7, 1.0, 1.0, 0.95]
CASE_TIMES = [0.0, 0.1, 0.2, 0.3, 0.1, 0.2, 0.2, 0.3, 0.5, 0.6, 0.7, 0.6, 0.7, 0.1, 0.2, 0.3]
CASE_GROUPS = ["A"] * 13 + ["B"] * 3
CASE_PQ = {0: 0.3, 2: 1.0, 3: 2 / 3, 4: 0.0}
CASE_MAP = (17 / 101 + 2) / 3
CASE_MCOV = (0.75 + 2 / 3 + 1 + 1 + 0) / 5
CASE_F1 = {-1: 0.0, 0: 3 / 7, 1: 0.0, 2: 2 / 3, 3: 1.0, 4: 0.0}


def _case_args(**changes):
    return {**CASE, **changes}


def test_class_panoptic_quality_by_hand():
    scores = class_panoptic_quality(**CASE, times=CASE_TIMES, groups=CASE_GROUPS, confidence=CASE_CONFIDENCE)
    assert set(scores["per_class"]) == {0, 2, 3, 4}
    car = scores["per_class"][0]
    assert (car["tp"], car["fp"], car["fn"]) == (1, 1, 2)
    assert car["sq"] == pytest.approx(0.75) and car["rq"] == pytest.approx(0.4) and car["pq"] == pytest.approx(0.3)
    assert (scores["per_class"][4]["tp"], scores["per_class"][4]["fp"], scores["per_class"][4]["fn"]) == (0, 1, 0)
    for code, pq in CASE_PQ.items():
        assert scores["per_class"][code]["pq"] == pytest.approx(pq)
    assert scores["pq"] == pytest.approx((0.3 + 1 + 2 / 3) / 4)
    assert scores["sq"] == pytest.approx((0.75 + 1 + 2 / 3) / 4)
    assert scores["rq"] == pytest.approx(2.4 / 4)


def test_a_tie_of_the_majority_vote_goes_to_the_smallest_code_without_confidence():
    scores = class_panoptic_quality(**CASE, times=CASE_TIMES, groups=CASE_GROUPS)
    assert set(scores["per_class"]) == {0, 1, 2, 3, 4}
    large, two_wheeler = scores["per_class"][1], scores["per_class"][2]
    assert (large["tp"], large["fp"], large["fn"]) == (0, 1, 0)
    assert (two_wheeler["tp"], two_wheeler["fp"], two_wheeler["fn"]) == (0, 0, 1)
    assert scores["pq"] == pytest.approx((0.3 + 2 / 3) / 5)


def test_a_tie_of_the_ground_truth_vote_goes_to_the_smallest_code():
    # One true instance, half car half pedestrian: its class is car (0); predicted as a pedestrian, it is a miss.
    scores = class_panoptic_quality([3, 0, 3, 0], [5, 5, 5, 5], [3, 3, 3, 3], [1, 1, 1, 1], times=None)
    assert scores["per_class"][0]["fn"] == 1 and scores["per_class"][3]["fp"] == 1 and scores["pq"] == 0.0


def test_windows_and_sequences_are_never_compared():
    # One window per sequence: A's car is {0-3, 8-10}, A's 10 is {0-2, 8-10} with classes car 3 x (0.9), group 3 x
    # (0.4): a tie, car by confidence; IoU 6/7, a match.  B's car and B's 10 stay apart: FN and FP.
    scores = class_panoptic_quality(
        **CASE, times=CASE_TIMES, groups=CASE_GROUPS, window=None, confidence=CASE_CONFIDENCE
    )
    car = scores["per_class"][0]
    assert (car["tp"], car["fp"], car["fn"]) == (1, 1, 1)
    assert car["sq"] == pytest.approx(6 / 7) and 4 not in scores["per_class"]
    # Without groups B's rows join A: B's row 15 joins A's instance 10, and A's car instance 0 takes B's rows
    # 13, 14.  The scores change, so the sequences were apart above.
    merged = class_panoptic_quality(**CASE, times=CASE_TIMES, window=None, confidence=CASE_CONFIDENCE)
    assert (merged["per_class"][0]["tp"], merged["per_class"][0]["fp"], merged["per_class"][0]["fn"]) == (1, 0, 0)
    assert merged["per_class"][0]["sq"] == pytest.approx(6 / 10)


def test_ignored_rows_are_left_out_after_the_windows_are_laid_out():
    # Row 0 (ignored) starts the windows: rows 1 (t 0.45) and 2 (t 0.55) are in windows 0 and 1.  The prediction
    # covers row 1: a TP in window 0, a FN in window 1 -> PQ 1 x 1 / (1 + 1/2).  (Leaving row 0 out first would put
    # both rows in one window, IoU 1/2 and no match.)
    scores = class_panoptic_quality([-2, 0, 0], [-1, 4, 4], [0, 0, -1], [7, 7, -1], times=[0.0, 0.45, 0.55])
    assert scores["pq"] == pytest.approx(2 / 3)
    assert (scores["per_class"][0]["tp"], scores["per_class"][0]["fn"]) == (1, 1)
    # An ignored row of a predicted instance does not count in the union.
    scores = class_panoptic_quality([0, 0, -2, -2], [1, 1, 9, 9], [0, 0, 0, 0], [3, 3, 3, 3], times=None)
    assert scores["pq"] == 1.0


def test_predicted_segments_of_background_and_true_instances_of_background_are_no_segments():
    scores = class_panoptic_quality([0, 0, -1, -1], [1, 1, 2, 2], [0, 0, -1, -1], [5, 5, 6, 6], times=None)
    assert set(scores["per_class"]) == {0} and scores["pq"] == 1.0


def test_mean_average_precision_by_hand():
    scores = mean_average_precision(**CASE, confidence=CASE_CONFIDENCE, times=CASE_TIMES, groups=CASE_GROUPS)
    assert set(scores["per_class"]) == {0, 2, 3}
    assert scores["per_class"][0] == pytest.approx(17 / 101)
    assert scores["per_class"][2] == scores["per_class"][3] == 1.0
    assert scores["map"] == pytest.approx(CASE_MAP)


def test_average_precision_of_the_101_recall_points():
    # Car: 2 true segments; ranked 0.9 (TP), 0.8 (FP), 0.7 (TP): precision 1 up to recall 1/2 (51 points), then
    # 2/3 at recall 1 (50 points).
    classes = [0] * 6
    instances_pred = [5, 5, 6, 6, 7, 7]
    instances_true = [0, 0, -1, -1, 1, 1]
    confidence = [0.9, 0.9, 0.8, 0.8, 0.7, 0.7]
    scores = mean_average_precision(classes, instances_true, classes, instances_pred, confidence, times=None)
    assert scores["map"] == pytest.approx((51 + 50 * 2 / 3) / 101)


def test_tied_scores_form_one_point_whatever_the_order():
    # One true car; two predictions of equal score, one right, one wrong: precision 1/2 at recall 1.
    for instances_pred in ([5, 5, 6], [6, 6, 5]):
        scores = mean_average_precision([0, 0, -1], [0, 0, -1], [0, 0, 0], instances_pred, [0.5, 0.5, 0.5], times=None)
        assert scores["map"] == pytest.approx(0.5)


def test_a_class_without_prediction_has_ap_zero_and_a_class_without_truth_no_ap():
    scores = mean_average_precision([0, 0, 3, 3], [1, 1, 2, 2], [0, 0, 4, 4], [1, 1, 2, 2], [1.0] * 4, times=None)
    assert scores["per_class"] == {0: 1.0, 3: 0.0} and scores["map"] == 0.5


def test_a_stricter_iou_threshold():
    # IoU 3/4: a true positive at 0.5, a false positive at 0.75 (the IoU must exceed the threshold) -> AP 0.
    args = ([0] * 4, [0] * 4, [0, 0, 0, -1], [1, 1, 1, -1], [0.5] * 4)
    assert mean_average_precision(*args, times=None)["map"] == 1.0
    assert mean_average_precision(*args, times=None, iou_threshold=0.74)["map"] == 1.0
    assert mean_average_precision(*args, times=None, iou_threshold=0.75)["map"] == 0.0


def test_pointwise_macro_f1_by_hand_and_against_scikit_learn():
    assert pointwise_macro_f1(CASE["classes_true"], CASE["classes_pred"]) == pytest.approx(sum(CASE_F1.values()) / 6)
    assert pointwise_macro_f1(CASE["classes_true"], CASE["classes_pred"], include_background=False) == pytest.approx(
        (3 / 7 + 2 / 3 + 1) / 5
    )
    kept = np.asarray(CASE["classes_true"]) != -2
    yt, yp = np.asarray(CASE["classes_true"])[kept], np.asarray(CASE["classes_pred"])[kept]
    assert pointwise_macro_f1(CASE["classes_true"], CASE["classes_pred"]) == pytest.approx(
        f1_score(yt, yp, average="macro")
    )
    assert pointwise_macro_f1(CASE["classes_true"], CASE["classes_pred"], include_background=False) == pytest.approx(
        f1_score(yt, yp, average="macro", labels=[0, 1, 2, 3, 4])
    )


def test_semantic_scores_by_hand():
    scores = semantic_scores(**CASE, confidence=CASE_CONFIDENCE, times=CASE_TIMES, groups=CASE_GROUPS)
    assert scores["pq"] == pytest.approx((0.3 + 1 + 2 / 3) / 4)
    assert scores["sq"] == pytest.approx((0.75 + 1 + 2 / 3) / 4)
    assert scores["rq"] == pytest.approx(0.6)
    assert scores["map"] == pytest.approx(CASE_MAP)
    assert scores["macro_f1"] == pytest.approx(sum(CASE_F1.values()) / 6)
    assert scores["mcov"] == pytest.approx(CASE_MCOV)
    assert set(scores["per_class"]) == {-1, 0, 1, 2, 3, 4}
    for code, expected_f1 in CASE_F1.items():
        assert scores["per_class"][code]["f1"] == pytest.approx(expected_f1)
    assert scores["per_class"][0]["ap"] == pytest.approx(17 / 101) and scores["per_class"][3]["pq"] == pytest.approx(
        2 / 3
    )
    assert math.isnan(scores["per_class"][-1]["pq"]) and math.isnan(scores["per_class"][-1]["ap"])
    assert math.isnan(scores["per_class"][4]["ap"]) and scores["per_class"][4]["pq"] == 0.0
    assert math.isnan(scores["per_class"][1]["pq"]) and math.isnan(scores["per_class"][1]["ap"])


def test_the_coverage_is_that_of_instance_coverage_on_the_kept_rows():
    kept = np.asarray(CASE["classes_true"]) != -2
    columns = {key: np.asarray(value)[kept] for key, value in CASE.items()}
    expected = instance_coverage(
        columns["instances_true"],
        columns["instances_pred"],
        times=np.asarray(CASE_TIMES)[kept],
        groups=np.asarray(CASE_GROUPS)[kept],
    )
    scores = semantic_scores(**CASE, confidence=CASE_CONFIDENCE, times=CASE_TIMES, groups=CASE_GROUPS)
    assert scores["mcov"] == pytest.approx(expected["mcov"]) == pytest.approx(CASE_MCOV)


@pytest.mark.parametrize("n", [0, 3])
def test_degenerate_input_scores_zero_never_nan(n):
    # No road user in truth or prediction (all background, or nothing at all).
    background = [-1] * n
    scores = semantic_scores(background, background, background, background, [1.0] * n, times=[0.0] * n)
    for key in ("pq", "sq", "rq", "map", "mcov"):
        assert scores[key] == 0.0
    assert scores["macro_f1"] == (1.0 if n else 0.0)  # background found everywhere, or no class at all
    assert pointwise_macro_f1(background, background, include_background=False) == 0.0


@pytest.mark.parametrize(
    ("changes", "name"),
    [
        ({"classes_true": [0, 0]}, "classes_true"),
        ({"instances_true": [0, 0]}, "instances_true"),
        ({"classes_pred": [0] * 17}, "classes_pred"),
        ({"instances_pred": [[0] * 16]}, "instances_pred"),
    ],
)
def test_lengths_must_match_and_the_error_names_the_argument(changes, name):
    with pytest.raises(ValueError, match=name):
        semantic_scores(**_case_args(**changes), confidence=CASE_CONFIDENCE, times=CASE_TIMES)


def test_the_other_arguments_are_checked_too():
    with pytest.raises(ValueError, match="confidence"):
        mean_average_precision(**CASE, confidence=[0.5] * 3, times=CASE_TIMES)
    with pytest.raises(ValueError, match="times"):
        class_panoptic_quality(**CASE, times=[0.0])
    with pytest.raises(ValueError, match="groups"):
        class_panoptic_quality(**CASE, times=CASE_TIMES, groups=["A"])
    with pytest.raises(ValueError, match="classes_pred"):
        pointwise_macro_f1([0, 1], [0])
    with pytest.raises(ValueError, match="classes_true"):
        pointwise_macro_f1(["car", "bus"], [0, 1])
    with pytest.raises(ValueError, match="confidence must be finite"):
        semantic_scores([0], [0], [0], [0], [np.nan], times=None)
    with pytest.raises(ValueError, match="iou_threshold"):
        mean_average_precision(**CASE, confidence=CASE_CONFIDENCE, times=CASE_TIMES, iou_threshold=0.3)
    with pytest.raises(ValueError, match="metric"):
        make_semantic_scorer("accuracy")


# ----------------------------------------------------------------------------------------------------------------
# Brute-force references: sets and Python loops, from the definitions.
# ----------------------------------------------------------------------------------------------------------------
def _brute_cells(times, groups, window):
    start = {}
    for t, g in zip(times, groups, strict=True):
        start[g] = min(start.get(g, math.inf), t)
    if window is None:
        return [(g, 0) for g in groups]
    return [(g, math.floor((t - start[g]) / window)) for t, g in zip(times, groups, strict=True)]


def _brute_segments(cells, instances, classes, kept, confidence=None):
    """{(cell, instance): (class, set of rows)} of the segments of a road-user class."""
    rows = defaultdict(set)
    for i, (cell, instance) in enumerate(zip(cells, instances, strict=True)):
        if kept[i] and instance >= 0:
            rows[(cell, instance)].add(i)
    segments = {}
    for key, members in rows.items():
        votes = Counter(classes[i] for i in members)
        weight = defaultdict(float)
        for i in sorted(members):
            weight[classes[i]] += 0.0 if confidence is None else confidence[i]
        best = min(votes, key=lambda c: (-votes[c], -round(weight[c], 9), c))
        if best >= 0:
            segments[key] = (best, members)
    return segments


def _brute_layout(data, window, with_confidence):
    cells = _brute_cells(data["times"], data["groups"], window)
    kept = [c != -2 for c in data["classes_true"]]
    confidence = data["confidence"] if with_confidence else None
    true = _brute_segments(cells, data["instances_true"], data["classes_true"], kept)
    pred = _brute_segments(cells, data["instances_pred"], data["classes_pred"], kept, confidence)
    return true, pred


def _iou(a, b):
    return len(a & b) / len(a | b)


def _brute_pq(true, pred):
    classes = {c for c, _ in true.values()} | {c for c, _ in pred.values()}
    per_class = {}
    for c in classes:
        ious = [
            _iou(g, p)
            for (cell_g, _), (cg, g) in true.items()
            for (cell_p, _), (cp, p) in pred.items()
            if cg == cp == c and cell_g == cell_p and _iou(g, p) > 0.5
        ]
        tp = len(ious)
        fp = sum(cp == c for cp, _ in pred.values()) - tp
        fn = sum(cg == c for cg, _ in true.values()) - tp
        sq = sum(ious) / tp if tp else 0.0
        rq = tp / (tp + fp / 2 + fn / 2) if tp + fp + fn else 0.0
        per_class[c] = (sq * rq, sq, rq, tp, fp, fn)
    return per_class


def _brute_ap(true, pred, scores, c, threshold):
    """AP of class c: greedy COCO matching in rank order, precision at each distinct score, 101 recall points."""
    truth = [(cell, g) for (cell, _), (cg, g) in true.items() if cg == c]
    ranked = sorted(((scores[key], key) for key, (cp, _) in pred.items() if cp == c), key=lambda s: -s[0])
    matched, hits = set(), []
    for score, (cell, _) in ranked:
        p = pred[(cell, _)][1]
        candidates = [(_iou(g, p), j) for j, (cell_g, g) in enumerate(truth) if cell_g == cell and j not in matched]
        best = max(candidates, default=(0.0, None))
        if best[0] > threshold:
            matched.add(best[1])
        hits.append((score, best[0] > threshold))
    curve = []
    for s in sorted({score for score, _ in hits}, reverse=True):
        tp = sum(hit for score, hit in hits if score >= s)
        n = sum(1 for score, _ in hits if score >= s)
        curve.append((tp / len(truth), tp / n))
    total = 0.0
    for r in np.linspace(0.0, 1.0, 101):
        total += max((p for recall, p in curve if recall >= r), default=0.0)
    return total / 101


def _random_data(seed, n=300):
    rng = np.random.default_rng(seed)
    instances_true = rng.integers(-1, 8, n)
    object_class = rng.integers(-1, 5, 8)
    classes_true = np.where(instances_true >= 0, object_class[np.maximum(instances_true, 0)], -1)
    noisy = rng.random(n) < 0.2
    classes_true[noisy] = rng.integers(-2, 5, noisy.sum())
    instances_pred = np.where(rng.random(n) < 0.7, instances_true, rng.integers(-1, 8, n))
    classes_pred = np.where(rng.random(n) < 0.7, classes_true, rng.integers(-1, 5, n))
    classes_pred[classes_pred == -2] = -1
    return {
        "classes_true": classes_true.tolist(),
        "instances_true": instances_true.tolist(),
        "classes_pred": classes_pred.tolist(),
        "instances_pred": instances_pred.tolist(),
        "confidence": rng.choice([0.25, 0.5, 0.75, 1.0], n).tolist(),
        "times": np.round(rng.uniform(0.0, 3.0, n), 2).tolist(),
        "groups": rng.integers(0, 3, n).tolist(),
    }


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize("window", [0.5, 1.0, None])
def test_against_brute_force_definitions(seed, window):
    data = _random_data(seed)
    args = {key: data[key] for key in CASE}
    true, pred = _brute_layout(data, window, with_confidence=True)
    expected_pq = _brute_pq(true, pred)
    scores = semantic_scores(
        **args, confidence=data["confidence"], times=data["times"], groups=data["groups"], window=window
    )
    panoptic = class_panoptic_quality(
        **args, times=data["times"], groups=data["groups"], window=window, confidence=data["confidence"]
    )
    assert set(panoptic["per_class"]) == set(expected_pq)
    for c, (pq, sq, rq, tp, fp, fn) in expected_pq.items():
        got = panoptic["per_class"][c]
        assert (got["tp"], got["fp"], got["fn"]) == (tp, fp, fn)
        assert (got["pq"], got["sq"], got["rq"]) == pytest.approx((pq, sq, rq))
    assert scores["pq"] == pytest.approx(np.mean([v[0] for v in expected_pq.values()]))

    segment_scores = {key: sum(data["confidence"][i] for i in rows) / len(rows) for key, (_, rows) in pred.items()}
    classes_in_truth = sorted({c for c, _ in true.values()})
    precision = mean_average_precision(
        **args, confidence=data["confidence"], times=data["times"], groups=data["groups"], window=window
    )
    assert sorted(precision["per_class"]) == classes_in_truth
    for c in classes_in_truth:
        assert precision["per_class"][c] == pytest.approx(_brute_ap(true, pred, segment_scores, c, 0.5))
    assert scores["map"] == pytest.approx(precision["map"])

    cover = [
        max((_iou(g, p) for (cell_p, _), (_, p) in pred.items() if cell_p == cell_g), default=0.0)
        for (cell_g, _), (_, g) in true.items()
    ]
    assert scores["mcov"] == pytest.approx(np.mean(cover) if cover else 0.0)

    kept = [c != -2 for c in data["classes_true"]]
    yt = [c for c, k in zip(data["classes_true"], kept, strict=True) if k]
    yp = [c for c, k in zip(data["classes_pred"], kept, strict=True) if k]
    assert scores["macro_f1"] == pytest.approx(f1_score(yt, yp, average="macro"))


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(6))
def test_average_precision_at_stricter_thresholds_against_brute_force(seed):
    data = _random_data(100 + seed)
    args = {key: data[key] for key in CASE}
    true, pred = _brute_layout(data, 0.5, with_confidence=True)
    segment_scores = {key: sum(data["confidence"][i] for i in rows) / len(rows) for key, (_, rows) in pred.items()}
    for threshold in (0.6, 0.8):
        got = mean_average_precision(
            **args, confidence=data["confidence"], times=data["times"], groups=data["groups"], iou_threshold=threshold
        )
        for c in got["per_class"]:
            assert got["per_class"][c] == pytest.approx(_brute_ap(true, pred, segment_scores, c, threshold))


# ----------------------------------------------------------------------------------------------------------------
# Invariants
# ----------------------------------------------------------------------------------------------------------------
@st.composite
def labellings(draw):
    n = draw(st.integers(0, 30))
    codes = st.lists(st.integers(-2, 4), min_size=n, max_size=n)
    ids = st.lists(st.integers(-1, 4), min_size=n, max_size=n)
    return {
        "classes_true": draw(codes),
        "instances_true": draw(ids),
        "classes_pred": [max(c, -1) for c in draw(codes)],
        "instances_pred": draw(ids),
        "confidence": draw(st.lists(st.sampled_from([0.1, 0.2, 0.3, 0.7, 1.0]), min_size=n, max_size=n)),
        "times": draw(st.lists(st.sampled_from([0.0, 0.2, 0.45, 0.5, 0.9, 1.3]), min_size=n, max_size=n)),
        "groups": draw(st.lists(st.integers(0, 1), min_size=n, max_size=n)),
    }


def _scores(data):
    return semantic_scores(
        data["classes_true"],
        data["instances_true"],
        data["classes_pred"],
        data["instances_pred"],
        data["confidence"],
        times=data["times"],
        groups=data["groups"],
    )


def _assert_same_scores(a, b):
    for key in ("pq", "sq", "rq", "map", "macro_f1", "mcov"):
        assert a[key] == pytest.approx(b[key], rel=1e-12, abs=1e-12), key
    assert set(a["per_class"]) == set(b["per_class"])
    for code in a["per_class"]:
        for key in ("pq", "ap", "f1"):
            assert a["per_class"][code][key] == pytest.approx(b["per_class"][code][key], nan_ok=True, abs=1e-12)


@settings(max_examples=150, deadline=None)
@given(labellings(), st.randoms(use_true_random=False))
def test_a_permutation_of_the_rows_changes_nothing(data, random):
    order = list(range(len(data["times"])))
    random.shuffle(order)
    permuted = {key: [values[i] for i in order] for key, values in data.items()}
    _assert_same_scores(_scores(data), _scores(permuted))


@settings(max_examples=150, deadline=None)
@given(labellings(), st.permutations(range(5)), st.permutations(range(5)))
def test_relabelling_the_instances_changes_nothing(data, true_ids, pred_ids):
    relabelled = dict(data)
    relabelled["instances_true"] = [true_ids[i] * 3 + 7 if i >= 0 else -1 for i in data["instances_true"]]
    relabelled["instances_pred"] = [pred_ids[i] + 100 if i >= 0 else -1 for i in data["instances_pred"]]
    _assert_same_scores(_scores(data), _scores(relabelled))


@settings(max_examples=150, deadline=None)
@given(labellings())
def test_a_perfect_prediction_scores_one(data):
    # Constant confidence: a tied vote goes to the smallest code in truth and prediction alike.
    perfect = dict(
        data,
        classes_pred=data["classes_true"],
        instances_pred=data["instances_true"],
        confidence=[1.0] * len(data["times"]),
    )
    scores = _scores(perfect)
    # With the sequences: an instance id of two sequences is two instances, each with its own class vote.
    has_road_user = bool(
        class_panoptic_quality(**{k: perfect[k] for k in CASE}, times=perfect["times"], groups=perfect["groups"])[
            "per_class"
        ]
    )
    for key in ("pq", "sq", "rq", "map", "mcov"):
        assert scores[key] == (1.0 if has_road_user else 0.0), key
    kept_rows = any(c != -2 for c in data["classes_true"])
    assert scores["macro_f1"] == (1.0 if kept_rows else 0.0)


# ----------------------------------------------------------------------------------------------------------------
# The scorer
# ----------------------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def scenes():
    return make_scenes(n_sequences=2, duration=6.0, random_state=3)


def _classifier_pipeline():
    stage1 = RadarDBSCAN(metric="xyv", eps_xyv=1.04, vr_scale=1.03, min_samples=3, vr_min=0.5)
    return make_pipeline(FrameTransform(), DopplerDensityFilter(), ClusterClassifier(stage1))


@pytest.mark.parametrize("metric", ["pq", "map", "macro_f1", "mcov"])
def test_the_scorer_in_cross_val_score_with_a_cluster_classifier(scenes, metric):
    y = road_user_class(scenes.data["label_id"])
    scorer = make_semantic_scorer(metric)
    scores = cross_val_score(
        _classifier_pipeline(),
        scenes.data,
        y,
        groups=scenes.groups,
        cv=GroupKFold(2),
        scoring=scorer,
        error_score="raise",
    )
    assert scores.shape == (2,) and np.all(np.isfinite(scores)) and np.all((scores >= 0) & (scores <= 1))


def test_the_scorer_is_semantic_scores_of_predict_instances(scenes):
    X, y = scenes.data, road_user_class(scenes.data["label_id"])
    model = _classifier_pipeline().fit(X, y)
    found = model[-1].predict_instances(model[:-1].transform(X))
    times = (X["timestamp"].to_numpy() - X["timestamp"].min()) * 1e-6
    sequence = X["sequence"].to_numpy()
    instances = pd.factorize(pd.Series(list(zip(X["track_id"], sequence, strict=True))))[0]
    instances[X["track_id"].to_numpy() == ""] = -1
    expected = semantic_scores(
        y, instances, found["class"], found["instance"], found["confidence"], times=times, groups=sequence
    )
    assert expected["pq"] > 0  # a case that can fail
    for metric in ("pq", "sq", "rq", "map", "macro_f1", "mcov"):
        assert make_semantic_scorer(metric)(model, X, y) == pytest.approx(expected[metric])


class _Failing:
    def predict_instances(self, X):
        raise RuntimeError("no model")


class _Nothing:
    def predict_instances(self, X):
        n = len(X)
        return pd.DataFrame({"class": [-1] * n, "instance": [-1] * n, "confidence": [1.0] * n})


def test_the_scorer_never_raises_on_failing_or_degenerate_predictions(scenes):
    X, y = scenes.data, road_user_class(scenes.data["label_id"])
    for metric in ("pq", "sq", "rq", "map", "macro_f1", "mcov"):
        assert make_semantic_scorer(metric)(_Failing(), X, y) == 0.0
        score = make_semantic_scorer(metric)(_Nothing(), X, y)
        assert np.isfinite(score) and (score == 0.0 or metric == "macro_f1")
    # No road user in truth or prediction.
    background = np.full(len(X), -1)
    assert make_semantic_scorer("pq")(_Nothing(), X, background) == 0.0


def test_the_scorer_raises_on_set_up_mistakes_and_pickles(scenes):
    X, y = scenes.data, road_user_class(scenes.data["label_id"])
    with pytest.raises(ValueError, match="instance column 'object'"):
        make_semantic_scorer(instance_column="object")(_Nothing(), X, y)
    with pytest.raises(ValueError, match="'t'"):
        make_semantic_scorer()(_Nothing(), X.drop(columns="timestamp"), y)
    scorer = pickle.loads(pickle.dumps(make_semantic_scorer("map", window=None, instance_column=None)))
    assert repr(scorer) == "make_semantic_scorer(metric='map', window=None, instance_column=None)"
    assert scorer(_Nothing(), X.drop(columns="timestamp"), y) == 0.0


def test_the_precision_recall_curve_is_cocos_interpolated_precision_and_its_mean_the_ap():
    """Three ranked segments of class 0 against two true ones: hit, miss, hit (by hand: 1, 1/2, 2/3)."""
    from sklearn_radar.metrics import semantic_scores

    # Windows of 1 s: each detection pair one segment; true objects 0 and 1 of class 0 in windows 0 and 2.
    times = [0.0, 0.1, 1.0, 1.1, 2.0, 2.1]
    classes_true = [0, 0, -1, -1, 0, 0]
    instances_true = [0, 0, -1, -1, 1, 1]
    classes_pred = [0, 0, 0, 0, 0, 0]
    instances_pred = [0, 0, 1, 1, 2, 2]
    confidence = [0.9, 0.9, 0.8, 0.8, 0.7, 0.7]
    found = semantic_scores(
        classes_true, instances_true, classes_pred, instances_pred, confidence, times=times, window=1.0
    )
    curve = found["precision_at_recall"][0]
    recall = np.linspace(0.0, 1.0, 101)
    # Interpolated: the best precision at this recall or more; recall 1/2 at precision 1, recall 1 at 2/3.
    expected = np.where(recall <= 0.5, 1.0, 2.0 / 3.0)
    np.testing.assert_allclose(curve, expected)
    assert found["per_class"][0]["ap"] == pytest.approx(curve.mean())
