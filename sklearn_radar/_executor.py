"""Where a run's work runs: one small protocol, in this process or on a dask cluster (the ``[distributed]`` extra).

Every command that runs work per sequence (``reproduce``, ``cluster``) takes
an executor and asks it, never whether a cluster exists:

``place(function, *args)``
    data kept where the tasks run (a handle: the value here, a dask future
    of a task's result there, computed again when its worker is lost);
``submit(function, *args)``
    one task; handles among the arguments are the data they stand for;
``gather(handles)`` / ``fetch(handle)``
    the values here;
``imap(function, items)``
    ``function(item)`` in order, a few at a time, each yielded as it ends;
``map(function, items)`` / ``ahead(function, items)``
    ``function(executor, item)`` for independent pieces of work (the
    repeats of a search, the searches that need no other step), at once
    where the executor can; ``ahead`` starts them now and yields them in
    order, so that the caller can save each as it ends;
``on_a_worker(function, handles, *args)``
    ``function(executor, handles, *args)`` as one task on a worker, which
    submits its own tasks (a search's loop: its Gaussian process then never
    queues for this process's GIL), with one BLAS thread;
``queued(function, batches)``
    every batch's tasks queued at once (a search's candidates), each batch's
    results yielded in order;
``blocks(sizes)``
    how sequences of these sizes are grouped into tasks.

Every function an executor runs, and the command's own thread for its
duration (:func:`connect_executor`), runs with its libraries' thread pools
(OpenMP, BLAS) bounded to what that work is given (:func:`thread_bound`):
``n_jobs`` threads here, split between the work running at once in
joblib's processes, and one thread per task on a dask worker, whose
threads are its tasks at a time.  Without it scikit-learn's
HistGradientBoosting and BLAS start a thread per core in every task, which
on a machine busy with other work made a step many times slower
(:ref:`performance`).

:class:`LocalExecutor` runs everything here (joblib's ``n_jobs`` for
:meth:`~LocalExecutor.map` and a search's candidates);
:class:`DaskExecutor` runs on a dask cluster and holds all dask code.
Without ``--scheduler`` or ``--workers`` dask is never imported.  Fault
tolerance is dask's: the scheduler re-runs the tasks of a worker that dies,
and results already gathered are not lost.
"""

from __future__ import annotations

import contextlib
import logging
import os
import sys
import tempfile
import threading
import warnings
from collections import deque
from concurrent.futures import ThreadPoolExecutor
from numbers import Integral

import numpy as np
from threadpoolctl import ThreadpoolController, threadpool_limits

#: What to install for ``--scheduler`` / ``--workers``.
EXTRA = "pip install 'sklearn-radar[distributed]'"
#: Seconds to wait for a scheduler before giving up with a one-line error.
CONNECT_TIMEOUT_S = 5.0

__all__ = [
    "CONNECT_TIMEOUT_S",
    "EXTRA",
    "DaskExecutor",
    "LocalExecutor",
    "balanced_blocks",
    "connect_executor",
    "peak_rss",
    "require_distributed",
    "thread_bound",
    "without_malloc_trim",
]

#: This thread's bound (:func:`thread_bound`): ``threads`` is the most threads its libraries may use, or absent.
_bound = threading.local()


@contextlib.contextmanager
def thread_bound(threads):
    """The OpenMP and BLAS thread pools of this thread's library calls at most ``threads`` while inside.

    A library that has more is set to ``threads`` and reset on leaving; one
    that has fewer (the caller's :func:`threadpoolctl.threadpool_limits`,
    ``OMP_NUM_THREADS``) keeps them.  Inside a bound of this thread as
    tight, it does nothing (costs nothing).  OpenMP's setting belongs to
    the thread that makes it, BLAS's to the process: work in another
    thread needs its own bound.

    Parameters
    ----------
    threads : int
        The most threads, >= 1.
    """
    outer = getattr(_bound, "threads", None)
    if outer is not None and outer <= threads:
        yield
        return
    with contextlib.ExitStack() as stack:
        for library in _above(threads):
            stack.enter_context(library.limit(limits=threads))
        _bound.threads = threads
        try:
            yield
        finally:
            _bound.threads = outer


