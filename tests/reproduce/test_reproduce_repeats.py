"""Repeated searches (``reproduce --repeats K``): the findings rule on planted values, and a tiny repeated run."""

import contextlib
import io
import json
import math
import statistics

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sklearn_radar.cli import main
from sklearn_radar.reproduce._sections._comparison import (
    CANNOT_TELL,
    DOES_NOT_HOLD,
    FINDINGS,
    HOLDS,
    combined_verdict,
    judge,
    paired_verdict,
)


def _reference(differences, strict=True):
    """The report's rule, written out with the statistics module: mean vs 2 standard errors of the mean."""
    mean = statistics.fmean(differences)
    if len(differences) == 1:  # no spread: no verdict
        return CANNOT_TELL
    se = statistics.stdev(differences) / math.sqrt(len(differences))
    if mean > 2 * se:
        return HOLDS
    if mean < -2 * se:
        return DOES_NOT_HOLD
    if se == 0:
        return DOES_NOT_HOLD if strict else HOLDS
    return CANNOT_TELL


@pytest.mark.parametrize(
    "differences, strict, expected",
    [
        ([0.010, 0.012, 0.011], True, HOLDS),  # mean 0.011, se 0.00058: far beyond the noise
        ([-0.010, -0.012, -0.011], True, DOES_NOT_HOLD),
        ([0.020, -0.010, 0.005], True, CANNOT_TELL),  # mean 0.005, se 0.0087
        ([0.004, 0.001, 0.003], True, HOLDS),  # mean 0.00267, 2 se = 0.00176
        ([0.004, 0.000, 0.003], True, CANNOT_TELL),  # mean 0.00233, 2 se = 0.00240
        ([0.0, 0.0, 0.0], True, DOES_NOT_HOLD),  # equal everywhere: not better
        ([0.0, 0.0, 0.0], False, HOLDS),  # ... but at least as good
        ([0.05], True, CANNOT_TELL),  # a single run gives no verdict, however large its difference
        ([-0.05], False, CANNOT_TELL),
        ([0.0], False, CANNOT_TELL),
    ],
)
def test_the_rule_on_planted_differences(differences, strict, expected):
    verdict, mean, se = paired_verdict(differences, strict=strict)
    assert verdict == expected == _reference(differences, strict)
    assert mean == pytest.approx(statistics.fmean(differences))
    if len(differences) > 1:
        assert se == pytest.approx(statistics.stdev(differences) / math.sqrt(len(differences)))
    else:
        assert se is None


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.floats(-0.05, 0.05, allow_nan=False, allow_subnormal=False), min_size=1, max_size=6),
    st.booleans(),
)
def test_the_rule_matches_its_statement_and_flips_with_the_sign(differences, strict):
    verdict, _, _ = paired_verdict(differences, strict=strict)
    if len(differences) == 1:
        assert verdict == CANNOT_TELL
        return
    if not any(differences):  # exactly zero is decided by strictness alone
        return
    # Away from the boundary the written-out rule decides alike (rounding can move a value exactly on it).
    mean = statistics.fmean(differences)
    se = statistics.stdev(differences) / math.sqrt(len(differences)) if len(differences) > 1 else 0.0
    if abs(abs(mean) - 2 * se) > 1e-12:
        assert verdict == _reference(differences, strict)
    flipped, _, _ = paired_verdict([-d for d in differences], strict=strict)
    swap = {HOLDS: DOES_NOT_HOLD, DOES_NOT_HOLD: HOLDS, CANNOT_TELL: CANNOT_TELL}
    if abs(abs(mean) - 2 * se) > 1e-12:
        assert flipped == swap[verdict]


def test_the_rule_rejects_no_values():
    with pytest.raises(ValueError, match="differences"):
        paired_verdict([])
    with pytest.raises(ValueError, match="differences"):
        paired_verdict([0.1, float("nan")])


def test_a_finding_of_several_comparisons_needs_all_of_them():
    assert combined_verdict([HOLDS, HOLDS]) == HOLDS
    assert combined_verdict([HOLDS, CANNOT_TELL]) == CANNOT_TELL
    assert combined_verdict([CANNOT_TELL, DOES_NOT_HOLD, HOLDS]) == DOES_NOT_HOLD


def _finding(text):
    return next(f for f in FINDINGS if f.text.startswith(text))


def test_findings_are_judged_on_paired_differences_not_on_the_spread_of_each_experiment():
    rng = np.random.default_rng(0)
    seed_effect = rng.normal(0.0, 0.01, 5)  # each repeat's seed moves both experiments alike (1 point)
    v8 = 0.71 + seed_effect
    planted = {
        8: v8,
        13: v8 + 0.0024 + rng.normal(0, 0.0002, 5),  # +0.24 points: inside each one's spread, clear when paired
        12: v8 - 0.01 + rng.normal(0, 0.0002, 5),  # -1 point: #12 < #8, as the paper says
        11: v8 + rng.normal(0, 0.01, 5),  # no planted difference, noise as large as the seeds'
    }
    scores = {number: list(values) for number, values in planted.items()}
    assert np.std(scores[13]) > 0.0024  # unpaired, the difference would drown in the seeds' noise
    verdict, values = judge(_finding("merging by continuation"), scores)
    assert verdict == HOLDS and values.startswith("#13 \u2212 #8 +0.2")
    assert judge(_finding("merging by velocity"), scores)[0] == HOLDS
    assert judge(_finding("#8's setting transferred"), scores)[0] == CANNOT_TELL
    scores[13] = list(v8 - 0.0024)  # planted the other way
    assert judge(_finding("merging by continuation"), scores)[0] == DOES_NOT_HOLD


