"""The overall progress of a reproduce run in plain lines: the work done so far, the time elapsed and the time left.

The work is counted in units of a few kinds (an iteration of a stage-1, stage-2 or baseline search, one pass of a
step without a search), each kind timed as it goes; how the share done and the time left follow from those rates:
:ref:`contributing-runner`.
"""

from __future__ import annotations

import importlib
import threading
import time

#: The kind of the data step and of the report: outside the share done and the time left.
DATA, REPORT = "data", "report"
#: The kind of a pass over the test half that scores a fixed setting.
SCORING = "scoring"
#: Seconds per unit of each kind of step, as measured in the default run (4 x 20 s simulated, 10 iterations, on a
#: shared 2-core machine): the weight of a unit in the share done until its kind is timed in this run.
EXPECTED_S_PER_UNIT = {
    "filter": 1.4,
    SCORING: 0.2,
    "stage 1": 0.35,
    "stage 2": 0.6,
    "filter-effect": 2.1,
    "baselines": 1.8,
    "tracking": 4.0,
    "classification": 40.0,
    "learned": 35.0,
}
#: The weight of a unit of a kind missing from :data:`EXPECTED_S_PER_UNIT`.
EXPECTED_S_OTHER = 1.0
#: The most kinds of step a status line names as not timed yet (the rest are counted).
NAMED_AT_MOST = 3
#: How the status line names a kind of step.
KIND_NAMES = {
    "filter": "the filter evaluation",
    "stage 1": "stage-1 searches",
    "stage 2": "stage-2 searches",
    "filter-effect": "the filter's effect",
    "baselines": "the baselines",
    "learned": "the learned grouping",
}
#: The numba kernels a run compiles on an empty cache (a new environment): the first steps then run slower.
KERNELS = (
    "sklearn_radar.cluster._radar_dbscan_kernels._dbscan_sorted",
    "sklearn_radar.cluster._merge_kernels._candidate_pairs",
    "sklearn_radar._neighbors._count_capped",
    "sklearn_radar.cluster._merge_kernels._continuation_edges",
    "sklearn_radar.cluster._merge_kernels._max_speeds",
    "sklearn_radar.cluster._merge_kernels._velocity_windows",
    "sklearn_radar._labels._number_by_first_row",
    "sklearn_radar.cluster._merge_kernels._merge_components",
    "sklearn_radar._neighbors._counting_order",
)


def uncompiled_kernels():
    """The :data:`KERNELS` not in numba's cache yet (empty when all are, or the cache cannot be read)."""
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
    """Where a run stands: ``work`` (per step key, its kind and units), done and timed per kind; the time left."""

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
        """Measured seconds per unit of ``kind``; None while no unit of it was timed."""
        return self._spent[kind] / self._units[kind] if self._units.get(kind) else None

    def expected_rate(self, kind):
        """Seconds per unit of ``kind``: measured, else :data:`EXPECTED_S_PER_UNIT`'s at the timed kinds' speed."""
        measured = self.rate(kind)
        if measured is not None:
            return measured
        timed = [known for known in self._units if known not in (DATA, REPORT) and self._units[known]]
        expected = sum(self._units[known] * _expected(known) for known in timed)
        speed = sum(self._spent[known] for known in timed) / expected if expected > 0 else 1.0
        return _expected(kind) * speed

    def share(self):
        """The share of the steps' work done, 0-1, each unit weighted by its kind's :meth:`expected_rate`."""
        done = total = 0.0
        for key, (kind, units) in self.work.items():
            if kind in (DATA, REPORT):
                continue
            rate = self.expected_rate(kind)
            done, total = done + self._done[key] * rate, total + units * rate
        return done / total if total > 0 else 1.0

    def _remaining(self):
        """Units of work left per kind, of the steps (not the data, not the report)."""
        remaining = {}
        for key, (kind, units) in self.work.items():
            if kind not in (DATA, REPORT) and units - self._done[key] > 0:
                remaining[kind] = remaining.get(kind, 0.0) + units - self._done[key]
        return remaining

    def untimed(self):
        """The kinds of work still to come that no unit of has been timed yet, in run order."""
        return [kind for kind in self._remaining() if self.rate(kind) is None]

    def left(self, known_only=False):
        """Seconds left at the measured rates, scaled by the overlap; None while a kind to come is not timed."""
        remaining = self._remaining()
        rates = {kind: self.rate(kind) for kind in remaining}
        if None in rates.values() and not known_only:
            return None
        spent = sum(self._spent.values())
        elapsed = time.perf_counter() - self.started
        overlap = min(1.0, elapsed / spent) if spent > 0 else 1.0
        return overlap * sum(remaining[kind] * rate for kind, rate in rates.items() if rate is not None)

    def status(self):
        """``"run 42 %, 0:53 elapsed, about 1:13 left"``, or the kinds not timed yet and the rest's time left."""
        with self._lock:
            elapsed = time.perf_counter() - self.started
            remaining = self._remaining()
            self._shown = max(self._shown, 1.0 if not remaining else min(self.share(), 0.99))
            text = f"run {100 * self._shown:.0f} %, {duration(elapsed)} elapsed"
            if not remaining:
                return text
            untimed = self.untimed()
            if not untimed:
                return f"{text}, about {duration(self.left())} left"
            names = [KIND_NAMES.get(kind, kind) for kind in untimed]
            if len(names) > NAMED_AT_MOST:
                names = [*names[: NAMED_AT_MOST - 1], f"{len(names) - NAMED_AT_MOST + 1} more kinds"]
            named = ", ".join(names[:-1]) + " and " + names[-1] if len(names) > 1 else names[0]
            known = self.left(known_only=True)
            rest = f"; the rest about {duration(known)}" if round(known) >= 1 else ""
            return f"{text}, time left unknown (not timed yet: {named}{rest})"

    def search_status(self, key):
        """``status(i, n) -> str`` for a :class:`~sklearn_radar.model_selection.ProgressPrinter`: a unit of ``key``."""

        def status(i, n):
            self.advance(key)
            return self.status()

        return status


def _expected(kind):
    return EXPECTED_S_PER_UNIT.get(kind, EXPECTED_S_OTHER)
