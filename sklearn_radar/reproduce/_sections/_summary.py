"""At a glance: the run's main results in a few lines, each pointing to the section that has the details."""

from __future__ import annotations

import numpy as np

from ...experiments import get_experiment
from .._constants import BEST_STAGE1, STAGE1
from .._experiment_records import repeated_scores
from .._results import RunResults
from ._base import OVERFIT_GAP, SETTING_PAPER, Section, objective_name, score_cell, setting_source, test_score
from ._comparison import CANNOT_TELL, DOES_NOT_HOLD, HOLDS, N_STANDARD_ERRORS, _chosen_rows, checked
from ._learned import glance_line as learned_glance_line
from ._objects import glance_line
from ._tracking import glance_line as tracking_glance_line


def markdown(results: RunResults) -> list[str]:
    """The best setting, the findings that hold, the overfitting, the paper's settings kept and the filter."""
    experiments = results.experiments
    lines = []
    stage1 = {number: e for number, e in experiments.items() if number in STAGE1}
    if stage1:
        best = max(stage1, key=lambda number: np.mean(repeated_scores(stage1[number])))
        e = stage1[best]
        ours8 = (
            f"; ours for #{BEST_STAGE1}: {score_cell(experiments[BEST_STAGE1])}"
            if BEST_STAGE1 in experiments and best != BEST_STAGE1
            else ""
        )
        paper = f" (the paper's best is #{BEST_STAGE1}, {get_experiment(BEST_STAGE1).v1_percent:.2f} %{ours8})"
        mean = " (mean over the repeats)" if results.meta.repeats > 1 else ""
        tuned = f" (the searches tuned for {objective_name(results)})"
        lines.append(f"- best point clustering by test V1{mean}{tuned}: #{best} {e.method}, {score_cell(e)}{paper}.")
    checks = checked(results)
    if checks:
        lines.append(f"- {findings_line(checks, results.meta.repeats)}")
    for line in (glance_line(results), learned_glance_line(results), tracking_glance_line(results)):
        if line:
            lines.append(f"- {line}")
    named = [(f"#{n}", e) for n, e in sorted(experiments.items())] + list((results.baselines or {}).items())
    over = [
        name for name, r in named if r.search is not None and r.search.cv_best - test_score(r, results) > OVERFIT_GAP
    ]
    if over:
        gap = f"{100 * OVERFIT_GAP:g} points" if results.meta.objective == "v1" else f"{OVERFIT_GAP:g}"
        lines.append(
            f"- cross-validated {objective_name(results)} more than {gap} above the test score (overfitting the "
            f"few training sequences): {', '.join(over)}."
        )
    kept = [f"#{n}" for n, e in sorted(experiments.items()) if setting_source(e) == SETTING_PAPER]
    if kept:
        lines.append(
            f"- the search found nothing better than the paper's setting for {', '.join(kept)}: the tables show the "
            f"paper's setting there, scored on our data (marked {SETTING_PAPER.split()[-1]})."
        )
    unmerged = [f"#{n}" for n, e in sorted(experiments.items()) if e.n_merges_test == 0]
    if unmerged:
        lines.append(
            f"- {', '.join(unmerged)} merged nothing on the test half: the scores equal those of the stage-1 input."
        )
    w = results.filter.windows if results.filter is not None else None
    row = _chosen_rows(results.filter).get(w.frame) if w is not None else None
    if w is not None and row is not None:
        lines.append(
            f"- the filter at the paper's chosen setting: {w.n_errors:,} error windows of {w.n_windows:,} (the "
            f"paper: {row.paper_errors}), background removed {row.removal_rate:.2f} % (the paper: "
            f"{row.paper_removal_rate:.2f} %); explained under Tables I and II."
        )
    drawn = results.figures.drawn
    shown = [f"[{FIGURE_NAMES.get(name, name)}]({file})" for name, file in drawn.items()]
    if shown:
        lines.append(f"- figures: {', '.join(shown)}.")
    if not lines:
        return []
    return ["", "## At a glance", "", *lines]


def findings_line(checks, repeats):
    """How many findings hold, do not and cannot be told, and why the run cannot tell."""
    count = {verdict: sum(v == verdict for _, v, _ in checks) for verdict in (HOLDS, DOES_NOT_HOLD, CANNOT_TELL)}
    why = ""
    if count[CANNOT_TELL]:
        why = (
            f" (within {N_STANDARD_ERRORS} standard errors of the repeats)"
            if repeats > 1
            else " (they compare single searches, and a single run gives no verdict on them: `--repeats 3` repeats "
            "each search)"
        )
    return (
        f"the paper's findings, {len(checks)} checked: {count[HOLDS]} hold, {count[DOES_NOT_HOLD]} do not hold, "
        f"{count[CANNOT_TELL]} cannot tell{why} (last section, 'The paper's findings, checked')."
    )


#: How the summary names each figure.
FIGURE_NAMES = {
    "table1_heatmap": "Table I heatmaps",
    "filter_scene": "what the filter removes",
    "v1_bars": "V1 ours vs the paper's",
    "scene": "Fig. 6 analogue",
    "convergence": "convergence of the searches",
    "tracks": "tracks over one test sequence",
    "precision_recall": "precision against recall per class",
}


SECTION = Section("summary", markdown)
