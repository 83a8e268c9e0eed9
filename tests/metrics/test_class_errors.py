"""class_errors against hand-computed cases, a segment-by-segment reference and class_panoptic_quality's counts."""

from collections import Counter, defaultdict

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sklearn_radar.metrics import class_errors, class_panoptic_quality


def test_each_place_by_hand():
    # One window.  Car 0 (3 detections): cluster 10 holds 2 of them, called a car: matched, right class.
    # Car 1 (2 detections): cluster 11 holds both, called a pedestrian: misclassified (and a wrong-class
    # pedestrian segment).  Pedestrian 2 (2 detections): cluster 12 holds both, called background:
    # misclassified as background.  Pedestrian 3 (2 detections): split over clusters 13 and 14 (IoU 1/2 each):
    # missed by the grouping; both clusters are called pedestrians, false ones.  Cluster 15, background
    # only, called a car: a false car segment.
    truth_class = [0, 0, 0, 0, 0, 3, 3, 3, 3, -1, -1]
    truth_inst = [0, 0, 0, 1, 1, 2, 2, 3, 3, -1, -1]
    pred_class = [0, 0, -1, 3, 3, -1, -1, 3, 3, 0, 0]
    pred_inst = [10, 10, -1, 11, 11, 12, 12, 13, 14, 15, 15]
    errors = class_errors(truth_class, truth_inst, pred_class, pred_inst, times=None)
    confusion = errors["confusion"]
    assert list(confusion.index) == [0, 3] and list(confusion.columns) == [-1, 0, 3]
    assert confusion.to_numpy().tolist() == [[0, 1, 1], [1, 0, 0]]
    car, pedestrian = errors["per_class"][0], errors["per_class"][3]
    assert (car.n_true, car.tp, car.misclassified, car.missed, car.fn) == (2, 1, 1, 0, 1)
    assert (car.n_pred, car.wrong_class, car.false, car.fp) == (2, 0, 1, 1)
    assert (pedestrian.n_true, pedestrian.tp, pedestrian.misclassified, pedestrian.missed) == (2, 0, 1, 1)
    assert (pedestrian.n_pred, pedestrian.wrong_class, pedestrian.false, pedestrian.fp) == (3, 1, 2, 3)


def test_background_cluster_without_instance_is_missed():
    # The classifier's instance column is -1 where the class is background: the grouping's cluster is gone, so
    # the road user counts as missed; with the cluster ids it is misclassified as background.
    truth_class, truth_inst = [2, 2, 2], [0, 0, 0]
    with_clusters = class_errors(truth_class, truth_inst, [-1, -1, -1], [7, 7, 7], times=None)
    without = class_errors(truth_class, truth_inst, [-1, -1, -1], [-1, -1, -1], times=None)
    assert with_clusters["confusion"].loc[2, -1] == 1 and with_clusters["per_class"][2].misclassified == 1
    assert without["confusion"].loc[2, -1] == 0 and without["per_class"][2].missed == 1


def test_windows_and_sequences_make_separate_segments():
    # The same car and cluster over two windows and in a second sequence: three matched segments.
    times = [0.0, 0.1, 0.6, 0.7, 0.0, 0.1]
    groups = [0, 0, 0, 0, 1, 1]
    errors = class_errors([0] * 6, [0] * 6, [0] * 6, [4] * 6, times=times, groups=groups)
    assert errors["confusion"].loc[0, 0] == 3 and errors["per_class"][0].n_true == 3
    one_window = class_errors([0] * 6, [0] * 6, [0] * 6, [4] * 6, times=times, groups=groups, window=None)
    assert one_window["per_class"][0].tp == 2


def test_ignored_detections_are_left_out():
    # Two ignored detections in cluster 5 would make its IoU with car 0 one half; left out, it matches.
    errors = class_errors([0, 0, -2, -2], [0, 0, 1, 1], [0, 0, 0, 0], [5, 5, 5, 5], times=None)
    assert errors["per_class"][0].tp == 1 and errors["per_class"][0].fp == 0


