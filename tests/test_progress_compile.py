"""The progress lines: the run says when it compiles the numba kernels, and estimates only what it measured."""

import importlib
import sys

import pytest

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


# ----------------------------------------------------------------------------- the progress lines (issue 46)


def _on_a_clock(work, monkeypatch):
    """A RunProgress on a clock the test moves (``clock[0]``)."""
    clock = [0.0]
    monkeypatch.setattr(_progress.time, "perf_counter", lambda: clock[0])
    return _progress.RunProgress(work, started=0.0), clock


def test_no_time_left_is_estimated_before_a_step_of_a_kind_still_to_come_was_timed(monkeypatch):
    # A quick scoring pass must not price a classification step that takes minutes ("about 0:01 left").
    progress, clock = _on_a_clock({"1": ("scoring", 1), "classification": ("classification", 1)}, monkeypatch)
    progress.start("1")
    clock[0] = 1.0
    progress.finish("1")
    status = progress.status()
    assert "about" not in status and "left" in status
    assert status.endswith("time left unknown (not timed yet: classification)")
    progress.start("classification")
    clock[0] = 130.0
    progress.finish("classification")
    assert progress.status() == "run 100 %, 2:10 elapsed"


def test_the_time_left_of_the_timed_kinds_is_said_beside_the_untimed_ones(monkeypatch):
    work = {"8": ("stage 1", 10), "9": ("stage 1", 10), "baselines": ("baselines", 60)}
    progress, clock = _on_a_clock(work, monkeypatch)
    progress.start("8")
    clock[0] = 5.0
    progress.finish("8")  # 0.5 s an iteration: #9's 10 iterations take about 5 s
    assert progress.status().endswith("time left unknown (not timed yet: the baselines; the rest about 0:05)")


def test_the_share_done_weighs_the_work_by_its_expected_cost(monkeypatch):
    # 12 stage-1 iterations done, 60 baseline iterations to come: the baselines are most of the run, not a
    # few per cent of it because their kind was not timed yet ("60 s at 93 %").
    from sklearn_radar.reproduce._progress import EXPECTED_S_PER_UNIT

    progress, clock = _on_a_clock({"8": ("stage 1", 12), "baselines": ("baselines", 60)}, monkeypatch)
    progress.start("8")
    clock[0] = 12 * 2 * EXPECTED_S_PER_UNIT["stage 1"]  # this machine runs at half the expected speed
    progress.finish("8")
    expected_baselines = 60 * 2 * EXPECTED_S_PER_UNIT["baselines"]
    share = clock[0] / (clock[0] + expected_baselines)
    assert progress.share() == pytest.approx(share)
    assert progress.status().startswith(f"run {100 * share:.0f} %,")
    assert share < 0.2


def test_a_run_whose_steps_all_ended_is_at_100_percent(monkeypatch):
    from sklearn_radar.reproduce._progress import DATA, REPORT

    work = {DATA: (DATA, 1), "filter": ("filter", 1), REPORT: (REPORT, 1)}
    progress, clock = _on_a_clock(work, monkeypatch)
    progress.finish(DATA, 7.0)
    progress.start("filter")
    clock[0] = 9.0
    progress.finish("filter")
    progress.start(REPORT)  # the report is being written: the steps are done
    assert progress.status() == "run 100 %, 0:09 elapsed"


def test_every_kind_of_step_has_an_expected_cost():
    from sklearn_radar.reproduce._progress import EXPECTED_S_PER_UNIT
    from sklearn_radar.reproduce._steps import STEPS

    assert {step.kind for step in STEPS.values()} == set(EXPECTED_S_PER_UNIT)


def test_a_status_line_names_at_most_three_untimed_kinds(monkeypatch):
    kinds = ["filter", "scoring", "stage 1", "stage 2", "baselines"]
    progress, _ = _on_a_clock({kind: (kind, 1) for kind in kinds}, monkeypatch)
    assert progress.status() == (
        "run 0 %, 0:00 elapsed, time left unknown (not timed yet: the filter evaluation, scoring and 3 more kinds)"
    )
