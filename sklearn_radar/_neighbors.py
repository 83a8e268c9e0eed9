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

_KEY_SHIFT = np.int64(2**32)
_KEY_OFFSET = np.int64(2**31)


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


def build_grid(x, y, t, cell_size) -> GridIndex:
    """Index points for radius-``cell_size`` searches (m); ``t`` in s."""
    x, y, t = (np.ascontiguousarray(a, dtype=np.float64) for a in (x, y, t))
    cell_x = np.floor(x / cell_size).astype(np.int64)
    cell_y = np.floor(y / cell_size).astype(np.int64)
    keys = cell_x * _KEY_SHIFT + (cell_y + _KEY_OFFSET)
    order = np.lexsort((t, keys))
    keys = keys[order]
    first = np.flatnonzero(np.r_[True, keys[1:] != keys[:-1]]) if len(keys) else np.zeros(0, np.int64)
    return GridIndex(
        order=order,
        x=x[order],
        y=y[order],
        t=t[order],
        cell_x=cell_x[order],
        cell_y=cell_y[order],
        cell_keys=keys[first],
        cell_start=first.astype(np.int64),
        cell_end=np.r_[first[1:], len(keys)].astype(np.int64),
    )


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
        grid.x, grid.y, grid.t, grid.cell_x, grid.cell_y, grid.cell_keys, grid.cell_start, grid.cell_end,
        float(radius) ** 2, float(before), float(after), int(cap),
    )  # fmt: skip
    counts = np.empty_like(sorted_counts)
    counts[grid.order] = sorted_counts
    return counts


@numba.njit(cache=True, nogil=True)
def _cell_range(cell_keys, cell_start, cell_end, key):
    c = np.searchsorted(cell_keys, key)
    if c < len(cell_keys) and cell_keys[c] == key:
        return cell_start[c], cell_end[c]
    return 0, 0


@numba.njit(cache=True, nogil=True)
def _count_capped(x, y, t, cell_x, cell_y, cell_keys, cell_start, cell_end, radius2, before, after, cap):
    n = len(x)
    counts = np.zeros(n, dtype=np.int64)
    for i in range(n):
        count = 0
        for dx in range(-1, 2):
            for dy in range(-1, 2):
                key = (cell_x[i] + dx) * 4294967296 + (cell_y[i] + dy + 2147483648)
                start, end = _cell_range(cell_keys, cell_start, cell_end, key)
                if start == end:
                    continue
                lo = start + np.searchsorted(t[start:end], t[i] - before, side="left")
                hi = start + np.searchsorted(t[start:end], t[i] + after, side="right")
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
            if count >= cap:
                break
        counts[i] = count
    return counts
