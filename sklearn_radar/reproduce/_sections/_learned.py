"""Beyond the paper: the learned grouping beside the object experiment and the strongest baseline, and where each
loses panoptic quality (the error anatomy)."""

from __future__ import annotations

from ...experiments._baselines import SLIDING_BASELINE
from .._results import RunResults
from ._base import Section, format_params, values_cell

#: The error anatomy's columns: (field of InstanceErrors, header).
ERROR_COLUMNS = (
    ("n_true", "GT segments"),
    ("missed", "missed"),
    ("noise", "as noise"),
    ("split", "split"),
    ("merged_with_object", "merged w/ object"),
    ("merged_with_background", "merged w/ background"),
    ("false", "false segments"),
    ("background", "background only"),
    ("part_of_object", "part of one object"),
    ("several_objects", "several objects"),
)


def markdown(results: RunResults) -> list[str]:
    """The learned grouping's test scores and the error anatomy of the settings it is set beside."""
    learned = results.learned
    if learned is None:
        return []
    link = {k: v for k, v in learned.params.items() if k.startswith("link__")}
    lines = [
        "",
        "### The learned grouping",
        "",
        "The learned grouping is the object experiment's front (FCS and the Doppler-density filter at the paper's "
        "setting) followed by `LinkClustering`: a gradient-boosting classifier of each detection's objectness and "
        "one of pairs of neighbouring detections (same road user or not), their links joined by mean-link "
        "agglomeration. It is fitted once, with the run's seed, on the training half's pre-clustered instances (the "
        "target the object-level scores use), its three thresholds tuned inside the fit for PQ on out-of-fold "
        "predictions of the training half; the fitted model, saved as "
        f"`{learned.model_file}`, labels the test half. "
        f"Tuned: link threshold {learned.link_threshold:.2f}, objectness threshold "
        f"{learned.objectness_threshold:.2f}, minimum cluster size {learned.min_cluster_size} (out-of-fold PQ "
        f"{learned.cv_pq:.3f}); fitted in {learned.fit_wall_time_s:.1f} s on "
        f"{learned.n_training_pairs:,} candidate pairs; {format_params(link)}.",
        "",
        "| setting | decides from | PQ (test) | recall | precision | V1 (test) |",
        "|---|---|---|---|---|---|",
        _row("learned grouping", learned.instance_test, learned.v1_test),
    ]
    if results.objects is not None:
        kept = results.objects.kept
        lines.append(_row("object experiment", kept.instance_test, kept.v1_test, repeat=results.objects.repeats))
    for name, baseline in (results.baselines or {}).items():
        if name in learned.errors and baseline.instance_test is not None:
            tuned = f", tuned for {results.meta.objective.upper()}"
            lines.append(_row(name + tuned, baseline.instance_test, baseline.v1_test, repeat=baseline.repeats))
    lines += _causal_rows(results)
    lines += [
        "",
        "Where each setting loses PQ on the test half (segments: one object, or one cluster, per 0.5 s window of a "
        "sequence; a ground-truth segment is missed when no cluster matches it with IoU > 0.5, as noise when more "
        "than half of it is noise, merged when one cluster holds more than half of it with another object's or "
        "background detections, split otherwise; a cluster's segment is false when it matches none). The object "
        "experiment and the baseline are their steps' kept settings (the first repeat), labelled again here; the "
        f"baseline is the offline one with the highest cross-validated {results.meta.objective.upper()} on the "
        "training half.",
        "",
        "| setting | " + " | ".join(header for _, header in ERROR_COLUMNS) + " | median size matched / missed |",
        "|---|" + "---|" * (len(ERROR_COLUMNS) + 1),
    ]
    for name, errors in learned.errors.items():
        cells = [str(getattr(errors, field)) for field, _ in ERROR_COLUMNS]
        sizes = f"{errors.median_size_matched:.0f} / {errors.median_size_missed:.0f}"
        lines.append(f"| {name} | " + " | ".join(cells) + f" | {sizes} |")
    return lines


