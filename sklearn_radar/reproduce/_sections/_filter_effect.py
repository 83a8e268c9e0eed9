"""The filter's effect on clustering: time and clusters with and without it, ours beside the paper's."""

from __future__ import annotations

from .._results import RunResults
from ._base import Section


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
        f"At {effect.setting_source}'s setting, on the test half: clustering its sequences one by one (each "
        f"sequence's fastest of 3 runs, summed over the sequences; stage 0 not counted) takes "
        f"{effect.filtered.clustering_s:.3f} s filtered and {effect.unfiltered.clustering_s:.3f} s unfiltered "
        f"({ours.time_saving_percent:.1f} % saved; paper: {paper.time_saving_percent} %); filtering leaves "
        f"{ours.fewer_clusters_per_sequence_percent:.1f} % fewer clusters per sequence "
        f"(paper: {paper.fewer_clusters_per_sequence_percent} %) and {ours.fewer_clusters_overall_percent:.1f} % "
        f"fewer overall (paper: {paper.fewer_clusters_overall_percent} %).",
    ]


SECTION = Section("filter-effect", markdown)
