"""The figures: V1 ours vs the paper's, a Fig. 6 analogue (one test sequence) and the searches' convergence."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...preprocessing import FrameTransform
from .._constants import BEST_STAGE1, FCS_BASELINE
from .._context import RunContext
from .._experiment_records import repeated_scores
from .._results import RunResults
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

#: What marks a setting that is the paper's, kept because the search found nothing better (tables and figures).
DAGGER = " \u2020"

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
            "better. Each bar's value (%, two decimals as in the tables) is written above it."
            + (
                f" Our bars are the mean over the {results.meta.repeats} repeats, the error bars one standard "
                "deviation either side (the \u00b1 of the value above each bar)."
                if results.meta.repeats > 1
                else " One run has no spread to show: with `--repeats 3` our bars get error bars (the standard "
                "deviation over the repeats)."
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
            "experiments on top, the scikit-learn baselines below (each panel on its own scale), one colour, line "
            "style and marker per curve. "
            "Where two searches found the same best score their lines coincide, and their markers, spaced along "
            f"each line at other places, alternate on it; right of the experiments' panel each final value is "
            f"written once with every experiment that ends there. #{BEST_STAGE1}, the paper's best method, is the "
            "wide grey band, drawn underneath so that a curve that coincides with it shows inside it. A dagger "
            "(\u2020) marks an experiment whose table keeps the paper's setting: scored on the same folds beside the "
            "search, it beat every setting the search tried, so the table's CV score is the paper's setting's and "
            "the curve, which shows only the search's own settings, ends below it (at it on a tie)."
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
    """``(baseline, best)`` of Fig. 6: #3 (or the first experiment run) and the best test score of the objective."""
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
        "everything else, the static background, is light grey there (noise). Each road user has one colour, the "
        "same in every panel, and a cluster takes the colour of the road user most of its detections belong to: "
        "two clusters of one colour split a road user, one cluster over two road users merges them. The "
        "clusterings also group "
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
    """``(median, low, high)`` over the repeats' ``convergences`` of the best score so far, cut to the shortest."""
    n = min(len(c) for c in convergences)
    best = np.maximum.accumulate(np.array([c[:n] for c in convergences], dtype=float), axis=1)
    return np.median(best, axis=0), best.min(axis=0), best.max(axis=0)


