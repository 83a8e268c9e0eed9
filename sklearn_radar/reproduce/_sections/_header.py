"""The report's title and what ran: data, split, budget, scores, version, wall time, interruption."""

from __future__ import annotations

from .._results import RunResults
from ._base import Section, counted


def markdown(results: RunResults) -> list[str]:
    """The title and the run's description."""
    meta = results.meta
    data, budget = meta.data, meta.budget
    wall_time = float("nan") if meta.wall_time_s is None else meta.wall_time_s
    lines = [
        "# sklearn-radar: the experiments of Scheiner et al. (ITSC 2019), re-run",
        "",
        f"- data: {data.source}; {data.n_detections:,} detections in {counted(data.n_sequences, 'sequence')}, split "
        f"by sequence into a training half ({data.n_train:,} detections) and a test half ({data.n_test:,}).",
        f"- budget: {budget.label}: {counted(budget.n_iter, 'Bayesian-optimisation iteration')} per tuned experiment "
        f"({budget.n_initial_points} random), {budget.cv_folds}-fold CV grouped by sequence on the training half. "
        "The paper used 100 iterations (30 random) on about a million detections of real data: "
        "`sklearn-radar reproduce --full` uses that budget on about a million simulated ones. "
        "The paper's own setting is scored beside each search and kept when the search found nothing better "
        "(marked \u2020 in the tables).",
        f"- scores: radar V-measure (V1) on the test half against the pre-clustered target; seed {meta.seed}; "
        f"sklearn-radar {meta.version}; wall time {wall_time:.0f} s.",
    ]
    if meta.repeats > 1:
        lines.append(
            f"- repeats: every tuned experiment and baseline searched {meta.repeats} times, with the repeat "
            f"seeds {meta.seed}-{meta.seed + meta.repeats - 1} (each search's own seed derived from its repeat's and "
            "its experiment), on the same split; each repeat's kept setting scored on the "
            "test half. Test scores are mean \u00b1 standard deviation over the repeats."
        )
    if meta.interrupted:
        lines.append(f"- **interrupted**: only {', '.join(meta.completed) or 'nothing'} finished.")
    return lines


SECTION = Section("header", markdown)
