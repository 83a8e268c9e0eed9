"""Beyond the paper: its next stage, a classifier of the clusters, and what the clustering does for it."""

from __future__ import annotations

import numpy as np

from .._classification import ClassifiedSetting
from .._constants import LEARNED, OBJECTS
from .._results import RunResults
from ._base import Section, format_params, format_score, objective_name, save_figure
from ._comparison import DOES_NOT_HOLD, HOLDS, N_STANDARD_ERRORS, paired_verdict
from ._figures import curve_styles

#: Published figures of radar instance segmentation on real RadarScenes data (learned models): (source, mAP@0.5,
#: macro-F1, mCov), in percent, None where the source gives none (../shared/reference/published-results.md).
PUBLISHED = (
    ("Liu et al., T-IV 2022 (PointNet++ / gMLP, then clustering)", 86.97, None, 89.53),
    ("RadarGNN, TUMFTM (semantic-segmentation F1; its mAP 56.5 is bird's-eye-view boxes)", None, 77.1, None),
)

#: The precision-recall figure's file in the output folder.
PRECISION_RECALL = "classification_precision_recall.png"

#: Fewer test sequences than this make the paired per-sequence check weak (its standard error rests on few values).
FEW_SEQUENCES = 5

#: The scores the answer to the paper's question is given in: the published one, and the one that counts objects.
ANSWERED_BY = (("map", "mAP@0.5"), ("pq", "class PQ"))


