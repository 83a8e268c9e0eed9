"""Union-find for the numba kernels of both stages (one implementation)."""

from __future__ import annotations

import numba


@numba.njit(cache=True, nogil=True)
def find(parent, i):
    """Root of ``i`` in the forest ``parent``, with path halving."""
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@numba.njit(cache=True, nogil=True)
def union_keep_smaller(parent, i, j):
    """Merge the sets of ``i`` and ``j``; the smaller root survives (the older cluster wins)."""
    a = find(parent, i)
    b = find(parent, j)
    if a < b:
        parent[b] = a
    elif b < a:
        parent[a] = b
