"""The paper's findings, checked against this run's test V1 scores."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .._constants import BEST_STAGE1, EXPERT, PAPER_FILTER_SETTING
from .._experiment_records import repeated_scores
from .._filter_records import FilterResult
from .._results import RunResults
from ._base import Section, frame_name, percent

#: The verdicts of a finding.
HOLDS, DOES_NOT_HOLD, CANNOT_TELL = "holds", "does not hold", "cannot tell"

#: A difference is beyond the noise when it exceeds this many standard errors of its mean.
N_STANDARD_ERRORS = 2

#: How large the noise of a single search is, measured on the default run's data (user guide, "Repeats: findings
#: beyond the noise"): what a single run of the experiments would have to exceed, and cannot measure itself.
SINGLE_RUN_NOISE = (
    "On the default run's data, three searches of each experiment (`--repeats 3`, seeds 0-2) moved test V1 by a "
    "standard deviation of 0.4 to 4.3 points per tuned stage-1 experiment, and a paired difference had to exceed "
    "0.2 to 6.4 points (2 standard errors over the three) to tell; one run cannot measure its own noise."
)


def paired_verdict(differences, *, strict=True):
    """The verdict on a claim that a difference of test scores is positive, from its values over repeats.

    The rule of the report, the only place it is decided: with ``d_k`` the
    paired difference of repeat ``k`` (the same repeat seed and split for
    both), ``K >= 2`` repeats, mean ``m`` and standard error
    ``se = sd(d, ddof=1) / sqrt(K)``, the claim *holds* when ``m > 2 se``
    and *does not hold* when ``m < -2 se``; otherwise the run *cannot tell*
    (the difference would have to exceed ``2 se`` either way).  Without any
    spread (``se = 0``, e.g. two settings that label alike in every repeat)
    a zero difference holds a non-strict claim (``>=``) and not a strict
    one (``>``).  A single run (K = 1) has no spread to measure the noise
    by: it *cannot tell*, whatever its one difference.

    Parameters
    ----------
    differences : array-like of float
        Paired differences, one per repeat, signed so that the claim says they are positive.
    strict : bool, default=True
        A strict claim (``>``) or not (``>=``).

    Returns
    -------
    verdict : {"holds", "does not hold", "cannot tell"}
    mean : float
        Mean difference.
    se : float or None
        Its standard error; None for a single run.
    """
    d = np.asarray(differences, dtype=float)
    if d.ndim != 1 or len(d) == 0 or not np.isfinite(d).all():
        raise ValueError(f"differences must be a non-empty list of finite numbers, got {differences!r}")
    mean = float(d.mean())
    if len(d) == 1:
        return CANNOT_TELL, mean, None
    se = float(d.std(ddof=1) / np.sqrt(len(d)))
    noise = N_STANDARD_ERRORS * se
    if mean > noise:
        return HOLDS, mean, se
    if mean < -noise:
        return DOES_NOT_HOLD, mean, se
    if noise == 0.0:  # no difference at all, and no spread
        return (DOES_NOT_HOLD if strict else HOLDS), mean, se
    return CANNOT_TELL, mean, se


def combined_verdict(verdicts):
    """A finding of several comparisons: holds when all hold, does not when one does not, else cannot tell."""
    verdicts = list(verdicts)
    if all(v == HOLDS for v in verdicts):
        return HOLDS
    return DOES_NOT_HOLD if DOES_NOT_HOLD in verdicts else CANNOT_TELL


@dataclass(frozen=True)
class Finding:
    """A claim of the paper about the experiments' V1 scores.

    Attributes
    ----------
    text : str
        The claim, as the report states it.
    claims : tuple of (int, int, bool)
        ``(a, b, strict)``: the claim that #a scores above #b (``strict``)
        or at least as well; the finding is all of them.
    """

    text: str
    claims: tuple[tuple[int, int, bool], ...]

    @property
    def numbers(self):
        """tuple of int : The experiments it compares, in increasing order; it is checked when all of them ran."""
        return tuple(sorted({n for a, b, _ in self.claims for n in (a, b)}))


#: The paper's findings (Section V), in the report's order.  Each names the experiments of Tables III and IV
#: that it compares, as the paper does.
FINDINGS = (
    Finding("a tuned baseline beats the expert setting (#2 > #1)", ((2, EXPERT, True),)),
    Finding("FCS is at least as good as CCS (#3 >= #2)", ((3, 2, False),)),
    Finding("the Euclidean criteria improve on the box (#5, #6 > #3)", ((5, 3, True), (6, 3, True))),
    Finding("range-adaptive N_min improves on the baseline (#7 > #3)", ((7, 3, True),)),
    Finding(
        "the combined method is the best stage-1 setting (#8 >= #2-#7)",
        tuple((BEST_STAGE1, n, False) for n in range(2, BEST_STAGE1)),
    ),
    Finding(
        "filtering helps the combined method (#8 > #9 and #8 > #10)",
        ((BEST_STAGE1, 9, True), (BEST_STAGE1, 10, True)),
    ),
    Finding("#8's setting transferred to the box criterion is worse (#11 < #8)", ((BEST_STAGE1, 11, True),)),
    Finding("merging by velocity estimates hurts (#12 < #8)", ((BEST_STAGE1, 12, True),)),
    Finding("merging by continuation helps slightly (#13 > #8)", ((13, BEST_STAGE1, True),)),
)


def _paired(scores, a, b):
    """Per-repeat differences #a - #b; a setting without repeats (the fixed #1) counts the same in each."""
    x, y = np.asarray(scores[a]), np.asarray(scores[b])
    if len(x) != len(y) and 1 not in (len(x), len(y)):
        raise ValueError(f"#{a} has {len(x)} repeats and #{b} {len(y)}: they cannot be paired")
    return x - y


