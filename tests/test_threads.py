"""The threads of the library calls: every step and task runs with what the command gives it (``--n-jobs``).

OpenMP (scikit-learn's HistGradientBoosting) and BLAS start a thread per
core unless told otherwise; on a machine busy with other work that made the
classification step 24x slower (issue 46).  Each test starts from a process
(or worker) whose libraries would use 4 threads, as on a 4-core machine,
and reads inside the work how many threads the libraries have there
(:func:`threadpoolctl.threadpool_info`): the figure the libraries
themselves report, not a timing.
"""

import io
import logging
import os
import re
from pathlib import Path
from unittest import mock

import pytest
from threadpoolctl import threadpool_info, threadpool_limits

from sklearn_radar._executor import connect_executor

#: Threads the libraries would use if nothing bounded them (as on a 4-core machine).
MANY = 4


def _threads(*_):
    """``{user_api: [threads of each loaded library]}`` for OpenMP and BLAS, in the calling thread."""
    import sklearn  # noqa: F401  (loads OpenMP and SciPy's BLAS, as any step does)

    found = {}
    for library in threadpool_info():
        found.setdefault(library["user_api"], []).append(library["num_threads"])
    return found


def _task(executor, item):
    """A step-like piece of work: its own threads, and those of a task it submits where the executor runs tasks."""
    return {"here": _threads(), "task": executor.fetch(executor.submit(_threads, item))}


def _all_one(found):
    """Whether every OpenMP and BLAS library of ``found`` (nested dicts and lists of :func:`_threads`) has 1."""
    if isinstance(found, dict) and set(found) <= {"openmp", "blas"} and found:
        return all(n == 1 for counts in found.values() for n in counts)
    if isinstance(found, dict):
        return bool(found) and all(_all_one(value) for value in found.values())
    return bool(found) and all(_all_one(value) for value in found)


def _every_path(executor):
    """What the libraries have in every way the executor runs work (a step, a task, a search's candidates, ...)."""
    return {
        "command": _threads(),  # the runner's own thread: the steps that wait for others run there
        "place": executor.fetch(executor.place(_threads, 0)),
        "submit": executor.fetch(executor.submit(_threads, 0)),
        "imap": list(executor.imap(_threads, [0, 1])),
        "queued": list(executor.queued(_threads, [[(0,), (1,)]])),
        "ahead": list(executor.ahead(_task, [0, 1])),
        "map": executor.map(_task, [0, 1]),
        "on_a_worker": executor.on_a_worker(lambda here, handles: _task(here, 0), []),
    }


def _spy_on_the_boosted_trees(monkeypatch):
    """The list to which each HistGradientBoosting fit from now on appends the OpenMP threads it fits with."""
    from sklearn.ensemble._hist_gradient_boosting import gradient_boosting

    used, plain = [], gradient_boosting._openmp_effective_n_threads

    def spy(*args, **kwargs):
        used.append(plain(*args, **kwargs))
        return used[-1]

    monkeypatch.setattr(gradient_boosting, "_openmp_effective_n_threads", spy)
    return used


def test_the_libraries_report_many_threads_unbounded():
    # The premise of the tests below: without a bound, the libraries have the threads the process gives them.
    with threadpool_limits(limits=MANY):
        found = _threads()
    assert found.get("openmp") and found.get("blas")
    assert all(n == MANY for counts in found.values() for n in counts)


def test_every_step_and_task_in_one_process_has_n_jobs_threads():
    with threadpool_limits(limits=MANY), connect_executor(n_jobs=1) as executor:
        found = _every_path(executor)
    assert _all_one(found), found


def test_n_jobs_is_split_between_the_work_at_once():
    # --n-jobs 2: two repeats at once in joblib's processes, one thread each; one at a time, both threads.
    with threadpool_limits(limits=MANY), connect_executor(n_jobs=2) as executor:
        alone, at_once = _threads(), executor.map(_task, [0, 1])
        candidates = next(executor.queued(_threads, [[(0,), (1,)]]))
    assert all(n == 2 for counts in alone.values() for n in counts), alone
    assert _all_one(at_once) and _all_one(candidates), (at_once, candidates)