def test_confidence_breaks_a_tie_of_the_vote():
    # Cluster 5: two detections called car (confidence 0.9), two called pedestrian (0.4): a car segment.
    args = ([0] * 4, [0] * 4, [0, 0, 3, 3], [5] * 4)
    assert class_errors(*args, times=None, confidence=[0.9, 0.9, 0.4, 0.4])["per_class"][0].tp == 1
    assert class_errors(*args, times=None, confidence=[0.1, 0.1, 0.4, 0.4])["confusion"].loc[0, 3] == 1


def test_no_road_user_gives_an_empty_matrix():
    errors = class_errors([-1, -1], [-1, -1], [-1, -1], [3, 3], times=None)
    assert errors["confusion"].shape == (0, 1) and errors["per_class"] == {}


def test_length_mismatch_names_the_array():
    with pytest.raises(ValueError, match="instances_pred"):
        class_errors([0, 0], [0, 0], [0, 0], [1], times=None)


def _reference(truth_class, truth_inst, pred_class, pred_inst):
    """Segment by segment, one frame, no ignored rows, no confidence: confusion counts and per-class counts."""
    rows_true, rows_pred = defaultdict(set), defaultdict(set)
    for i, (g, p) in enumerate(zip(truth_inst, pred_inst, strict=True)):
        if g >= 0:
            rows_true[g].add(i)
        if p >= 0:
            rows_pred[p].add(i)

    def majority(rows, classes):
        counts = Counter(classes[i] for i in rows)
        return min(counts, key=lambda c: (-counts[c], c))

    class_true = {g: majority(r, truth_class) for g, r in rows_true.items()}
    class_pred = {p: majority(r, pred_class) for p, r in rows_pred.items()}
    pairs = Counter()
    found_true, found_pred = set(), set()
    for g, rg in rows_true.items():
        if class_true[g] < 0:
            continue
        for p, rp in rows_pred.items():
            if 2 * len(rg & rp) > len(rg | rp):
                pairs[class_true[g], max(class_pred[p], -1)] += 1
                found_true.add(g)
                found_pred.add(p)
    per_class = {}
    for c in {v for v in class_true.values() if v >= 0} | {v for v in class_pred.values() if v >= 0}:
        n_true = sum(v == c for v in class_true.values())
        n_pred = sum(v == c for v in class_pred.values())
        missed = sum(v == c and g not in found_true for g, v in class_true.items())
        false = sum(v == c and p not in found_pred for p, v in class_pred.items())
        per_class[c] = (n_true, pairs[c, c], missed, n_pred, false)
    return pairs, per_class


@settings(max_examples=60, deadline=None)
@given(st.data())
def test_matches_reference_and_class_panoptic_quality(data):
    n = data.draw(st.integers(0, 30))
    truth_inst = np.array(data.draw(st.lists(st.integers(-1, 4), min_size=n, max_size=n)), dtype=np.int64)
    pred_inst = np.array(data.draw(st.lists(st.integers(-1, 4), min_size=n, max_size=n)), dtype=np.int64)
    truth_class = np.array(data.draw(st.lists(st.integers(-1, 3), min_size=n, max_size=n)), dtype=np.int64)
    pred_class = np.array(data.draw(st.lists(st.integers(-1, 3), min_size=n, max_size=n)), dtype=np.int64)
    errors = class_errors(truth_class, truth_inst, pred_class, pred_inst, times=None)
    pairs, per_class = _reference(truth_class, truth_inst, pred_class, pred_inst)
    confusion = errors["confusion"]
    got = {(int(t), int(p)): int(confusion.loc[t, p]) for t in confusion.index for p in confusion.columns}
    assert {key: value for key, value in got.items() if value} == {k: v for k, v in pairs.items() if v}
    assert set(errors["per_class"]) == set(per_class)
    panoptic = class_panoptic_quality(truth_class, truth_inst, pred_class, pred_inst, times=None)["per_class"]
    for code, (n_true, tp, missed, n_pred, false) in per_class.items():
        found = errors["per_class"][code]
        assert (found.n_true, found.tp, found.missed, found.n_pred, found.false) == (n_true, tp, missed, n_pred, false)
        assert found.tp + found.misclassified + found.missed == found.n_true
        assert found.tp + found.wrong_class + found.false == found.n_pred
        assert (found.tp, found.fp, found.fn) == (panoptic[code].tp, panoptic[code].fp, panoptic[code].fn)
