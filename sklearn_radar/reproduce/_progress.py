"""The overall progress of a reproduce run: an estimate of its length at the start, elapsed time and ETA.

Plain lines only (no carriage returns, no terminal control), so the output
reads the same in a terminal and piped to a file.  The estimate is a cost
model per step, calibrated on the default run and ``--full`` on an idle
2-core machine; as steps finish, the remaining time is rescaled by how fast
this machine actually went.
"""

from __future__ import annotations

import importlib
import time

from ._constants import BASELINES, FILTER, FILTER_EFFECT, STAGE2
from ._results import Budget

#: Seconds per iteration of one search on about 90,000 training detections (:data:`REFERENCE_TRAIN`), by kind of
#: step, measured on the default run on an idle 2-core machine (the four baselines together; commit 0d7f519).
PER_ITERATION = {"stage 1": 0.2, "stage 2": 0.3, BASELINES: 3.1}
#: The training detections of that measurement.
REFERENCE_TRAIN = 90_000
#: How an iteration's time grows with the training detections, by kind of step: fitted to the default run and
#: ``--full --repeats 1 --n-jobs 2`` (100 iterations on 6.3 times the training data: about 0.49 s per stage-1
#: iteration, 0.53 s per stage-2 iteration, 6.3 s per iteration of the four baselines; 21 min 40 s in all) on
#: the same 2-core machine at commit cd345b9.  The progress lines correct the estimate as the run goes.
SIZE_EXPONENT = {"stage 1": 0.49, "stage 2": 0.31, BASELINES: 0.38}
#: Shortest time of one iteration (the optimiser's and the scoring's fixed costs), s, by kind of step.
MIN_PER_ITERATION = {"stage 1": 0.15, "stage 2": 0.15, BASELINES: 1.0}
#: Each search also scores the paper's setting and the kept one on the test half: about two iterations more.
EXTRA_ITERATIONS = 2
#: Seconds per detection of the steps without a search.
PER_DETECTION = {FILTER: 1.2e-5, FILTER_EFFECT: 5e-6, "fixed": 2e-6}
#: Seconds to draw the figures and write the report.
REPORT_S = 6.0
#: Seconds of the first run in a new environment spent compiling the numba kernels the run uses, by kernel (later
#: runs load them from numba's cache): the default run's cold minus warm time in a new virtual environment on the
#: 2-core machine, 12-13 s, shared out by each kernel's compile time (docs/performance.rst, "Compile time").
COMPILE_S = {
    "sklearn_radar.cluster._radar_dbscan_kernels._dbscan_sorted": 3.6,
    "sklearn_radar.cluster._merge_kernels._candidate_pairs": 3.0,
    "sklearn_radar._neighbors._count_capped": 1.4,
    "sklearn_radar.cluster._merge_kernels._continuation_edges": 1.1,
    "sklearn_radar.cluster._merge_kernels._max_speeds": 1.1,
    "sklearn_radar.cluster._merge_kernels._velocity_frames": 0.5,
    "sklearn_radar._labels._number_by_first_row": 0.6,
    "sklearn_radar.cluster._merge_kernels._merge_components": 0.3,
    "sklearn_radar._neighbors._counting_order": 0.3,
}


def step_cost(key, budget: Budget, n_train, n_test, n_detections, tuned):
    """Estimated seconds of one step on an idle 2-core machine.

    Parameters
    ----------
    key : str
        Step key (``"filter"``, ``"8"``, ``"baselines"``, ...).
    budget : Budget
    n_train, n_test, n_detections : float
        Detections of the training half, the test half and all of the data.
    tuned : bool
        Whether the step is an experiment with a search.

    Returns
    -------
    seconds : float
    """
    if key == FILTER:
        return PER_DETECTION[FILTER] * n_detections
    if key == FILTER_EFFECT:
        return PER_DETECTION[FILTER_EFFECT] * n_test
    if key != BASELINES and not tuned:
        return PER_DETECTION["fixed"] * n_test
    kind = BASELINES if key == BASELINES else ("stage 2" if int(key) in STAGE2 else "stage 1")
    scale = (max(n_train, 1) / REFERENCE_TRAIN) ** SIZE_EXPONENT[kind]
    per_iteration = max(MIN_PER_ITERATION[kind], PER_ITERATION[kind] * scale)
    return (budget.n_iter + EXTRA_ITERATIONS) * per_iteration


