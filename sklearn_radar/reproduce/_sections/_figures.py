"""The figures: a Fig. 6 analogue (one test sequence, clustered) and the searches' convergence."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._constants import FCS_BASELINE
from .._context import RunContext
from .._results import RunResults
from ._base import Section, save_figure

#: The figures' files in the output folder.
SCENE = "fig6_scene.png"
CONVERGENCE = "convergence.png"


def markdown(results: RunResults) -> list[str]:
    """The figures drawn, or why none was."""
    drawn = results.figures.drawn
    lines = ["", "## Figures", ""]
    if drawn.get("scene"):
        lines += [
            "Fig. 6 analogue, one test sequence: raw data, target, baseline and best clustering. Clusters that "
            "hold no detection of a moving road user (background-only: guard rails, parked cars, clutter) are drawn "
            "as black crosses; the paper's V-measure does not count them, the panoptic quality counts each as a "
            "false positive.",
            "",
            f"![scene]({SCENE})",
            "",
        ]
    if drawn.get("convergence"):
        lines += ["Best cross-validated score so far, per tuned experiment:", "", f"![convergence]({CONVERGENCE})"]
    if results.figures.missing:
        lines += [f"(figures not drawn: {results.figures.missing})"]
    return lines


def figures(out: Path, results: RunResults, context: RunContext) -> dict[str, str]:
    """The scene view, when an experiment ran, and the convergence curves, when a search ran."""
    import matplotlib.pyplot as plt

    drawn = {}
    if context.labels:
        _scene_figure(plt, out / SCENE, results, context)
        drawn["scene"] = SCENE
    curves = {f"#{number}": e.search.convergence for number, e in results.experiments.items() if e.search}
    curves.update({name: baseline.search.convergence for name, baseline in (results.baselines or {}).items()})
    if curves:
        fig, ax = plt.subplots(figsize=(8, 5))
        for name, scores in curves.items():
            ax.plot(np.arange(1, len(scores) + 1), np.maximum.accumulate(scores), label=name)
        score = "PQ" if results.meta.objective == "pq" else "V1"
        ax.set(xlabel="iteration", ylabel=f"best mean CV {score} so far", title="Bayesian optimisation convergence")
        ax.legend(fontsize=7, ncol=2)
        save_figure(fig, out / CONVERGENCE)
        drawn["convergence"] = CONVERGENCE
    return drawn


def _scene_figure(plt, path, results, context):
    """Raw data, target, the FCS baseline (#3, or the first experiment run) and the best experiment, one sequence."""
    from ...preprocessing import FrameTransform

    scenes, test = context.scenes, context.test
    data = FrameTransform().fit_transform(scenes.data.iloc[test])
    sequence = scenes.groups[test]
    first = sequence == sequence[0]
    scores = {
        number: _objective_score(e, results) for number, e in results.experiments.items() if number in context.labels
    }
    best = max(scores, key=scores.get)
    baseline = FCS_BASELINE if FCS_BASELINE in context.labels else min(context.labels)
    panels = [
        ("raw data", None),
        ("target (pre-clustered ground truth)", context.target[test]),
        (f"baseline #{baseline}", context.labels[baseline]),
        (f"best: #{best}", context.labels[best]),
    ]
    fig, axes = plt.subplots(1, 4, figsize=(20, 5.5), sharex=True, sharey=True)
    x, y = data["x"].to_numpy()[first], data["y"].to_numpy()[first]
    target = np.asarray(context.target[test])[first]
    for k, (ax, (title, labels)) in enumerate(zip(axes, panels, strict=True)):
        if labels is None:
            ax.scatter(x, y, s=0.5, c="0.3")
        else:
            labels = np.asarray(labels)[first]
            noise = labels < 0
            background = _background_only(labels, target) if k >= 2 else np.zeros(len(labels), dtype=bool)
            coloured = ~noise & ~background
            ax.scatter(x[noise], y[noise], s=0.3, c="0.8")
            ax.scatter(x[coloured], y[coloured], s=1.5, c=labels[coloured] % 20, cmap="tab20", vmin=0, vmax=19)
            if background.any():
                ax.scatter(x[background], y[background], s=4, c="k", marker="x", linewidths=0.5)
                n_clusters = len(np.unique(labels[~noise]))
                n_background = len(np.unique(labels[background]))
                title = f"{title}\n{n_background} of {n_clusters} clusters background-only (x)"
        ax.set(title=title, xlabel="x (m, FCS)", aspect="equal")
    axes[0].set_ylabel("y (m, FCS)")
    fig.suptitle(
        f"test sequence {sequence[0]}: each cluster its own colour, background-only clusters black x, noise grey"
    )
    save_figure(fig, path)


def _objective_score(result, results):
    """The test score the run ranks by: PQ when it tuned for PQ (and has it), else V1."""
    if results.meta.objective == "pq" and result.instance_test is not None:
        return result.instance_test.pq
    return result.v1_test


def _background_only(labels, target):
    """Per row: whether its cluster holds no detection of a moving road user (``target >= 0``)."""
    clustered = labels >= 0
    with_object = np.unique(labels[clustered & (target >= 0)])
    return clustered & ~np.isin(labels, with_object)


SECTION = Section("figures", markdown, figures)
