"""The neighbour grid and the label numbering against their plain numpy definitions."""

import numpy as np
import pytest

from sklearn_radar._labels import consecutive_labels, rank_by_first_appearance
from sklearn_radar._neighbors import CELL_COORDINATE_BOUND, build_grid, cell_key, neighbor_cells


def _grid_problem(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(0, 400))
    spread = rng.choice([0.5, 5.0, 60.0, 1e5])  # the last: a bounding box too sparse for the counting sort
    x, y = rng.normal(0, spread, n), rng.normal(0, 3.0, n)
    t = np.round(rng.uniform(0, 3, n), 1)  # ties in time, as within one scan
    if seed % 2:
        t = np.sort(t)  # time-sorted input, as a sequence usually comes
    return x, y, t, float(rng.uniform(0.3, 2.0))


@pytest.mark.parametrize("seed", range(40))
def test_grid_order_is_lexsort_by_cell_then_time_then_row(seed):
    x, y, t, cell = _grid_problem(seed)
    grid = build_grid(x, y, t, cell)
    cx, cy = np.floor(x / cell).astype(np.int64), np.floor(y / cell).astype(np.int64)
    np.testing.assert_array_equal(grid.order, np.lexsort((np.arange(len(t)), t, cy, cx)))


@pytest.mark.parametrize("seed", range(40))
def test_neighbor_cells_are_the_occupied_cells_of_the_3_by_3_block(seed):
    x, y, t, cell = _grid_problem(seed)
    grid = build_grid(x, y, t, cell)
    table = neighbor_cells(grid.cell_keys, grid.cell_start, grid.cell_x, grid.cell_y)
    where = {(int(grid.cell_x[s]), int(grid.cell_y[s])): c for c, s in enumerate(grid.cell_start)}
    for c, s in enumerate(grid.cell_start):
        cx, cy = int(grid.cell_x[s]), int(grid.cell_y[s])
        expected = [where.get((cx + dx, cy + dy), -1) for dx in (-1, 0, 1) for dy in (-1, 0, 1)]
        assert table[c].tolist() == expected


@pytest.mark.parametrize("seed", range(30))
def test_consecutive_labels_number_clusters_by_first_row(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(0, 300))
    roots = rng.integers(-2, rng.choice([3, n + 1, 10 * n + 5, 10**9]), n)  # small keys take the linear path
    expected = np.full(n, -1)
    clustered = roots >= 0
    expected[clustered] = rank_by_first_appearance(roots[clustered])
    np.testing.assert_array_equal(consecutive_labels(roots), expected)
    first = {}
    for r in roots.tolist():  # by hand: ids 0, 1, ... in order of first row
        if r >= 0:
            first.setdefault(r, len(first))
    assert consecutive_labels(roots).tolist() == [first[r] if r >= 0 else -1 for r in roots.tolist()]


def test_cell_keys_sort_as_x_then_y_over_the_whole_coordinate_range():
    bound = int(CELL_COORDINATE_BOUND)
    cells = np.array([-bound, -bound + 1, -1, 0, 1, bound - 2, bound - 1], dtype=np.int64)
    cell_x, cell_y = (grid.ravel() for grid in np.meshgrid(cells, cells, indexing="ij"))  # x major, y minor
    keys = cell_key.py_func(cell_x, cell_y)
    assert np.all(np.diff(keys) > 0)
    assert [cell_key(a, b) for a, b in zip(cell_x, cell_y, strict=True)] == keys.tolist()  # compiled = numpy
    with pytest.raises(ValueError, match="'y'"):
        build_grid(np.zeros(2), np.array([0.0, CELL_COORDINATE_BOUND]), np.zeros(2), 1.0)
