"""The run's estimate counts numba's compile time when the kernels are not in the cache yet."""

import importlib
import sys

from sklearn_radar.reproduce import _progress


def test_every_kernel_of_the_compile_estimate_exists_and_is_a_cached_numba_kernel():
    for name in _progress.COMPILE_S:
        module, kernel = name.rsplit(".", 1)
        dispatcher = getattr(importlib.import_module(module), kernel)
        assert dispatcher._cache._cache_file._index_path  # numba's cache=True: an index file per kernel
    assert 0.0 <= _progress.compile_cost() <= sum(_progress.COMPILE_S.values())


def test_compile_cost_counts_a_kernel_until_its_first_compilation_fills_the_cache(tmp_path, monkeypatch):
    (tmp_path / "fresh_kernel_module.py").write_text(
        "import numba\n\n\n@numba.njit(cache=True)\ndef twice(x):\n    return 2 * x\n", encoding="utf-8"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "fresh_kernel_module", raising=False)
    module = importlib.import_module("fresh_kernel_module")
    monkeypatch.setattr(_progress, "COMPILE_S", {"fresh_kernel_module.twice": 7.0})
    assert _progress.compile_cost() == 7.0
    assert module.twice(3) == 6  # compiles and writes the cache
    assert _progress.compile_cost() == 0.0
