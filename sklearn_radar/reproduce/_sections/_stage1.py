"""Table III: the point-clustering experiments (#1-#11), ours beside the paper's."""

from __future__ import annotations

from .._results import RunResults
from ._base import Section, experiment_table


def markdown(results: RunResults) -> list[str]:
    """Table III, for the stage-1 experiments that ran."""
    rows = [e for e in results.experiments.values() if e.stage == 1]
    return experiment_table("Point clustering (Table III)", rows, results) if rows else []


SECTION = Section("stage-1", markdown)
