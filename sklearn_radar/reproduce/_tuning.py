"""How a reproduce step tunes a pipeline: the training half placed once per run, each search's seed and set-up."""

from __future__ import annotations

import threading
import time
import zlib

import joblib
import numpy as np
from sklearn.base import clone

from .._skopt import Real
from ..model_selection import ProgressPrinter
from ..model_selection._sequence_search import (
    SearchData,
    bayes_search,
    candidate_scores,
    fixed_prefix,
    sized_sequence_folds,
)
from ._constants import SOURCE_PAPER, SOURCE_SEARCH
from ._experiment_records import SearchRecord

#: Stage-0 outputs kept per run (:meth:`TrainingData.prepared`): the inputs of the experiments, not of every setting.
PREPARED_KEPT = 4


def search_seed(run_seed, key):
    """The seed in ``[0, 2**32)`` of the search of ``key`` in repeat ``run_seed`` (:ref:`user-guide-tuning`)."""
    stream = int(key) if key.isdigit() else zlib.crc32(key.encode("utf-8"))
    return int(np.random.SeedSequence(run_seed, spawn_key=(stream,)).generate_state(1)[0])


def with_cluster_gate(space, stage, objective):
    """The search space, plus the cluster-level Doppler gate ``cluster_vr_min`` (m/s) when tuning for PQ."""
    if objective != "pq":
        return space
    name = f"{'merge' if stage == 2 else 'cluster'}__cluster_vr_min"
    return {**space, name: Real(0.0, 1.5, name=name)}


def tune(env, key, estimator, space, label, start_from=None, seed=None):
    """Bayesian optimisation on the training half with grouped CV; returns (best params, SearchRecord).

    The search's loop is one task where the executor runs it; its iterations are printed (and counted as units of
    step ``key``) when it runs alone here.  ``seed`` is its random seed (None: the run's).  ``start_from`` (e.g.
    the paper's optimum) is scored on the same folds and kept when the search found nothing better.
    """
    start = time.perf_counter()
    folds = sized_sequence_folds(env.train, [env.sequences.size([s]) for s in env.train], env.budget.cv_folds)
    raw = env.training.raw(env.executor)
    estimator = _without_cache(estimator)
    searched, searched_space, data, prefix = estimator, space, raw, ""
    fixed = fixed_prefix(estimator, space)
    if fixed is not None:  # stage 0 once for every candidate and fold, per sequence
        stage0, searched, searched_space, prefix = fixed
        data = env.training.prepared(env.executor, stage0)
    # The paper's setting is scored on the same folds (on the data as searched, when it sets only the searched step).
    start_here = bool(start_from) and all(name.startswith(prefix) for name in start_from)
    options = {
        "objective": env.objective,
        "n_iter": env.budget.n_iter,
        "n_initial_points": env.budget.n_initial_points,
        "n_points": env.n_points,
        "random_state": env.seed if seed is None else seed,
        "start_from": {name[len(prefix) :]: value for name, value in start_from.items()} if start_here else None,
    }
    printer = None
    if env.executor.alone:
        status = env.progress.search_status(key)
        printer = ProgressPrinter(env.budget.n_iter, label=label, stream=env.progress.stream, status=status)
    found = env.executor.on_a_worker(_search, data.blocks, data.ids, searched, searched_space, folds, options, printer)
    best = {prefix + name: value for name, value in native_params(found.best_params).items()}
    cv_best, source, known = found.best_score, SOURCE_SEARCH, found.start_score
    if start_from:
        if not start_here:
            known = candidate_scores(raw, estimator, [start_from], folds, env.objective)[0]
        if known >= cv_best:
            best = {name: start_from[name] for name in space if name in start_from}
            cv_best, source = known, SOURCE_PAPER
    record = SearchRecord(
        cv_best=cv_best,
        convergence=found.scores,
        best_source=source,
        cv_start_from=known,
        search_wall_time_s=time.perf_counter() - start,
    )
    return best, record


def _search(executor, blocks, ids, estimator, space, folds, options, callback):
    """:func:`~sklearn_radar.model_selection._sequence_search.bayes_search` on the blocks, where ``executor`` runs."""
    return bayes_search(estimator, space, SearchData(blocks, ids, executor), folds, callback=callback, **options)


class TrainingData:
    """The training half placed once per run; the last :data:`PREPARED_KEPT` stage-0 outputs shared by searches."""

    def __init__(self, sequences, train):
        self.sequences, self.train = sequences, train
        self._raw, self._prepared = None, {}
        self._lock = threading.Lock()

    def __getstate__(self):  # a copy in another process (joblib) places its own
        return {"sequences": self.sequences, "train": self.train, "_raw": None, "_prepared": {}}

    def __setstate__(self, state):
        self.__dict__.update(state, _lock=threading.Lock())

    def raw(self, executor):
        with self._lock:
            if self._raw is None:
                self._raw = self.sequences.search_data(self.train)
            return self._raw.on(executor)

    def prepared(self, executor, stage0):
        raw = self.raw(executor)
        key = joblib.hash(stage0)
        with self._lock:
            found = self._prepared.get(key)
            if found is None:
                found = self._prepared[key] = raw.prepare(stage0)
                while len(self._prepared) > PREPARED_KEPT:
                    self._prepared.pop(next(iter(self._prepared)))
        return found.on(executor)


def native_params(params):
    """Parameters with numpy scalars as Python numbers."""
    return {key: (value.item() if isinstance(value, np.generic) else value) for key, value in params.items()}


def _without_cache(estimator):
    """A pipeline without its cache folder (which a worker on another machine cannot reach)."""
    if hasattr(estimator, "steps"):
        return clone(estimator).set_params(memory=None)
    return estimator
