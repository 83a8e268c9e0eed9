"""The overall progress of a reproduce run: the work done so far, the time elapsed and the time left.

Plain lines only (no carriage returns, no terminal control), so the output
reads the same in a terminal and piped to a file.  No cost model: the run
counts its work in units of a few kinds (an iteration of a stage-1, stage-2
or baseline search, one pass of a step without a search over its data) and
measures the seconds each kind took so far.  The time left is the work left
at those rates; a kind not measured yet is priced like a test-half scoring
pass (a candidate's evaluation clusters about as much data), else like any
step measured; before the first step ends, the time left is not known.  When
work ran concurrently, its seconds add up to more than the time elapsed, and
the rates are scaled by that overlap.
"""

from __future__ import annotations

import importlib
import threading
import time

#: The kind of the data step and of the report, whose measured time prices a kind that has none yet.
DATA, REPORT = "data", "report"
#: The kind of a pass over the test half that scores a fixed setting: the price of a search iteration until one is
#: measured (each candidate clusters the training half).
SCORING = "scoring"
#: The numba kernels a run compiles on an empty cache (a new environment): the first steps then run slower.
KERNELS = (
    "sklearn_radar.cluster._radar_dbscan_kernels._dbscan_sorted",
    "sklearn_radar.cluster._merge_kernels._candidate_pairs",
    "sklearn_radar._neighbors._count_capped",
    "sklearn_radar.cluster._merge_kernels._continuation_edges",
    "sklearn_radar.cluster._merge_kernels._max_speeds",
    "sklearn_radar.cluster._merge_kernels._velocity_frames",
    "sklearn_radar._labels._number_by_first_row",
    "sklearn_radar.cluster._merge_kernels._merge_components",
    "sklearn_radar._neighbors._counting_order",
)


def uncompiled_kernels():
    """The :data:`KERNELS` not in numba's cache yet (their cache index is missing or stale).

    Returns
    -------
    names : list of str
        Empty when every kernel is cached (or numba's cache cannot be read).
    """
    names = []
    for name in KERNELS:
        module, kernel = name.rsplit(".", 1)
        try:
            cached = bool(getattr(importlib.import_module(module), kernel)._cache._cache_file._load_index())
        except Exception:  # another numba's cache internals: no claim either way
            cached = True
        if not cached:
            names.append(name)
    return names


def duration(seconds):
    """``75`` -> ``"1:15"``, ``4000`` -> ``"1:06:40"``: a duration as [h:]mm:ss."""
    seconds = max(0, round(seconds))
    hours, rest = divmod(seconds, 3600)
    minutes, seconds = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{seconds:02d}" if hours else f"{minutes}:{seconds:02d}"


class RunProgress:
    """Where a run stands: its work done, measured per kind, and the time left at the measured rates.

    Parameters
    ----------
    work : dict of str to (str, float)
        Per step key, its kind and its units of work, in run order.
    started : float
        ``time.perf_counter()`` at the start of the run.
    stream : file-like or None
        Where :meth:`say` prints (None: nowhere).
    searches : int, default=0
        The run's searches, for the lines of :meth:`search_ended`.

    A copy in another process (joblib) prints nothing and counts for itself.
    """

    def __init__(self, work, started, stream=None, searches=0):
        self.work = dict(work)
        self.searches, self._ended = searches, 0
        self.started = started
        self.stream = stream
        self._lock = threading.Lock()
        self._done = dict.fromkeys(self.work, 0.0)
        self._spent, self._units = {}, {}
        self._last = {}
        self._shown = 0.0

    def __getstate__(self):
        state = dict(self.__dict__)
        del state["_lock"]
        return {**state, "stream": None}

    def __setstate__(self, state):
        self.__dict__.update(state, _lock=threading.Lock())

    def say(self, text):
        """Print a line (whole, also from several threads)."""
        if self.stream is not None:
            with self._lock:
                print(text, file=self.stream, flush=True)

    def search_ended(self, label):
        """Say that the search ``label``, which ran beside others, ended, and how many have."""
        status = self.status()
        with self._lock:
            self._ended += 1
            text = f"    search {label} ended ({self._ended}/{self.searches} of the concurrent searches) | {status}"
        self.say(text)

    def start(self, key):
        """Step ``key`` begins: its next units are timed from now."""
        with self._lock:
            self._last[key] = time.perf_counter()

    def advance(self, key, units=1.0):
        """``units`` more of step ``key`` are done, in the time since its start or its last advance."""
        with self._lock:
            now = time.perf_counter()
            self._add(key, units, now - self._last.get(key, now))
            self._last[key] = now

    def finish(self, key, seconds=None):
        """Step ``key`` ended: the rest of its units, done in ``seconds`` (None: since its last advance)."""
        with self._lock:
            now = time.perf_counter()
            seconds = now - self._last.get(key, now) if seconds is None else seconds
            self._add(key, self.work[key][1] - self._done[key], seconds)
            self._last.pop(key, None)

    def _add(self, key, units, seconds):
        kind, total = self.work[key]
        units = min(max(units, 0.0), total - self._done[key])
        self._done[key] += units
        self._spent[kind] = self._spent.get(kind, 0.0) + max(seconds, 0.0)
        self._units[kind] = self._units.get(kind, 0.0) + units

    def rate(self, kind):
        """Measured seconds per unit of ``kind``; unmeasured: a scoring pass's, else any step's; else None."""
        measured = [known for known in self._units if known not in (DATA, REPORT) and self._units[known]]
        for known in (kind, SCORING, *measured):
            if self._units.get(known):
                return self._spent[known] / self._units[known]
        return None

    def left(self):
        """Seconds left (None before a step is measured): the work left at the measured rates.

        The rates are scaled by how much of the work ran at once (its
        measured seconds add up to more than the time elapsed then).
        """
        remaining = {kind: 0.0 for kind, _ in self.work.values()}
        for key, (kind, units) in self.work.items():
            remaining[kind] += units - self._done[key]
        rates = {kind: self.rate(kind) for kind, units in remaining.items() if units > 0}
        if None in rates.values():
            return None
        spent = sum(self._spent.values())
        elapsed = time.perf_counter() - self.started
        overlap = min(1.0, elapsed / spent) if spent > 0 else 1.0
        return overlap * sum(remaining[kind] * rate for kind, rate in rates.items())

    def status(self):
        """``"run 42 %, 0:53 elapsed, about 1:13 left"`` (the share never goes back)."""
        with self._lock:
            elapsed = time.perf_counter() - self.started
            left = self.left()
            if left is None:
                return f"run {100 * self._shown:.0f} %, {duration(elapsed)} elapsed, time left not measured yet"
            self._shown = max(self._shown, min(elapsed / max(elapsed + left, 1e-9), 0.99))
            return f"run {100 * self._shown:.0f} %, {duration(elapsed)} elapsed, about {duration(left)} left"

    def search_status(self, key):
        """A ``status`` for :class:`~sklearn_radar.model_selection.ProgressPrinter` of a search of step ``key``.

        Returns
        -------
        status : callable
            ``status(i, n) -> str`` after each iteration: one unit of ``key`` done.
        """

        def status(i, n):
            self.advance(key)
            return self.status()

        return status


__all__ = ["DATA", "KERNELS", "REPORT", "SCORING", "RunProgress", "duration", "uncompiled_kernels"]
