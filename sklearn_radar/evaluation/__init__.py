"""Evaluation of the framework's stages against the paper's results.

Filter evaluation (Sec. "Filtering Results" of Scheiner et al. 2019):
:func:`filter_grid` enumerates the Doppler threshold and the spatial radius
of Eq. 1 and counts the errors per setting (Table I);
:func:`filter_settings_table` measures chosen settings beside
:data:`PAPER_TABLE_II` (Table II); :class:`FilterEvaluationOptions` holds the
options of both.
"""

from ._filter import PAPER_TABLE_II, FilterEvaluationOptions, filter_removal_rates, plot_filter_errors
from ._filter_parts import filter_error_windows, filter_errors, filter_grid, filter_settings_table

__all__ = [
    "PAPER_TABLE_II",
    "FilterEvaluationOptions",
    "filter_error_windows",
    "filter_errors",
    "filter_grid",
    "filter_removal_rates",
    "filter_settings_table",
    "plot_filter_errors",
]