def glance_line(results: RunResults):
    """The learned grouping's test PQ and missed segments beside those it is compared with, for "At a glance"."""
    learned = results.learned
    if learned is None:
        return None
    others = {name: errors for name, errors in learned.errors.items() if name != "learned grouping"}
    scores = {"object experiment": results.objects.kept.instance_test.pq} if results.objects is not None else {}
    for name, baseline in (results.baselines or {}).items():
        if name in others and baseline.instance_test is not None:
            scores[name] = baseline.instance_test.pq
    against = " and ".join(
        f"{pq:.3f} for the {name}" if name == "object experiment" else f"{pq:.3f} for {name}"
        for name, pq in scores.items()
    )
    pq = learned.instance_test.pq
    line = f"the learned grouping (fitted on the training half's labels): test PQ {pq:.3f} offline"
    if against:
        line += f" against {against}"
    if learned.causal is not None:
        line += f", {learned.causal.instance_test.pq:.3f} causal"
        if results.objects is not None:
            line += f" against {results.objects.kept.causal_instance_test.pq:.3f} for the object experiment causal"
    line += " (one fit, one seed: no verdict)"
    own = learned.errors.get("learned grouping")
    if own is not None:
        line += f"; missed ground-truth segments {own.missed}"
        if others:
            line += " against " + " and ".join(str(errors.missed) for errors in others.values()) + " in that order"
    return line + "; its section has the details."


def _causal_rows(results):
    """The causal learned grouping's row, and those of the causal settings the run has (object experiment, sliding
    baseline); with the paragraph that says how it was fitted."""
    causal = results.learned.causal
    if causal is None:
        return ["", "This run fitted no causal learned grouping (a run of an older version): offline only."]
    rows = [_row("learned grouping, causal", causal.instance_test, causal.v1_test, decides="past only")]
    if results.objects is not None:
        kept = results.objects.kept
        rows.append(
            _row(
                "object experiment, causal",
                kept.causal_instance_test,
                kept.causal_v1_test,
                repeat=results.objects.repeats,
                decides="past only",
            )
        )
    sliding = (results.baselines or {}).get(SLIDING_BASELINE)
    if sliding is not None and sliding.instance_test is not None:
        name = f"{SLIDING_BASELINE}, tuned for {results.meta.objective.upper()}"
        rows.append(_row(name, sliding.instance_test, sliding.v1_test, repeat=sliding.repeats, decides="past only"))
    offline = results.learned.params
    changed = {  # the causal model's link settings that differ from the offline model's (listed above)
        k: v for k, v in causal.params.items() if k.startswith("link__") and offline.get(k) != v
    }
    return [
        *rows,
        "",
        "The causal learned grouping (`LinkClustering(causal=True)`, saved as "
        f"`{causal.model_file}`, what `sklearn-radar stream --experiment learned` runs scan by scan) is fitted on "
        "the same training half from features of the past only, its thresholds tuned with the causal "
        "agglomeration (each time's new detections join the clusters so far; the minimum size confirms a detection "
        "at its time); its test labels are the stream's final ids. Tuned: link threshold "
        f"{causal.link_threshold:.2f}, objectness threshold {causal.objectness_threshold:.2f}, minimum cluster size "
        f"{causal.min_cluster_size} (out-of-fold PQ {causal.cv_pq:.3f}); fitted in {causal.fit_wall_time_s:.1f} s"
        + (f"; its settings unlike the offline model's: {format_params(changed)}" if changed else "")
        + (
            f" (with cluster_window, each pair's link also sees the cluster its earlier detection already belongs to, "
            f"over the last {changed['link__cluster_window']:g} s)."
            if changed.get("link__cluster_window") is not None
            else "."
        ),
    ]


def _row(name, scores, v1, repeat=None, decides="past and future"):
    first = " (first repeat)" if repeat else ""
    return (
        f"| {name}{first} | {decides} | {values_cell([scores.pq], 'pq')} | {scores.recall:.3f} | "
        f"{scores.precision:.3f} | {values_cell([v1])} |"
    )


SECTION = Section("learned", markdown)
