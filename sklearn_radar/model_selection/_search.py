"""Bayesian parameter search as in Scheiner et al. 2019, Sec. "Parameter Optimization"."""

from __future__ import annotations

import sys
import time
from numbers import Integral, Real

import numpy as np
from sklearn.model_selection import GroupKFold
from sklearn.utils._param_validation import HasMethods, Interval, validate_params

from .._skopt import BayesSearchCV
from ..metrics import radar_v_measure_scorer

__all__ = ["ProgressPrinter", "make_bayes_search"]


class ProgressPrinter:
    """scikit-optimize callback printing one line per evaluated candidate.

    Pass it to :meth:`BayesSearchCV.fit`,
    ``search.fit(X, y, groups=groups, callback=ProgressPrinter(search.n_iter))``.
    Each line shows the iteration ``i/n``, the candidate's mean cross-validated
    score, the best score so far and the seconds since the printer was
    created (create it right before ``fit``)::

        [stage 1] iteration  12/100  score 0.8123  best 0.8456  elapsed 34.2 s

    With ``n_points > 1`` skopt calls back once per batch; one line is still
    printed per candidate.  Lines are plain (no carriage returns), so the
    output reads the same piped to a file.

    Parameters
    ----------
    n_iter : int
        Total number of iterations, for the ``i/n`` display.
    label : str, default=""
        Printed in brackets at the start of each line (e.g. the experiment).
    stream : file-like or None, default=None
        Where to write; None means :data:`sys.stdout` at the time of printing
        (so that redirections made after construction are honoured).
    status : callable or None, default=None
        ``status(i, n) -> str`` after iteration ``i`` of ``n``, appended to
        the line after ``" | "``: e.g. the overall progress of a longer run
        that holds this search.

    Attributes
    ----------
    scores : list of float
        Score of each evaluated candidate, in order.
    best_score : float
        Best score so far (-inf before the first candidate).
    """

    def __init__(self, n_iter, label="", stream=None, status=None):
        self.n_iter = n_iter
        self.label = label
        self.stream = stream
        self.status = status
        self.scores = []
        self.best_score = -np.inf
        self._start = time.perf_counter()
        self._seen = 0

    def __call__(self, result):
        """Print the candidates added since the last call; never stops the search.

        Parameters
        ----------
        result : scipy.optimize.OptimizeResult
            skopt's result so far; ``result.func_vals`` holds the negated
            score of every candidate evaluated (of the current search
            subspace).

        Returns
        -------
        stop : None
            Never a true value, which would stop the search.
        """
        # func_vals are the negated scores (skopt minimises); a new search
        # subspace restarts them, then everything in them is new.
        values = -np.asarray(result.func_vals, dtype=np.float64)
        new = values[self._seen :] if len(values) >= self._seen else values
        self._seen = len(values)
        stream = self.stream if self.stream is not None else sys.stdout
        prefix = f"[{self.label}] " if self.label else ""
        width = len(str(self.n_iter))
        for score in new:
            self.scores.append(float(score))
            self.best_score = max(self.best_score, float(score))
            extra = "" if self.status is None else f" | {self.status(len(self.scores), self.n_iter)}"
            stream.write(
                f"{prefix}iteration {len(self.scores):>{width}}/{self.n_iter}  score {score:.4f}  "
                f"best {self.best_score:.4f}  elapsed {time.perf_counter() - self._start:.1f} s{extra}\n"
            )
        stream.flush()


