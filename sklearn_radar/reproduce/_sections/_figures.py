"""The figures: V1 ours vs the paper's, a Fig. 6 analogue (one test sequence) and the searches' convergence."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._constants import BEST_STAGE1, FCS_BASELINE
from .._context import RunContext
from .._results import RunResults, repeated_scores
from ._base import SETTING_PAPER, Section, objective_name, percent, save_figure, setting_source, test_score

#: The figures' files in the output folder.
V1_BARS = "v1_ours_vs_paper.png"
SCENE = "fig6_scene.png"
CONVERGENCE = "convergence.png"

#: Line styles of the convergence curves; with the 20 colours of tab20 no two of up to 80 curves look alike.
LINESTYLES = ("-", "--", "-.", ":")


def markdown(results: RunResults) -> list[str]:
    """The figures drawn, each with its caption, or why none was."""
    drawn = results.figures.drawn
    lines = ["", "## Figures", ""]
    if drawn.get("v1_bars"):
        lines += [
            "V1 on the test half, ours beside the paper's, per experiment (Tables III and IV); a dagger (\u2020) "
            "after the number marks experiments whose setting is the paper's, kept because the search found nothing "
            "better."
            + (
                f" Our bars are the mean over the {results.meta.repeats} repeats, the error bars one standard "
                "deviation either side."
                if results.meta.repeats > 1
                else ""
            ),
            "",
            f"![V1 ours vs paper]({V1_BARS})",
            "",
        ]
    if drawn.get("scene"):
        lines += [*scene_caption(results), "", f"![scene]({SCENE})", ""]
    if drawn.get("convergence"):
        lines += [
            f"Best mean cross-validated {objective_name(results)} so far (training half), per search: one colour and "
            f"line style per curve (the scikit-learn baselines dashed); #{BEST_STAGE1}, the paper's best method, is "
            "the wide black band with dots, drawn underneath so that a curve that coincides with it shows inside it."
            + (
                f" With {results.meta.repeats} repeats per search, each line is the median over the repeats and the "
                "shaded band around it spans their minimum to maximum."
                if results.meta.repeats > 1
                else ""
            ),
            "",
            f"![convergence]({CONVERGENCE})",
        ]
    if results.figures.missing:
        lines += [f"(figures not drawn: {results.figures.missing})"]
    return lines


def scene_panels(results: RunResults):
    """(baseline, best): the experiments of Fig. 6's clustered panels, from the run's results.

    The baseline is the FCS box baseline #3 (or the first experiment run),
    the best the experiment with the highest test score of the run's
    objective.
    """
    experiments = results.experiments
    best = max(experiments, key=lambda number: test_score(experiments[number], results))
    baseline = FCS_BASELINE if FCS_BASELINE in experiments else min(experiments)
    return baseline, best


def scene_caption(results: RunResults):
    """Fig. 6's caption: what the panels show and what the background-only clusters are."""
    baseline, best = scene_panels(results)
    shares = []
    for number in dict.fromkeys((baseline, best)):
        scores = results.experiments[number].instance_test
        if scores is not None:
            shares.append(f"#{number} {percent(scores.background_cluster_share)}")
    over_test = (
        f" Over the whole test half, the share of background-only clusters is {', '.join(shares)}." if shares else ""
    )
    return [
        f"Fig. 6 analogue, one test sequence: raw data, target, the FCS baseline (#{baseline}) and the best "
        f"experiment by test {objective_name(results)} (#{best}). The target labels only moving road users; "
        "everything else, the static background, is grey there (noise). The clusterings also group background "
        "detections, e.g. along the streaks that guard rails, parked cars and buildings leave as the car drives: "
        "a cluster that holds no detection of a moving road user is *background-only* and drawn as black crosses, "
        "and each panel's title counts them. The paper's V-measure does not count them (background is not part of "
        "its target); the panoptic quality of the object-level section counts each as a false positive." + over_test,
    ]


