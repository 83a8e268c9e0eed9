"""Table IV: the cluster-merging experiments (#12, #13), ours beside the paper's, and their stage-1 setting."""

from __future__ import annotations

from .._constants import BEST_STAGE1, STAGE2
from .._results import RunResults
from ._base import Section, experiment_table, format_params, percent


def markdown(results: RunResults) -> list[str]:
    """Table IV, for the stage-2 experiments that ran, and the stage-1 setting they merged."""
    rows = [e for e in results.experiments.values() if e.stage == 2]
    if not rows:
        return []
    base = results.experiments.get(BEST_STAGE1)
    names = " and ".join(f"#{n}" for n in STAGE2)
    alone = f" (#{BEST_STAGE1} scores {percent(base.v1_test)} alone)" if base else ""
    return [
        *experiment_table("Cluster merging (Table IV)", rows),
        "",
        f"Stage 1 of {names}: {format_params(rows[0].stage1_params)}{alone}",
    ]


SECTION = Section("stage-2", markdown)
