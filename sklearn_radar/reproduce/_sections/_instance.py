"""Beyond the paper: object-level scores of every experiment and baseline, where V1 cannot see background clusters."""

from __future__ import annotations

from .._experiment_records import InstanceScores
from .._results import RunResults
from ._base import Section, repeats_legend, score_cell


def markdown(results: RunResults) -> list[str]:
    """One row per experiment and baseline that carries object-level scores."""
    rows = [
        (f"#{number} {result.method}", result, result.instance_test)
        for number, result in sorted((results.experiments or {}).items())
    ]
    rows += [(name, result, result.instance_test) for name, result in (results.baselines or {}).items()]
    rows = [row for row in rows if row[2] is not None]
    if not rows:
        return []
    window = rows[0][2].window_s
    objective = "panoptic quality (PQ)" if results.meta.objective == "pq" else "the paper's V-measure (V1)"
    lines = [
        "",
        "## Beyond the paper: object-level scores",
        "",
        f"The searches maximised {objective}. The paper's V-measure does not penalise clusters made of static "
        "background, so tuning for it can cluster guard rails for free. The scores below count what a user of "
        f"one cluster per moving road user counts, per {window:g} s time window of each test sequence (Scheiner et al. "
        "2021): a ground-truth segment is one object's detections in a window, a predicted segment one cluster's; a "
        "match needs IoU > 0.5. PQ = SQ x RQ (Kirillov et al. 2019), RQ is the F1 score of the matches, SQ their "
        "mean IoU; every unmatched cluster segment is a false positive, background-only ones included. mCov and "
        "mWCov are the mean and size-weighted mean best IoU of each ground-truth segment (they ignore extra "
        "clusters). 'bg segments' and 'bg clusters' are the shares of predicted segments and of clusters that hold "
        "no detection of a moving road user."
        + repeats_legend(results)
        + (
            " `sklearn-radar reproduce --objective pq` tunes every setting for PQ instead."
            if results.meta.objective == "v1"
            else ""
        ),
        "",
        "| setting | V1 | PQ | SQ | F1 (RQ) | precision | recall | mCov | mWCov | bg segments | bg clusters |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    lines += [_row(name, result, scores) for name, result, scores in rows]
    return lines


def _row(name, result, s: InstanceScores):
    values = (s.sq, s.rq, s.precision, s.recall, s.mcov, s.mwcov)
    shares = (s.background_segment_share, s.background_cluster_share)
    return (
        f"| {name} | {score_cell(result)} | {score_cell(result, 'pq')} | "
        + " | ".join(f"{value:.3f}" for value in values)
        + " | "
        + " | ".join(f"{100 * share:.1f} %" for share in shares)
        + " |"
    )


SECTION = Section("instance", markdown)
