"""Running on a dask.distributed cluster: ``--scheduler ADDRESS`` / ``--workers N`` (the ``[distributed]`` extra).

Everything that touches dask is here, and dask is imported only when a
cluster is asked for: without ``--scheduler`` or ``--workers`` the package
never imports it.

Two ways the work reaches the workers, both by dask's own futures:

* a search of ``reproduce`` (:mod:`sklearn_radar.reproduce._search`) places
  each training sequence on a worker once, as a task's result, and runs one
  task per candidate and sequence there; only parameters go out and small
  score summaries come back;
* :func:`map_sequences` runs a function once per sequence as dask tasks
  (stages 0-2 never cross sequences), keeping only a few results in flight
  and returning them in sequence order, so the caller can stream them.

Fault tolerance is dask's: the scheduler re-runs the tasks of a worker that
dies (a nanny restarts the worker process), and results already gathered by
the client are not lost.
"""

from __future__ import annotations

import contextlib
import logging
import os
import threading
from collections import deque
from dataclasses import dataclass, field
from numbers import Integral

#: What to install for ``--scheduler`` / ``--workers``.
EXTRA = "pip install 'sklearn-radar[distributed]'"
#: Seconds to wait for a scheduler before giving up with a one-line error.
CONNECT_TIMEOUT_S = 5.0

__all__ = [
    "CONNECT_TIMEOUT_S",
    "EXTRA",
    "Cluster",
    "connect_cluster",
    "map_sequences",
    "require_distributed",
    "without_malloc_trim",
]


def require_distributed():
    """Import and return ``dask.distributed``; ImportError naming the extra to install when it is missing.

    Returns
    -------
    distributed : module
    """
    try:
        import dask.distributed as distributed
    except ImportError as error:
        missing = getattr(error, "name", None) or "dask.distributed"
        raise ImportError(
            f"--scheduler/--workers need dask.distributed ({missing} is not installed): {EXTRA}"
        ) from None
    return distributed


def check_workers(workers):
    """``workers`` as a positive int; ValueError naming ``--workers`` otherwise."""
    if isinstance(workers, bool) or not isinstance(workers, Integral) or workers < 1:
        raise ValueError(f"--workers must be a whole number of worker processes >= 1, got {workers!r}")
    return int(workers)


@dataclass
class Cluster:
    """The cluster a run uses.

    Attributes
    ----------
    client : distributed.Client
    address : str
        The scheduler's address.
    n_workers : int
        Worker processes when connected.
    n_threads : int
        Worker threads in total (tasks that run at the same time).
    n_malloc_trim : int, default=0
        Workers that run with dask's ``MALLOC_TRIM_THRESHOLD_`` (about 2x
        slower clustering; :func:`without_malloc_trim`), said in
        :meth:`describe`.
    """

    client: object
    address: str
    n_workers: int
    n_threads: int
    n_malloc_trim: int = 0
    _turn: int = field(default=-1, repr=False)

    def next_worker(self):
        """A worker's address, in turn over the workers (by thread), for spreading long tasks; None if none."""
        workers = self.client.scheduler_info().get("workers", {})
        slots = sorted(address for address, info in workers.items() for _ in range(info.get("nthreads", 1)))
        if not slots:
            return None
        with _TURN_LOCK:
            self._turn += 1
            return slots[self._turn % len(slots)]

    def describe(self):
        """One line: where the cluster is, how many tasks run at a time, and workers that run slowly."""
        text = f"dask cluster at {self.address}: {self.n_workers} worker(s), {self.n_threads} thread(s)"
        if self.n_malloc_trim:
            text += (
                f"; {self.n_malloc_trim} worker(s) run with dask's {MALLOC_TRIM}, which makes the clustering"
                " about 2x slower: start them with DASK_CONFIG=<folder> holding a dask.yaml that sets"
                f" distributed.nanny.pre-spawn-environ.{MALLOC_TRIM}: null"
            )
        return text


def _first_line(error):
    text = str(error).strip()
    return text.splitlines()[0] if text else type(error).__name__