def markdown(results: RunResults) -> list[str]:
    """The semantic scores of each classified clustering, the published figures, and the answer with its noise."""
    found = results.classification
    if found is None:
        return []
    rows = found.settings
    window = next(iter(rows.values())).scores.window_s
    lines = [
        "",
        "## Beyond the paper: classifying the clusters",
        "",
        'The paper clusters so that a classifier can name the road users, and leaves open "the impact of the '
        'proposed clustering framework on a classifier". Here a `ClusterClassifier` (the cluster features of '
        "`sklearn_radar.classification.cluster_features`, a `HistGradientBoostingClassifier`) is trained on the "
        "clusters of each setting on the training half, cut into "
        f"{window:g} s time windows; a segment's target is the class of the annotated road user whose detections "
        "in the window have IoU > 0.5 with it, background otherwise. Segments classified as background become noise. "
        "The point-wise classifier, the same classifier on single detections with no clustering (instances: "
        "connected detections of one class), is what a user would try instead. Scores on the test half, per "
        f"{window:g} s window, against the annotated road users (`sklearn_radar.metrics.semantic_scores`): class PQ "
        "(a match needs the same class and IoU > 0.5; the mean over classes), mAP@0.5 (instances ranked by the "
        "classifier's confidence; COCO's 101-point interpolation; the mean over classes), macro-F1 over the "
        "detections (background counted as a class) and the class-agnostic mCov. Background-only segments: the "
        "share of segments with no detection of a road user of the target the object-level scores use, of the "
        "clustering (before: the object-level table's 'bg segments') and of what the classifier keeps (after). "
        "Classes are the library's road-user classes (`sklearn_radar.classification`; the data section maps the "
        "RadarScenes labels onto them). With repeats, a cell gives the mean \u00b1 sd over the classifiers of each "
        "repeat's setting (the other columns are the first repeat's). Where the run has them, the settings meant "
        "for objects are classified too: the object experiment (tuned for PQ) and the learned grouping (its fitted "
        "model's clusters); the question below is asked of the others, which the run's objective tuned.",
        "",
        "| classified clusters of | clustering's test V1 | clustering's test PQ | class PQ | mAP@0.5 | macro-F1 "
        "| mCov | background-only segments before / after | training examples |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name, row in rows.items():
        v1, pq = clustering_scores(results, name)
        before = background_before(results, name, row)
        before = "-" if before is None else f"{100 * before:.1f} %"
        pq_cell, map_cell, f1_cell, mcov_cell = (_repeated(row, key) for key in ("pq", "map", "macro_f1", "mcov"))
        lines.append(
            f"| {name}, {_source(name, row.setting_source)} | {_v1_cell(v1)} | {_cell(pq)} | {pq_cell} | {map_cell} | "
            f"{f1_cell} | "
            f"{mcov_cell} | {before} / {100 * row.background_share_after:.1f} % | {row.n_training_examples:,} |"
        )
    for source, map_percent, f1_percent, mcov_percent in PUBLISHED:
        lines.append(
            f"| *published, real RadarScenes data:* {source} | - | - | - | {_percent(map_percent)} | "
            f"{_percent(f1_percent)} | {_percent(mcov_percent)} | - | - |"
        )
    lines += [
        "",
        "Our figures are on simulated data, the published ones on real recordings, with learned models trained on "
        "far more data: they show the scale, not a comparison.",
        "",
        "Average precision by class (test half): "
        + "; ".join(f"{name}: {_per_class(row, 'ap')}" for name, row in rows.items()),
        "",
    ]
    if results.figures.drawn.get("precision_recall"):
        lines += [
            "Precision against recall per class (test half): each classified setting's segments ranked by the "
            "classifier's confidence (its probability of the class it gives), a segment a hit when it has the class "
            "and IoU > 0.5 with an annotated road user of it; the precision is COCO's interpolated one (the best at "
            "this recall or more), whose mean over the 101 recall points is the AP in the legend. A curve that stays "
            "high to the right ranks its correct segments first.",
            "",
            f"![precision-recall per class]({PRECISION_RECALL})",
            "",
        ]
    lines += answer_lines(results)
    lines += [
        "",
        "Settings: " + "; ".join(f"{name}: {format_params(row.params)}" for name, row in rows.items() if row.params),
    ]
    return lines


def clustering_scores(results: RunResults, name):
    """(test V1, test PQ) of the clustering ``name`` (``"#8"``, ``"objects"``, a baseline), means over the repeats."""
    records = _test_records(results, name)
    if records is None:
        return None, None
    pq = [float(r.instance_test.pq) for r in records if r.instance_test is not None]
    return float(np.mean([r.v1_test for r in records])), float(np.mean(pq)) if pq else None


def background_before(results: RunResults, name, row: ClassifiedSetting):
    """The clustering's background-only segment share: its own ``instance_test``'s, else the step's; None point-wise."""
    if row.background_share_before is None:
        return None
    records = _test_records(results, name)
    if records is not None and records[0].instance_test is not None:
        return records[0].instance_test.background_segment_share
    return row.background_share_before


def cv_score(results: RunResults, name):
    """The mean cross-validated score over the repeats of a paper's or baseline clustering ``name``; else None."""
    result = _clustering(results, name)
    if result is None:
        return None
    scores = [r.search.cv_best for r in result.repeats or [result] if r.search is not None]
    return float(np.mean(scores)) if scores else None


def _clustering(results: RunResults, name):
    """The experiment or baseline result of the clustering ``name``; None when it did not run (or is neither)."""
    if name.startswith("#") and name[1:].isdigit():
        return results.experiments.get(int(name[1:]))
    return (results.baselines or {}).get(name)


def _test_records(results: RunResults, name):
    """The records with the test scores of each repeat of clustering ``name``; None when it did not run."""
    if name == OBJECTS:
        return None if results.objects is None else results.objects.repeats or [results.objects.kept]
    if name == LEARNED:
        return None if results.learned is None else [results.learned]
    result = _clustering(results, name)
    return None if result is None else result.repeats or [result]


def answer_lines(results: RunResults) -> list[str]:
    """Whether the clustering with the best CV score of those classified gives the best classifier, with its noise."""
    rows = {
        name: row
        for name, row in results.classification.settings.items()
        if row.background_share_before is not None and name not in (OBJECTS, LEARNED)
    }
    label = objective_name(results)
    scored = {name: cv_score(results, name) for name in rows}
    scored = {name: value for name, value in scored.items() if value is not None}
    if not scored:
        return []
    best = max(scored, key=scored.get)
    shown = format_score(scored[best], results)
    tied = [name for name in scored if name != best and format_score(scored[name], results) == shown]
    rivals = {name: row for name, row in rows.items() if name != best and name not in tied}
    if not rivals:
        return []
    chosen = f"{best}, CV {label} {shown}"
    if tied:
        one = len(tied) == 1
        chosen += (
            f"; {', '.join(tied)} {'ties' if one else 'tie'} it and {'is' if one else 'are'} left out of the rivals"
        )
    lines = []
    for score, score_label in ANSWERED_BY:
        rival = max(rivals, key=lambda name: np.mean(_values(rivals[name], score)))
        lines.append(
            f"- Does the clustering with the best cross-validated {label} of those classified ({chosen}) give the "
            f"best classifier by {score_label}? {_verdict(rows[best], rivals[rival], rival, score, score_label)}"
        )
    unsearched = [name for name in rows if name not in scored]
    other = "PQ" if label == "V1" else "V1"
    lines.append(
        f"- The clustering is chosen by its cross-validated {label} (training half), never by a test score"
        + (
            f"; without a search ({', '.join(unsearched)}) a setting has no CV score and is a rival only"
            if unsearched
            else ""
        )
        + f". The searches maximised {label}, so there is no cross-validated {other} to choose by"
        + ("; `--objective pq` asks the question for PQ." if label == "V1" else ".")
    )
    return lines


def _verdict(ours: ClassifiedSetting, theirs: ClassifiedSetting, rival, score, score_label):
    """The paired comparison of one score by the report's rule: by repeat when both repeated alike, else by sequence."""
    mine, other = _values(ours, score), _values(theirs, score)
    if len(mine) > 1 and len(mine) == len(other):
        differences, unit = np.subtract(mine, other), "repeats"
    else:
        differences, unit = np.subtract(ours.per_sequence[score], theirs.per_sequence[score]), "test sequences"
    said, mean, se = paired_verdict(differences)
    head = (
        f"{score_label} {_figure(np.mean(mine), score)} against {_figure(np.mean(other), score)} for the best "
        f"other, {rival}"
    )
    if se is None:
        return f"{head}; one test sequence cannot tell a difference from the spread between sequences."
    words = {HOLDS: "yes, it is higher", DOES_NOT_HOLD: "no, it is lower"}.get(said, "cannot tell (within the noise)")
    weak = (
        f"; {len(differences)} test sequences make a weak check: the `--full` data have 8"
        if unit == "test sequences" and len(differences) < FEW_SEQUENCES
        else ""
    )
    return (
        f"{head}: {words} (mean paired difference over the {len(differences)} {unit} "
        f"{_difference(mean, score)} \u00b1 {_difference(se, score, sign='')} standard error; it counts beyond "
        f"{N_STANDARD_ERRORS:g} standard errors{weak})."
    )


def _figure(value, score):
    """One score as the table prints it: class PQ as a fraction (3 decimals), the others in percent (1 decimal)."""
    return f"{value:.3f}" if score == "pq" else f"{100 * value:.1f} %"


def _difference(value, score, sign="+"):
    """A difference of one score in the table's unit: a fraction for class PQ, percentage points otherwise."""
    return f"{value:{sign}.3f}" if score == "pq" else f"{100 * value:{sign}.1f} points"


def _values(row: ClassifiedSetting, score):
    """The score of each repeat (one value for a single run)."""
    return [float(getattr(scores, score)) for scores in row.repeats or [row.scores]]


def _repeated(row: ClassifiedSetting, score):
    """``"0.392"`` / ``"31.1 %"``, or mean \u00b1 sd over the repeats."""
    values = _values(row, score)
    if len(values) == 1:
        return _figure(values[0], score)
    sd = np.std(values, ddof=1)
    return f"{_figure(np.mean(values), score).removesuffix(' %')} \u00b1 {_figure(sd, score)}"


def _per_class(row: ClassifiedSetting, score):
    return (
        ", ".join(f"{name} {_figure(figures[score], score)}" for name, figures in row.scores.per_class.items()) or "-"
    )


def _cell(value):
    return "-" if value is None else f"{value:.3f}"


def _v1_cell(value):
    """V1 in percent, as the report's other tables give it."""
    return "-" if value is None else f"{100 * value:.2f} %"


def _source(name, source):
    """Where the setting comes from, without repeating the experiment's number: ``"tuned"`` for ``"tuned #8"``."""
    return source.removesuffix(f" {name}")


def _percent(value):
    return "-" if value is None else f"{value:.2f} %"


def figures(out, results: RunResults, context) -> dict[str, str]:
    """The precision-recall curves per class of every classified setting, when the step ran (with curves)."""
    found = results.classification
    if found is None or not any(row.scores.precision_at_recall for row in found.settings.values()):
        return {}
    save_figure(precision_recall_figure(found), out / PRECISION_RECALL)
    return {"precision_recall": PRECISION_RECALL}


def precision_recall_figure(found):
    """One panel per road-user class: each classified setting's interpolated precision against recall."""
    import matplotlib.pyplot as plt

    rows = {name: row for name, row in found.settings.items() if row.scores.precision_at_recall}
    classes = list(dict.fromkeys(c for row in rows.values() for c in row.scores.precision_at_recall))
    fig, axes = plt.subplots(1, len(classes), figsize=(3.2 * len(classes), 4.4), sharey=True, squeeze=False)
    recall = np.linspace(0.0, 1.0, 101)
    styles = curve_styles(len(rows))
    for ax, name in zip(axes[0], classes, strict=True):
        for row, (colour, line, _) in zip(rows.values(), styles, strict=True):
            precision = row.scores.precision_at_recall.get(name)
            if precision is not None:
                ap = row.scores.per_class.get(name, {}).get("ap", float(np.mean(precision)))
                ax.step(recall, precision, where="post", color=colour, linestyle=line, label=f"{ap:.0%}")
        ax.set_title(name)
        ax.set_xlabel("recall")
        ax.set_xlim(0.0, 1.0)
        ax.set_ylim(0.0, 1.02)
        ax.legend(fontsize=6, title="AP@0.5", title_fontsize=6, loc="upper right")
    axes[0][0].set_ylabel("precision (interpolated)")
    # The settings' long names once, below the panels; each panel's legend gives their AP in the same styles.
    keys = [plt.Line2D([], [], color=colour, linestyle=line) for colour, line, _ in styles]
    fig.legend(keys, list(rows), loc="lower center", ncol=min(4, len(rows)), fontsize=7, frameon=False)
    fig.set_layout_engine("tight", rect=(0.0, 0.13, 1.0, 1.0))  # room for the settings' legend
    fig.suptitle(
        f"Precision-recall of the classified segments per class, test half ({_window(found)} s "
        "windows, IoU > 0.5; ranked by the classifier's confidence)"
    )
    return fig


def _window(found):
    return f"{next(iter(found.settings.values())).scores.window_s:g}"


SECTION = Section("classification", markdown, figures)
