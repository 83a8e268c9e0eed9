"""Numba kernels called without numba's dispatch, for the stream's small per-scan calls."""

from __future__ import annotations

import numba

_ENTRIES = {}


def entry_point(kernel, args):
    """The compiled ``kernel`` for the types of ``args``, to be called as ``entry_point(kernel, args)(*args)``.

    Numba's dispatcher types every argument at each call, which for a stream's scan (many arrays, or nested typed
    containers) can cost more than the kernel itself (:ref:`online-learned`).  A caller that always passes the same
    types (contiguous arrays of fixed dtypes, the same containers) compiles once and then calls the machine code
    directly: the entry point found at the first call serves every later one.

    Parameters
    ----------
    kernel : numba.core.registry.CPUDispatcher
        A ``numba.njit`` function.
    args : tuple
        Arguments of the types every call will pass.

    Returns
    -------
    entry : callable
    """
    found = _ENTRIES.get(kernel)
    if found is None:
        signature = tuple(numba.typeof(arg) for arg in args)
        kernel.compile(signature)
        found = _ENTRIES[kernel] = kernel.overloads[signature].entry_point
    return found
