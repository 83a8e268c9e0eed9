"""The paper's findings, checked against this run's test V1 scores."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from .._constants import BEST_STAGE1, EXPERT, PAPER_FILTER_SETTING
from .._results import FilterResult, RunResults
from ._base import Section, frame_name, percent


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


@dataclass(frozen=True)
class FilterFinding:
    """A claim of the paper about the filter (Tables I and II).

    Attributes
    ----------
    text : str
        The claim, as the report states it.
    check : callable
        ``check(filter: FilterResult) -> (holds, values) or None``: whether it
        holds and the numbers that decide it; None when the tables lack them.
    """

    text: str
    check: Callable[[FilterResult], tuple[bool, str] | None]


def _chosen_rows(f: FilterResult):
    """Table II's rows at the paper's chosen setting, by coordinate system."""
    vr, d_xy = PAPER_FILTER_SETTING
    return {row.frame: row for row in f.table_ii if abs(row.vr_threshold - vr) < 1e-9 and abs(row.d_xy - d_xy) < 1e-9}


def _chosen_without_errors(f: FilterResult):
    row = _chosen_rows(f).get("frame")
    return None if row is None else (row.errors == 0, f"ours {row.errors} errors, paper {row.paper_errors}")


def _some_cell_without_errors(f: FilterResult):
    fewest = {frame: min(v for row in grid.errors.data for v in row) for frame, grid in f.table_i.items()}
    values = ", ".join(f"fewest errors {frame_name(frame)} {count:g}" for frame, count in fewest.items())
    return any(best is not None for best in f.best_removal_with_zero_errors.values()), values


def _fcs_removes_more(f: FilterResult):
    rows = _chosen_rows(f)
    if not {"frame", "car"} <= set(rows):
        return None
    fcs, ccs = rows["frame"].removal_rate, rows["car"].removal_rate
    return fcs > ccs, f"FCS {fcs:.2f} %, CCS {ccs:.2f} %"


_VR, _D_XY = PAPER_FILTER_SETTING

#: The paper's findings about the filter (Section V-A), in the report's order.
FILTER_FINDINGS = (
    FilterFinding(
        f"the chosen filter setting (FCS, eta_1 = {_VR:.2f} m/s, d_xy = {_D_XY:.1f} m) loses no object window "
        "(Table II: 0 errors)",
        _chosen_without_errors,
    ),
    FilterFinding("some filter setting of the grid has 0 errors (Table I)", _some_cell_without_errors),
    FilterFinding("FCS removes more background than CCS at the chosen setting (Table II)", _fcs_removes_more),
)


def checked(results: RunResults):
    """Every finding that this run can check: (text, holds, the numbers that decide it), in the report's order.

    Returns
    -------
    checks : list of (str, bool, str)
    """
    v1 = results.v1_test()
    checks = []
    if results.filter is not None:
        for finding in FILTER_FINDINGS:
            outcome = finding.check(results.filter)
            if outcome is not None:
                checks.append((finding.text, *outcome))
    for finding in FINDINGS:
        if all(n in v1 for n in finding.numbers):
            values = ", ".join(f"#{n} {percent(v1[n])}" for n in finding.numbers)
            checks.append((finding.text, finding.holds(v1), values))
    return checks


def markdown(results: RunResults) -> list[str]:
    """Each finding whose experiments (or filter tables) ran: holds or not, with the numbers; [] when none can be."""
    checks = [
        f"- {text}: **{'holds' if holds else 'does not hold'}** here ({values})."
        for text, holds, values in checked(results)
    ]
    if not checks:
        return []
    reduced = ", and this run used a reduced budget." if results.meta.budget.reduced else "."
    data = (
        "(see 'The data' above)" if results.statistics is not None else "(`sklearn-radar stats` prints its statistics)"
    )
    return [
        "",
        "## The paper's findings, checked",
        "",
        *checks,
        "",
        f"Absolute values differ from the paper's: the data here are not the paper's {data}, the target is our "
        "pre-clustering of its ground truth" + reduced,
    ]


SECTION = Section("comparison", markdown)
