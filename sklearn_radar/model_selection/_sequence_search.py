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

import time
from dataclasses import dataclass, field
from numbers import Integral
from typing import ClassVar

import numpy as np
from scipy.stats import rankdata
from sklearn.base import BaseEstimator, MetaEstimatorMixin, _fit_context, clone
from sklearn.utils import check_consistent_length, check_random_state, column_or_1d
from sklearn.utils._param_validation import HasMethods, Interval, StrOptions
from threadpoolctl import threadpool_limits

from .._executor import LocalExecutor, balanced_blocks
from .._skopt import Optimizer, dimensions_aslist
from ..metrics._parts import FailedPart, combine_parts, sequence_parts
from ._search import ProgressPrinter

__all__ = [
    "SearchData",
    "SearchResult",
    "SequenceSearchCV",
    "balanced_blocks",
    "bayes_search",
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


def _rows(X, rows):
    """Rows ``rows`` (positions) of a DataFrame or an array."""
    return X.iloc[rows] if hasattr(X, "iloc") else X[rows]


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
        sequences = [(_rows(X, r), target[r]) for r in rows]
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
    fold_scores : list of list of float
        Per candidate, the score of each fold (in the order of the folds).
    start_score : float or None
        The mean fold score of the search's ``start_from``; None when it had none.
    """

    candidates: list
    scores: list
    best_params: dict
    best_score: float
    fold_scores: list = field(default_factory=list)
    start_score: float | None = None


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
    return [_mean(row) for row in candidate_fold_scores(data, estimator, candidates, folds, objective)]


def candidate_fold_scores(data, estimator, candidates, folds, objective):
    """:func:`candidate_scores` before the mean: per candidate, the score of each fold, in the order of ``folds``."""
    parts = data.parts(estimator, candidates, objective)
    _check_not_all_failed(parts)
    return [_fold_scores(data, row, folds, objective) for row in parts]


def _check_not_all_failed(parts):
    failures = [p for row in parts for p in row if isinstance(p, FailedPart)]
    if failures and len(failures) == sum(len(row) for row in parts):
        raise ValueError(f"every fit of {len(parts)} candidate(s) failed, e.g. {failures[0].error}")


def _fold_scores(data, row, folds, objective):
    """A candidate's score on each fold from its parts (in :attr:`SearchData.sequence_ids` order)."""
    position = {sequence_id: i for i, sequence_id in enumerate(data.sequence_ids)}
    return [combine_parts(objective, [row[position[s]] for s in fold]) for fold in folds]


def _mean(fold_scores):
    return float(np.mean(fold_scores))


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
    start_from=None,
):
    """The paper's Bayesian optimisation (skopt's ask and tell, as ``BayesSearchCV`` runs it) on ``data``.

    The one search engine: :class:`SequenceSearchCV` and ``sklearn-radar reproduce`` both run their searches here
    (:ref:`contributing-decisions`).

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
    start_from : dict or None, default=None
        A known setting (e.g. the paper's) scored on the same folds after the search, as
        :attr:`SearchResult.start_score`; it does not enter the search.

    Returns
    -------
    result : SearchResult
    """
    names = sorted(space)
    optimizer = Optimizer(
        dimensions_aslist(space), n_initial_points=n_initial_points, random_state=check_random_state(random_state)
    )
    candidates, fold_scores = [], []
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
        for told in _step_fold_scores(data, estimator, step, batched, folds, objective):
            result = optimizer.tell(points[done : done + len(told)], [-_mean(row) for row in told])
            candidates += step[done : done + len(told)]
            fold_scores += told
            done += len(told)
            if callback is not None and callback(result):
                remaining = 0
                break
        remaining -= len(points)
    scores = [_mean(row) for row in fold_scores]
    best = int(np.argmax(scores))
    start_score = None if start_from is None else candidate_scores(data, estimator, [start_from], folds, objective)[0]
    return SearchResult(
        candidates=candidates,
        scores=scores,
        best_params=candidates[best],
        best_score=scores[best],
        fold_scores=fold_scores,
        start_score=start_score,
    )


