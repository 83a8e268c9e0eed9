"""The filter's effect on clustering: time and clusters with and without it, ours beside the paper's."""

from __future__ import annotations

from .._filter_records import time_savings_percent
from .._results import RunResults
from ._base import Section
from ._comparison import DOES_NOT_HOLD, HOLDS, N_STANDARD_ERRORS, paired_verdict


def markdown(results: RunResults) -> list[str]:
    """One paragraph, when the filter effect ran."""
    effect = results.filter_effect
    if effect is None:
        return []
    ours, paper = effect.measured, effect.paper
    return [
        "",
        "## The filter's effect on clustering",
        "",
        f"At {effect.setting_source}'s setting, on the test half: filtering leaves "
        f"{ours.fewer_clusters_per_sequence_percent:.1f} % fewer clusters per sequence "
        f"(paper: {paper.fewer_clusters_per_sequence_percent} %) and {ours.fewer_clusters_overall_percent:.1f} % "
        f"fewer overall (paper: {paper.fewer_clusters_overall_percent} %). {time_saving_text(effect)}",
    ]


def time_saving_text(effect):
    """The clustering time the filter saves, when the rounds tell it from the noise (the findings' rule)."""
    filtered, unfiltered, paper = effect.filtered, effect.unfiltered, effect.paper.time_saving_percent
    times = (
        f"clustering the test sequences one by one (stage 0 not counted) takes {filtered.clustering_s:.3f} s "
        f"filtered and {unfiltered.clustering_s:.3f} s unfiltered"
    )
    if filtered.clustering_times_s is None:  # results of an older version: one timing, no spread
        return f"The time saving cannot be measured from these results: {times}, timed once (paper: {paper} %)."
    savings = time_savings_percent(filtered, unfiltered)
    verdict, mean, se = paired_verdict(savings)
    times = times.replace("not counted)", f"not counted; median of {len(savings)} timing rounds)", 1)
    spread = f"{mean:+.1f} \u00b1 {N_STANDARD_ERRORS * se:.1f} % saved (mean \u00b1 {N_STANDARD_ERRORS} standard errors"
    spread += f" over the rounds; paper: {paper} %)"
    if verdict == HOLDS:
        return f"Filtering saves clustering time: {times}, {spread}."
    if verdict == DOES_NOT_HOLD:
        return f"Filtering costs clustering time here: {times}, {spread}."
    return (
        f"The time saving cannot be measured on this data: {times}, {spread}, within the timing noise of "
        f"clusterings that short."
    )


SECTION = Section("filter-effect", markdown)
