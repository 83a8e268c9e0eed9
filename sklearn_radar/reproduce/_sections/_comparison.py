"""The paper's findings, checked against this run's test V1 scores."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from .._constants import BEST_STAGE1, EXPERT
from .._results import RunResults
from ._base import Section, percent


@dataclass(frozen=True)
class Finding:
    """A claim of the paper about the experiments' V1 scores.

    Attributes
    ----------
    text : str
        The claim, as the report states it.
    numbers : tuple of int
        The experiments it compares; it is checked when all of them ran.
    holds : callable
        ``holds(v1: dict[int, float]) -> bool``.
    """

    text: str
    numbers: tuple[int, ...]
    holds: Callable[[dict[int, float]], bool]


#: The paper's findings (Section V), in the report's order.  Each names the experiments of Tables III and IV
#: that it compares, as the paper does.
FINDINGS = (
    Finding("a tuned baseline beats the expert setting (#2 > #1)", (EXPERT, 2), lambda v: v[2] > v[EXPERT]),
    Finding("FCS is at least as good as CCS (#3 >= #2)", (2, 3), lambda v: v[3] >= v[2]),
    Finding(
        "the Euclidean criteria improve on the box (#5, #6 > #3)", (3, 5, 6), lambda v: v[5] > v[3] and v[6] > v[3]
    ),
    Finding("range-adaptive N_min improves on the baseline (#7 > #3)", (3, 7), lambda v: v[7] > v[3]),
    Finding(
        "the combined method is the best stage-1 setting (#8 >= #2-#7)",
        tuple(range(2, BEST_STAGE1 + 1)),
        lambda v: v[BEST_STAGE1] >= max(v[n] for n in range(2, BEST_STAGE1)),
    ),
    Finding(
        "filtering helps the combined method (#8 > #9 and #8 > #10)",
        (BEST_STAGE1, 9, 10),
        lambda v: v[BEST_STAGE1] > v[9] and v[BEST_STAGE1] > v[10],
    ),
    Finding(
        "#8's setting transferred to the box criterion is worse (#11 < #8)",
        (BEST_STAGE1, 11),
        lambda v: v[11] < v[BEST_STAGE1],
    ),
    Finding("merging by velocity estimates hurts (#12 < #8)", (BEST_STAGE1, 12), lambda v: v[12] < v[BEST_STAGE1]),
    Finding("merging by continuation helps slightly (#13 > #8)", (BEST_STAGE1, 13), lambda v: v[13] > v[BEST_STAGE1]),
)


def markdown(results: RunResults) -> list[str]:
    """Each finding whose experiments ran: holds or not, with the scores; [] when none can be checked."""
    v1 = results.v1_test()
    checks = []
    for finding in FINDINGS:
        if all(n in v1 for n in finding.numbers):
            values = ", ".join(f"#{n} {percent(v1[n])}" for n in finding.numbers)
            verdict = "holds" if finding.holds(v1) else "does not hold"
            checks.append(f"- {finding.text}: **{verdict}** here ({values}).")
    if not checks:
        return []
    reduced = ", and this run used a reduced budget." if results.meta.budget.reduced else "."
    return [
        "",
        "## The paper's findings, checked",
        "",
        *checks,
        "",
        "Absolute V1 values differ from the paper's: the data here are simulated (see the "
        "simulator's statistics), the target is our pre-clustering of its ground truth" + reduced,
    ]


SECTION = Section("comparison", markdown)
