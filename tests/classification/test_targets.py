"""The training target of a segment (IoU > 0.5 with an instance, else background): hand cases and a slow loop."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sklearn_radar.classification._targets import instance_classes, segment_targets


def _targets(classes, instances, predicted, sequence=None, windows=None):
    """segment_targets of detection-level labels: the segments are the (sequence, window, predicted) groups."""
    predicted = np.asarray(predicted)
    n = len(predicted)
    sequence = None if sequence is None else np.asarray(sequence, dtype=float)
    windows = np.zeros(n, dtype=np.int64) if windows is None else np.asarray(windows, dtype=np.int64)
    keys = sorted(
        {(0 if sequence is None else sequence[i], windows[i], predicted[i]) for i in range(n) if predicted[i] >= 0}
    )
    rows = np.array(
        [keys.index((0 if sequence is None else sequence[i], windows[i], predicted[i])) if predicted[i] >= 0 else -1
         for i in range(n)]
    )  # fmt: skip
    targets = segment_targets(np.asarray(classes), np.asarray(instances), sequence, windows, rows, len(keys))
    return dict(zip(keys, targets.tolist(), strict=True))


def _reference(classes, instances, predicted, sequence, windows):
    """The rule, segment by segment: the class (most frequent, ties: smallest) of an instance with IoU > 0.5."""
    classes, instances, predicted = map(np.asarray, (classes, instances, predicted))
    n = len(predicted)
    result = {}
    for key in {(sequence[i], windows[i], predicted[i]) for i in range(n) if predicted[i] >= 0}:
        p = {i for i in range(n) if (sequence[i], windows[i], predicted[i]) == key}
        result[key] = -1
        for g_id in {instances[i] for i in range(n) if instances[i] >= 0 and sequence[i] == key[0]}:
            whole = [i for i in range(n) if instances[i] == g_id and sequence[i] == key[0]]
            g = {i for i in whole if windows[i] == key[1]}
            if g and len(p & g) / len(p | g) > 0.5:
                values, counts = np.unique(classes[whole], return_counts=True)
                result[key] = int(values[np.argmax(counts)])  # np.unique sorts: the first maximum is the smallest
    return result


def test_a_cluster_that_is_the_object_takes_its_class():
    assert _targets([3, 3, 3, -1], [0, 0, 0, -1], [5, 5, 5, -1]) == {(0, 0, 5): 3}


def test_iou_must_exceed_one_half():
    # Cluster 1 = 2 of the object's 4 detections: IoU 1/2, not more -> background.  Cluster 2 = 3 of 4 and one
    # background detection: IoU 3/5 -> the object's class.
    assert _targets([2, 2, 2, 2], [0, 0, 0, 0], [1, 1, -1, -1])[(0, 0, 1)] == -1
    assert _targets([2, 2, 2, 2, -1], [0, 0, 0, 0, -1], [2, 2, 2, -1, 2])[(0, 0, 2)] == 2


def test_background_clusters_and_ignored_instances():
    # Cluster 7 holds background only; cluster 8 is an ANIMAL (-2): its target is -2, left out by the classifiers.
    got = _targets([-1, -1, -2, -2], [-1, -1, 4, 4], [7, 7, 8, 8])
    assert got == {(0, 0, 7): -1, (0, 0, 8): -2}


def test_matching_is_per_window():
    # One object over two windows, one cluster over both: within each window the cluster is the object (IoU 1),
    # although over the whole sequence a second cluster holds half of the object's windows-1 detections.
    classes, instances = [0] * 6, [0] * 6
    predicted, windows = [1, 1, 1, 1, 2, 2], [0, 0, 1, 1, 1, 1]
    got = _targets(classes, instances, predicted, windows=windows)
    assert got == {(0, 0, 1): 0, (0, 1, 1): -1, (0, 1, 2): -1}  # windows 1: 2 of 4 each, IoU 1/2


def test_equal_ids_in_two_sequences_are_different_instances():
    # Instance 0 of sequence 1 (a car) and instance 0 of sequence 2 (a pedestrian) must not be merged.
    got = _targets([0, 0, 3, 3], [0, 0, 0, 0], [9, 9, 9, 9], sequence=[1, 1, 2, 2])
    assert got == {(1.0, 0, 9): 0, (2.0, 0, 9): 3}


def test_the_class_of_an_instance_is_its_most_frequent_one():
    assert instance_classes(np.array([0, 0, 0, 1, 1, 2]), np.array([4, 4, 1, 2, 3, -1])).tolist() == [4, 2, -1]


@settings(max_examples=150, deadline=None)
@given(
    n=st.integers(1, 25),
    seed=st.integers(0, 2**31 - 1),
    n_instances=st.integers(1, 4),
    n_clusters=st.integers(1, 4),
)
def test_equals_the_segment_by_segment_rule(n, seed, n_instances, n_clusters):
    rng = np.random.default_rng(seed)
    sequence = rng.integers(1, 3, n).astype(float)
    windows = rng.integers(0, 2, n)
    instances = rng.integers(-1, n_instances, n)
    classes = np.where(instances >= 0, rng.integers(-2, 5, n), -1)
    predicted = rng.integers(-1, n_clusters, n)
    got = _targets(classes, instances, predicted, sequence=sequence, windows=windows)
    assert got == _reference(classes, instances, predicted, sequence, windows)


@pytest.mark.parametrize("n_segments", [0, 3])
def test_without_objects_every_segment_is_background(n_segments):
    rows = np.arange(3) if n_segments else np.full(3, -1)
    targets = segment_targets(np.full(3, -1), np.full(3, -1), None, np.zeros(3, dtype=np.int64), rows, n_segments)
    assert targets.tolist() == [-1] * n_segments