class ProgressBayesSearchCV(BayesSearchCV):
    """:class:`skopt.BayesSearchCV` that prints a :class:`ProgressPrinter` line per candidate.

    Identical to ``BayesSearchCV`` except for one added parameter,
    ``progress``: when true, :meth:`fit` prepends a :class:`ProgressPrinter`
    (labelled ``progress`` when it is a string) to the callbacks.
    :func:`make_bayes_search` builds one with the paper's settings.

    Read more in the :ref:`User Guide <user-guide-tuning>`.

    Parameters
    ----------
    estimator, search_spaces, optimizer_kwargs, n_iter, scoring, fit_params, n_jobs, n_points, iid, refit, cv, \
verbose, pre_dispatch, random_state, error_score, return_train_score
        As in :class:`skopt.BayesSearchCV`, with its defaults.
    progress : bool or str, default=False
        If true, :meth:`fit` prints one line per evaluated candidate; a
        string is printed in brackets at the start of each line.

    Attributes
    ----------
    best_estimator_ : estimator
        The candidate with the best mean cross-validated score, refitted on
        all of X (when ``refit``).
    best_index_ : int
        Row of ``cv_results_`` of the best candidate.
    best_params_ : dict
        Parameters of the best candidate.
    best_score_ : float
        Mean cross-validated score of the best candidate.
    cv_results_ : dict of numpy (masked) ndarrays
        Scores, fit times and parameters of every candidate, as in
        :class:`sklearn.model_selection.GridSearchCV`.
    feature_names_in_ : ndarray of str
        Column names of X, when X is a DataFrame (and ``refit``).
    multimetric_ : bool
        Whether more than one score is computed.
    n_splits_ : int
        Number of cross-validation folds.
    optimizer_kwargs_ : dict
        Arguments the :class:`skopt.Optimizer` of each search space was
        built with.
    optimizers_ : list of skopt.Optimizer
        The optimiser of each search space, with every point it evaluated.
    refit_time_ : float
        Seconds spent refitting the best candidate on all of X.
    scorer_ : callable
        The scorer used (``scoring``, or the estimator's ``score``).

    See Also
    --------
    make_bayes_search : the paper's search as a ProgressBayesSearchCV.
    """

    def __init__(
        self,
        estimator,
        search_spaces,
        optimizer_kwargs=None,
        n_iter=50,
        scoring=None,
        fit_params=None,
        n_jobs=1,
        n_points=1,
        iid="deprecated",
        refit=True,
        cv=None,
        verbose=0,
        pre_dispatch="2*n_jobs",
        random_state=None,
        error_score="raise",
        return_train_score=False,
        progress=False,
    ):
        super().__init__(
            estimator,
            search_spaces,
            optimizer_kwargs=optimizer_kwargs,
            n_iter=n_iter,
            scoring=scoring,
            fit_params=fit_params,
            n_jobs=n_jobs,
            n_points=n_points,
            iid=iid,
            refit=refit,
            cv=cv,
            verbose=verbose,
            pre_dispatch=pre_dispatch,
            random_state=random_state,
            error_score=error_score,
            return_train_score=return_train_score,
        )
        self.progress = progress

    def fit(self, X, y=None, *, groups=None, callback=None, **fit_params):
        """Run the search (see :meth:`skopt.BayesSearchCV.fit`), printing progress if asked.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            The detections.
        y : array-like of shape (n_detections,), default=None
            Target per detection (e.g.
            :func:`~sklearn_radar.metrics.precluster_target`).
        groups : array-like of shape (n_detections,), default=None
            Sequence of each detection, for a grouped ``cv``.
        callback : callable or list of callables, default=None
            Called after each step with the optimiser's result, after the
            progress printer; a true return value stops the search.
        **fit_params : dict
            Passed to the estimator's ``fit``.

        Returns
        -------
        self : ProgressBayesSearchCV
            The fitted search.
        """
        callbacks = [] if callback is None else list(callback) if isinstance(callback, (list, tuple)) else [callback]
        if self.progress:
            label = self.progress if isinstance(self.progress, str) else ""
            callbacks.insert(0, ProgressPrinter(self._n_candidates(), label=label))
        return super().fit(X, y, groups=groups, callback=callbacks or None, **fit_params)

    def _n_candidates(self):
        """Candidates the search will evaluate (skopt's ``total_iterations`` miscounts a dict space)."""
        if isinstance(self.search_spaces, dict):
            return self.n_iter
        return sum(space[1] if isinstance(space, tuple) else self.n_iter for space in self.search_spaces)


