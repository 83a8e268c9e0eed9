"""The names of the columns that the stage-0 transformers return, for ``get_feature_names_out``.

scikit-learn's output API (``set_output``) needs them: with
``transform="pandas"`` it wraps an array result in a DataFrame with these
names and renames the columns of a DataFrame result to them in place
(``sklearn.utils._set_output.PandasAdapter``).  They must therefore be
exactly the columns :func:`~sklearn_radar._validation.write_columns`
produces, in its order.
"""

from __future__ import annotations

import numpy as np
from sklearn.utils.validation import _check_feature_names_in

from .._schema import WORK_LAYOUT


def feature_names_out(estimator, input_features, *, added, array_width):
    """Output column names of a transformer that adds the columns ``added``.

    Parameters
    ----------
    estimator : fitted transformer
        Fitted on a DataFrame (it has ``feature_names_in_``) or an array.
    input_features : array-like of str or None
        Checked against ``feature_names_in_`` (or ``n_features_in_``) as
        scikit-learn does; None means the names seen in ``fit``.
    added : tuple of str
        The columns ``transform`` writes into a DataFrame, in writing order.
    array_width : int
        How many columns ``transform`` returns for an array.

    Returns
    -------
    names : ndarray of object
        DataFrame fit: the input columns in their order, then the columns of
        ``added`` that were not among them.  Array fit: the names of
        :data:`~sklearn_radar._schema.WORK_LAYOUT` up to ``array_width``.
    """
    input_features = _check_feature_names_in(estimator, input_features)
    if hasattr(estimator, "feature_names_in_"):
        return _frame_columns_after_adding(input_features, added)
    return _work_array_columns(array_width, input_features)


def work_array_width(n_input_columns, written):
    """Columns of the array that ``write_columns`` makes from ``n_input_columns`` and the columns ``written``."""
    return max(n_input_columns, max(WORK_LAYOUT.position(name) for name in written) + 1)


def _frame_columns_after_adding(input_features, added):
    """``DataFrame.assign`` order: existing columns stay in place, new ones follow in ``added`` order."""
    present = set(input_features)
    return np.asarray([*input_features, *(name for name in added if name not in present)], dtype=object)


def _work_array_columns(width, input_features):
    """The working layout's names; a column beyond the layout is passed through and keeps its input name."""
    layout = WORK_LAYOUT.columns
    return np.asarray([*layout[:width], *input_features[len(layout) : width]], dtype=object)
