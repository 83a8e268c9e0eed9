"""The data size and optimisation budget of a reproduce run (``meta.budget``)."""

from __future__ import annotations

from dataclasses import field

from ._constants import PAPER_N_ITER
from ._records import NOT_WRITTEN, JsonRecord, record


@record
class Budget(JsonRecord):
    """Data size and optimisation budget of a run.

    Attributes
    ----------
    label : str
        Name of the budget in the report, e.g. ``"reduced (default run)"``.
    n_iter : int
        Bayesian-optimisation iterations per tuned experiment.
    n_initial_points : int
        Random points among them.
    cv_folds : int
        Folds of the grouped cross-validation on the training half.
    n_sequences : int or None, default=None
        Simulated sequences; None when read back from ``results.json``,
        which records the data in ``meta.data`` instead.
    duration : float or None, default=None
        Length of each simulated sequence, s; None as ``n_sequences``.
    """

    label: str
    n_iter: int
    n_initial_points: int
    cv_folds: int
    n_sequences: int | None = field(default=None, metadata=NOT_WRITTEN)
    duration: float | None = field(default=None, metadata=NOT_WRITTEN)

    @classmethod
    def default(cls, n_iter=None):
        """The default run's budget: 4 sequences x 20 s, ``n_iter`` iterations (None: 10; 30 % random), 2 folds."""
        n_iter = 10 if n_iter is None else n_iter
        return cls._of("reduced (default run)", n_iter, cv_folds=2, n_sequences=4, duration=20.0)

    @classmethod
    def full(cls, n_iter=None):
        """The paper's budget (``--full``): 17 sequences x 30 s, ``n_iter`` iterations (None: 100), 3 folds."""
        n_iter = PAPER_N_ITER if n_iter is None else n_iter
        return cls._of("the paper's (--full)", n_iter, cv_folds=3, n_sequences=17, duration=30.0)

    @classmethod
    def _of(cls, label, n_iter, **sizes):
        return cls(label=label, n_iter=n_iter, n_initial_points=max(1, round(0.3 * n_iter)), **sizes)

    @property
    def reduced(self):
        """bool : Whether the run had fewer iterations than the paper's 100."""
        return self.n_iter < PAPER_N_ITER