def figures(out: Path, results: RunResults, context: RunContext) -> dict[str, str]:
    """The V1 bars and the scene view, when an experiment ran, and the convergence curves, when a search ran."""
    import matplotlib.pyplot as plt

    drawn = {}
    if results.experiments:
        _v1_bars(plt, out / V1_BARS, results)
        drawn["v1_bars"] = V1_BARS
    if context.labels:
        _scene_figure(plt, out / SCENE, results, context)
        drawn["scene"] = SCENE
    curves = {f"#{number}": _convergences(e) for number, e in results.experiments.items() if e.search}
    curves.update({name: _convergences(baseline) for name, baseline in (results.baselines or {}).items()})
    if curves:
        _convergence(plt, out / CONVERGENCE, curves, results)
        drawn["convergence"] = CONVERGENCE
    return drawn


def _convergences(result):
    """The convergence of each repeat's search (one list for a single run)."""
    return [r.search.convergence for r in result.repeats or [result] if r.search is not None]


def best_so_far(convergences):
    """(median, minimum, maximum) over repeats of the best score so far, per iteration.

    Parameters
    ----------
    convergences : list of list of float
        Each repeat's score per iteration; repeats of different lengths are cut to the shortest.

    Returns
    -------
    median, low, high : ndarray
    """
    n = min(len(c) for c in convergences)
    best = np.maximum.accumulate(np.array([c[:n] for c in convergences], dtype=float), axis=1)
    return np.median(best, axis=0), best.min(axis=0), best.max(axis=0)