def test_the_bound_is_undone_after_the_command_and_never_raises_a_callers_limit():
    with threadpool_limits(limits=MANY):
        with connect_executor(n_jobs=1):
            pass
        assert all(n == MANY for counts in _threads().values() for n in counts)
    with threadpool_limits(limits=1), connect_executor(n_jobs=-1):
        assert _all_one(_threads())  # -1 (every core) does not undo the caller's one thread


def test_the_classification_step_fits_its_boosted_trees_on_n_jobs_threads(tiny_folder, tmp_path, monkeypatch):
    # The step of the issue, through the runner: the threads scikit-learn's HistGradientBoosting fits with.
    from sklearn_radar.reproduce import reproduce

    used = _spy_on_the_boosted_trees(monkeypatch)
    with threadpool_limits(limits=MANY):
        reproduce(tiny_folder, tmp_path / "out", n_iter=1, experiments="1,classification", stream=io.StringIO())
    assert used and set(used) == {1}, used


def test_a_callers_bound_holds_in_the_classifiers_fit(tiny_folder, monkeypatch):
    # The library's classifiers fit their boosted trees in the caller's thread: threadpoolctl bounds them there.
    from sklearn_radar.classification import road_user_class
    from sklearn_radar.datasets import load_radarscenes
    from sklearn_radar.experiments import experiment_pipeline
    from sklearn_radar.reproduce._classification import classifier_model, model_input, point_model

    used = _spy_on_the_boosted_trees(monkeypatch)
    data = load_radarscenes(tiny_folder).data
    X, y = model_input(data), road_user_class(data["label_id"])
    with threadpool_limits(limits=MANY), threadpool_limits(limits=1):
        classifier_model(experiment_pipeline(1)).fit(X, y)
        fits = len(used)
        point_model().fit(X, y)
    assert 0 < fits < len(used) and set(used) == {1}, used


def test_no_numba_kernel_runs_on_numba_threads():
    # No kernel is parallel (parallel=True, prange): numba's thread pool never starts, so there is nothing to bound.
    # A parallel kernel would need numba.set_num_threads in thread_bound.
    package = Path(__file__).resolve().parents[1] / "sklearn_radar"
    parallel = [
        f"{path.relative_to(package)}:{n}"
        for path in package.rglob("*.py")
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1)
        if re.search(r"parallel\s*=\s*True|\bprange\b", line)
    ]
    assert parallel == []


# ----------------------------------------------------------------------------- on a dask cluster


@pytest.fixture(scope="module")
def many_threads_cluster():
    """Two workers (one thread each) whose environment gives the libraries 4 threads, not dask's default 1.

    A worker started without dask's nanny settings (``OMP_NUM_THREADS=1``
    and the like), e.g. by another tool or another dask configuration,
    has a thread per core.
    """
    distributed = pytest.importorskip("dask.distributed")
    import dask

    names = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS")
    many = {f"distributed.nanny.pre-spawn-environ.{name}": MANY for name in names}
    # dask writes its pre-spawn variables into this process's environment too (an earlier cluster's 1 would stay).
    with (
        mock.patch.dict(os.environ, {name: str(MANY) for name in names}),
        dask.config.set(many),
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=logging.ERROR
        ) as cluster,
    ):
        with distributed.Client(cluster, set_as_default=False) as client:
            assert _none_one(client.run(_threads)), "the workers were to start with many threads"
        yield cluster


def _none_one(per_worker):
    """Whether no library of any worker has 1 thread (OpenBLAS takes at most one per core)."""
    return all(n > 1 for found in per_worker.values() for counts in found.values() for n in counts)


def test_every_step_and_task_on_a_dask_cluster_has_one_thread(many_threads_cluster):
    with threadpool_limits(limits=MANY), connect_executor(scheduler=many_threads_cluster.scheduler_address) as cluster:
        found = _every_path(cluster)
        name = cluster.submit(_threads, 0).key
    assert _all_one(found), found
    assert name.startswith("_threads-")  # dask still names a task after its function
