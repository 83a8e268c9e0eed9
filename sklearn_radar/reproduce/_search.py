"""The reproduce run's remote searches: a whole search as one task on the dask cluster.

The search itself (skopt's ask and tell, one task per candidate and
sequence, scores combined per fold) is
:mod:`sklearn_radar.model_selection._sequence_search`; only running it on a
worker, so that concurrent searches do not share this process's GIL, is
specific to the run.
"""

from __future__ import annotations

from ..model_selection._sequence_search import SearchData, search_and_score_start

__all__ = ["search_on_a_worker"]


def search_on_a_worker(cluster, estimator, space, data, folds, start_from=None, **options):
    """:func:`search_and_score_start` as one task on the cluster: its Gaussian process runs on a worker.

    Several searches at once would otherwise share this process (and its
    GIL) for their Gaussian processes.  The task gets the blocks by key, so
    that dask does not bring their data to it; from the worker it submits
    the candidates' tasks as usual (``worker_client``: while it waits, its
    worker thread runs other tasks).  Same code, same single BLAS thread as
    dask gives its workers: the same result as here.
    """
    keys = [block.key for block in data.blocks]
    # In turn over the workers: dask's scheduler put 6 of 8 searches on one of 2 workers (measured); any other
    # worker may take it when that one is lost.
    worker = cluster.next_worker() if hasattr(cluster, "next_worker") else None
    future = cluster.client.submit(
        _search_task,
        estimator,
        space,
        keys,
        data.ids,
        folds,
        start_from,
        options,
        workers=None if worker is None else [worker],
        allow_other_workers=True,
        pure=False,
    )
    return future.result()


def _search_task(estimator, space, keys, ids, folds, start_from, options):
    from types import SimpleNamespace

    from distributed import Future, worker_client
    from threadpoolctl import threadpool_limits

    # One BLAS thread in this worker process for good, as dask's environment gives it and as the command's
    # process computes its Gaussian processes: the same rounding.  Not undone: searches share the process.
    threadpool_limits(limits=1, user_api="blas")
    with worker_client() as client:
        data = SearchData([Future(key, client=client) for key in keys], ids, SimpleNamespace(client=client))
        return search_and_score_start(estimator, space, data, folds, start_from, **options)