# Skipping nested validation is safe: the estimator is only stored here, and validated when the search fits it.
@validate_params(
    {
        "estimator": [HasMethods(["fit"])],
        "search_space": [dict, list],
        "n_iter": [Interval(Integral, 1, None, closed="left")],
        "n_initial_points": [Interval(Integral, 0, None, closed="left")],
        "cv": [Interval(Integral, 2, None, closed="left"), HasMethods(["split", "get_n_splits"]), list],
        "scoring": [callable, None],
        "n_jobs": [Integral, None],
        "n_points": [Interval(Integral, 1, None, closed="left")],
        "random_state": ["random_state"],
        "error_score": [Real],
        "verbose": ["verbose"],
        "optimizer_kwargs": [dict, None],
    },
    prefer_skip_nested_validation=True,
)
def make_bayes_search(
    estimator,
    search_space,
    *,
    n_iter=100,
    n_initial_points=30,
    cv=3,
    scoring=None,
    n_jobs=None,
    n_points=1,
    random_state=None,
    error_score=0.0,
    verbose=0,
    optimizer_kwargs=None,
):
    """The paper's Bayesian optimisation as a :class:`skopt.BayesSearchCV`.

    Scheiner et al. tune each clustering stage separately "with a maximum of
    100 iterations (30 for exploration and 70 for exploitation)"; these are
    the defaults.  Cross-validation is grouped by sequence (pass
    ``groups=`` to ``fit``), candidates are scored by the radar V-measure
    (:func:`~sklearn_radar.metrics.radar_v_measure_scorer`), and a failing
    candidate scores ``error_score=0.0`` instead of stopping the search or
    feeding NaN to the Gaussian process.

    Read more in the :ref:`User Guide <user-guide-tuning>`.

    Parameters
    ----------
    estimator : estimator
        Usually :func:`sklearn_radar.experiments.experiment_pipeline`; give
        it ``memory=`` so that the preprocessing (and, for stage 2, stage 1)
        is computed once per cross-validation subset instead of once per
        candidate.
    search_space : dict or list
        ``{parameter: skopt dimension}`` (e.g.
        :func:`sklearn_radar.experiments.search_space`), or anything
        ``BayesSearchCV`` accepts as ``search_spaces``.
    n_iter : int, default=100
        Candidates evaluated in total, >= 1.
    n_initial_points : int, default=30
        Random candidates before the Gaussian process guides the search
        (``optimizer_kwargs={"n_initial_points": ...}``; skopt's own default
        of 10 would make a short search purely random), >= 0.
    cv : int, cross-validation splitter or list of (train, test) index arrays, default=3
        An int (>= 2) means :class:`~sklearn.model_selection.GroupKFold`
        with that many folds: every sequence lies wholly in one fold, the
        folds being balanced in detections.  ``fit`` then needs ``groups=``.
        A splitter (with ``split`` and ``get_n_splits``) or a list of
        folds is used as given.
    scoring : callable or None, default=None
        ``scorer(estimator, X, y)``; None means
        :func:`~sklearn_radar.metrics.radar_v_measure_scorer`.
    n_jobs : int or None, default=None
        Fits run in parallel (joblib): the ``cv`` folds of the ``n_points``
        candidates of one step, so at most ``cv * n_points`` at a time.
    n_points : int, default=1
        Candidates proposed per step, >= 1; raise it with ``n_jobs`` to use more
        workers than folds (slightly less sequential guidance).
    random_state : int, RandomState instance or None, default=None
        Seed of the optimiser (random points, acquisition).
    error_score : float, default=0.0
        Score of a candidate whose fit fails.
    verbose : int or bool, default=0
        0: silent.  1: one progress line per candidate (iteration, score,
        best so far, elapsed seconds; see :class:`ProgressPrinter`).
        ``>= 2``: in addition scikit-learn's own messages at level
        ``verbose - 1``.
    optimizer_kwargs : dict or None, default=None
        Further arguments of :class:`skopt.Optimizer`, merged with
        ``n_initial_points``.  For example ``{"acq_optimizer": "sampling"}``
        makes a guided step cheaper than skopt's default L-BFGS acquisition
        search (several seconds per step at 30-100 points on 2 CPUs).

    Returns
    -------
    search : ProgressBayesSearchCV
        An unfitted :class:`skopt.BayesSearchCV` (subclass adding only the
        progress lines).  Call ``search.fit(X, y, groups=groups)``; then
        ``best_params_``, ``best_score_``, ``cv_results_`` and
        ``best_estimator_`` (refitted on all of X) are available.

    Notes
    -----
    Clusterers have no out-of-sample ``predict``, so the scorer fits the
    candidate again on each test fold (the fit on the training folds is
    scikit-learn's protocol but does not enter the score).

    ``error_score`` covers a candidate that fails on *some* folds only:
    scikit-learn raises when every fit of a step fails, and a Bayesian step
    is a single candidate.  The radar scorer itself never raises for a failing
    candidate.

    With a cached pipeline, pass only the columns it reads
    (:data:`sklearn_radar.experiments.PIPELINE_COLUMNS`): the cache hashes
    its whole input on every call.

    Examples
    --------
    >>> from sklearn_radar.datasets import make_scenes
    >>> from sklearn_radar.experiments import experiment_pipeline, search_space
    >>> from sklearn_radar.metrics import precluster_target
    >>> from sklearn_radar.model_selection import make_bayes_search
    >>> scenes = make_scenes(n_sequences=3, duration=3.0, random_state=0)
    >>> y = precluster_target(scenes.data, scenes.target)
    >>> search = make_bayes_search(experiment_pipeline(3), search_space(3), n_iter=3,
    ...                            n_initial_points=3, cv=3, random_state=0)
    >>> search = search.fit(scenes.data, y, groups=scenes.groups)
    >>> bool(0.0 <= search.best_score_ <= 1.0)
    True
    """
    if scoring is None:
        scoring = radar_v_measure_scorer
    if isinstance(cv, Integral) and not isinstance(cv, bool):
        cv = GroupKFold(n_splits=int(cv))
    return ProgressBayesSearchCV(
        estimator,
        search_space,
        optimizer_kwargs={**(optimizer_kwargs or {}), "n_initial_points": n_initial_points},
        n_iter=n_iter,
        scoring=scoring,
        n_jobs=n_jobs,
        n_points=n_points,
        cv=cv,
        verbose=max(int(verbose) - 1, 0),
        random_state=random_state,
        error_score=error_score,
        progress=verbose > 0,
    )
