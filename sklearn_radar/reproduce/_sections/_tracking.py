"""Beyond the paper: the settings streamed online with a tracker, and a baseline tracker (MOTA, IDF1, HOTA)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._constants import LEARNED
from .._context import RunContext
from .._results import RunResults
from .._tracking import TrackingScores
from ._base import Section, format_params, save_figure
from ._figures import tracks_figure

#: The tracks figure's file in the output folder.
TRACKS = "tracks.png"

#: The columns of the tracking table after the setting and the ids.
COLUMNS = ("MOTA", "IDF1", "HOTA", "DetA", "AssA", "ID switches", "false positives", "misses", "object-windows")


def markdown(results: RunResults) -> list[str]:
    """The object settings and the baseline tracker, then the paper's settings; the tuned trackers; the figure."""
    step = results.tracking
    if step is None:
        return []
    window = step.baseline.scores.window_s
    settings = step.settings
    ours = [key for key in settings if not key.isdigit()]
    paper = [key for key in settings if key.isdigit()]
    lines = [
        "",
        "## Beyond the paper: object tracking online",
        "",
        "Each setting streamed scan by scan through the online pipeline (`sklearn_radar.online.OnlinePipeline`: "
        "the frame transform, the filter and stage 1 causal, stage 2 deciding each pair as soon as its data "
        "are complete) on every test sequence, with a tracker on its object ids "
        "(`sklearn_radar.online.Tracker`: a constant-velocity Kalman filter with Doppler updates, association by "
        "the clustering's own ids then the Hungarian method on the Mahalanobis distance, confirmation after "
        "`min_hits` scans, end after `max_age` s). "
        f"The ids are scored against the annotated moving road users per {window:g} s time window: "
        "a ground-truth object and an id match in a window when their detections' IoU exceeds 0.5; an ID switch "
        "is a match whose id differs from the object's previous match; MOTA = 1 - (misses + false positives + ID "
        f"switches) / object-windows (CLEAR MOT), where *object-windows* counts each annotated moving road user "
        f"once in every {window:g} s window it is seen in, over the test half's sequences (an object seen for 5 s "
        f"counts {5 / window:g}; not the objects of the data section, which counts each once over both halves); "
        "IDF1 is the F1 score of the one-to-one assignment of whole tracks (Ristani et al. 2016); HOTA the "
        "geometric mean of the detection accuracy DetA and the association accuracy AssA, averaged over IoU "
        "thresholds 0.05-0.95 (Luiten et al. 2021). *Tracker*: the tracker's ids as given at each scan (what a "
        "car sees); *object ids*: the pipeline's own ids as given at each scan, without the tracker; *final*: "
        "those ids after every later merge resolved (not causal). The baseline tracker is what a user would "
        "write: SlidingDBSCAN's clusters of each scan assigned to the tracks' last centroids by the Hungarian "
        "method within a gate in metres (no motion model, no Doppler), with the same confirmation and end rule.",
    ]
    header = "| setting | ids | " + " | ".join(COLUMNS) + " |"
    rule = "|---|---|" + "---|" * len(COLUMNS)
    if ours or step.baseline is not None:
        lines += ["", "Settings meant for objects, and the baseline tracker:", "", header, rule]
        for key in ours:
            lines += _rows(key, settings[key])
        baseline = step.baseline
        if baseline is not None:
            lines.append(
                f"| baseline: SlidingDBSCAN + nearest centroid | baseline tracker | {_cells(baseline.scores)} |"
            )
    if paper:
        lines += [
            "",
            "The paper's settings (tuned for V1, which does not count the static background: most of their "
            "clusters are static background, and each such cluster, when confirmed, is a false positive of MOTA):",
            "",
            header,
            rule,
        ]
        for key in paper:
            lines += _rows(key, settings[key])
    lines += ["", *_tuned_lines(step)]
    lines += ["", "Settings: " + "; ".join(f"{_name(k, r)}: {format_params(r.params)}" for k, r in settings.items())]
    if results.figures.drawn.get("tracks"):
        lines += ["", *tracks_caption(results), "", f"![tracks]({TRACKS})"]
    return lines


def _name(key, result):
    return f"#{key} {result.method}" if key.isdigit() else result.method


def _rows(key, result):
    name = f"{_name(key, result)} ({result.setting_source})"
    rows = []
    for ids, scores in (("Tracker", result.tracked), ("object ids", result.reported), ("final", result.final)):
        if scores is not None:
            rows.append(f"| {name} | {ids} | {_cells(scores)} |")
    return rows


