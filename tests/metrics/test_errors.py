"""instance_errors against hand-computed cases and a loop-by-loop reference, and against panoptic_quality's counts."""

from collections import Counter

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sklearn_radar.metrics import instance_errors, instance_scores


def test_each_cause_by_hand():
    # One window (times None).  Object 0: matched by cluster 10.  Object 1 (4 detections): 3 are noise.
    # Objects 2 and 3 (3 detections each): cluster 11 holds both (IoU 3/6, not above one half): both merged with an
    # object.  Object 4 (2 detections): cluster 12 holds both plus 3 background detections: merged with background;
    # cluster 12 is then a false "part of one object".  Object 5 (4 detections): two clusters of 2 (IoU 1/2): split;
    # clusters 13 and 14 are false parts.  Cluster 15: background only.
    truth = [0, 0, 1, 1, 1, 1, 2, 2, 2, 3, 3, 3, 4, 4, -1, -1, -1, 5, 5, 5, 5, -1]
    pred = [10, 10, 20, -1, -1, -1, 11, 11, 11, 11, 11, 11, 12, 12, 12, 12, 12, 13, 13, 14, 14, 15]
    errors = instance_errors(truth, pred, times=None)
    assert errors["n_true"] == 6 and errors["n_pred"] == 7
    assert errors["matched"] == 1 and errors["missed"] == 5
    assert (errors["noise"], errors["merged_with_object"], errors["merged_with_background"], errors["split"]) == (
        1,
        2,
        1,
        1,
    )
    # False: 20 (part of object 1), 11 (several), 12 (part), 13 and 14 (parts), 15 (background).
    assert (errors["false"], errors["background"], errors["part_of_object"], errors["several_objects"]) == (6, 1, 4, 1)
    assert errors["median_size_matched"] == 2.0 and errors["median_size_missed"] == 3.0


def test_windows_make_separate_segments():
    # The same object and cluster in two windows: two matched segments.
    errors = instance_errors([0, 0, 0, 0], [1, 1, 1, 1], times=[0.0, 0.1, 0.6, 0.7])
    assert errors["n_true"] == 2 and errors["matched"] == 2 and errors["false"] == 0


def test_no_objects():
    errors = instance_errors([-1, -1], [3, -1], times=None)
    assert errors["missed"] == 0 and errors["background"] == 1 and np.isnan(errors["median_size_missed"])


def test_lengths_must_agree():
    with pytest.raises(ValueError, match="equal length"):
        instance_errors([0, 0], [0], times=None)


def reference(truth, pred, groups):
    """Segments one by one (one window per sequence)."""
    causes = Counter()
    true_keys = {(g, t) for g, t in zip(groups, truth, strict=True) if t != -1}
    pred_keys = {(g, p) for g, p in zip(groups, pred, strict=True) if p != -1}

    def rows(key, labels):
        return {i for i in range(len(truth)) if groups[i] == key[0] and labels[i] == key[1]}

    def iou(a, b):
        return len(a & b) / len(a | b)

    matched_pred = set()
    for tk in true_keys:
        t_rows = rows(tk, truth)
        partners = [pk for pk in pred_keys if iou(t_rows, rows(pk, pred)) > 0.5]
        if partners:
            causes["matched"] += 1
            matched_pred.update(partners)
            continue
        if 2 * sum(pred[i] == -1 for i in t_rows) > len(t_rows):
            causes["noise"] += 1
            continue
        best = max(pred_keys, key=lambda pk: len(t_rows & rows(pk, pred)), default=None)
        if best is not None and 2 * len(t_rows & rows(best, pred)) > len(t_rows):
            others = {truth[i] for i in rows(best, pred) if truth[i] != -1}
            causes["merged_with_object" if len(others) > 1 else "merged_with_background"] += 1
        else:
            causes["split"] += 1
    for pk in pred_keys - matched_pred:
        objects = {truth[i] for i in rows(pk, pred) if truth[i] != -1}
        causes[("background", "part_of_object")[len(objects)] if len(objects) < 2 else "several_objects"] += 1
    return causes


@settings(max_examples=150, deadline=None)
@given(
    st.lists(st.tuples(st.integers(-1, 3), st.integers(-1, 3), st.integers(0, 1)), min_size=1, max_size=40),
)
def test_equals_the_reference_and_the_panoptic_counts(rows):
    truth, pred, groups = (np.array(column) for column in zip(*rows, strict=True))
    errors = instance_errors(truth, pred, times=None, groups=groups)
    expected = reference(truth.tolist(), pred.tolist(), groups.tolist())
    for key in ("matched", "noise", "merged_with_object", "merged_with_background", "split"):
        assert errors[key] == expected[key], key
    for key in ("background", "part_of_object", "several_objects"):
        assert errors[key] == expected[key], key
    scores = instance_scores(truth, pred, times=None, groups=groups)
    assert errors["matched"] == scores["tp"]
    assert errors["missed"] == scores["fn"] and errors["false"] == scores["fp"]
    assert errors["missed"] == sum(
        errors[k] for k in ("noise", "merged_with_object", "merged_with_background", "split")
    )
