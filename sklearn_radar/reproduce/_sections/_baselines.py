"""Beyond the paper: the scikit-learn clusterers a user would otherwise pick, tuned and scored the same way."""

from __future__ import annotations

from .._results import RunResults
from ._base import Section, format_params, percent


def markdown(results: RunResults) -> list[str]:
    """One row per baseline, when the baselines ran."""
    if not results.baselines:
        return []
    lines = [
        "",
        "## Beyond the paper: the clusterers a user would otherwise pick",
        "",
        "Same FCS + filter input, same budget and split.",
        "",
        "| clusterer | V1 (test) | parameters | wall time |",
        "|---|---|---|---|",
    ]
    for name, result in results.baselines.items():
        lines.append(
            f"| {name} | {percent(result.v1_test)} | {format_params(result.params)} | {result.wall_time_s:.0f} s |"
        )
    return lines


SECTION = Section("baselines", markdown)
