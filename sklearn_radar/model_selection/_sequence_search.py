"""Bayesian search per sequence: skopt's ask and tell, one task per candidate and sequence, scores combined per fold.

:class:`~sklearn_radar.model_selection.make_bayes_search` (skopt's
``BayesSearchCV``) scores a candidate on a fold with one fit of the whole
fold.  Stages 0-2 never cross sequences, so here a candidate's work is one
task per training sequence, and a fold's score is combined from the small
summaries of its sequences (:mod:`sklearn_radar.metrics._parts`: contingency
counts for the V-measure, matches for the panoptic quality).

Where the tasks run is the executor's (:mod:`sklearn_radar._executor`):

* on a dask cluster (``reproduce --workers``) each sequence's data is placed
  on a worker once per run and stays there; stage 0 runs there once per
  search; a candidate's task ships only the parameters there and a summary
  back.  The data enters the cluster as tasks, not as scattered data, so
  that the scheduler can compute it again when a worker is lost;
* in one process the same tasks run here, or with joblib's ``n_jobs``.

The optimiser loop is ``BayesSearchCV``'s (skopt's ask and tell, the same
optimiser and random state, candidates in the same order), so a search's
result depends on neither where its tasks ran nor how many ran at a time:
only on the seed and on ``n_points``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from sklearn.base import clone
from sklearn.utils import check_random_state

from .._executor import LocalExecutor, balanced_blocks
from .._skopt import Optimizer, dimensions_aslist
from ..metrics._parts import FailedPart, combine_parts, sequence_parts

__all__ = [
    "SearchData",
    "SearchResult",
    "balanced_blocks",
    "bayes_search",
    "search_and_score_start",
    "sequence_folds",
    "sized_sequence_folds",
]


def candidate_parts(estimator, params, sequence, objective):
    """Fit ``estimator`` with ``params`` on one sequence and summarise its labels against the target.

    Parameters
    ----------
    estimator : estimator with ``fit_predict``
        The searched estimator (cloned here, never modified).
    params : dict
        The candidate.
    sequence : tuple of (DataFrame, ndarray)
        The sequence's detections (stage 0 applied) and their target.
    objective : {"v1", "pq"}
        What the summary is for (:func:`sklearn_radar.metrics._parts.score_parts`).

    Returns
    -------
    parts : object or FailedPart
        The summary (:func:`sklearn_radar.metrics._parts.sequence_parts`);
        a :class:`FailedPart` when the fit or the score raised (the fold
        then scores 0.0, as the package's scorers score a failing fit).
    """
    X, target = sequence
    return sequence_parts(clone(estimator).set_params(**params), X, target, objective)


def prepared_sequence(stage0, sequence):
    """One sequence with stage 0 applied (``stage0`` None: as it is); the target is unchanged."""
    if stage0 is None:
        return sequence
    X, target = sequence
    return clone(stage0).fit_transform(X), target


def prepared_block(stage0, block):
    """:func:`prepared_sequence` of every sequence of a block."""
    return [prepared_sequence(stage0, sequence) for sequence in block]


def block_parts(estimator, params, block, objective):
    """:func:`candidate_parts` of every sequence of a block, in order: one task on a cluster."""
    return [candidate_parts(estimator, params, sequence, objective) for sequence in block]


def _identity(value):
    return value


class SearchData:
    """A search's training sequences, each ``(detections, target)``, in blocks where its executor runs the tasks.

    A block is what one task works on, as the executor groups them
    (:meth:`sklearn_radar._executor.DaskExecutor.blocks`): in one process
    every sequence is a block of its own; on a cluster the sequences are
    grouped into one block per worker thread, balanced in detections.

    Parameters
    ----------
    blocks : list
        The executor's handle of each block (here: the list of its sequences).
    ids : list of list
        The sequence ids of each block.
    executor : LocalExecutor, DaskExecutor or None, default=None
        Where the blocks live and the tasks run (:mod:`sklearn_radar._executor`);
        None: here, with ``n_jobs``.
    n_jobs : int or None, default=None
        Tasks at a time here (joblib) when ``executor`` is None.
    """

    def __init__(self, blocks, ids, executor=None, n_jobs=None):
        self.blocks = blocks
        self.ids = ids
        self.executor = executor if executor is not None else LocalExecutor(n_jobs)

    @classmethod
    def place(cls, X, target, groups, executor=None, n_jobs=None):
        """Split the rows into sequences (in increasing sequence id) and put them where their tasks run.

        Each block is placed by the executor (on a cluster: a task's result,
        kept by a worker until this object is dropped, computed again if
        that worker is lost).
        """
        executor = executor if executor is not None else LocalExecutor(n_jobs)
        groups, target = np.asarray(groups), np.asarray(target)
        sequence_ids = np.unique(groups)
        rows = [np.flatnonzero(groups == sequence_id) for sequence_id in sequence_ids]
        sequences = [(X.iloc[r], target[r]) for r in rows]
        positions = executor.blocks([len(r) for r in rows])
        blocks = [executor.place(_identity, [sequences[p] for p in block]) for block in positions]
        return cls(blocks, [[sequence_ids[p] for p in block] for block in positions], executor)

    def on(self, executor):
        """The same blocks, their tasks submitted by ``executor`` (e.g. a worker's, or one with other ``n_jobs``)."""
        return SearchData(self.blocks, self.ids, executor)

    def prepare(self, stage0):
        """The sequences with ``stage0`` applied to each (where they are); ``self`` when it is None."""
        if stage0 is None:
            return self
        prepared = [self.executor.place(prepared_block, stage0, block) for block in self.blocks]
        return SearchData(prepared, self.ids, self.executor)

    @property
    def sequence_ids(self):
        """Every sequence id, in the order of :meth:`parts`."""
        return [sequence_id for block in self.ids for sequence_id in block]

    def parts(self, estimator, candidates, objective):
        """``candidate_parts`` of every candidate on every sequence: per candidate, in :attr:`sequence_ids` order."""
        return list(self.iter_parts(estimator, candidates, objective))

    def iter_parts(self, estimator, candidates, objective):
        """:meth:`parts` of each candidate in turn, yielded as soon as it and those before it are done.

        On a cluster every candidate's tasks are queued at once (the workers
        never wait for this process between candidates); here each candidate
        is evaluated when the caller asks for it
        (:meth:`~sklearn_radar._executor.DaskExecutor.queued`).
        """
        batches = [[(estimator, params, block, objective) for block in self.blocks] for params in candidates]
        for per_block in self.executor.queued(block_parts, batches):
            yield [part for block in per_block for part in block]


def sequence_folds(groups, n_folds):
    """The sequence ids of each cross-validation fold: ``GroupKFold`` over the detections' sequences.

    With fewer than two sequences, the one fold is all of them.

    Parameters
    ----------
    groups : array-like of shape (n_detections,)
        Sequence of each training detection.
    n_folds : int
        Folds wanted (at most the number of sequences).

    Returns
    -------
    folds : list of ndarray
    """
    ids, sizes = np.unique(np.asarray(groups), return_counts=True)
    return sized_sequence_folds(ids, sizes, n_folds)


def sized_sequence_folds(ids, sizes, n_folds):
    """:func:`sequence_folds` from the sequences' sizes alone (no row per detection needed).

    ``GroupKFold``'s assignment: the largest sequence first (ties: the
    later id first), each to the fold with the fewest detections so far
    (ties: the first such fold).

    Parameters
    ----------
    ids : array-like of shape (n_sequences,)
        Sequence ids, increasing.
    sizes : array-like of int of shape (n_sequences,)
        Detections per sequence.
    n_folds : int

    Returns
    -------
    folds : list of ndarray
        The ids of each fold, increasing.
    """
    ids, sizes = np.asarray(ids), np.asarray(sizes)
    n_folds = min(n_folds, len(ids))
    if n_folds < 2:
        return [ids]
    order = np.argsort(sizes, kind="stable")[::-1]
    totals = np.zeros(n_folds)
    fold_of = np.empty(len(ids), dtype=np.int64)
    for position in order:
        lightest = int(np.argmin(totals))
        totals[lightest] += sizes[position]
        fold_of[position] = lightest
    return [ids[fold_of == f] for f in range(n_folds)]


@dataclass
class SearchResult:
    """What a search found: every candidate in order, its mean fold score, and the best.

    Attributes
    ----------
    candidates : list of dict
    scores : list of float
        Mean over the folds, per candidate.
    best_params : dict
        The first candidate with the highest score.
    best_score : float
    """

    candidates: list
    scores: list
    best_params: dict
    best_score: float


def candidate_scores(data, estimator, candidates, folds, objective):
    """Mean fold score of each candidate; a fold with a failed sequence scores 0.0.

    Parameters
    ----------
    data : SearchData
    estimator : estimator with ``fit_predict``
    candidates : list of dict
    folds : list of ndarray
        Sequence ids per fold (:func:`sequence_folds`).
    objective : {"v1", "pq"}

    Returns
    -------
    scores : list of float

    Raises
    ------
    ValueError
        When every task of these candidates failed: a set-up mistake rather
        than bad candidates (scikit-learn's searches raise then, too).
    """
    parts = data.parts(estimator, candidates, objective)
    _check_not_all_failed(parts)
    return [_mean_fold_score(data, row, folds, objective) for row in parts]


def _check_not_all_failed(parts):
    failures = [p for row in parts for p in row if isinstance(p, FailedPart)]
    if failures and len(failures) == sum(len(row) for row in parts):
        raise ValueError(f"every fit of {len(parts)} candidate(s) failed, e.g. {failures[0].error}")


def _mean_fold_score(data, row, folds, objective):
    """A candidate's mean fold score from its parts (in :attr:`SearchData.sequence_ids` order)."""
    position = {sequence_id: i for i, sequence_id in enumerate(data.sequence_ids)}
    return float(np.mean([combine_parts(objective, [row[position[s]] for s in fold]) for fold in folds]))


def bayes_search(
    estimator,
    space,
    data,
    folds,
    *,
    objective,
    n_iter,
    n_initial_points,
    n_points=1,
    random_state=None,
    callback=None,
):
    """The paper's Bayesian optimisation (skopt's ask and tell, as ``BayesSearchCV`` runs it) on ``data``.

    Parameters
    ----------
    estimator : estimator with ``fit_predict``
    space : dict of str to skopt dimension
    data : SearchData
    folds : list of ndarray
        Sequence ids per fold (:func:`sequence_folds`).
    objective : {"v1", "pq"}
    n_iter : int
        Candidates in all.
    n_initial_points : int
        Random candidates before the Gaussian process guides.
    n_points : int, default=1
        Candidates per step (the last step may hold fewer).
    random_state : int, RandomState or None, default=None
    callback : callable or None, default=None
        Called with skopt's result after every step (e.g. a
        :class:`~sklearn_radar.model_selection.ProgressPrinter`); a true
        return value stops the search.

    Returns
    -------
    result : SearchResult
    """
    names = sorted(space)
    optimizer = Optimizer(
        dimensions_aslist(space), n_initial_points=n_initial_points, random_state=check_random_state(random_state)
    )
    candidates, scores = [], []
    remaining = n_iter
    while remaining > 0:
        # The random candidates do not depend on any score: with one candidate per step they are all asked (on a
        # cluster, queued) at once and told one by one in the same order: the same search as one at a time.
        batched = n_points == 1 and optimizer.n_random_left > 1
        if batched:
            points = optimizer.ask_random(min(remaining, optimizer.n_random_left))
        else:
            points = optimizer.ask(n_points=min(remaining, n_points))
        points = [[np.array(value).item() for value in point] for point in points]
        step = [dict(zip(names, point, strict=True)) for point in points]
        done = 0
        for told in _step_scores(data, estimator, step, batched, folds, objective):
            result = optimizer.tell(points[done : done + len(told)], [-score for score in told])
            candidates += step[done : done + len(told)]
            scores += told
            done += len(told)
            if callback is not None and callback(result):
                remaining = 0
                break
        remaining -= len(points)
    best = int(np.argmax(scores))
    return SearchResult(candidates=candidates, scores=scores, best_params=candidates[best], best_score=scores[best])


def _step_scores(data, estimator, step, batched, folds, objective):
    """The scores of a step's candidates, per ``tell``: all at once, or (``batched``) one candidate at a time."""
    if not batched:
        yield candidate_scores(data, estimator, step, folds, objective)
        return
    for row in data.iter_parts(estimator, step, objective):
        _check_not_all_failed([row])
        yield [_mean_fold_score(data, row, folds, objective)]


def search_and_score_start(estimator, space, data, folds, start_from=None, *, callback=None, **options):
    """:func:`bayes_search`, then the mean fold score of ``start_from`` (None: not scored) on the same folds.

    Returns
    -------
    found : SearchResult
    known : float or None
    """
    found = bayes_search(estimator, space, data, folds, callback=callback, **options)
    known = None
    if start_from is not None:
        known = candidate_scores(data, estimator, [start_from], folds, options["objective"])[0]
    return found, known
