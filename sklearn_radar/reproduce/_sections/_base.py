"""What every report section is, and the formatting that several sections share."""

from __future__ import annotations

import io
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..._files import atomic_write
from .._constants import BEST_STAGE1, FRAME_NAMES, SOURCE_PAPER
from .._context import RunContext
from .._experiment_records import ExperimentResult, repeated_scores
from .._filter_records import GridTable
from .._results import RunResults

#: Markdown of a section: its lines, each starting a new line of report.md; [] leaves the section out.
Markdown = Callable[[RunResults], list[str]]

#: Figures of a section: draw them into the output folder, return {figure name: file name} of those drawn.
Figures = Callable[[Path, RunResults, RunContext], dict[str, str]]


@dataclass(frozen=True)
class Section:
    """One section of ``report.md``.

    Attributes
    ----------
    name : str
        Short name, e.g. ``"filter"``.
    markdown : callable
        ``markdown(results: RunResults) -> list[str]``: the section's lines
        (typically a blank line and a heading first); ``[]`` when there is
        nothing to report, e.g. a step that did not run.
    figures : callable or None, default=None
        ``figures(out: Path, results: RunResults, context: RunContext) ->
        dict[str, str]``: draw the section's figures into ``out`` (with
        :func:`save_figure`) and return ``{figure name: file name}`` of those
        drawn; they are recorded in ``results.figures`` before any markdown
        is written.  Called only when matplotlib is installed, with the
        Agg backend selected.
    """

    name: str
    markdown: Markdown
    figures: Figures | None = None


def format_params(params):
    """``{"cluster__eps_xy": 0.6, ...}`` -> ``"eps_xy=0.6, ..."`` (3 significant digits; shared settings left out)."""
    shown = []
    for key, value in (params or {}).items():
        name = key.split("__")[-1]
        if name in ("eps_t", "n_jobs", "mode", "metric"):
            continue
        if isinstance(value, (int, float)):
            shown.append(f"{_SHORT.get(name, name)}={value:.3g}")
        else:
            shown.append(f"{name}={value}")
    return ", ".join(shown)


_SHORT = {"eps_phi": "eps_phi (rad)"}


def counted(n, noun):
    """``"1 iteration"``, ``"10 iterations"``: ``n`` and the noun, plural unless ``n`` is 1 (an ``s`` appended)."""
    return f"{n:,} {noun}" + ("" if n == 1 else "s")


def percent(value):
    """A share 0-1 as ``"71.55 %"``; ``"-"`` for None or NaN."""
    return "-" if value is None or (isinstance(value, float) and np.isnan(value)) else f"{100 * value:.2f} %"


def score_cell(result, score="v1"):
    """A test score (``"v1"`` in %, ``"pq"``) of ``result``: one value, or mean and sd over repeats; or ``"-"``."""
    return values_cell(repeated_scores(result, score), score)


def values_cell(values, score="v1", sign="\u00b1"):
    """Scores of the repeats as :func:`score_cell` writes them: one value, or mean ``sign`` sd; ``"-"`` for none."""
    if len(values) == 0:
        return "-"
    scale, unit, digits = (100, " %", 2) if score == "v1" else (1, "", 3)
    if len(values) == 1:
        return f"{scale * values[0]:.{digits}f}{unit}"
    return f"{scale * np.mean(values):.{digits}f} {sign} {scale * np.std(values, ddof=1):.{digits}f}{unit}"


def repeats_legend(results: RunResults):
    """What a score cell means in a run of several repeats; ``""`` for a single run."""
    repeats = results.meta.repeats
    if repeats < 2:
        return ""
    return (
        f" Test scores are mean \u00b1 standard deviation over {repeats} searches with different seeds on the same "
        "split (results.json `repeats` holds each); the other columns are those of the first repeat."
    )


def frame_name(frame):
    """``"frame"`` -> ``"FCS"``, ``"car"`` -> ``"CCS"``."""
    return FRAME_NAMES[frame]


def grid_markdown(table: GridTable):
    """A table of Table I as a markdown table."""
    data = table.to_frame()
    header = "| eta_1 (m/s) \\ d_xy (m) | " + " | ".join(f"{c:.1f}" for c in data.columns) + " |"
    rule = "|---|" + "---|" * len(data.columns)
    rows = [f"| {i:.2f} | " + " | ".join(f"{v:g}" for v in data.loc[i]) + " |" for i in data.index]
    return "\n".join([header, rule, *rows])


#: The "setting" column: where an experiment's parameters come from, and the legend of each mark.
SETTING_SEARCH = "search"
SETTING_PAPER = "paper's \u2020"
SETTING_FIXED = "fixed"
SETTING_DERIVED = f"#{BEST_STAGE1}'s"

#: A cross-validated score this far above the test score (0-1) is pointed out as overfitting.
OVERFIT_GAP = 0.05


def setting_source(e: ExperimentResult):
    """Where the experiment's parameters come from: one of the ``SETTING_*`` marks."""
    if e.search is not None:
        return SETTING_PAPER if e.search.best_source == SOURCE_PAPER else SETTING_SEARCH
    return SETTING_DERIVED if e.derived_from_8 is not None else SETTING_FIXED


def objective_name(results: RunResults):
    """``"V1"`` or ``"PQ"``: the score the searches maximised."""
    return "PQ" if results.meta.objective == "pq" else "V1"


def test_score(result, results: RunResults):
    """The test score of an experiment or baseline in the run's objective (V1, or PQ when tuned for PQ)."""
    if results.meta.objective == "pq" and result.instance_test is not None:
        return result.instance_test.pq
    return result.v1_test


