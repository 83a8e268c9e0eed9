"""The run says when it compiles the numba kernels (their cache is empty): its first steps then run slower."""

import importlib
import sys

from sklearn_radar.reproduce import _progress


def test_every_kernel_of_the_compile_note_exists_and_is_a_cached_numba_kernel():
    for name in _progress.KERNELS:
        module, kernel = name.rsplit(".", 1)
        dispatcher = getattr(importlib.import_module(module), kernel)
        assert dispatcher._cache._cache_file._index_path  # numba's cache=True: an index file per kernel
    assert set(_progress.uncompiled_kernels()) <= set(_progress.KERNELS)


def test_a_kernel_counts_as_uncompiled_until_its_first_compilation_fills_the_cache(tmp_path, monkeypatch):
    (tmp_path / "fresh_kernel_module.py").write_text(
        "import numba\n\n\n@numba.njit(cache=True)\ndef twice(x):\n    return 2 * x\n", encoding="utf-8"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "fresh_kernel_module", raising=False)
    module = importlib.import_module("fresh_kernel_module")
    monkeypatch.setattr(_progress, "KERNELS", ("fresh_kernel_module.twice",))
    assert _progress.uncompiled_kernels() == ["fresh_kernel_module.twice"]
    assert module.twice(3) == 6  # compiles and writes the cache
    assert _progress.uncompiled_kernels() == []