def judge(finding: Finding, scores):
    """``(verdict, values)`` of ``finding`` from the per-repeat test V1 ``scores`` by experiment number."""
    verdicts, shown = [], []
    single = all(len(scores[n]) == 1 for n in finding.numbers)
    for a, b, strict in finding.claims:
        verdict, mean, se = paired_verdict(_paired(scores, a, b), strict=strict)
        verdicts.append(verdict)
        if not single:
            shown.append(f"#{a} \u2212 #{b} {_points(mean)} \u00b1 {100 * N_STANDARD_ERRORS * se:.2f} points")
    if single:
        shown = [f"#{n} {percent(scores[n][0])}" for n in finding.numbers]
        if len(finding.claims) == 1:
            ((a, b, _),) = finding.claims
            shown.append(f"#{a} \u2212 #{b} {_points(scores[a][0] - scores[b][0])} points")
    return combined_verdict(verdicts), ", ".join(shown)


def _points(difference):
    """A difference of scores 0-1 in signed percentage points, ``"+0.24"``; never ``"-0.00"``."""
    return f"{round(100 * difference, 2) + 0.0:+.2f}"


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


#: The texts of the filter's findings, which no search and no seed decide.
FILTER_TEXTS = frozenset(finding.text for finding in FILTER_FINDINGS)


def checked(results: RunResults):
    """``[(text, verdict, values)]`` of every finding this run can check, in the report's order."""
    scores = {number: repeated_scores(result) for number, result in results.experiments.items()}
    checks = []
    if results.filter is not None:
        for finding in FILTER_FINDINGS:
            outcome = finding.check(results.filter)
            if outcome is not None:
                holds, values = outcome
                checks.append((finding.text, HOLDS if holds else DOES_NOT_HOLD, values))
    for finding in FINDINGS:
        if all(n in scores for n in finding.numbers):
            checks.append((finding.text, *judge(finding, scores)))
    return checks


def markdown(results: RunResults) -> list[str]:
    """Each finding whose experiments (or filter tables) ran, its verdict with the numbers, and the rule."""
    checks = checked(results)
    if not checks:
        return []
    repeats = results.meta.repeats
    single = "here" if repeats > 1 else "from this single run"
    lines = [
        f"- {text}: **{verdict}** {'here' if text in FILTER_TEXTS else single} ({values})."
        for text, verdict, values in checks
    ]
    reduced = ", and this run used a reduced budget." if results.meta.budget.reduced else "."
    data = (
        "(see 'The data' above)" if results.statistics is not None else "(`sklearn-radar stats` prints its statistics)"
    )
    if repeats > 1:
        rule = (
            f"The rule: each experiment was searched {repeats} times, with the seeds {results.meta.seed}-"
            f"{results.meta.seed + repeats - 1} on the same split, and a comparison uses the paired differences of "
            "test V1 over the repeats (repeat k of one experiment against repeat k of the other; the fixed #1 is "
            "the same in every repeat). A finding **holds** when the mean difference has the paper's sign and "
            f"exceeds {N_STANDARD_ERRORS} standard errors of the mean, **does not hold** when it has the opposite "
            f"sign beyond {N_STANDARD_ERRORS} standard errors, and the run **cannot tell** otherwise; a finding of "
            "several comparisons holds when all hold. The numbers are the mean differences in percentage points "
            f"\u00b1 {N_STANDARD_ERRORS} standard errors: the margin a difference has to exceed to tell. The "
            "filter's findings come from fixed tables: no search, no seed."
        )
    else:
        rule = (
            "The rule: this is a single run (`--repeats 1`), one search per experiment, and a single search's "
            "random start moves its test V1 by more than most of these differences, so a single run gives no "
            f"verdict about the experiments: each **cannot tell**. {SINGLE_RUN_NOISE} `--repeats 3` searches each "
            "experiment with 3 seeds and calls a finding holding (or not) only when the mean paired difference "
            f"exceeds {N_STANDARD_ERRORS} standard errors of the repeats. The filter's findings come from fixed "
            "tables: no search, no seed."
        )
    return [
        "",
        "## The paper's findings, checked",
        "",
        *lines,
        "",
        rule,
        "",
        f"Absolute values differ from the paper's: the data here are not the paper's {data}, the target is our "
        "pre-clustering of its ground truth" + reduced,
    ]


SECTION = Section("comparison", markdown)