@contextlib.contextmanager
def connect_cluster(scheduler=None, workers=None, *, timeout=CONNECT_TIMEOUT_S):
    """Connect to (or start) a dask cluster for the duration; its client is the default one.

    Parameters
    ----------
    scheduler : str or None, default=None
        Address of a running scheduler (``tcp://host:8786``).
    workers : int or None, default=None
        Start a local cluster of this many worker processes (one thread each).
    timeout : float, default=5.0
        Seconds to wait for the scheduler, s.

    Yields
    ------
    cluster : Cluster or None
        None when neither ``scheduler`` nor ``workers`` is given: nothing
        changes and dask is not imported.

    Raises
    ------
    ValueError
        For both arguments at once or a bad ``workers``.
    ImportError
        If dask.distributed is not installed (names the extra).
    OSError
        If the scheduler cannot be reached within ``timeout`` (names the address).
    """
    if scheduler is None and workers is None:
        yield None
        return
    if scheduler is not None and workers is not None:
        raise ValueError("give either --scheduler (an existing cluster) or --workers (a local one), not both")
    if workers is not None:
        workers = check_workers(workers)
    if scheduler is not None and (not isinstance(scheduler, str) or not scheduler.strip()):
        raise ValueError(f"--scheduler must be a scheduler address such as tcp://host:8786, got {scheduler!r}")
    distributed = require_distributed()
    import dask

    with contextlib.ExitStack() as stack:
        # A few seconds to connect, not dask's default 30 s; a bad address must not look like a hang.
        stack.enter_context(dask.config.set({"distributed.comm.timeouts.connect": f"{timeout}s"}))
        if scheduler is not None:
            try:
                client = distributed.Client(scheduler, timeout=f"{timeout}s", set_as_default=True)
            except (OSError, TimeoutError, ValueError, TypeError) as error:
                raise OSError(
                    f"cannot reach the dask scheduler at {scheduler} within {timeout:g} s: {_first_line(error)}"
                ) from None
        else:
            stack.enter_context(without_malloc_trim())
            local = distributed.LocalCluster(
                n_workers=workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address=None,
                silence_logs=logging.ERROR,
            )
            stack.callback(local.close)
            client = distributed.Client(local, set_as_default=True)
        stack.callback(client.close)
        info = client.scheduler_info()
        workers_info = info.get("workers", {})
        cluster = Cluster(
            client=client,
            address=client.scheduler.address,
            n_workers=len(workers_info),
            n_threads=sum(w.get("nthreads", 1) for w in workers_info.values()) or 1,
            n_malloc_trim=_workers_with_malloc_trim(client),
        )
        yield cluster


_TURN_LOCK = threading.Lock()

#: What dask sets for every worker process it spawns and we do not want (:func:`without_malloc_trim`).
MALLOC_TRIM = "MALLOC_TRIM_THRESHOLD_"
#: A dask configuration file for ``dask worker`` processes without it (dask drops an entry set to null); give
#: its folder in ``DASK_CONFIG``.  Environment-variable settings cannot do it: dask lower-cases their keys.
WORKER_CONFIG = f"distributed:\n  nanny:\n    pre-spawn-environ:\n      {MALLOC_TRIM}: null\n"


@contextlib.contextmanager
def without_malloc_trim():
    """Worker processes spawned inside get no ``MALLOC_TRIM_THRESHOLD_``; dask's other variables stay.

    dask sets that variable (65,536 bytes) for every worker process it
    spawns, to give memory back to the system sooner.  It also fixes glibc's
    mmap threshold, so that every array above 128 kB is mapped and unmapped
    anew: our clustering ran 2.1x slower per detection in such a worker
    (0.130 s instead of 0.061 s for the same 8 sequences, measured), and 2
    workers were slower than 1 process.  dask also writes it into this
    process's environment when it spawns a worker, which later workers
    would inherit, so it is removed from there for the duration and put
    back afterwards.
    """
    import dask

    before = os.environ.pop(MALLOC_TRIM, None)
    try:
        with dask.config.set({f"distributed.nanny.pre-spawn-environ.{MALLOC_TRIM}": None}):
            yield
    finally:
        os.environ.pop(MALLOC_TRIM, None)
        if before is not None:
            os.environ[MALLOC_TRIM] = before


def malloc_trim_setting():
    """This process's ``MALLOC_TRIM_THRESHOLD_``, or None (a function, so that a worker reads its own)."""
    return os.environ.get(MALLOC_TRIM)


def _workers_with_malloc_trim(client):
    """How many of the cluster's workers run with ``MALLOC_TRIM_THRESHOLD_`` set."""
    return sum(1 for value in client.run(malloc_trim_setting).values() if value is not None)


def map_sequences(cluster, function, items, *, in_flight=None):
    """``function(item)`` for each item, in order; on the cluster when there is one.

    With a cluster, at most ``in_flight`` tasks (default: twice the worker
    threads) are submitted or held at a time, and each result is yielded as
    soon as it and those before it are done: the caller can write them out
    as a stream, so neither the driver nor a worker ever holds more than a
    few sequences.  Without one, the items run one after the other here.

    Parameters
    ----------
    cluster : Cluster or None
    function : callable
        Must be importable by the workers (a module-level function).
    items : iterable
    in_flight : int or None, default=None

    Yields
    ------
    result
        ``function(item)``, in the order of ``items``.
    """
    if cluster is None:
        for item in items:
            yield function(item)
        return
    in_flight = in_flight or 2 * max(cluster.n_threads, 1)
    pending = deque()
    iterator = iter(items)
    # pure=False: a re-run after a lost worker computes the task again instead of sharing a key.
    for item in iterator:
        pending.append(cluster.client.submit(function, item, pure=False))
        if len(pending) >= in_flight:
            break
    while pending:
        future = pending.popleft()
        result = future.result()
        future.release()
        for item in iterator:
            pending.append(cluster.client.submit(function, item, pure=False))
            break
        yield result


def worker_peak_rss(cluster):
    """Peak resident memory of each worker process so far, bytes (``{address: bytes}``)."""
    return cluster.client.run(peak_rss)


def peak_rss():
    """Peak resident memory of this process, bytes: ``VmHWM`` (Linux), else ``ru_maxrss``.

    ``ru_maxrss`` survives ``exec`` on Linux, so a process started by a
    large one would report its parent's peak; ``VmHWM`` is the process's own.
    """
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    import resource

    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak * (1 if os.uname().sysname == "Darwin" else 1024)