def format_score(value, results: RunResults):
    """A score of the run's objective: V1 in percent, PQ with 3 decimals; ``"-"`` for None."""
    if value is None:
        return "-"
    return f"{value:.3f}" if results.meta.objective == "pq" else percent(value)


def cv_cell(result, results: RunResults):
    """The mean cross-validated score of a search's kept setting; ``"-"`` without a search."""
    return format_score(None if result.search is None else result.search.cv_best, results)


def overfit_lines(named, results: RunResults):
    """Lines naming the ``named`` (name, result) whose CV score is more than :data:`OVERFIT_GAP` above their test."""
    over = [
        f"{name} (CV {format_score(r.search.cv_best, results)}, test {format_score(test_score(r, results), results)})"
        for name, r in named
        if r.search is not None and r.search.cv_best - test_score(r, results) > OVERFIT_GAP
    ]
    if not over:
        return []
    gap = f"{100 * OVERFIT_GAP:g} points" if results.meta.objective == "v1" else f"{OVERFIT_GAP:g}"
    return [
        "",
        f"CV above test by more than {gap}: {'; '.join(over)}. The search chose these settings on the training "
        "sequences, and they do not carry over as well to the test sequences (overfitting to few sequences).",
    ]


def experiment_table(title, rows: list[ExperimentResult], results: RunResults, stage2=False):
    """The lines of a heading ``title``, Table III (or IV, ``stage2``) of ``rows`` by number, and its legend."""
    score = objective_name(results)
    extra = " stage-1 clusters | merges |" if stage2 else ""
    lines = [
        "",
        f"## {title}",
        "",
        f"| # | method | CS | filtered | V1 (ours) | V1 (paper) | CV {score} (train) | setting |{extra} "
        "our parameters | paper's parameters |",
        "|---|---|---|---|---|---|---|---|" + ("---|---|" if stage2 else "") + "---|---|",
    ]
    rows = sorted(rows, key=lambda e: e.number)
    lines += [experiment_row(e, results, stage2) for e in rows]
    lines += [
        "",
        *column_legend(results, stage2, short=stage2 and any(e.stage == 1 for e in results.experiments.values())),
    ]
    lines += overfit_lines([(f"#{e.number}", e) for e in rows], results)
    return lines


def column_legend(results: RunResults, stage2=False, short=False):
    """What each column of Tables III and IV means (one paragraph); ``short``: only the columns Table III lacks."""
    score = objective_name(results)
    folds = results.meta.budget.cv_folds
    merges = (
        " *stage-1 clusters*: clusters of the stage-1 setting on the test half, before merging; *merges*: pairs of "
        "them that met the merge criterion (0: the experiment returned its stage-1 clustering unchanged)."
        if stage2
        else ""
    )
    if short:
        return ["Columns as in Table III;" + merges]
    return [
        "Columns: *V1 (ours)*: radar V-measure of our setting on the test half; *V1 (paper)*: the paper's; "
        f"*CV {score} (train)*: mean {score} of our setting over the {folds} cross-validation folds of the training "
        "half, the score the search maximised (a CV well above the test score means the setting fits the training "
        f"sequences better than new ones); *setting*: where our parameters come from: `{SETTING_SEARCH}` the "
        f"Bayesian search's best, `{SETTING_PAPER}` the paper's setting, scored beside the search on the same folds "
        "and kept because the search found nothing better (results.json `best_source`), "
        f"`{SETTING_FIXED}` the paper's fixed expert setting (not tuned), `{SETTING_DERIVED}` "
        f"#{BEST_STAGE1}'s setting transferred (not tuned); *CS*: coordinate system (FCS: frame/world, "
        "CCS: car); *filtered*: whether the Doppler-density filter ran first." + merges + repeats_legend(results)
    ]


def experiment_row(e: ExperimentResult, results: RunResults, stage2=False):
    """One experiment's row of Table III or IV."""
    cells = [
        e.number,
        e.method,
        frame_name(e.frame),
        "yes" if e.filtered else "no",
        score_cell(e),
        f"{e.paper_v1_percent:.2f} %",
        cv_cell(e, results),
        setting_source(e),
    ]
    if stage2:
        cells += [_count(e.n_stage1_clusters_test), _count(e.n_merges_test)]
    cells += [format_params(e.params), format_params(e.paper_params)]
    return "| " + " | ".join(str(cell) for cell in cells) + " |"


def _count(value):
    return "-" if value is None else f"{value:,}"


#: Inches a figure's y-axis label and tick labels take on the left, and between two panels in a row.
FIGURE_LEFT_MARGIN, PANEL_GAP = 0.9, 0.15


def scene_size(x, y, *, width, extra_height, panels=1):
    """``(width, height)``, in, of a row of ``panels`` equal-aspect scatter panels fitted to ``x, y`` (m)."""
    span_x = max(float(np.ptp(x)), 1.0) if len(x) else 1.0
    span_y = max(float(np.ptp(y)), 1.0) if len(y) else 1.0
    panel_width = (width - FIGURE_LEFT_MARGIN) / panels - PANEL_GAP * (panels - 1) / panels
    return width, panel_width * span_y / span_x + extra_height


def save_figure(fig, path):
    """Lay out ``fig`` (tightly, unless it has a layout engine), write it to ``path`` as PNG (90 dpi), close it."""
    import matplotlib.pyplot as plt

    buffer = io.BytesIO()
    if fig.get_layout_engine() is None:
        fig.tight_layout()
    fig.savefig(buffer, format="png", dpi=90)
    plt.close(fig)
    atomic_write(path, lambda stream: stream.write(buffer.getvalue()))
