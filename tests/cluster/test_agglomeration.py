"""The greedy mean-link agglomeration of LinkClustering: hand-worked graphs and the plain-Python reference."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sklearn_radar.cluster._agglomeration import mean_link_merges, roots_at


def _load_reference():
    """The plain-Python implementation next to this file (tests run with --import-mode=importlib)."""
    path = Path(__file__).with_name("_agglomeration_reference.py")
    spec = importlib.util.spec_from_file_location("_agglomeration_reference", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


reference_merges = _load_reference().reference_merges


def _merges(n, edges, floor):
    i, j, p = (np.array(values) for values in zip(*edges, strict=True)) if edges else ([], [], [])
    child, survivor, link = mean_link_merges(n, i, j, p, floor)
    return [(int(a), int(b), float(c)) for a, b, c in zip(child, survivor, link, strict=True)]


def _partition(roots):
    groups = {}
    for node, root in enumerate(roots.tolist()):
        groups.setdefault(root, []).append(node)
    return sorted(groups.values())


# 0 -0.9- 1 -0.8- 2 -0.7- 3 -0.6- 4, and 0 -0.2- 2.
CHAIN = [(0, 1, 0.9), (1, 2, 0.8), (0, 2, 0.2), (2, 3, 0.7), (3, 4, 0.6)]


def test_a_chain_worked_by_hand():
    # 1. (0, 1) at 0.9; both have 2 neighbours: 0 (the smaller) survives.  {0, 1}-2 then has the pairs 0.2 and
    #    0.8: mean 0.5, not above the floor 0.5.  2. (2, 3) at 0.7, both 2 neighbours: 2 survives; {2, 3}-4 has
    #    the pair 0.6 only (3-4).  3. ({2, 3}, 4) at 0.6: {2, 3} has 2 neighbours, 4 one: 2 survives.
    assert _merges(5, CHAIN, 0.5) == [(1, 0, 0.9), (3, 2, 0.7), (4, 2, 0.6)]


def test_the_chain_does_not_chain():
    # Connected components of the links above 0.5 would join all five; the mean link keeps {0, 1} apart.
    merges = np.array(_merges(5, CHAIN, 0.5)).T
    child, survivor, link = merges[0].astype(int), merges[1].astype(int), merges[2]
    assert _partition(roots_at(5, child, survivor, link, 0.5)) == [[0, 1], [2, 3, 4]]
    assert _partition(roots_at(5, child, survivor, link, 0.65)) == [[0, 1], [2, 3], [4]]
    assert _partition(roots_at(5, child, survivor, link, 0.85)) == [[0, 1], [2], [3], [4]]
    assert _partition(roots_at(5, child, survivor, link, 0.95)) == [[0], [1], [2], [3], [4]]


def test_a_merge_can_raise_the_mean_link_above_the_floor():
    # 0-2 alone (0.45) is below the floor 0.5; once 0 and 1 merge, {0, 1}-2 has 0.45 and 0.75: mean 0.6.
    assert _merges(3, [(0, 1, 0.9), (0, 2, 0.45), (1, 2, 0.75)], 0.5) == [(1, 0, 0.9), (2, 0, 0.6)]


def test_missing_pairs_carry_no_evidence():
    # 2 links to 0 only; 1 and 2 were never a candidate pair, so {0, 1}-2 is 0.7, not (0.7 + 0) / 2.
    assert _merges(3, [(0, 1, 0.9), (0, 2, 0.7)], 0.5) == [(1, 0, 0.9), (2, 0, 0.7)]


def test_the_side_with_more_neighbours_survives():
    # 1 has three neighbours, 0 one: 0 is merged into 1.
    assert _merges(4, [(0, 1, 0.9), (1, 2, 0.3), (1, 3, 0.3)], 0.5) == [(0, 1, 0.9)]


def test_equal_links_merge_by_the_smaller_node_first():
    assert _merges(4, [(2, 3, 0.7), (0, 1, 0.7)], 0.5) == [(1, 0, 0.7), (3, 2, 0.7)]


def test_no_edges_no_merges():
    assert _merges(3, [], 0.5) == []
    child, survivor, link = mean_link_merges(0, [], [], [], 0.1)
    assert len(child) == len(survivor) == len(link) == 0
    assert roots_at(3, child, survivor, link, 0.5).tolist() == [0, 1, 2]


@pytest.mark.parametrize(
    "i, j, p, match",
    [
        ([0], [1, 2], [0.5], "one value per edge"),
        ([0], [3], [0.5], "nodes 0 to 2"),
        ([1], [1], [0.5], "itself"),
        ([0, 1], [1, 0], [0.5, 0.5], "twice"),
        ([0], [1], [np.nan], "finite"),
    ],
)
def test_bad_edges_raise(i, j, p, match):
    with pytest.raises(ValueError, match=match):
        mean_link_merges(3, i, j, p, 0.5)


@st.composite
def graphs(draw):
    n = draw(st.integers(1, 30))
    pairs = draw(st.sets(st.tuples(st.integers(0, n - 1), st.integers(0, n - 1)).filter(lambda e: e[0] < e[1])))
    pairs = sorted(pairs)
    # Few distinct values: many ties, the hard case for the order.
    levels = st.sampled_from([0.1, 0.3, 0.5, 0.6, 0.7, 0.9]) | st.floats(0, 1)
    probability = [draw(levels) for _ in pairs]
    return n, pairs, probability


@settings(max_examples=300, deadline=None)
@given(graphs(), st.sampled_from([0.0, 0.2, 0.5, 0.8]))
def test_the_kernel_equals_the_plain_python_reference(graph, floor):
    n, pairs, probability = graph
    edges = [(a, b, p) for (a, b), p in zip(pairs, probability, strict=True)]
    expected = reference_merges([a for a, _ in pairs], [b for _, b in pairs], probability, floor)
    assert _merges(n, edges, floor) == expected


@settings(max_examples=100, deadline=None)
@given(graphs(), st.sampled_from([0.2, 0.5, 0.8]))
def test_replaying_a_low_floor_gives_every_higher_one(graph, threshold):
    n, pairs, probability = graph
    edges = [(a, b, p) for (a, b), p in zip(pairs, probability, strict=True)]
    low = np.array(_merges(n, edges, 0.0)).reshape(-1, 3).T
    high = np.array(_merges(n, edges, threshold)).reshape(-1, 3).T
    replayed = roots_at(n, low[0].astype(int), low[1].astype(int), low[2], threshold)
    direct = roots_at(n, high[0].astype(int), high[1].astype(int), high[2], threshold)
    assert replayed.tolist() == direct.tolist()


def test_the_kernel_equals_the_reference_on_a_large_graph():
    rng = np.random.default_rng(0)
    n = 3000
    a = rng.integers(0, n - 40, 20000)
    b = a + rng.integers(1, 30, len(a))
    keys = np.unique(a * n + b)
    a, b = keys // n, keys % n
    p = rng.random(len(a))
    edges = list(zip(a.tolist(), b.tolist(), p.tolist(), strict=True))
    assert _merges(n, edges, 0.1) == reference_merges(a.tolist(), b.tolist(), p.tolist(), 0.1)