def _cells(scores: TrackingScores) -> str:
    def score(value):
        return "-" if value is None else f"{value:.3f}"

    values = (scores.mota, scores.idf1, scores.hota, scores.deta, scores.assa)
    counts = (scores.id_switches, scores.false_positives, scores.misses, scores.n_objects)
    return " | ".join([*(score(v) for v in values), *(str(c) for c in counts)])


def _tuned_lines(step):
    """What the trackers were tuned on, for what, and the values chosen."""
    lines = []
    tracker = step.tracker
    if tracker is not None:
        lines.append(
            f"The Tracker's parameters were chosen on the training half, on the {tracker.tuned_on} setting's ids, "
            f"for {tracker.criterion} among {tracker.n_candidates} combinations of `min_hits`, `max_age` (s) and "
            f"`gate` (standard deviations), the others at their defaults: {_values(tracker.params)} (training "
            f"{tracker.criterion} {tracker.train_score:.3f}); every setting above but the learned grouping runs "
            "with them. `params.json` saves them under `tracker` for `sklearn-radar stream --track`."
        )
    else:
        lines.append(
            "The run has no object experiment, on whose ids the Tracker is tuned: it ran at its defaults "
            "(`--experiments objects,tracking` tunes it)."
        )
    learned = step.learned_tracker
    if learned is not None:
        lines.append(
            "The learned grouping streams its causal model (`LinkClustering(causal=True)`, fitted by the learned "
            "step on the training half), with a Tracker chosen the same way on that stream's training-half ids "
            "(in-sample: the model was fitted on that half); the Tracker follows its confirmed clusters only, those "
            f"the offline model keeps: {_values(learned.params)} (training "
            f"{learned.criterion} {learned.train_score:.3f})."
        )
    baseline = step.baseline
    if baseline is not None:
        t = baseline.tracker
        lines.append(
            f"Baseline tracker: SlidingDBSCAN ({format_params(baseline.clusterer_params)}; "
            f"{baseline.clusterer_source}), its tracker's `gate` (m), `min_hits` and `max_age` (s) chosen the same "
            f"way among {t.n_candidates}: {_values(t.params)} (training {t.criterion} {t.train_score:.3f})."
        )
    return [" ".join(lines)]


def _values(params):
    return ", ".join(f"{name}={value:g}" for name, value in params.items())


def glance_line(results: RunResults):
    """The best tracked setting (by test MOTA), the learned grouping when tracked, the baseline tracker, for "At a
    glance"; or None."""
    step = results.tracking
    tracked = {} if step is None else {k: r for k, r in step.settings.items() if r.tracked is not None}
    if not tracked:
        return None
    mota = {k: r.tracked.mota for k, r in tracked.items()}
    key = max(mota, key=lambda k: -np.inf if np.isnan(mota[k]) else mota[k])
    line = (
        f"tracking online, test half: {_name(key, tracked[key])} with the Tracker (the best by test MOTA) "
        f"{_said(tracked[key].tracked)}"
    )
    if key != LEARNED and LEARNED in tracked:
        line += f"; {_name(LEARNED, tracked[LEARNED])} (causal) with the Tracker {_said(tracked[LEARNED].tracked)}"
    if step.baseline is not None:
        line += f"; the baseline tracker (SlidingDBSCAN + nearest centroid) {_said(step.baseline.scores)}"
    return line + "; its section has the details."


def _said(scores):
    hota = "-" if scores.hota is None else f"{scores.hota:.3f}"
    return f"MOTA {scores.mota:.3f}, IDF1 {scores.idf1:.3f}, HOTA {hota}"


def lead_setting(results: RunResults):
    """``(key, result)`` of the first tracked setting (the one the figure draws), or None."""
    step = results.tracking
    if step is None or not step.settings:
        return None
    return next(iter(step.settings.items()))


def tracks_caption(results: RunResults):
    """The tracks figure's caption."""
    key, result = lead_setting(results)
    return [
        f"Tracks over one test sequence (sequence frame, x-y): left the moving road users as annotated (one colour "
        f"per object), right our tracks ({_name(key, result)} with the Tracker, one colour per track id; the two "
        "panels' colours are unrelated). Each path joins an id's centroids per 0.1 s, from a dot at its first "
        "appearance; light grey: every other detection (static background, noise, unconfirmed clusters)."
    ]


def figures(out: Path, results: RunResults, context: RunContext) -> dict[str, str]:
    """The tracks of the drawn test sequence, ground truth against ours, when the tracking step ran."""
    if results.tracking is None or not context.tracks or lead_setting(results) is None:
        return {}
    key, result = lead_setting(results)
    save_figure(tracks_figure(context, f"{_name(key, result)} with the Tracker"), out / TRACKS)
    return {"tracks": TRACKS}


SECTION = Section("tracking", markdown, figures)
