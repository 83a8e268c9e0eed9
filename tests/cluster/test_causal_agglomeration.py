"""The causal mean-link agglomeration of LinkClustering: merges time by time, worked by hand."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sklearn_radar.cluster._causal_agglomeration import (
    confirmed_roots,
    live_clusters,
    new_state,
    sequence_merges,
    step,
)


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
    assert live_clusters(state) == ({4: 1}, {})


def test_the_state_holds_the_evidence_between_live_clusters():
    state = new_state()
    step(state, 0.0, [0, 1], [0], [1], [0.9], 0.25, 0.5)
    step(state, 0.1, [2], [0, 1], [2, 2], [0.2, 0.3], 0.25, 0.5)
    sizes, evidence = live_clusters(state)
    assert sizes == {0: 2, 2: 1}
    assert list(evidence) == [(0, 2)] and evidence[0, 2][1] == 2
    assert evidence[0, 2][0] == pytest.approx(0.5)


def test_a_low_mean_stops_the_merging_and_a_node_below_objectness_is_noise():
    t = np.array([0.0, 0.0, 0.0])
    node = np.array([True, True, False])
    roots, sizes = sequence_merges(t, node, np.array([0]), np.array([1]), np.array([0.5]), 0.25, 0.5)
    np.testing.assert_array_equal(roots, [0, 1, -1])  # 0.5 does not exceed 0.5
    np.testing.assert_array_equal(sizes, [1, 1, 0])


def test_a_merge_longer_than_max_extent_is_refused():
    # Nodes 0 at (0, 0) and 1 at (3, 4) at 0 s, linked with 0.9: 5 m apart (the diagonal of their box).
    # Node 2 at (0, 0.5) at 0.1 s, linked to 0 with 0.9 and to 1 with 0.9.
    t = np.array([0.0, 0.0, 0.1])
    x, y = np.array([0.0, 3.0, 0.0]), np.array([0.0, 4.0, 0.5])
    node = np.ones(3, dtype=bool)
    i, j, links = np.array([0, 0, 1]), np.array([1, 2, 2]), np.array([0.9, 0.9, 0.9])
    roots, _ = sequence_merges(t, node, i, j, links, 0.25, 0.5)
    np.testing.assert_array_equal(roots, [0, 0, 0])  # no limit: one cluster
    roots, _ = sequence_merges(t, node, i, j, links, 0.25, 0.5, x, y, max_extent=5.0)
    np.testing.assert_array_equal(roots, [0, 0, 0])  # 5 m does not exceed 5 m
    # 4.9 m: 0 and 1 stay apart; 2 joins 0 (box 0.5 m; mean link 0.9 to each, ties to the smaller pair (0, 2));
    # then {0, 2} and 1 (mean 0.9) would span 5 m: refused.
    roots, sizes = sequence_merges(t, node, i, j, links, 0.25, 0.5, x, y, max_extent=4.9)
    np.testing.assert_array_equal(roots, [0, 1, 0])
    np.testing.assert_array_equal(sizes, [1, 1, 2])
    # Step by step the same.
    state = new_state()
    step(state, 0.0, [0, 1], [0], [1], [0.9], 0.25, 0.5, x[:2], y[:2], 4.9)
    clusters, _, child, survivor = step(state, 0.1, [2], [0, 1], [2, 2], [0.9, 0.9], 0.25, 0.5, x[2:], y[2:], 4.9)
    assert clusters.tolist() == [0] and list(zip(child.tolist(), survivor.tolist(), strict=True)) == [(2, 0)]
    # Only the nodes of the pair window count: at 0.3 s node 3 links to node 2 (0.9, 0.2 s earlier); node 0
    # (0 s) has left the window, so the box of {0, 2} and 3 is that of node 2 (0, 0.5) and node 3.  Node 3 at
    # (3, 4.5): 5.0 m, refused; at (2.5, 4.5): 4.72 m, merged (with node 0 counted it would be 5.15 m).
    for x3, merged in ((3.0, False), (2.5, True)):
        state = new_state()
        step(state, 0.0, [0, 1], [0], [1], [0.9], 0.25, 0.5, x[:2], y[:2], 4.9)
        step(state, 0.1, [2], [0, 1], [2, 2], [0.9, 0.9], 0.25, 0.5, x[2:], y[2:], 4.9)
        clusters, *_ = step(state, 0.3, [3], [2], [3], [0.9], 0.25, 0.5, [x3], [4.5], 4.9)
        assert clusters.tolist() == ([0] if merged else [3])


def test_max_extent_needs_the_positions():
    with pytest.raises(ValueError, match="max_extent needs the positions"):
        sequence_merges(np.zeros(2), np.ones(2, dtype=bool), [0], [1], [0.9], 0.25, 0.5, max_extent=1.0)
    with pytest.raises(ValueError, match="one position per node"):
        sequence_merges(np.zeros(2), np.ones(2, dtype=bool), [0], [1], [0.9], 0.25, 0.5, np.zeros(1), np.zeros(1))


def _reference_merges(t, node, i, j, links, window, threshold):
    """The causal agglomeration as its definition reads, in plain Python: at each time, clusters whose last node
    is more than ``window`` older retire; the new nodes enter as singletons; their pairs add P(link) to the sum
    and count between the clusters they join; then the pair of clusters with the largest mean (ties: the
    smaller pair of numbers) merges, the younger into the older, while that mean exceeds ``threshold``."""
    evidence, cluster_of, size, last, parent = {}, {}, {}, {}, {}
    roots, sizes = np.full(len(t), -1), np.zeros(len(t), dtype=int)
    e = 0
    for now in np.unique(t):
        for c in [c for c in last if not now - last[c] <= window]:
            del size[c], last[c]
            evidence = {pair: v for pair, v in evidence.items() if c not in pair}
        new = [k for k in np.flatnonzero(t == now) if node[k]]
        for k in new:
            cluster_of[k], size[k], last[k], parent[k] = k, 1, now, k
        while e < len(j) and t[j[e]] == now:
            a, b = cluster_of[i[e]], j[e]
            found = evidence.setdefault((a, b), [0.0, 0])
            found[0] += links[e]
            found[1] += 1
            e += 1
        while evidence:
            (a, b), (s, k) = max(evidence.items(), key=lambda item: (item[1][0] / item[1][1], -item[0][0], -item[0][1]))
            if not s / k > threshold:
                break
            del evidence[a, b]
            for (p, q), (s_b, k_b) in [(pair, v) for pair, v in evidence.items() if b in pair]:
                c = q if p == b else p
                del evidence[p, q]
                mine = evidence.pop((min(a, c), max(a, c)), None)
                evidence[min(a, c), max(a, c)] = [mine[0] + s_b, mine[1] + k_b] if mine else [s_b, k_b]
            for n, c in cluster_of.items():
                if c == b:
                    cluster_of[n] = a
            size[a] += size.pop(b)
            last[a] = max(last[a], last.pop(b))
            parent[b] = a
        for k in new:
            sizes[k] = size[cluster_of[k]]
    for k in parent:
        root = k
        while parent[root] != root:
            root = parent[root]
        roots[k] = root
    return roots, sizes


@settings(max_examples=60, deadline=None)
@given(st.data())
def test_the_merges_are_those_of_the_definition(data):
    # Many detections over few times: more live clusters and recent nodes than the state first holds, mean links
    # on a grid of tenths (ties), pairs within the window (each later end a node).
    n = data.draw(st.integers(1, 200))
    t = np.sort(np.array(data.draw(st.lists(st.integers(0, 12), min_size=n, max_size=n)))) * 0.05
    node = np.array(data.draw(st.lists(st.booleans(), min_size=n, max_size=n)))
    window, threshold = 0.25, data.draw(st.sampled_from([0.3, 0.5, 0.7]))
    i, j = [], []
    for b in np.flatnonzero(node):
        earlier = [a for a in np.flatnonzero(node[:b]) if t[b] - t[a] <= window]
        i += sorted(data.draw(st.sets(st.sampled_from(earlier), max_size=6))) if earlier else []
        j += [b] * (len(i) - len(j))
    links = np.array(data.draw(st.lists(st.integers(0, 10), min_size=len(i), max_size=len(i)))) / 10
    i, j = np.array(i, dtype=np.int64), np.array(j, dtype=np.int64)
    roots, sizes = sequence_merges(t, node, i, j, links, window, threshold)
    expected_roots, expected_sizes = _reference_merges(t, node, i, j, links, window, threshold)
    np.testing.assert_array_equal(roots, expected_roots)
    np.testing.assert_array_equal(sizes, expected_sizes)