def _step_fold_scores(data, estimator, step, batched, folds, objective):
    """The fold scores of a step's candidates, per ``tell``: all at once, or (``batched``) one candidate at a time."""
    if not batched:
        yield candidate_fold_scores(data, estimator, step, folds, objective)
        return
    for row in data.iter_parts(estimator, step, objective):
        _check_not_all_failed([row])
        yield [_fold_scores(data, row, folds, objective)]


def fixed_prefix(estimator, space):
    """(the steps before the last, the last step, its space, its parameter prefix) when ``space`` tunes only the last.

    The steps before (stage 0: frame transform, filter) then compute the same
    for every candidate, so the search can apply them to each sequence once
    and search the last step alone, its space's names without the prefix.
    None for anything else.
    """
    steps = getattr(estimator, "steps", None)
    if not steps or len(steps) < 2:
        return None
    name, last = steps[-1]
    prefix = f"{name}__"
    if not all(key.startswith(prefix) for key in space):
        return None
    searched_space = {key[len(prefix) :]: dimension for key, dimension in space.items()}
    return clone(estimator[:-1]).set_params(memory=None), clone(last), searched_space, prefix


class SequenceSearchCV(MetaEstimatorMixin, BaseEstimator):
    """Bayesian parameter search with sequence-grouped folds, one fit per candidate and sequence.

    The search of :func:`make_bayes_search` (the paper's 100 iterations, 30
    of them random, skopt's Gaussian process and ask-and-tell protocol,
    :class:`~sklearn.model_selection.GroupKFold` folds), computed the way
    ``python -m sklearn_radar reproduce`` computes it: the estimator's stages
    never cross sequences, so a candidate is fitted on each sequence once
    (instead of once per training and once per test fold), and a fold's
    score is combined from its sequences' small summaries (contingency
    counts for the radar V-measure, matches for the panoptic quality).
    When the space tunes only a pipeline's last step, the steps before it
    (e.g. :class:`~sklearn_radar.FrameTransform` and
    :class:`~sklearn_radar.DopplerDensityFilter`) run once per sequence for
    the whole search.  Candidates and scores are those of
    ``make_bayes_search(estimator, search_spaces, cv=cv, ...)`` with the same
    seed (tested, to rounding).

    Parameters
    ----------
    estimator : estimator with ``fit_predict``
        A clusterer, or a pipeline ending in one, that clusters each
        sequence on its own (as every estimator of this package does: its
        labels on several sequences are those on each, renumbered).
    search_spaces : dict of str to skopt dimension
        ``{parameter: dimension}`` (e.g.
        :func:`sklearn_radar.experiments.search_space`): a
        ``skopt.space`` ``Real``, ``Integer`` or ``Categorical``, or
        anything skopt reads as one (``(low, high)``, a list of choices).
    n_iter : int, default=100
        Candidates evaluated in total, >= 1.
    n_initial_points : int, default=30
        Random candidates before the Gaussian process guides the search,
        >= 0 (the paper: 30 for exploration, 70 for exploitation).
    n_points : int, default=1
        Candidates proposed per step, >= 1 (with ``n_jobs``, more fits at a
        time; slightly less sequential guidance).
    cv : int, default=3
        Folds, >= 2: ``GroupKFold``'s assignment of the sequences (every
        sequence wholly in one fold, the folds balanced in detections).
        Since a clusterer scores what it clusters, a fold's score is that of
        the candidate fitted on the fold.
    scoring : {"v1", "pq"}, default="v1"
        ``"v1"``: the radar V-measure
        (:func:`~sklearn_radar.metrics.radar_v_measure_scorer`, the paper's
        Eq. 7); ``"pq"``: the panoptic quality per 0.5 s time window
        (:func:`~sklearn_radar.metrics.panoptic_quality_scorer`), which needs
        a time column (``t`` in s, or ``timestamp`` in µs) in what the
        clusterer reads.
    refit : bool, default=True
        Fit the best candidate on all of X as :attr:`best_estimator_`.
    random_state : int, RandomState instance or None, default=None
        Seed of the optimiser (random points, acquisition).
    n_jobs : int or None, default=None
        Fits at a time (joblib), over the sequences of the candidates of a
        step; None means 1.
    verbose : int or bool, default=0
        0: silent; >= 1: one :class:`ProgressPrinter` line per candidate.

    Attributes
    ----------
    best_estimator_ : estimator
        The best candidate fitted on all of X (only when ``refit``).
    best_index_ : int
        Row of :attr:`cv_results_` of the best candidate (the first with the
        highest mean score).
    best_params_ : dict
        Parameters of the best candidate.
    best_score_ : float
        Its mean fold score.
    cv_results_ : dict of ndarray
        scikit-learn's layout (:class:`~sklearn.model_selection.GridSearchCV`):
        ``params``, ``param_<name>`` (masked arrays), ``split<k>_test_score``,
        ``mean_test_score``, ``std_test_score`` and ``rank_test_score``, one
        row per candidate in the order evaluated.  There are no fit times:
        a candidate's fits are per sequence, not per fold.
    multimetric_ : bool
        Always False: one score.
    n_splits_ : int
        Folds used (``cv``).
    refit_time_ : float
        Seconds spent refitting the best candidate (only when ``refit``).

    See Also
    --------
    make_bayes_search : the same search as skopt's ``BayesSearchCV`` (one fit per fold).

    Notes
    -----
    The Gaussian process runs with one BLAS thread, as in ``reproduce``: on
    its small matrices multi-threaded BLAS is slower (:ref:`User Guide
    <user-guide-tuning>`).  A fold holding a sequence whose fit fails scores 0.0; when every fit of a
    step fails, :meth:`fit` raises.

    Examples
    --------
    >>> from sklearn_radar import datasets, experiments
    >>> from sklearn_radar.metrics import precluster_target
    >>> from sklearn_radar.model_selection import SequenceSearchCV
    >>> data = datasets.make_scenes(n_sequences=3, duration=3.0, random_state=0)
    >>> pipeline, space = experiments.experiment_pipeline(3), experiments.search_space(3)
    >>> search = SequenceSearchCV(pipeline, space, n_iter=4, n_initial_points=3)
    >>> search.fit(data.data, precluster_target(data.data, data.target), data.groups).n_splits_
    3
    >>> sorted(search.best_params_)
    ['cluster__eps_vr', 'cluster__eps_xy', 'cluster__min_samples', 'cluster__vr_min']
    >>> search.cv_results_["rank_test_score"].shape
    (4,)
    """

    _parameter_constraints: ClassVar[dict] = {
        "estimator": [HasMethods(["fit_predict"])],
        "search_spaces": [dict],
        "n_iter": [Interval(Integral, 1, None, closed="left")],
        "n_initial_points": [Interval(Integral, 0, None, closed="left")],
        "n_points": [Interval(Integral, 1, None, closed="left")],
        "cv": [Interval(Integral, 2, None, closed="left")],
        "scoring": [StrOptions({"v1", "pq"})],
        "refit": ["boolean"],
        "random_state": ["random_state"],
        "n_jobs": [Integral, None],
        "verbose": ["verbose"],
    }

    def __init__(
        self,
        estimator,
        search_spaces,
        *,
        n_iter=100,
        n_initial_points=30,
        n_points=1,
        cv=3,
        scoring="v1",
        refit=True,
        random_state=None,
        n_jobs=None,
        verbose=0,
    ):
        self.estimator = estimator
        self.search_spaces = search_spaces
        self.n_iter = n_iter
        self.n_initial_points = n_initial_points
        self.n_points = n_points
        self.cv = cv
        self.scoring = scoring
        self.refit = refit
        self.random_state = random_state
        self.n_jobs = n_jobs
        self.verbose = verbose

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.target_tags.required = True
        tags.input_tags.pairwise = False
        return tags

    # The estimator is validated when the candidates are fitted (each with its own parameters).
    @_fit_context(prefer_skip_nested_validation=False)
    def fit(self, X, y, groups=None, *, callback=None):
        """Search the space on ``X``, the folds made of whole sequences of ``groups``.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            The detections, as the estimator reads them (e.g. the columns of
            :data:`sklearn_radar.experiments.PIPELINE_COLUMNS`).
        y : array-like of shape (n_detections,)
            Target per detection (e.g.
            :func:`~sklearn_radar.metrics.precluster_target`): instance id,
            -1 for background.
        groups : array-like of shape (n_detections,)
            Sequence of each detection; required (a sequence is never split
            between folds).
        callback : callable or list of callables, default=None
            Called after every step with skopt's result (its ``func_vals``
            are the negated scores so far), after the progress printer; a
            true return value stops the search.

        Returns
        -------
        self : SequenceSearchCV
            The fitted search.
        """
        y, groups = self._check_target_and_groups(X, y, groups)
        space = self._checked_space()
        folds = sequence_folds(groups, self.cv)
        data = SearchData.place(X, y, groups, n_jobs=self.n_jobs)
        searched, searched_space, prefix = self.estimator, space, ""
        fixed = fixed_prefix(self.estimator, space)
        if fixed is not None:
            stage0, searched, searched_space, prefix = fixed
            data = data.prepare(stage0)
        with threadpool_limits(limits=1, user_api="blas"):
            found = bayes_search(
                searched,
                searched_space,
                data,
                folds,
                objective=self.scoring,
                n_iter=self.n_iter,
                n_initial_points=self.n_initial_points,
                n_points=self.n_points,
                random_state=self.random_state,
                callback=self._callback(callback),
            )
        candidates = [{prefix + key: value for key, value in params.items()} for params in found.candidates]
        self.cv_results_ = _cv_results(candidates, found.fold_scores)
        self.best_index_ = int(np.argmax(found.scores))
        self.best_params_ = candidates[self.best_index_]
        self.best_score_ = found.scores[self.best_index_]
        self.n_splits_ = len(folds)
        self.multimetric_ = False
        if self.refit:
            start = time.perf_counter()
            self.best_estimator_ = clone(self.estimator).set_params(**self.best_params_).fit(X, y)
            self.refit_time_ = time.perf_counter() - start
        return self

    def _check_target_and_groups(self, X, y, groups):
        if y is None:  # scikit-learn's wording
            raise ValueError(f"{type(self).__name__} requires y to be passed, but the target y is None")
        if groups is None:
            raise ValueError("groups is required: the sequence of each detection, so that folds never split one")
        y, groups = column_or_1d(y), column_or_1d(groups)
        check_consistent_length(X, y, groups)
        n_sequences = len(np.unique(groups))
        if n_sequences < self.cv:
            raise ValueError(f"cv={self.cv} folds need at least {self.cv} sequences in groups, got {n_sequences}")
        return y, groups

    def _checked_space(self):
        if not self.search_spaces:
            raise ValueError("search_spaces is empty: give at least one parameter to search")
        known = self.estimator.get_params(deep=True)
        unknown = sorted(name for name in self.search_spaces if name not in known)
        if unknown:
            raise ValueError(f"search_spaces names parameters that {type(self.estimator).__name__} lacks: {unknown}")
        return dict(self.search_spaces)

    def _callback(self, callback):
        """The callbacks as one (None when there are none): progress lines first, stops when any returns true."""
        callbacks = [] if callback is None else list(callback) if isinstance(callback, (list, tuple)) else [callback]
        if self.verbose:
            callbacks.insert(0, ProgressPrinter(self.n_iter))
        if not callbacks:
            return None

        def every(result):
            return any([bool(call(result)) for call in callbacks])  # a list: every callback sees every step

        return every


def _cv_results(candidates, fold_scores):
    """scikit-learn's ``cv_results_`` of a search: per candidate its parameters and fold scores."""
    scores = np.asarray(fold_scores, dtype=np.float64).reshape(len(candidates), -1)
    results = {"params": candidates}
    for name in sorted({name for params in candidates for name in params}):
        column = np.ma.MaskedArray(np.empty(len(candidates), dtype=object), mask=True)
        for row, params in enumerate(candidates):
            if name in params:
                column[row] = params[name]
        results[f"param_{name}"] = column
    for fold in range(scores.shape[1]):
        results[f"split{fold}_test_score"] = scores[:, fold]
    results["mean_test_score"] = scores.mean(axis=1)
    results["std_test_score"] = scores.std(axis=1)
    results["rank_test_score"] = rankdata(-results["mean_test_score"], method="min").astype(np.int32)
    return results
