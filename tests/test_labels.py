"""drop_small_clusters: whole sizes and sizes so far, against hand-made cases and a row-by-row count."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from sklearn_radar._labels import drop_small_clusters


def count_so_far(roots, t):
    """Per row: the rows of its cluster at or before its time (a loop written for the test)."""
    return np.array([np.sum((roots == r) & (t <= ti)) if r >= 0 else 0 for r, ti in zip(roots, t, strict=True)])


def test_whole_size_by_hand():
    roots = np.array([5, 5, 7, -1, 5, 7, 9])
    np.testing.assert_array_equal(drop_small_clusters(roots, 3), [5, 5, -1, -1, 5, -1, -1])
    np.testing.assert_array_equal(drop_small_clusters(roots, 2), [5, 5, 7, -1, 5, 7, -1])
    np.testing.assert_array_equal(drop_small_clusters(roots, 1), roots)


def test_size_so_far_by_hand():
    """Cluster 4 at t = 0, 0, 1, 2 s and cluster 8 at 0, 3 s: rows of one time count together."""
    roots = np.array([4, 8, 4, 4, -1, 4, 8])
    t = np.array([0.0, 0.0, 0.0, 1.0, 1.0, 2.0, 3.0])
    np.testing.assert_array_equal(drop_small_clusters(roots, 3, t), [-1, -1, -1, 4, -1, 4, -1])
    np.testing.assert_array_equal(drop_small_clusters(roots, 2, t), [4, -1, 4, 4, -1, 4, 8])


def test_input_is_not_changed():
    roots = np.array([1, 1, 2])
    drop_small_clusters(roots, 2, np.zeros(3))
    np.testing.assert_array_equal(roots, [1, 1, 2])


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.tuples(st.integers(-1, 4), st.integers(0, 5)), min_size=0, max_size=40),
    st.integers(1, 6),
)
def test_matches_a_row_by_row_count(rows, min_size):
    roots = np.array([r for r, _ in rows], dtype=np.int64)
    t = np.array([ti * 0.05 for _, ti in rows], dtype=np.float64)
    whole = np.array([np.sum(roots == r) if r >= 0 else 0 for r in roots])
    np.testing.assert_array_equal(drop_small_clusters(roots, min_size), np.where(whole >= min_size, roots, -1))
    so_far = count_so_far(roots, t)
    np.testing.assert_array_equal(drop_small_clusters(roots, min_size, t), np.where(so_far >= min_size, roots, -1))
