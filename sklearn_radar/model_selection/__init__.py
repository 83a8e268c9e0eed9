"""Splitting by sequence and Bayesian parameter search (Scheiner et al. 2019, Sec. "Parameter Optimization").

:func:`sequence_train_test_split` halves a data set by whole sequences;
:func:`make_bayes_search` builds the paper's 100-iteration (30 random)
Bayesian search with sequence-grouped cross-validation and the radar
V-measure as skopt's ``BayesSearchCV``; :class:`SequenceSearchCV` is the same
search fitted once per candidate and sequence (as ``reproduce`` runs it);
:class:`ProgressPrinter` prints one line per candidate.
"""

from ._search import ProgressBayesSearchCV, ProgressPrinter, make_bayes_search
from ._sequence_search import SequenceSearchCV
from ._split import sequence_train_test_split

__all__ = [
    "ProgressBayesSearchCV",
    "ProgressPrinter",
    "SequenceSearchCV",
    "make_bayes_search",
    "sequence_train_test_split",
]