def bound_for_good(threads):
    """:func:`thread_bound` for the rest of this thread's life (a dask worker's thread, whose tasks all get one)."""
    outer = getattr(_bound, "threads", None)
    if outer is not None and outer <= threads:
        return
    for library in _above(threads):
        library.limit(limits=threads)
    _bound.threads = threads


#: ``(len(sys.modules), ThreadpoolController)`` of this process when last looked for (:func:`_above`).
_libraries = (0, None)


def _above(threads):
    """The loaded OpenMP and BLAS libraries that would use more than ``threads`` threads in this thread."""
    global _libraries
    # scikit-learn loads its OpenMP and SciPy's BLAS when imported: loaded after the bound, they would escape it.
    import sklearn  # noqa: F401

    # Looking for the libraries takes 3-20 ms: again only when a module was imported since (a library comes with one).
    if _libraries[1] is None or _libraries[0] != len(sys.modules):
        _libraries = (len(sys.modules), ThreadpoolController())
    controller = _libraries[1]
    return [
        controller.select(filepath=library["filepath"])
        for library in controller.info()
        if library["num_threads"] > threads
    ]


def _bounded(threads, function, *args):
    """``function(*args)`` with :func:`thread_bound` ``(threads)`` (in whichever process runs it)."""
    with thread_bound(threads):
        return function(*args)


class _OneThread:
    """``function`` as a dask task: its worker thread's libraries bounded to one thread for good, then the call.

    ``__name__`` is the function's, so that dask names the task after it.
    """

    def __init__(self, function):
        self.function = function
        self.__name__ = getattr(function, "__name__", type(function).__name__)

    def __call__(self, *args):
        bound_for_good(1)
        return self.function(*args)


