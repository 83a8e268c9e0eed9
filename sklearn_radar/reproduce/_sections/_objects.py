"""Beyond the paper: the object experiment against the strongest scikit-learn baseline, offline and causally."""

from __future__ import annotations

import numpy as np

from .._experiment_records import repeated_scores
from .._results import RunResults
from ._base import Section, format_params, values_cell
from ._comparison import DOES_NOT_HOLD, HOLDS, N_STANDARD_ERRORS, paired_verdict

#: Baselines that decide from the past only, set beside the object experiment's causal run.
CAUSAL_MARK = "sliding past window"


def markdown(results: RunResults) -> list[str]:
    """The object experiment's scores beside the best offline and the best causal baseline, and their difference."""
    objects = results.objects
    if objects is None:
        return []
    kept = objects.kept
    offline_pq = [r.instance_test.pq for r in objects.every_repeat]
    causal_pq = [r.causal_instance_test.pq for r in objects.every_repeat]
    lines = [
        "",
        "## Beyond the paper: the framework set up for objects",
        "",
        "The object experiment is the paper's #12 on #8 (FCS, the Doppler-density filter at 0.10 m/s and 1.4 m, "
        "Eq. 5 with N_min(r) and eps_t = 0.25 s, then Eq. 6 velocity merging) with a tuned minimum cluster size "
        "(causally: a cluster is confirmed once it has that many detections): the object-level "
        "ablation (`benchmarks/ablation_object_level.py`, user guide 'Counting objects') found no change of the "
        "framework's stage-1 choices that raises panoptic quality beyond the noise, and dropping small merged "
        "clusters the one change that did. It is tuned for PQ, whatever "
        "the run's objective, in two "
        "searches (stage 1, then stage 2 on it) of the run's budget each, and the kept setting is scored on the "
        "test half offline and causally (every stage deciding from the past only, as a car must). "
        f"Stage 1: {format_params(kept.stage1_params)}; stage 2: {format_params(kept.params)}.",
        "",
        "| setting | decides from | tuned for | PQ (test) | V1 (test) |",
        "|---|---|---|---|---|",
        _row("object experiment", "past and future", "PQ", offline_pq, kept.v1_test),
    ]
    offline, causal = _best_baselines(results) if comparable(results) else (None, None)
    if offline is not None:
        lines.append(_row(offline[0], "past and future", "PQ", repeated_scores(offline[1], "pq"), offline[1].v1_test))
    lines.append(_row("object experiment, causal", "the past", "PQ", causal_pq, kept.causal_v1_test))
    if causal is not None:
        lines.append(_row(causal[0], "the past", "PQ", repeated_scores(causal[1], "pq"), causal[1].v1_test))
    lines.append("")
    for mode, ours, baseline in (("Offline", offline_pq, offline), ("Causally", causal_pq, causal)):
        if baseline is not None:
            lines.append(f"- {mode}: " + verdict(ours, repeated_scores(baseline[1], "pq"), baseline[0]))
    if results.baselines and not comparable(results):
        lines.append(NOT_COMPARED)
    elif offline is None and causal is None:
        lines.append("The baselines did not run, so there is nothing to compare with (`--experiments ...,baselines`).")
    return lines


def verdict(ours, theirs, name):
    """What the paired PQ differences (repeat k against repeat k) say, by :func:`~._comparison.paired_verdict`."""
    n = min(len(ours), len(theirs))
    differences = np.asarray(ours[:n], dtype=np.float64) - np.asarray(theirs[:n], dtype=np.float64)
    said, mean, se = paired_verdict(differences)
    if se is None:
        return (
            f"PQ {mean:+.3f} against {name} in one run: one run cannot tell a difference from the seed-to-seed "
            "spread; run with `--repeats 5` for a verdict."
        )
    words = {HOLDS: "higher", DOES_NOT_HOLD: "lower"}.get(said, "cannot tell (within the noise)")
    return (
        f"PQ {mean:+.3f} \u00b1 {se:.3f} (mean paired difference \u00b1 standard error, {n} repeats; it counts beyond "
        f"{N_STANDARD_ERRORS:g} standard errors) against {name}: {words}."
    )


def glance_line(results: RunResults):
    """The object experiment's PQ offline and causally beside the best baselines', for "At a glance"; or None."""
    objects = results.objects
    if objects is None:
        return None
    ours = {
        "offline": [r.instance_test.pq for r in objects.every_repeat],
        "causally": [r.causal_instance_test.pq for r in objects.every_repeat],
    }
    baselines = _best_baselines(results) if comparable(results) else (None, None)
    parts = []
    for (mode, pq), baseline in zip(ours.items(), baselines, strict=True):
        part = f"{values_cell(pq, 'pq')} {mode}"
        if baseline is not None:
            theirs = repeated_scores(baseline[1], "pq")
            part += f" against {values_cell(theirs, 'pq')} for {baseline[0]}, also tuned for PQ ({_said(pq, theirs)})"
        parts.append(part)
    apart = (
        " (not set beside the baselines, which this run tuned for V1: `--objective pq` compares them)"
        if results.baselines and not comparable(results)
        else ""
    )
    return (
        f"the framework set up for objects, tuned for PQ: test PQ {'; '.join(parts)}{apart}; its section has the "
        "details."
    )


def _said(ours, theirs):
    """The paired verdict on "ours is higher" in a few words: one run gives none."""
    n = min(len(ours), len(theirs))
    if n < 2:
        return "one run: no verdict"
    said = paired_verdict(np.subtract(ours[:n], theirs[:n]))[0]
    where = {HOLDS: "higher", DOES_NOT_HOLD: "lower"}.get(said)
    if where is None:
        return f"{n} repeats: within the noise"
    return f"{n} repeats: {where} beyond {N_STANDARD_ERRORS:g} standard errors"


def _best_baselines(results: RunResults):
    """``(name, result)`` of the offline and of the causal baseline with the best cross-validated score, or Nones."""
    scored = {name: result for name, result in (results.baselines or {}).items() if result.instance_test is not None}
    best = {}
    for causal in (False, True):
        named = [(name, r) for name, r in scored.items() if (CAUSAL_MARK in name) == causal]
        best[causal] = max(named, key=lambda item: item[1].search.cv_best, default=None)
    return best[False], best[True]


def comparable(results: RunResults):
    """Whether the run's baselines were tuned for PQ, as the object experiment: only then are they set beside it."""
    return results.meta.objective == "pq"


#: Why a run tuned for V1 does not set its baselines beside the object experiment.
NOT_COMPARED = (
    "The baselines of this run were tuned for V1, the run's objective, and the object experiment for PQ: their PQ "
    "is not set beside its PQ here, as a comparison would favour the setting tuned for the score compared (their "
    "scores are in the object-level table). `--objective pq` tunes both for PQ and compares them."
)


def _row(name, decides_from, objective, pq, v1):
    return f"| {name} | {decides_from} | {objective} | {values_cell(pq, 'pq')} | {values_cell([v1])} |"


SECTION = Section("objects", markdown)