def test_the_fixed_expert_setting_counts_the_same_in_every_repeat_and_a_single_run_cannot_tell():
    finding = _finding("a tuned baseline beats the expert")
    assert judge(finding, {1: [0.70], 2: [0.72, 0.73, 0.71]})[0] == HOLDS  # +2 points, se 0.58
    assert judge(finding, {1: [0.70], 2: [0.69, 0.73, 0.71]})[0] == CANNOT_TELL  # +1 point, se 1.15
    verdict, values = judge(finding, {1: [0.70], 2: [0.7501]})  # 5 points, but a single run
    assert verdict == CANNOT_TELL and values == "#1 70.00 %, #2 75.01 %, #2 \u2212 #1 +5.01 points"
    with pytest.raises(ValueError, match="cannot be paired"):
        judge(finding, {1: [0.70, 0.71], 2: [0.72, 0.73, 0.71]})


def test_the_convergence_band_spans_the_repeats():
    from sklearn_radar.reproduce._sections._figures import best_so_far

    median, low, high = best_so_far([[0.1, 0.3, 0.2], [0.2, 0.1, 0.5], [0.0, 0.4, 0.1]])
    # best so far: [0.1, 0.3, 0.3], [0.2, 0.2, 0.5], [0.0, 0.4, 0.4]
    assert median.tolist() == [0.1, 0.3, 0.4]
    assert low.tolist() == [0.0, 0.2, 0.3] and high.tolist() == [0.2, 0.4, 0.5]


def test_the_progress_counts_each_repeated_step_once_per_repeat():
    from sklearn_radar.reproduce._budget import Budget
    from sklearn_radar.reproduce._steps import units

    def _repeated(key, repeats):
        return units(key, Budget.default(), repeats) / units(key, Budget.default(), 1)

    assert [_repeated(key, 3) for key in ("filter", "1", "2", "8", "10", "11", "13", "filter-effect", "baselines")] == [
        1,
        1,
        3,
        3,
        3,
        3,
        3,
        1,
        3,
    ]


def test_repeats_below_one_are_a_one_line_error(capsys):
    assert main(["reproduce", "--repeats", "0"]) == 2  # a usage error
    err = capsys.readouterr().err
    assert "--repeats" in err and len(err.strip().splitlines()) == 1


@pytest.fixture(scope="module")
def repeated_report(tiny_folder, tmp_path_factory):
    out = tmp_path_factory.mktemp("report") / "out"
    argv = ["reproduce", "--data", str(tiny_folder), "--out", str(out), "--n-iter", "2", "--repeats", "2"]
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        assert main([*argv, "--experiments", "1,2,8,13", "--n-jobs", "2"]) == 0
    return out


def test_a_repeated_run_records_every_repeat_and_reports_mean_sd_and_the_rule(repeated_report):
    from sklearn_radar.reproduce._results import RunResults

    text = (repeated_report / "results.json").read_text()
    document = json.loads(text)
    assert document["meta"]["repeats"] == 2
    experiments = document["experiments"]
    assert "repeats" not in experiments["1"]  # the fixed expert setting has no seed
    for key in ("2", "8", "13"):
        record = experiments[key]
        repeats = record["repeats"]
        assert [r["seed"] for r in repeats] == [0, 1]
        assert all(len(r["convergence"]) == 2 and 0 <= r["v1_test"] <= 1 for r in repeats)
        # The record's own values are those of the first repeat (the run's seed).
        assert (record["v1_test"], record["params"], record["convergence"]) == (
            repeats[0]["v1_test"],
            repeats[0]["params"],
            repeats[0]["convergence"],
        )
    assert json.dumps(RunResults.from_json_dict(document).to_json_dict(), indent=1) == text

    report = (repeated_report / "report.md").read_text()
    assert "searched 2 times, with the seeds 0-1" in report
    row = next(line for line in report.splitlines() if line.startswith("| 8 |"))
    v1 = [100 * r["v1_test"] for r in experiments["8"]["repeats"]]
    assert f"{np.mean(v1):.2f} \u00b1 {np.std(v1, ddof=1):.2f} %" in row
    findings = report.split("## The paper's findings, checked", 1)[1]
    assert "exceeds 2 standard errors" in findings
    # Each verdict is the rule applied to the paired differences that results.json holds.
    scores = {int(k): [r["v1_test"] for r in e.get("repeats", [e])] for k, e in experiments.items()}
    for text, a, b in (("(#2 > #1)", 2, 1), ("(#13 > #8)", 13, 8)):
        line = next(line for line in findings.splitlines() if text in line)
        differences = [x - y for x, y in zip(scores[a], scores[b] * (2 if len(scores[b]) == 1 else 1), strict=True)]
        assert f"**{_reference(differences)}** here" in line
        mean = 100 * statistics.fmean(differences)
        assert f"#{a} \u2212 #{b} {mean:+.2f} \u00b1 " in line
    assert (repeated_report / "convergence.png").is_file()
    assert "the median over the repeats" in report and "error bars one standard deviation" in report


def test_repeats_run_one_after_the_other_give_what_concurrent_repeats_give(repeated_report, tiny_folder, tmp_path):
    # The fixture ran the repeats concurrently (--n-jobs 2); one at a time they have the same seeds and results.
    from sklearn_radar.reproduce import reproduce

    document = reproduce(tiny_folder, tmp_path / "out", n_iter=2, experiments="2", repeats=2, stream=io.StringIO())
    concurrent = json.loads((repeated_report / "results.json").read_text())["experiments"]["2"]["repeats"]
    sequential = document["experiments"]["2"]["repeats"]
    for key in ("seed", "params", "v1_test", "convergence", "cv_best"):
        assert [r[key] for r in sequential] == [r[key] for r in concurrent], key