class LocalExecutor:
    """Everything in this process; ``n_jobs`` joblib workers for :meth:`map` and a search's candidates.

    Every function it runs has its libraries bounded to :attr:`threads`
    threads (:func:`thread_bound`), those in joblib's processes to their
    share of them.

    Parameters
    ----------
    n_jobs : int or None, default=None
        Candidates (and repeats) at a time, and the threads of the library
        calls in all (joblib's: -1 is every core); None: one.
    alone : bool, default=True
        Whether the work runs alone (its progress lines may be printed),
        not beside other work of :meth:`map`.
    note : str or None, default=None
        Why the run is here although a cluster was asked for
        (:func:`connect_executor`): the first line of the run says it.
    """

    def __init__(self, n_jobs=None, *, alone=True, note=None):
        self.n_jobs = n_jobs
        self.alone = alone
        self.note = note

    @property
    def threads(self):
        """The most threads of the library calls of the work here, >= 1 (``n_jobs``, None: 1)."""
        return _effective_n_jobs(self.n_jobs)

    def describe(self):
        """The run's first line about where it runs (None: nothing to say)."""
        return self.note

    def place(self, function, *args):
        return _bounded(self.threads, function, *args)

    def submit(self, function, *args, priority=0):
        return _bounded(self.threads, function, *args)

    def gather(self, handles):
        return list(handles)

    def fetch(self, handle):
        return handle

    def blocks(self, sizes):
        """Every sequence a task of its own: joblib's ``n_jobs`` spreads them."""
        return [[position] for position in range(len(sizes))]

    def imap(self, function, items):
        for item in items:
            yield _bounded(self.threads, function, item)

    def queued(self, function, batches):
        """Per batch, ``[function(*call) for call in batch]``, computed when the caller asks for it (``n_jobs``)."""
        for batch in batches:
            concurrent = min(len(batch), self.threads)
            if concurrent < 2:
                yield [_bounded(self.threads, function, *call) for call in batch]
            else:
                from joblib import Parallel, delayed

                share = max(1, self.threads // concurrent)
                yield Parallel(n_jobs=self.n_jobs)(delayed(_bounded)(share, function, *call) for call in batch)

    def ahead(self, function, items, on_done=None):
        """``function(self, item)`` for each item when the caller asks for it, in order (here, one at a time)."""
        for item in items:
            yield _done(on_done, item, _bounded(self.threads, function, self, item))

    def map(self, function, items, on_done=None):
        """``[function(executor, item) for item in items]``: with ``n_jobs`` above 1, up to ``n_jobs`` at once.

        Those at once run in joblib's processes, the cores split between
        them, each seeing a quiet executor (``alone`` false: their progress
        lines would interleave).
        """
        items = list(items)
        concurrent = min(len(items), self.threads)
        if concurrent < 2:
            return list(self.ahead(function, items, on_done))
        from joblib import Parallel, delayed

        inner = LocalExecutor(max(1, self.threads // concurrent), alone=False)
        found = Parallel(n_jobs=concurrent)(delayed(_bounded)(inner.threads, function, inner, item) for item in items)
        return [_done(on_done, item, result) for item, result in zip(items, found, strict=True)]

    def on_a_worker(self, function, handles, *args):
        # The Gaussian process works on tiny matrices, where multi-threaded BLAS was 20x slower (measured).
        with thread_bound(self.threads), threadpool_limits(limits=1, user_api="blas"):
            return function(self, handles, *args)

    @contextlib.contextmanager
    def pipeline_cache(self, folder, prefix):
        """A pipeline-cache folder inside ``folder`` for the duration (removed after)."""
        with tempfile.TemporaryDirectory(prefix=prefix, dir=folder) as cache:
            yield cache


def _effective_n_jobs(n_jobs):
    if n_jobs is None:
        return 1
    from joblib import effective_n_jobs

    return effective_n_jobs(n_jobs)


def _done(on_done, item, result):
    if on_done is not None:
        on_done(item, result)
    return result


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


#: dask priority of the steps' per-sequence tasks (:meth:`DaskExecutor.submit` default); a search's have 0.
STEP_PRIORITY = 10


class DaskExecutor:
    """The work on a dask cluster: data as tasks' results on the workers, tasks by dask's futures.

    Parameters
    ----------
    client : distributed.Client
    address : str
        The scheduler's address.
    n_workers : int
        Worker processes when connected.
    n_threads : int
        Worker threads in total (tasks that run at the same time).
    n_malloc_trim : int, default=0
        Workers that run with dask's ``MALLOC_TRIM_THRESHOLD_`` (slower
        clustering; :func:`without_malloc_trim`), said in :meth:`describe`.
    threads : int, default=1
        The most threads of the library calls of the work that runs in this
        process (:meth:`ahead`); a task on a worker has one.
    """

    alone = False
    n_jobs = 1

    def __init__(self, client, address, n_workers, n_threads, n_malloc_trim=0, threads=1):
        self.client = client
        self.address = address
        self.n_workers = n_workers
        self.n_threads = n_threads
        self.n_malloc_trim = n_malloc_trim
        self.threads = threads
        self._turn = -1
        self._lock = threading.Lock()

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

    def place(self, function, *args):
        """``function(*args)`` as a task's result kept on a worker (not scattered: a lost worker loses nothing)."""
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message="Sending large graph", category=UserWarning)
            return self.client.submit(_OneThread(function), *args, pure=False)

    def submit(self, function, *args, priority=STEP_PRIORITY):
        """One task; by default ahead of the searches' queued candidates (the steps wait for theirs in turn)."""
        # pure=False: a re-run after a lost worker computes the task again instead of sharing a key.
        return self.client.submit(_OneThread(function), *args, pure=False, priority=priority)

    def gather(self, handles):
        return self.client.gather(list(handles))

    def fetch(self, handle):
        return handle.result()

    def blocks(self, sizes):
        """One block per worker thread, balanced in detections: a task's round trip would cost as much as a small
        sequence's clustering (:ref:`user-guide-cluster`)."""
        return balanced_blocks(sizes, self.n_threads)

    def queued(self, function, batches, priority=0):
        """Per batch, ``[function(*call) for call in batch]``: every batch's tasks queued at once, yielded in order.

        The workers never wait for this process between batches (a search's
        candidates); a caller that stops early drops the batches it no
        longer needs.  Priority 0: behind the steps' tasks.
        """
        task = _OneThread(function)
        queued = [
            [self.client.submit(task, *call, pure=False, priority=priority) for call in batch] for batch in batches
        ]
        try:
            for futures in queued:
                yield self.client.gather(futures)
        finally:
            for futures in queued:
                for future in futures:
                    future.release()

    def imap(self, function, items, in_flight=None):
        """``function(item)`` in order, at most ``in_flight`` (default: twice the threads) submitted at a time.

        Each result is yielded as soon as it and those before it are done:
        neither this process nor a worker ever holds more than a few items.
        """
        in_flight = in_flight or 2 * max(self.n_threads, 1)
        pending, iterator, task = deque(), iter(items), _OneThread(function)
        for item in iterator:
            pending.append(self.client.submit(task, item, pure=False))
            if len(pending) >= in_flight:
                break
        while pending:
            future = pending.popleft()
            result = future.result()
            future.release()
            for item in iterator:
                pending.append(self.client.submit(task, item, pure=False))
                break
            yield result

    def ahead(self, function, items, on_done=None):
        """Every ``function(self, item)`` starts now, each in a thread here awaiting its tasks; yielded in order.

        A search alone keeps the workers busy only while its candidates run,
        not while its Gaussian process chooses the next one; several at once
        fill those gaps.  ``on_done(item, result)`` is called in the item's
        thread as it ends; the thread's libraries have :attr:`threads`.
        """
        items = list(items)
        pool = ThreadPoolExecutor(max_workers=max(len(items), 1), thread_name_prefix="sklearn-radar")
        futures = [
            pool.submit(lambda item=item: _done(on_done, item, _bounded(self.threads, function, self, item)))
            for item in items
        ]
        return self._in_order(pool, futures)

    @staticmethod
    def _in_order(pool, futures):
        try:
            for future in futures:
                yield future.result()
        finally:
            pool.shutdown(wait=False, cancel_futures=True)

    def map(self, function, items, on_done=None):
        return list(self.ahead(function, items, on_done))

    def on_a_worker(self, function, handles, *args):
        """``function(worker's executor, handles, *args)`` as one task on a worker, in turn over the workers.

        The handles go by key, so that dask does not bring their data to
        that task; from the worker it submits tasks as usual
        (``worker_client``: while it waits, its thread runs other tasks).
        """
        # In turn over the workers: dask's scheduler put 6 of 8 searches on one of 2 workers (measured); any other
        # worker may take it when that one is lost.
        worker = self._next_worker()
        future = self.client.submit(
            _on_this_worker,
            function,
            [handle.key for handle in handles],
            args,
            workers=None if worker is None else [worker],
            allow_other_workers=True,
            pure=False,
        )
        return future.result()

    def _next_worker(self):
        workers = self.client.scheduler_info().get("workers", {})
        slots = sorted(address for address, info in workers.items() for _ in range(info.get("nthreads", 1)))
        if not slots:
            return None
        with self._lock:
            self._turn += 1
            return slots[self._turn % len(slots)]

    @contextlib.contextmanager
    def pipeline_cache(self, folder, prefix):
        """No pipeline cache: its folder is not where a worker on another machine can reach it."""
        yield None


def balanced_blocks(sizes, n_blocks):
    """Positions of ``sizes`` in ``n_blocks`` blocks of near-equal total size (largest first, to the lightest).

    Each block lists its positions in increasing order; no block is empty
    when ``n_blocks <= len(sizes)``.
    """
    n_blocks = max(1, min(n_blocks, len(sizes)))
    blocks, totals = [[] for _ in range(n_blocks)], np.zeros(n_blocks)
    for position in np.argsort(-np.asarray(sizes), kind="stable"):
        lightest = int(np.argmin(totals))
        blocks[lightest].append(int(position))
        totals[lightest] += sizes[position]
    return [sorted(block) for block in blocks]


def _on_this_worker(function, keys, args):
    from distributed import Future, worker_client

    # One thread for good, as dask's environment gives a worker's tasks and as a search in one process computes its
    # Gaussian process (one BLAS thread): the same rounding.  Not undone: the worker's tasks share the process.
    bound_for_good(1)
    with worker_client() as client:
        here = DaskExecutor(client, client.scheduler.address, 0, 1)
        return function(here, [Future(key, client=client) for key in keys], *args)


def _first_line(error):
    text = str(error).strip()
    return text.splitlines()[0] if text else type(error).__name__


@contextlib.contextmanager
def connect_executor(scheduler=None, workers=None, n_jobs=None, *, in_process_reason=None, timeout=CONNECT_TIMEOUT_S):
    """The executor of a command for the duration: here, or on a dask cluster (connected to or started).

    Parameters
    ----------
    scheduler : str or None, default=None
        Address of a running scheduler (``tcp://host:8786``).
    workers : int or None, default=None
        Start a local cluster of this many worker processes (one thread each).
    n_jobs : int or None, default=None
        Work at a time in this process (:class:`LocalExecutor`), and the
        threads of the library calls in this process (-1: every core;
        None: one): this thread has them for the duration
        (:func:`thread_bound`), a task on a dask worker one.
    in_process_reason : str or None, default=None
        Why a local cluster (``workers``) would be slower than this process
        for this command's work: then none is started, and the executor's
        first line says why.
    timeout : float, default=5.0
        Seconds to wait for the scheduler, s.

    Yields
    ------
    executor : LocalExecutor or DaskExecutor
        A :class:`LocalExecutor` when neither ``scheduler`` nor ``workers``
        is given (dask is not imported).

    Raises
    ------
    ValueError
        For both arguments at once or a bad ``workers``.
    ImportError
        If dask.distributed is not installed (names the extra).
    OSError
        If the scheduler cannot be reached within ``timeout`` (names the address).
    """
    if scheduler is not None and workers is not None:
        raise ValueError("give either --scheduler (an existing cluster) or --workers (a local one), not both")
    if workers is not None:
        workers = check_workers(workers)
    if scheduler is not None and (not isinstance(scheduler, str) or not scheduler.strip()):
        raise ValueError(f"--scheduler must be a scheduler address such as tcp://host:8786, got {scheduler!r}")
    if scheduler is None and (workers is None or in_process_reason is not None):
        note = None if workers is None else f"--workers {workers}: {in_process_reason}; running in this process"
        executor = LocalExecutor(n_jobs, note=note)
        with thread_bound(executor.threads):
            yield executor
        return
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
        workers_info = client.scheduler_info().get("workers", {})
        executor = DaskExecutor(
            client=client,
            address=client.scheduler.address,
            n_workers=len(workers_info),
            n_threads=sum(w.get("nthreads", 1) for w in workers_info.values()) or 1,
            n_malloc_trim=_workers_with_malloc_trim(client),
            threads=_effective_n_jobs(n_jobs),
        )
        with thread_bound(executor.threads):
            yield executor


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
    anew, which slows our clustering down (by how much:
    :ref:`user-guide-cluster`).  dask also writes it into this
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


def worker_peak_rss(executor):
    """Peak resident memory of each worker process so far, bytes (``{address: bytes}``)."""
    return executor.client.run(peak_rss)


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