def curve_styles(n):
    """``n`` distinct ``(colour, line style, marker)``: tab10's colours, the line styles in turn, a marker each."""
    import matplotlib

    colours = matplotlib.colormaps["tab10"].colors
    return [
        (colours[k % 10], LINESTYLES[(k + k // 10) % len(LINESTYLES)], MARKERS[k % len(MARKERS)] if k < 40 else "")
        for k in range(n)
    ]


#: Markers of the convergence curves, one per curve in turn.
MARKERS = ("o", "s", "^", "v", "D", "P", "X", "<", ">", "h", "*")


def convergence_figure(curves, results: RunResults):
    """Best CV score so far per iteration of the ``curves``: the experiments (top, #8 highlighted), the baselines."""
    import matplotlib.pyplot as plt

    experiments = {name: c for name, c in curves.items() if name.startswith("#")}
    baselines = {name: c for name, c in curves.items() if name not in experiments}
    groups = [("the paper's experiments", experiments), ("scikit-learn baselines", baselines)]
    groups = [(title, group) for title, group in groups if group]
    daggered = {f"#{n}" for n, e in results.experiments.items() if setting_source(e) == SETTING_PAPER}
    in_percent = results.meta.objective != "pq"  # V1 in percent, as the tables give it
    if in_percent:
        groups = [(title, {name: [[100 * v for v in c] for c in cs] for name, cs in g.items()}) for title, g in groups]
    fig, axes = plt.subplots(
        len(groups), 1, figsize=(11, 5.4 * len(groups) + 0.4), sharex=True, squeeze=False, layout="constrained"
    )
    for ax, (title, group) in zip(axes[:, 0], groups, strict=True):
        _convergence_panel(ax, group, daggered)
        unit = " (%)" if in_percent else ""
        ax.set(ylabel=f"best mean CV {objective_name(results)} so far{unit}", title=title)
        ax.grid(alpha=0.3)
        ax.xaxis.get_major_locator().set_params(integer=True)
        long_names = max(len(name) for name in group) > SHORT_NAME
        if not long_names:  # the experiments: their numbers beside the values they end at (baselines rarely tie)
            _end_labels(ax, group, " %" if in_percent else "")
        # Below the panel, across its width: the plot keeps the figure's width (long baseline names, one a row).
        ax.legend(
            fontsize=10, loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=1 if long_names else 4, frameon=False
        )
    axes[-1][0].set_xlabel("iteration")
    fig.suptitle("Bayesian optimisation convergence (training half)")
    return fig


def _end_labels(ax, curves, unit):
    """Each panel's final best scores on its right, once per value, naming every curve that ends there."""
    ends = {}
    for name, convergences in curves.items():
        final = best_so_far(convergences)[0][-1]
        ends.setdefault(f"{final:.2f}{unit}" if unit else f"{final:.3f}", []).append((final, name))
    ax.autoscale_view()
    low, high = ax.get_ylim()
    placed = []  # axes fractions, upwards, at least END_LABEL_GAP apart
    for text, named in sorted(ends.items(), key=lambda item: item[1][0][0]):
        wanted = (named[0][0] - low) / (high - low)
        at = max(wanted, placed[-1] + END_LABEL_GAP) if placed else wanted
        placed.append(at)
        ax.annotate(
            f"{', '.join(name for _, name in named)}: {text}",
            xy=(1.0, wanted),
            xytext=(1.02, at),
            xycoords="axes fraction",
            textcoords="axes fraction",
            va="center",
            fontsize=9,
            arrowprops={"arrowstyle": "-", "color": "0.5", "linewidth": 0.6},
        )


#: The longest curve name that is labelled at the end of its curve too (an experiment's "#13 \u2020").
SHORT_NAME = 12
#: The smallest vertical gap between two end labels of :func:`_end_labels`, as a share of the panel's height.
END_LABEL_GAP = 0.07


def _convergence_panel(ax, curves, daggered=frozenset()):
    """One line per search (median over repeats, band min-max), markers staggered; ``daggered`` names get a dagger."""
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
            label=f"{name}{DAGGER}" if name in daggered else name,
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
            label=f"{highlight}{DAGGER if highlight in daggered else ''} (the paper's best)",
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
        label=f"ours (test half, mean \u00b1 sd of {results.meta.repeats} repeats)"
        if several
        else "ours (test half, one run: no spread to show)",
        color="tab:blue",
    )
    ax.bar(positions + width / 2, paper, width, label="the paper's", color="tab:gray")
    # Each bar's value above it (above its error bar), in the figure's unit.
    for position, value, sd in zip(positions - width / 2, ours, spread, strict=True):
        text = f"{value:.2f} \u00b1 {sd:.2f}" if several else f"{value:.2f}"
        ax.annotate(text, (position, value + sd), **BAR_LABEL)
    for position, value in zip(positions + width / 2, paper, strict=True):
        ax.annotate(f"{value:.2f}", (position, value), **BAR_LABEL)
    labels = [f"#{e.number}" + (" \u2020" if setting_source(e) == SETTING_PAPER else "") for e in experiments]
    ax.set_xticks(positions, labels)
    ax.set_ylim(0, 100)  # from 0: the bars' lengths compare as the scores do
    ax.set(ylabel="V1 (%)", title="V1 per experiment, ours vs the paper's (\u2020: the paper's setting kept)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.08), ncol=2, fontsize=11, frameon=False)
    ax.grid(axis="y", alpha=0.3)
    return fig


#: How a bar's value is written above it: vertical, just above its top (or its error bar), in points.
BAR_LABEL = {
    "xytext": (0, 3),
    "textcoords": "offset points",
    "ha": "center",
    "va": "bottom",
    "rotation": 90,
    "fontsize": 9,
}


def scene_figure(results: RunResults, context: RunContext):
    """Raw data, target, the FCS baseline and the best experiment on the sequence drawn, in a 2 x 2 grid."""
    import matplotlib.pyplot as plt

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
    objects = np.asarray(sequence.scenes.target)
    shown = np.unique(objects[target >= 0])  # the road users any panel colours
    colours = dict(zip(shown.tolist(), distinct_colours(len(shown)), strict=True))
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
            owner = majority_object(labels, objects, target)
            ax.scatter(x[coloured], y[coloured], s=2.5, c=[colours[o] for o in owner[coloured].tolist()], zorder=3)
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
        f"test sequence {sequence.id}: one colour per road user, the same in every panel; a cluster takes the colour "
        "of the road user most of its detections belong to\nbackground-only clusters dark grey, noise and static "
        "background light grey"
    )
    return fig


#: The time step of the tracks figure's paths, s: each path joins an id's centroids per step.
PATH_STEP_S = 0.1
#: The margin of the tracks figure's view around the detections of any id, m.
TRACKS_MARGIN_M = 10.0


def tracks_figure(context: RunContext, ours: str):
    """The drawn test sequence's paths, x-y: the moving road users (left) and our tracks (``ours``, right)."""
    import matplotlib.pyplot as plt

    sequence = context.sequences.fetch(context.drawn_sequence)
    data = sequence.scenes.data
    work = FrameTransform(frame="frame").fit_transform(data)
    x, y = work["x"].to_numpy(), work["y"].to_numpy()
    t = data["timestamp"].to_numpy(dtype=np.float64) * 1e-6
    panels = (
        ("ground truth: annotated moving road users", np.asarray(context.tracks["truth"]), "objects"),
        (f"ours: {ours}", np.asarray(context.tracks["ours"]), "track ids"),
    )
    # The view: every id's detections, with a margin (the clutter far from the road users left out).
    shown_rows = (panels[0][1] >= 0) | (panels[1][1] >= 0)
    if not shown_rows.any():
        shown_rows = np.ones(len(x), dtype=bool)
    low = np.array([x[shown_rows].min(), y[shown_rows].min()]) - TRACKS_MARGIN_M
    high = np.array([x[shown_rows].max(), y[shown_rows].max()]) + TRACKS_MARGIN_M
    width, height = scene_size(np.r_[low[0], high[0]], np.r_[low[1], high[1]], width=13.0, extra_height=0.8, panels=2)
    fig, axes = plt.subplots(1, 2, figsize=(width, height + 0.6), sharex=True, sharey=True, layout="constrained")
    inside = (x >= low[0]) & (x <= high[0]) & (y >= low[1]) & (y <= high[1])
    for ax, (title, ids, noun) in zip(axes, panels, strict=True):
        grey = inside & (ids < 0)
        ax.scatter(x[grey], y[grey], s=0.3, c="0.85", zorder=1, rasterized=True)
        shown = np.unique(ids[ids >= 0])
        for colour, label in zip(distinct_colours(len(shown)), shown.tolist(), strict=True):
            px, py = _path(x, y, t, ids == label)
            ax.plot(px, py, "-", color=colour, lw=1.2, zorder=2)
            ax.plot(px[:1], py[:1], "o", color=colour, ms=3, zorder=3)
        ax.set(title=f"{title} ({len(shown)} {noun})", aspect="equal", xlabel="x (m, sequence frame)")
        ax.set(xlim=(low[0], high[0]), ylim=(low[1], high[1]))
    axes[0].set_ylabel("y (m, sequence frame)")
    fig.suptitle(
        f"test sequence {sequence.id}: paths of ids over time (one colour per id, a dot where it first appears; "
        f"centroids per {PATH_STEP_S:g} s)\nlight grey: every other detection (static background, noise, "
        "unconfirmed clusters)"
    )
    return fig


def _path(x, y, t, rows):
    """The centroids of the detections ``rows`` per :data:`PATH_STEP_S`, in time order."""
    step = np.floor(t[rows] / PATH_STEP_S).astype(np.int64)
    _, code = np.unique(step, return_inverse=True)
    code = code.ravel()
    count = np.bincount(code)
    return np.bincount(code, x[rows]) / count, np.bincount(code, y[rows]) / count


#: The colour of background-only clusters in the scene figure: darker than noise, duller than any cluster colour.
BACKGROUND_COLOUR = "0.5"


def majority_object(labels, objects, target):
    """Per row: the road user (``objects``) owning most of its cluster's road-user detections (lowest id), or -1."""
    owner = np.full(len(labels), -1, dtype=np.asarray(objects).dtype)
    counted = (labels >= 0) & (target >= 0)
    if not counted.any():
        return owner
    pairs, counts = np.unique(np.stack([labels[counted], objects[counted]]), axis=1, return_counts=True)
    # Per cluster, the road user with the most detections (lexsort: by cluster, then count descending, then id).
    order = np.lexsort((pairs[1], -counts, pairs[0]))
    clusters, first = np.unique(pairs[0][order], return_index=True)
    winner = dict(zip(clusters.tolist(), pairs[1][order][first].tolist(), strict=True))
    clustered = labels >= 0
    owner[clustered] = [winner.get(label, -1) for label in labels[clustered].tolist()]
    return owner


def distinct_colours(n):
    """``n`` RGB colours, no two alike and none grey: tab10's, tab20's light shades, tab20b, tab20c, then hues."""
    import matplotlib

    def coloured(colours):
        return [c for c in colours if max(c) - min(c) > 0.05]  # no grey

    tab20 = matplotlib.colormaps["tab20"].colors
    found = coloured(tab20[0::2]) + coloured(tab20[1::2])
    found += coloured(matplotlib.colormaps["tab20b"].colors) + coloured(matplotlib.colormaps["tab20c"].colors)
    if n > len(found):
        hsv = matplotlib.colormaps["hsv"]
        found += [tuple(hsv(k / (n - len(found)))[:3]) for k in range(n - len(found))]
    return [tuple(float(v) for v in c) for c in found[:n]]


def _background_only(labels, target):
    """Per row: whether its cluster holds no detection of a moving road user (``target >= 0``)."""
    clustered = labels >= 0
    with_object = np.unique(labels[clustered & (target >= 0)])
    return clustered & ~np.isin(labels, with_object)


SECTION = Section("figures", markdown, figures)
