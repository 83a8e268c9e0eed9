"""Beyond the paper: the settings streamed online (causal), their object ids scored over time (IDF1, MOTA)."""

from __future__ import annotations

from .._results import RunResults
from .._tracking import TrackingScores
from ._base import Section, format_params


def markdown(results: RunResults) -> list[str]:
    """A table of the streamed settings, when the tracking step ran."""
    tracking = results.tracking
    if not tracking:
        return []
    window = next(iter(tracking.values())).final.window_s
    lines = [
        "",
        "## Beyond the paper: object tracking online",
        "",
        "Each setting streamed scan by scan through the online pipeline (`sklearn_radar.online.OnlinePipeline`: "
        "the frame transform, the filter and stage 1 causal, stage 2 deciding each pair as soon as its data "
        "are complete; its clusters equal the offline pipeline's with `causal=True`) on every test sequence. "
        f"Its object ids are scored against the annotated moving road users per {window:g} s time window "
        "(`sklearn_radar.metrics.tracking_scores`): a ground-truth object and an id match in a window when their "
        "detections' IoU exceeds 0.5; an ID switch is a match whose id differs from the object's previous match; "
        "MOTA = 1 - (misses + false positives + ID switches) / object-windows (CLEAR MOT), where *object-windows* "
        f"counts each annotated moving road user once in every {window:g} s window it is seen in, over the test "
        f"half's sequences (an object seen for 5 s counts {5 / window:g}; not the objects of the data section, "
        "which counts each once over both halves); *scans*: the test half's scans streamed; IDF1 is the F1 score "
        "of the one-to-one assignment of whole tracks (Ristani et al. 2016). 'As reported' scores the id given "
        "with each detection when its scan was labelled (what a tracker sees live); 'final' the id after every "
        "later merge (stage-1 clusters meeting, stage-2 merges) resolved to the surviving one.",
        "",
        "| setting | IDF1 final | ID switches final | MOTA final | IDF1 as reported | ID switches as reported "
        "| MOTA as reported | object-windows | scans | merges (aliases) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for number, result in sorted(tracking.items()):
        final, reported = result.final, result.reported
        lines.append(
            f"| #{number} {result.method} ({result.setting_source}) | {_scores(final)} | {_scores(reported)} | "
            f"{final.n_objects} | {result.n_scans} | {result.n_aliases} |"
        )
    lines += ["", "Settings: " + "; ".join(f"#{n}: {format_params(r.params)}" for n, r in sorted(tracking.items()))]
    return lines


def _scores(scores: TrackingScores) -> str:
    return f"{scores.idf1:.3f} | {scores.id_switches} | {scores.mota:.3f}"


SECTION = Section("tracking", markdown)
