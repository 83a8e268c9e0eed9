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
            "Fig. 6 analogue, one test sequence: raw data, target, baseline and best clustering.",
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
        ax.set(xlabel="iteration", ylabel="best mean CV V1 so far", title="Bayesian optimisation convergence")
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
    scores = {number: e.v1_test for number, e in results.experiments.items() if number in context.labels}
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
    for ax, (title, labels) in zip(axes, panels, strict=True):
        if labels is None:
            ax.scatter(x, y, s=0.5, c="0.3")
        else:
            labels = np.asarray(labels)[first]
            noise = labels < 0
            ax.scatter(x[noise], y[noise], s=0.3, c="0.8")
            ax.scatter(x[~noise], y[~noise], s=1.5, c=labels[~noise] % 20, cmap="tab20", vmin=0, vmax=19)
        ax.set(title=title, xlabel="x (m, FCS)", aspect="equal")
    axes[0].set_ylabel("y (m, FCS)")
    fig.suptitle(f"test sequence {sequence[0]}: each cluster its own colour, noise grey")
    save_figure(fig, path)


SECTION = Section("figures", markdown, figures)