def compile_cost():
    """Estimated seconds the run will spend compiling: :data:`COMPILE_S` of the kernels not in numba's cache.

    A kernel is cached when its cache index (one small file per kernel,
    written at its first compilation) exists and matches the source file;
    after an install or an edit of the source, it does not.

    Returns
    -------
    seconds : float
        0 when every kernel is cached (or numba's cache cannot be read).
    """
    seconds = 0.0
    for name, cost in COMPILE_S.items():
        module, kernel = name.rsplit(".", 1)
        try:
            cached = bool(getattr(importlib.import_module(module), kernel)._cache._cache_file._load_index())
        except Exception:  # another numba's cache internals: no claim either way
            cached = True
        seconds += 0.0 if cached else cost
    return seconds


def duration(seconds):
    """``75`` -> ``"1:15"``, ``4000`` -> ``"1:06:40"``: a duration as [h:]mm:ss."""
    seconds = max(0, round(seconds))
    hours, rest = divmod(seconds, 3600)
    minutes, seconds = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{seconds:02d}" if hours else f"{minutes}:{seconds:02d}"


def rough(seconds):
    """A duration in words for the estimate: ``"about 2 min"``, ``"about 1.5 h"``."""
    if seconds < 90:
        return f"about {max(1, round(seconds / 10) * 10)} s"
    if seconds < 3600:
        return f"about {round(seconds / 60)} min"
    return f"about {seconds / 3600:.1f} h"


class RunProgress:
    """Where a run stands: the share of its estimated work done, the time elapsed and the time left.

    Parameters
    ----------
    costs : dict of str to float
        Estimated seconds of each step, in run order (:func:`step_cost`).
    started : float
        ``time.perf_counter()`` at the start of the run.

    Attributes
    ----------
    done : float
        Estimated seconds of the work finished so far.
    """

    def __init__(self, costs, started):
        self.costs = dict(costs)
        self.total = sum(self.costs.values()) or 1.0
        self.started = started
        self.done = 0.0
        self._current = None
        self._credited = {}

    def credit(self, key, fraction):
        """``fraction`` of step ``key`` ended ahead of the step (a search that ran concurrently)."""
        share = self.costs.get(key, 0.0) * min(max(fraction, 0.0), 1.0)
        self._credited[key] = self._credited.get(key, 0.0) + share
        self.done += share

    def start(self, key):
        """A step begins."""
        self._current = key

    def advance(self, fraction):
        """The current step is ``fraction`` (0-1) done."""
        return self._done_with(min(max(fraction, 0.0), 1.0))

    def finish(self, key):
        """A step ended (what :meth:`credit` counted already is not counted twice)."""
        self.done += max(self.costs.get(key, 0.0) - self._credited.pop(key, 0.0), 0.0)
        self._current = None

    def _done_with(self, fraction):
        if not self._current:
            return self.done
        remaining = max(self.costs.get(self._current, 0.0) - self._credited.get(self._current, 0.0), 0.0)
        return self.done + remaining * fraction

    def status(self, fraction=0.0):
        """``"run 42 %, 0:53 elapsed, about 1:13 left"``, with ``fraction`` of the current step done."""
        done = self._done_with(min(max(fraction, 0.0), 1.0))
        elapsed = time.perf_counter() - self.started
        share = done / self.total
        # The machine's speed relative to the estimate, once a few percent of the work tells it.
        speed = elapsed / done if share >= 0.03 and done > 0 else 1.0
        left = (self.total - done) * speed
        return f"run {100 * share:.0f} %, {duration(elapsed)} elapsed, about {duration(left)} left"

    def search_status(self, part=0, parts=1):
        """A ``status`` for :class:`~sklearn_radar.model_selection.ProgressPrinter` of search ``part`` of ``parts``.

        Returns
        -------
        status : callable
            ``status(i, n) -> str`` after iteration ``i`` of ``n``.
        """
        return lambda i, n: self.status((part + i / max(n, 1)) / parts)


__all__ = ["COMPILE_S", "REPORT_S", "RunProgress", "compile_cost", "duration", "rough", "step_cost"]
