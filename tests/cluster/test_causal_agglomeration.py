"""The causal mean-link agglomeration of LinkClustering: merges time by time, worked by hand."""

import numpy as np

from sklearn_radar.cluster._causal_agglomeration import confirmed_roots, new_state, sequence_merges, step


def test_the_causal_merges_worked_by_hand():
    # Nodes 0, 1 at 0 s; 2 at 0.1 s; 3 at 0.2 s; 4 at 0.6 s; pair window 0.25 s, threshold 0.5.
    #   0 s: (0, 1) 0.9 -> {0, 1}.
    #   0.1 s: (0, 2) 0.2, (1, 2) 0.3: mean 0.25 -> 2 alone.
    #   0.2 s: (0, 3) 0.8, (1, 3) 0.9, (2, 3) 0.9.  Means: {0,1}-3 0.85, 2-3 0.9: 3 joins 2 (the older);
    #          then {0,1}-{2,3}: (0.2 + 0.3 + 0.8 + 0.9) / 4 = 0.55 > 0.5: the old clusters merge, 0 survives.
    #   0.6 s: node 4, no pair; cluster 0 (last node at 0.2 s) retires.
    t = np.array([0.0, 0.0, 0.1, 0.2, 0.6])
    node = np.ones(5, dtype=bool)
    i = np.array([0, 0, 1, 0, 1, 2])
    j = np.array([1, 2, 2, 3, 3, 3])
    links = np.array([0.9, 0.2, 0.3, 0.8, 0.9, 0.9])
    roots, sizes = sequence_merges(t, node, i, j, links, 0.25, 0.5)
    np.testing.assert_array_equal(roots, [0, 0, 0, 0, 4])
    np.testing.assert_array_equal(sizes, [2, 2, 1, 4, 1])
    np.testing.assert_array_equal(confirmed_roots(roots, sizes, 2), [0, 0, -1, 0, -1])
    # The same, step by step: the merges in order, the older survives, and the retired cluster is forgotten.
    state = new_state()
    step(state, 0.0, [0, 1], [0], [1], [0.9], 0.25, 0.5)
    clusters, counts, child, survivor = step(state, 0.1, [2], [0, 1], [2, 2], [0.2, 0.3], 0.25, 0.5)
    assert clusters.tolist() == [2] and counts.tolist() == [1] and len(child) == 0
    clusters, counts, child, survivor = step(state, 0.2, [3], [0, 1, 2], [3, 3, 3], [0.8, 0.9, 0.9], 0.25, 0.5)
    assert clusters.tolist() == [0] and counts.tolist() == [4]
    assert list(zip(child.tolist(), survivor.tolist(), strict=True)) == [(3, 2), (2, 0)]
    step(state, 0.6, [4], [], [], [], 0.25, 0.5)
    total, _, size, *_ = state
    assert sorted(size.keys()) == [4] and sorted(total.keys()) == [4]


def test_a_low_mean_stops_the_merging_and_a_node_below_objectness_is_noise():
    t = np.array([0.0, 0.0, 0.0])
    node = np.array([True, True, False])
    roots, sizes = sequence_merges(t, node, np.array([0]), np.array([1]), np.array([0.5]), 0.25, 0.5)
    np.testing.assert_array_equal(roots, [0, 1, -1])  # 0.5 does not exceed 0.5
    np.testing.assert_array_equal(sizes, [1, 1, 0])
