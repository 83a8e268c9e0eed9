"""Spatio-temporal neighbour search kernels (numba), apart from the estimators.

Points live in a square x-y grid whose cell side equals the search radius,
so the neighbours of a point lie in its own and the eight surrounding cells.
Within a cell the points are sorted by time, so the time window is two
binary searches.  Nothing quadratic is ever materialised: the kernels count
(or visit) candidates on the fly, and a count stops at its cap.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

#: A cell key packs the x and y cell coordinates into one int64, y in the low ``_Y_BITS`` bits (shifted to be
#: non-negative), so the keys sort as (x, y).  Everything below derives from this one number.
_Y_BITS = 32
_KEY_SHIFT = np.int64(2**_Y_BITS)
_KEY_OFFSET = np.int64(2 ** (_Y_BITS - 1))
#: Cell coordinates must lie in [-CELL_COORDINATE_BOUND, CELL_COORDINATE_BOUND) for their key not to overflow.
CELL_COORDINATE_BOUND = float(2 ** (_Y_BITS - 1))


@dataclass
class GridIndex:
    """Points sorted by (grid cell, time), with the table of occupied cells."""

    order: np.ndarray  # sorted position -> input row
    x: np.ndarray  # m, sorted
    y: np.ndarray  # m, sorted
    t: np.ndarray  # s, sorted
    cell_x: np.ndarray  # integer cell coordinates, sorted
    cell_y: np.ndarray
    cell_keys: np.ndarray  # occupied cells, ascending
    cell_start: np.ndarray  # first sorted position of each occupied cell
    cell_end: np.ndarray  # one past the last


@numba.njit(cache=True, nogil=True, inline="always")
def cell_key(cell_x, cell_y):
    """The int64 key of grid cell (cell_x, cell_y); keys sort as (x, y).  ``cell_key.py_func`` serves numpy arrays."""
    return cell_x * _KEY_SHIFT + (cell_y + _KEY_OFFSET)


def build_grid(x, y, t, cell_size) -> GridIndex:
    """Index points for radius-``cell_size`` searches (m); ``t`` in s.

    Raises
    ------
    ValueError
        Naming the column, when a coordinate lies beyond 2**31 cells from
        the origin (about 1e9 m for a 0.5 m cell), where the cell key
        would overflow.
    """
    x, y, t = (np.ascontiguousarray(a, dtype=np.float64) for a in (x, y, t))
    cell_x = _cell_coordinates(x, cell_size, "x")
    cell_y = _cell_coordinates(y, cell_size, "y")
    order, cell_keys, cell_start, cell_end = cell_runs(cell_x, cell_y, t)
    return GridIndex(
        order=order,
        x=x[order],
        y=y[order],
        t=t[order],
        cell_x=cell_x[order],
        cell_y=cell_y[order],
        cell_keys=cell_keys,
        cell_start=cell_start,
        cell_end=cell_end,
    )


def cell_runs(cell_x, cell_y, t):
    """Items sorted by (grid cell, ``t``, row), as runs of equal cells: the cell table of a grid.

    Parameters
    ----------
    cell_x, cell_y : ndarray of int64, shape (n,)
        Cell coordinates of each item, within ``[-CELL_COORDINATE_BOUND, CELL_COORDINATE_BOUND)``.
    t : ndarray, shape (n,)
        Order of the items within a cell (the time, s, of a point).

    Returns
    -------
    order : ndarray of int64, shape (n,)
        Sorted position -> item.
    cell_keys : ndarray of int64
        :func:`cell_key` of each occupied cell, ascending.
    cell_start, cell_end : ndarray of int64
        First sorted position of each occupied cell, and one past its last.
    """
    keys = cell_key.py_func(cell_x, cell_y)
    order = _cell_time_order(cell_x, cell_y, t, keys)
    keys = keys[order]
    first = np.flatnonzero(np.r_[True, keys[1:] != keys[:-1]]) if len(keys) else np.zeros(0, np.int64)
    return order, keys[first], first.astype(np.int64), np.r_[first[1:], len(keys)].astype(np.int64)


def _cell_time_order(cell_x, cell_y, t, keys):
    """``np.lexsort((t, keys))``: by cell (x major, y minor), then time, then row; linear when the grid is compact.

    When the occupied bounding box has at most about 16 cells per point, a
    stable counting sort by cell of the time-sorted rows gives the same
    order as the comparison sort, in linear time.
    """
    n = len(t)
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    x_low, y_low = cell_x.min(), cell_y.min()
    width = int(cell_y.max() - y_low) + 1
    n_boxes = (int(cell_x.max() - x_low) + 1) * width
    if n_boxes > 16 * n + 65536:  # a sparse bounding box: the counts would cost more than the sort
        return np.lexsort((t, keys))
    by_time = np.arange(n) if np.all(t[1:] >= t[:-1]) else np.argsort(t, kind="stable")
    return _counting_order((cell_x - x_low) * width + (cell_y - y_low), by_time, n_boxes)


@numba.njit(cache=True, nogil=True)
def _counting_order(box, by_time, n_boxes):
    """Stable counting sort of the rows ``by_time`` by their ``box`` number."""
    count = np.zeros(n_boxes + 1, dtype=np.int64)
    for i in range(len(box)):
        count[box[i] + 1] += 1
    for b in range(n_boxes):
        count[b + 1] += count[b]
    order = np.empty(len(box), dtype=np.int64)
    for i in by_time:
        order[count[box[i]]] = i
        count[box[i]] += 1
    return order


def _cell_coordinates(values, cell_size, name):
    """``floor(values / cell_size)`` as int64; ValueError names the column when it cannot be one."""
    with np.errstate(over="ignore", invalid="ignore"):
        cells = np.floor(values / cell_size)
    if len(cells) and not np.all((cells >= -CELL_COORDINATE_BOUND) & (cells < CELL_COORDINATE_BOUND)):
        worst = float(np.max(np.abs(values)))
        raise ValueError(
            f"column {name!r} holds a coordinate of magnitude {worst:.3g} m, beyond the neighbour grid's reach "
            f"of {CELL_COORDINATE_BOUND * cell_size:.3g} m (2**{_Y_BITS - 1} cells of {cell_size:g} m); shift the data "
            f"nearer the origin, "
            f"or, if that is no position in m (another column read as {name!r}, e.g. a plain array in another "
            f"layout than the working detection array), pass the detection table as a DataFrame"
        )
    return cells.astype(np.int64)


def count_neighbors(grid: GridIndex, radius, before, after, cap) -> np.ndarray:
    """Number of other points within ``radius`` (m) and the time window, capped.

    A point j is a neighbour of i when ``hypot(x_j - x_i, y_j - y_i) <= radius``
    and ``t_i - before <= t_j <= t_i + after`` (s); i itself does not count.
    Counting stops at ``cap``.

    Returns
    -------
    counts : ndarray of int64 in input row order
    """
    sorted_counts = _count_capped(
        grid.x,
        grid.y,
        grid.t,
        grid.cell_x,
        grid.cell_y,
        grid.cell_keys,
        grid.cell_start,
        grid.cell_end,
        float(radius) ** 2,
        float(before),
        float(after),
        int(cap),
    )
    counts = np.empty_like(sorted_counts)
    counts[grid.order] = sorted_counts
    return counts


@numba.njit(cache=True, nogil=True)
def neighbor_cells(cell_keys, cell_start, cell_x, cell_y):
    """For each occupied cell, the indices of its 3 x 3 neighbourhood in the cell table (-1: empty).

    Slot ``3 * (dx + 1) + (dy + 1)`` holds the cell at offset (dx, dy).  The
    keys are sorted and a neighbour's key grows with the cell's, so one
    forward-moving position per column offset finds them all: linear in the
    number of cells.
    """
    n_cells = len(cell_keys)
    table = np.full((n_cells, 9), -1, dtype=np.int64)
    position = np.zeros(3, dtype=np.int64)
    for c in range(n_cells):
        first = cell_start[c]
        for dx in range(-1, 2):
            low = cell_key(cell_x[first] + dx, cell_y[first] - 1)
            q = position[dx + 1]
            while q < n_cells and cell_keys[q] < low:
                q += 1
            position[dx + 1] = q
            for dy in range(3):
                key = low + dy
                while q < n_cells and cell_keys[q] < key:
                    q += 1
                if q < n_cells and cell_keys[q] == key:
                    table[c, 3 * (dx + 1) + dy] = q
    return table


@numba.njit(cache=True, nogil=True)
def point_cells(cell_start, cell_end, n):
    """Cell index of every (sorted) point."""
    cell = np.empty(n, dtype=np.int64)
    for c in range(len(cell_start)):
        cell[cell_start[c] : cell_end[c]] = c
    return cell


@numba.njit(cache=True, nogil=True, inline="always")
def time_range(times, start, end, t_low, t_high):
    """Positions in [start, end) of a time-sorted run whose times lie in [t_low, t_high]."""
    if end - start <= 16:  # short runs: a linear walk beats two binary searches
        lo = start
        while lo < end and times[lo] < t_low:
            lo += 1
        hi = lo
        while hi < end and times[hi] <= t_high:
            hi += 1
        return lo, hi
    lo = start + np.searchsorted(times[start:end], t_low, side="left")
    hi = start + np.searchsorted(times[start:end], t_high, side="right")
    return lo, hi


@numba.njit(cache=True, nogil=True)
def _count_capped(x, y, t, cell_x, cell_y, cell_keys, cell_start, cell_end, radius2, before, after, cap):
    n = len(x)
    cells = neighbor_cells(cell_keys, cell_start, cell_x, cell_y)
    point_cell = point_cells(cell_start, cell_end, n)
    counts = np.zeros(n, dtype=np.int64)
    for i in range(n):
        count = 0
        for k in range(9):
            c = cells[point_cell[i], k]
            if c < 0:
                continue
            lo, hi = time_range(t, cell_start[c], cell_end[c], t[i] - before, t[i] + after)
            for j in range(lo, hi):
                if j != i:
                    ddx = x[j] - x[i]
                    ddy = y[j] - y[i]
                    if ddx * ddx + ddy * ddy <= radius2:
                        count += 1
                        if count >= cap:
                            break
            if count >= cap:
                break
        counts[i] = count
    return counts