def curve_styles(n):
    """``n`` distinct (colour, line style) pairs: tab20's colours, dark and light alternating, then the next style."""
    import matplotlib

    colours = matplotlib.colormaps["tab20"].colors
    order = [*range(0, 20, 2), *range(1, 20, 2)]  # the 10 strong colours first, then their light partners
    return [(colours[order[k % 20]], LINESTYLES[(k // 20) % len(LINESTYLES)] if k < 80 else "-") for k in range(n)]


def _convergence(plt, path, curves, results):
    fig, ax = plt.subplots(figsize=(9, 7))
    highlight = f"#{BEST_STAGE1}"
    others = [name for name in curves if name != highlight]
    styles = curve_styles(len(others))
    for k, name in enumerate(others):
        colour, linestyle = styles[k]
        # The baselines dashed, the paper's experiments solid, while the 20 colours tell every curve apart.
        if len(others) <= 20 and name not in (f"#{n}" for n in results.experiments):
            linestyle = "--"
        median, low, high = best_so_far(curves[name])
        iterations = np.arange(1, len(median) + 1)
        if len(curves[name]) > 1:
            ax.fill_between(iterations, low, high, color=colour, alpha=0.15, linewidth=0, zorder=1.5)
        ax.plot(
            iterations,
            median,
            color=colour,
            linestyle=linestyle,
            linewidth=1.5,
            label=name,
            zorder=2,
        )
    if highlight in curves:
        # Underneath, wide: a curve that coincides with it stays visible inside the black band.
        median, low, high = best_so_far(curves[highlight])
        iterations = np.arange(1, len(median) + 1)
        if len(curves[highlight]) > 1:
            ax.fill_between(iterations, low, high, color="0.6", alpha=0.35, linewidth=0, zorder=0.5)
        ax.plot(
            iterations,
            median,
            color="black",
            linewidth=4.5,
            marker="o",
            markersize=6,
            label=f"{highlight} (the paper's best)",
            zorder=1,
        )
    ax.set(
        xlabel="iteration",
        ylabel=f"best mean CV {objective_name(results)} so far",
        title="Bayesian optimisation convergence (training half)",
    )
    ax.xaxis.get_major_locator().set_params(integer=True)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2)
    save_figure(fig, path)


def _v1_bars(plt, path, results):
    experiments = [results.experiments[number] for number in sorted(results.experiments)]
    positions = np.arange(len(experiments))
    repeated = [100 * np.asarray(repeated_scores(e)) for e in experiments]
    ours = [float(np.mean(values)) for values in repeated]
    spread = [float(np.std(values, ddof=1)) if len(values) > 1 else 0.0 for values in repeated]
    paper = [e.paper_v1_percent for e in experiments]
    fig, ax = plt.subplots(figsize=(max(7.5, 0.7 * len(experiments) + 2), 4.5))
    width = 0.4
    several = results.meta.repeats > 1
    ax.bar(
        positions - width / 2,
        ours,
        width,
        yerr=spread if several else None,
        capsize=3,
        label=f"ours (test half, mean \u00b1 sd of {results.meta.repeats} repeats)" if several else "ours (test half)",
        color="tab:blue",
    )
    ax.bar(positions + width / 2, paper, width, label="paper", color="tab:gray")
    labels = [f"#{e.number}" + (" \u2020" if setting_source(e) == SETTING_PAPER else "") for e in experiments]
    ax.set_xticks(positions, labels)
    low = min(min(ours), min(paper))
    ax.set_ylim(max(0.0, 10 * np.floor(low / 10) - 10), 100)
    ax.set(ylabel="V1 (%)", title="V1 per experiment, ours vs the paper's (\u2020: the paper's setting kept)")
    ax.legend(loc="lower right", fontsize=8)
    ax.grid(axis="y", alpha=0.3)
    save_figure(fig, path)


def _scene_figure(plt, path, results, context):
    """Raw data, target, the FCS baseline (#3, or the first experiment run) and the best experiment, one sequence."""
    from ...preprocessing import FrameTransform

    sequence = context.sequences.fetch(context.drawn_sequence)
    data = FrameTransform().fit_transform(sequence.X)
    baseline, best = scene_panels(results)
    panels = [
        ("raw data", None),
        ("target (pre-clustered ground truth)", sequence.target),
        (f"baseline #{baseline}", context.labels[baseline]),
        (f"best: #{best}", context.labels[best]),
    ]
    fig, axes = plt.subplots(1, 4, figsize=(20, 5.5), sharex=True, sharey=True)
    x, y = data["x"].to_numpy(), data["y"].to_numpy()
    target = np.asarray(sequence.target)
    for k, (ax, (title, labels)) in enumerate(zip(axes, panels, strict=True)):
        if labels is None:
            ax.scatter(x, y, s=0.5, c="0.3")
        else:
            labels = np.asarray(labels)
            noise = labels < 0
            background = _background_only(labels, target) if k >= 2 else np.zeros(len(labels), dtype=bool)
            coloured = ~noise & ~background
            ax.scatter(x[noise], y[noise], s=0.3, c="0.8")
            ax.scatter(x[coloured], y[coloured], s=1.5, c=labels[coloured] % 20, cmap="tab20", vmin=0, vmax=19)
            if k >= 2:
                n_clusters = len(np.unique(labels[~noise]))
                n_background = len(np.unique(labels[background]))
                if background.any():
                    ax.scatter(x[background], y[background], s=4, c="k", marker="x", linewidths=0.5)
                title = f"{title}\n{n_background} of {n_clusters} clusters background-only (x)"
        ax.set(title=title, xlabel="x (m, FCS)", aspect="equal")
    axes[0].set_ylabel("y (m, FCS)")
    fig.suptitle(
        f"test sequence {sequence.id}: each cluster its own colour, background-only clusters black x, "
        "noise and static background grey"
    )
    save_figure(fig, path)


def _background_only(labels, target):
    """Per row: whether its cluster holds no detection of a moving road user (``target >= 0``)."""
    clustered = labels >= 0
    with_object = np.unique(labels[clustered & (target >= 0)])
    return clustered & ~np.isin(labels, with_object)


SECTION = Section("figures", markdown, figures)
