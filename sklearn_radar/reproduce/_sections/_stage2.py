"""Table IV: the cluster-merging experiments (#12, #13), ours beside the paper's, their stage-1 setting and merges."""

from __future__ import annotations

from .._constants import BEST_STAGE1, STAGE2
from .._results import RunResults
from ._base import Section, experiment_table, format_params, percent


def markdown(results: RunResults) -> list[str]:
    """Table IV, for the stage-2 experiments that ran, the stage-1 setting they merged and what merging did."""
    rows = sorted((e for e in results.experiments.values() if e.stage == 2), key=lambda e: e.number)
    if not rows:
        return []
    base = results.experiments.get(BEST_STAGE1)
    names = " and ".join(f"#{n}" for n in STAGE2)
    alone = f" (#{BEST_STAGE1} scores {percent(base.v1_test)} alone)" if base else ""
    lines = [
        *experiment_table("Cluster merging (Table IV)", rows, results, stage2=True),
        "",
        f"Stage 1 of {names}: {format_params(rows[0].stage1_params)}{alone}",
    ]
    for e in rows:
        if e.n_merges_test is None:
            continue
        if e.n_merges_test == 0:
            same_as_base = base is not None and e.stage1_params == _stage1_part(base.params)
            equal = f"#{BEST_STAGE1}'s to every decimal" if same_as_base else "those of its stage-1 setting alone"
            lines += [
                "",
                f"#{e.number} merged no pair of stage-1 clusters on the test half: its clustering is its stage-1 "
                f"input, unchanged, so its scores equal {equal}.",
            ]
        else:
            lines += [
                "",
                f"#{e.number} merged {e.n_merges_test:,} pairs of stage-1 clusters on the test half: "
                f"{e.n_stage1_clusters_test:,} stage-1 clusters became {e.n_clusters_test:,}.",
            ]
    return lines


def _stage1_part(params):
    return {key: value for key, value in params.items() if key.startswith("cluster__")}


SECTION = Section("stage-2", markdown)
