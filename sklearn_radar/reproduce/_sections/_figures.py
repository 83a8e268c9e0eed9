"""The figures: V1 ours vs the paper's, a Fig. 6 analogue (one test sequence) and the searches' convergence."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._constants import BEST_STAGE1, FCS_BASELINE
from .._context import RunContext
from .._results import RunResults, repeated_scores
from ._base import (
    SETTING_PAPER,
    Section,
    objective_name,
    percent,
    save_figure,
    scene_size,
    setting_source,
    test_score,
)

#: The figures' files in the output folder.
V1_BARS = "v1_ours_vs_paper.png"
SCENE = "fig6_scene.png"
CONVERGENCE = "convergence.png"

#: Line styles of the convergence curves; with the 10 colours of tab10 and a marker each no two of up to 40 curves
#: look alike.
LINESTYLES = ("-", "--", "-.", ":")


def markdown(results: RunResults) -> list[str]:
    """The figures drawn, each with its caption, or why none was."""
    drawn = results.figures.drawn
    lines = ["", "## Figures", ""]
    if drawn.get("v1_bars"):
        lines += [
            "V1 on the test half, ours beside the paper's, per experiment (Tables III and IV), on an axis from 0 "
            "(bar lengths compare as the scores do); a dagger (\u2020) "
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
            f"Best mean cross-validated {objective_name(results)} so far (training half), per search: the paper's "
            "experiments on top, the scikit-learn baselines below (each panel on its own scale), one colour and "
            "marker per curve. "
            "Where two searches found the same best score their lines coincide, and their markers, spaced along "
            f"each line at other places, alternate on it. #{BEST_STAGE1}, the paper's best method, is the wide grey "
            "band, drawn underneath so that a curve that coincides with it shows inside it."
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
        f"Fig. 6 analogue, one test sequence: raw data and target (top), the FCS baseline (#{baseline}) and the best "
        f"experiment by test {objective_name(results)} (#{best}, bottom). The target labels only moving road users; "
        "everything else, the static background, is light grey there (noise). The clusterings also group "
        "background detections, e.g. along the streaks that guard rails, parked cars and buildings leave as the car "
        "drives: a cluster that holds no detection of a moving road user is *background-only* and drawn in dark "
        "grey, beneath the coloured clusters, and each panel's title counts them. The paper's V-measure does not "
        "count them (background is not part of its target); the panoptic quality of the object-level section counts "
        "each as a false positive." + over_test,
    ]


def figures(out: Path, results: RunResults, context: RunContext) -> dict[str, str]:
    """The V1 bars and the scene view, when an experiment ran, and the convergence curves, when a search ran."""
    drawn = {}
    if results.experiments:
        save_figure(v1_bars_figure(results), out / V1_BARS)
        drawn["v1_bars"] = V1_BARS
    if context.labels:
        save_figure(scene_figure(results, context), out / SCENE)
        drawn["scene"] = SCENE
    curves = convergence_curves(results)
    if curves:
        save_figure(convergence_figure(curves, results), out / CONVERGENCE)
        drawn["convergence"] = CONVERGENCE
    return drawn


def convergence_curves(results: RunResults):
    """``{name: [convergence of each repeat]}`` of every search: the experiments', then the baselines'."""
    curves = {f"#{number}": _convergences(e) for number, e in results.experiments.items() if e.search}
    curves.update({name: _convergences(baseline) for name, baseline in (results.baselines or {}).items()})
    return {name: found for name, found in curves.items() if found}


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
    """``n`` distinct (colour, line style, marker) triples: tab10's colours with a marker each, then the next style.

    The markers tell apart curves that coincide (a search that found the
    same best score as another draws on top of it): each curve's markers sit
    at other places along the line (:func:`convergence_figure`).
    """
    import matplotlib

    colours = matplotlib.colormaps["tab10"].colors
    return [
        (colours[k % 10], LINESTYLES[(k // 10) % len(LINESTYLES)], MARKERS[k % len(MARKERS)] if k < 40 else "")
        for k in range(n)
    ]


#: Markers of the convergence curves, one per curve in turn.
MARKERS = ("o", "s", "^", "v", "D", "P", "X", "<", ">", "h", "*")


def convergence_figure(curves, results: RunResults):
    """Best CV score so far per iteration: the paper's experiments (top, #8 highlighted) and the baselines (below).

    Parameters
    ----------
    curves : dict of str to list of list of float
        :func:`convergence_curves`.
    results : RunResults

    Returns
    -------
    fig : matplotlib Figure
    """
    import matplotlib.pyplot as plt

    experiments = {name: c for name, c in curves.items() if name.startswith("#")}
    baselines = {name: c for name, c in curves.items() if name not in experiments}
    groups = [("the paper's experiments", experiments), ("scikit-learn baselines", baselines)]
    groups = [(title, group) for title, group in groups if group]
    fig, axes = plt.subplots(
        len(groups), 1, figsize=(11, 4.6 * len(groups) + 0.4), sharex=True, squeeze=False, layout="constrained"
    )
    for ax, (title, group) in zip(axes[:, 0], groups, strict=True):
        _convergence_panel(ax, group)
        ax.set(ylabel=f"best mean CV {objective_name(results)} so far", title=title)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=10, loc="center left", bbox_to_anchor=(1.01, 0.5), frameon=False)
    axes[-1][0].set_xlabel("iteration")
    axes[-1][0].xaxis.get_major_locator().set_params(integer=True)
    fig.suptitle("Bayesian optimisation convergence (training half)")
    return fig


def _convergence_panel(ax, curves):
    """One line per search (the median over its repeats, a band from their minimum to maximum), markers staggered."""
    highlight = f"#{BEST_STAGE1}"
    others = [name for name in curves if name != highlight]
    styles = curve_styles(len(others))
    for k, name in enumerate(others):
        colour, linestyle, marker = styles[k]
        median, low, high = best_so_far(curves[name])
        iterations = np.arange(1, len(median) + 1)
        if len(curves[name]) > 1:
            ax.fill_between(iterations, low, high, color=colour, alpha=0.12, linewidth=0, zorder=1.5)
        # Markers spaced along the line, each curve's shifted by another share of the spacing (the golden ratio's
        # multiples spread any two curves' shifts apart): the markers of coinciding curves alternate.
        every = (MARKER_STEP * ((k * GOLDEN) % 1.0), MARKER_STEP)
        ax.plot(
            iterations,
            median,
            color=colour,
            linestyle=linestyle,
            linewidth=1.6,
            marker=marker,
            markersize=6.5,
            markevery=every,
            label=name,
            zorder=2,
        )
    if highlight in curves:
        median, low, high = best_so_far(curves[highlight])
        iterations = np.arange(1, len(median) + 1)
        if len(curves[highlight]) > 1:
            ax.fill_between(iterations, low, high, color="0.6", alpha=0.3, linewidth=0, zorder=0.5)
        # Underneath, wide and grey: a curve that coincides with it stays visible inside it.
        ax.plot(
            iterations,
            median,
            color="0.25",
            linewidth=5,
            alpha=0.45,
            solid_capstyle="butt",
            label=f"{highlight} (the paper's best)",
            zorder=1,
        )


#: The spacing of a convergence curve's markers, as a share of the axes' diagonal (about 5 markers per curve).
MARKER_STEP = 0.2
#: The golden ratio's fractional part: the k-th curve's markers are shifted by ``(k * GOLDEN) % 1`` of the spacing.
GOLDEN = (5**0.5 - 1) / 2


def v1_bars_figure(results: RunResults):
    """Test V1 per experiment, ours beside the paper's, on an axis from 0 to 100 %."""
    import matplotlib.pyplot as plt

    experiments = [results.experiments[number] for number in sorted(results.experiments)]
    positions = np.arange(len(experiments))
    repeated = [100 * np.asarray(repeated_scores(e)) for e in experiments]
    ours = [float(np.mean(values)) for values in repeated]
    spread = [float(np.std(values, ddof=1)) if len(values) > 1 else 0.0 for values in repeated]
    paper = [e.paper_v1_percent for e in experiments]
    fig, ax = plt.subplots(figsize=(max(7.5, 0.7 * len(experiments) + 2), 5), layout="constrained")
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
    ax.bar(positions + width / 2, paper, width, label="the paper's", color="tab:gray")
    labels = [f"#{e.number}" + (" \u2020" if setting_source(e) == SETTING_PAPER else "") for e in experiments]
    ax.set_xticks(positions, labels)
    ax.set_ylim(0, 100)  # from 0: the bars' lengths compare as the scores do
    ax.set(ylabel="V1 (%)", title="V1 per experiment, ours vs the paper's (\u2020: the paper's setting kept)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.08), ncol=2, fontsize=11, frameon=False)
    ax.grid(axis="y", alpha=0.3)
    return fig


def scene_figure(results: RunResults, context: RunContext):
    """Raw data, target, the FCS baseline (#3, or the first experiment run) and the best experiment, one sequence.

    Four panels in a 2 x 2 grid, each of the data's aspect.  Object clusters
    are drawn in colour on top; background-only clusters small and dark
    grey beneath them, noise light grey beneath those.
    """
    import matplotlib.pyplot as plt

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
    x, y = data["x"].to_numpy(), data["y"].to_numpy()
    width, height = scene_size(x, y, width=13.0, extra_height=0.6, panels=2)  # a row: its panels and title
    fig, axes = plt.subplots(2, 2, figsize=(width, 2 * height + 0.5), sharex=True, sharey=True, layout="constrained")
    target = np.asarray(sequence.target)
    for k, (ax, (title, labels)) in enumerate(zip(axes.flat, panels, strict=True)):
        if labels is None:
            ax.scatter(x, y, s=0.5, c="0.3", rasterized=True)
        else:
            labels = np.asarray(labels)
            noise = labels < 0
            background = _background_only(labels, target) if k >= 2 else np.zeros(len(labels), dtype=bool)
            coloured = ~noise & ~background
            ax.scatter(x[noise], y[noise], s=0.3, c="0.85", zorder=1)
            ax.scatter(x[background], y[background], s=0.8, c=BACKGROUND_COLOUR, zorder=2)
            ax.scatter(
                x[coloured], y[coloured], s=2.5, c=labels[coloured] % 20, cmap="tab20", vmin=0, vmax=19, zorder=3
            )
            if k >= 2:
                n_clusters = len(np.unique(labels[~noise]))
                n_background = len(np.unique(labels[background]))
                title = f"{title}: {n_background:,} of {n_clusters:,} clusters background-only"
        ax.set(title=title, aspect="equal")
    for ax in axes[1]:
        ax.set_xlabel("x (m, FCS)")
    for ax in axes[:, 0]:
        ax.set_ylabel("y (m, FCS)")
    fig.suptitle(
        f"test sequence {sequence.id}: each object cluster its own colour, background-only clusters dark grey, "
        "noise and static background light grey"
    )
    return fig


#: The colour of background-only clusters in the scene figure: darker than noise, duller than any cluster colour.
BACKGROUND_COLOUR = "0.5"


def _background_only(labels, target):
    """Per row: whether its cluster holds no detection of a moving road user (``target >= 0``)."""
    clustered = labels >= 0
    with_object = np.unique(labels[clustered & (target >= 0)])
    return clustered & ~np.isin(labels, with_object)


SECTION = Section("figures", markdown, figures)
