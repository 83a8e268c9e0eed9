"""Beyond the paper: the scikit-learn clusterers a user would otherwise pick, tuned and scored the same way."""

from __future__ import annotations

from ...experiments import SKLEARN_BASELINES
from ...model_selection._bounds import bounds_reached
from .._results import RunResults
from ._base import Section, cv_cell, format_params, objective_name, overfit_lines, repeats_legend, score_cell


def markdown(results: RunResults) -> list[str]:
    """One row per baseline, when the baselines ran, and what the columns mean."""
    if not results.baselines:
        return []
    score = objective_name(results)
    lines = [
        "",
        "## Beyond the paper: the clusterers a user would otherwise pick",
        "",
        "Same FCS + filter input, same budget and split.",
        "",
        f"| clusterer | V1 (test) | CV {score} (train) | parameters | at a search bound | wall time |",
        "|---|---|---|---|---|---|",
    ]
    for name, result in results.baselines.items():
        lines.append(
            f"| {name} | {score_cell(result)} | {cv_cell(result, results)} | {format_params(result.params)} "
            f"| {_at_bound(name, result)} | {result.wall_time_s:.0f} s |"
        )
    lines += [
        "",
        f"Columns: *V1 (test)*: radar V-measure on the test half; *CV {score} (train)*: mean {score} of the kept "
        f"setting over the {results.meta.budget.cv_folds} cross-validation folds of the training half (what the "
        "search maximised); *at a search bound*: tuned parameters that stopped at an end of their search range (in "
        "any repeat), so that a wider range might have scored better; *wall time*: search and scoring, s."
        + repeats_legend(results),
    ]
    lines += overfit_lines(list(results.baselines.items()), results)
    return lines


def _at_bound(name, result):
    """The parameters of any repeat that stopped at an end of the baseline's range today, or "none"."""
    space = SKLEARN_BASELINES[name][1] if name in SKLEARN_BASELINES else {}
    reached = {key for r in result.repeats or [result] for key in bounds_reached(r.params, space)}
    return ", ".join(key.split("__")[-1] for key in space if key in reached) or "none"


SECTION = Section("baselines", markdown)
