"""Tables I and II: the Doppler-density filter's errors and background removal, and the Table I heatmap."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...evaluation import plot_filter_errors
from ...preprocessing import DopplerDensityFilter, FrameTransform
from .._constants import FRAMES, PAPER_FILTER_SETTING
from .._context import RunContext
from .._results import RunResults
from ._base import Section, frame_name, grid_markdown, percent, save_figure, scene_size

#: The figures' files in the output folder.
HEATMAP = "table1_heatmap.png"
FILTER_SCENE = "filter_scene.png"
#: The paper's chosen setting (eta_1 in m/s, d_xy in m), marked in the heatmap.
CHOSEN = PAPER_FILTER_SETTING


def markdown(results: RunResults) -> list[str]:
    """Table I in both coordinate systems, the best zero-error removal, Table II and the heatmap."""
    f = results.filter
    if f is None:
        return []
    lines = [
        "",
        "## Detection filtering (Tables I and II)",
        "",
        "Table I: (object, 150 ms window) cases in which a moving object kept less than 75 % of its "
        "detections, per filter setting, FCS:",
        "",
        grid_markdown(f.table_i["frame"].errors),
        "",
        "The same in CCS:",
        "",
        grid_markdown(f.table_i["car"].errors),
        "",
    ]
    for frame, best in f.best_removal_with_zero_errors.items():
        if best is None:
            found = "no grid cell has 0 errors"
        else:
            found = (
                f"{percent(best.background_removed)} at eta_1 = {best.vr_threshold:.2f} m/s, d_xy = {best.d_xy:.1f} m"
            )
        lines.append(f"- best background removal with 0 errors, {frame_name(frame)}: {found}")
    lines += ["", *mismatch_lines(results)]
    lines += [
        "",
        "Table II: background removal rates of the paper's settings.",
        "",
        "| CS | eta_1 (m/s) | d_xy (m) | removal (ours) | errors (ours) | objects removed (ours) "
        "| removal (paper) | errors (paper) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for row in f.table_ii:
        lines.append(
            f"| {frame_name(row.frame)} | {row.vr_threshold:.2f} | {row.d_xy:.1f} | {row.removal_rate:.2f} % | "
            f"{row.errors} | {row.object_removal_rate:.2f} % | {row.paper_removal_rate:.2f} % | {row.paper_errors} |"
        )
    lines += [
        "",
        "Columns: *removal*: share of the static background's detections (target -1) that the filter removes, the "
        "paper's 'removal rate'; *errors*: Table I's count at that setting; *objects removed (ours)*: share of the "
        "moving road users' detections that the filter removes (the paper does not report it; errors count only "
        "the windows where this loss is concentrated).",
        "",
        "Table I as heatmaps (FCS left, CCS right), one cell per setting with its error count, rows and columns "
        "in the tables' order, both panels on one colour scale from 0 (a shade is the same count in both); the "
        f"outlined cell with the asterisk (*) is the paper's chosen setting, eta_1 = {CHOSEN[0]:.2f} m/s and d_xy = "
        f"{CHOSEN[1]:.1f} m, as in the paper's Table I.",
        "",
        f"![Table I as a heatmap]({HEATMAP})",
    ]
    if results.figures.drawn.get("filter_scene"):
        lines += [
            "",
            f"What the filter removes at the chosen setting (FCS, eta_1 = {CHOSEN[0]:.2f} m/s, d_xy = "
            f"{CHOSEN[1]:.1f} m), one test sequence in the world frame: kept detections dark grey (background) "
            "and green (moving road users), removed background light blue, and the figure's point, the removed "
            "detections of moving road users, as large magenta crosses drawn on top of everything else; the legend "
            "counts each. Left the whole sequence, right a zoom on the removed road-user detections (the dashed box "
            "on the left).",
            "",
            f"![what the filter removes]({FILTER_SCENE})",
        ]
    return lines


def mismatch_lines(results: RunResults):
    """Our Table I beside the paper's error counts: the ranges, whether a 0-error cell exists, and why errors arise."""
    f = results.filter
    ranges = []
    for frame, grid in f.table_i.items():
        values = [value for row in grid.errors.data for value in row]
        ranges.append(f"{min(values):g}-{max(values):g} error windows per setting in {frame_name(frame)}")
    paper = [row.paper_errors for row in f.table_ii]
    zero = [frame_name(frame) for frame, best in f.best_removal_with_zero_errors.items() if best is not None]
    paper_zero = sum(1 for row in f.table_ii if row.paper_errors == 0)
    zero_text = (
        f"cells with 0 errors exist in {' and '.join(zero)}"
        if zero
        else f"no cell of ours has 0 errors, while {paper_zero} of the paper's five settings have 0"
    )
    lines = [
        f"Ours beside the paper: our grids count {' and '.join(ranges)}; the paper's Table II lists "
        f"{min(paper)}-{max(paper)} errors for its five settings, and {zero_text}."
    ]
    w = f.windows
    if w is None:
        return lines
    share = w.n_errors / w.n_windows if w.n_windows else float("nan")
    text = (
        f"At the paper's chosen setting ({frame_name(w.frame)}, eta_1 = {w.vr_threshold:.2f} m/s, d_xy = "
        f"{w.d_xy:.1f} m), {w.n_errors:,} of {w.n_windows:,} (object, {1000 * w.window_s:g} ms) windows are errors "
        f"({percent(share)})."
    )
    if w.n_errors:
        text += (
            f" An error window holds {w.mean_detections_error:.1f} detections on average, against "
            f"{w.mean_detections:.1f} for all windows, and {w.n_errors_sparse:,} of the {w.n_errors:,} hold at most 3, "
            f"where removing a single detection leaves less than {100 * w.min_kept:g} %"
            + (
                ": the errors come from sparse windows, whose few detections find too few neighbours within d_xy "
                "to pass the density test."
                if 2 * w.n_errors_sparse >= w.n_errors
                else "."
            )
            + _trend(f, w)
            + " The count depends on how many such sparse windows the data hold (see the data's statistics); the "
            "paper does not give its number of windows, so the counts compare only roughly."
        )
    return [*lines, "", text]


def _trend(f, w):
    """How the errors change with d_xy at the chosen eta_1, when they fall."""
    grid = f.table_i.get(w.frame)
    if grid is None:
        return ""
    errors = grid.errors.to_frame()
    rows = [index for index in errors.index if abs(index - w.vr_threshold) < 1e-9]
    if not rows:
        return ""
    row = errors.loc[rows[0]]
    first, last = row.index[0], row.index[-1]
    if not row[last] < row[first]:
        return ""
    return (
        f" A larger d_xy finds them neighbours: at eta_1 = {w.vr_threshold:.2f} m/s the errors fall from "
        f"{row[first]:g} at d_xy = {first:g} m to {row[last]:g} at {last:g} m."
    )


def figures(out: Path, results: RunResults, context: RunContext) -> dict[str, str]:
    """Table I's errors (from the saved results) as heatmaps, FCS beside CCS; what the filter removes in a sequence."""
    if results.filter is None:
        return {}
    save_figure(filter_scene_figure(context), out / FILTER_SCENE)
    save_figure(heatmap_figure(results), out / HEATMAP)
    return {"table1_heatmap": HEATMAP, "filter_scene": FILTER_SCENE}


def heatmap_figure(results: RunResults):
    """Table I's error counts, FCS beside CCS, on one colour scale from 0 (one shade is one count in both)."""
    import matplotlib.pyplot as plt

    grids = {frame: results.filter.table_i[frame].errors.to_frame() for frame in FRAMES}
    highest = max(float(np.nanmax(grid.to_numpy(dtype=float))) for grid in grids.values())
    fig, axes = plt.subplots(1, len(grids), figsize=(12, 5), sharey=True, layout="constrained")
    for ax, (frame, grid) in zip(axes, grids.items(), strict=True):
        plot_filter_errors(grid, ax=ax, chosen=CHOSEN, vmax=highest, colorbar=False)
        ax.set_title(f"Table I errors, {frame_name(frame)}")
    for ax in axes[1:]:
        ax.set_ylabel("")
    fig.colorbar(axes[0].images[0], ax=axes, label="error windows (object, 150 ms) below 75 % kept", shrink=0.9)
    return fig


#: How what the filter keeps and removes is drawn, in drawing order: the removed road-user detections, the figure's
#: point and few (tens against thousands), last and on top, large filled crosses in a colour no other kind has.
FILTER_SCENE_KINDS = (
    ("removed background", {"s": 0.6, "c": "lightskyblue", "marker": "o"}),
    ("kept background", {"s": 0.6, "c": "0.35", "marker": "o"}),
    ("kept, moving road users", {"s": 2.0, "c": "tab:green", "marker": "o"}),
    ("removed, moving road users", {"s": 70, "c": "magenta", "marker": "X", "edgecolors": "black", "linewidths": 0.6}),
)
#: Drawing order of the removed road-user detections: above every other kind.
REMOVED_OBJECTS_ZORDER = 10
#: The zoomed panel's margin around the removed road-user detections, m, and its smallest side, m.
ZOOM_MARGIN, ZOOM_MIN_SIDE = 5.0, 30.0


def filter_scene_figure(context: RunContext):
    """One test sequence in FCS at the chosen setting: the whole scene, and a zoom on the removed road users."""
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.patches import Rectangle

    drawn = context.sequences.fetch(context.drawn_sequence)
    prepared = FrameTransform(frame="frame").fit_transform(drawn.scenes.data)
    keep = DopplerDensityFilter(vr_threshold=CHOSEN[0], d_xy=CHOSEN[1]).fit_transform(prepared)["keep"]
    keep = keep.to_numpy(dtype=bool)
    is_object = np.asarray(drawn.scenes.target) >= 0
    x, y = prepared["x"].to_numpy(), prepared["y"].to_numpy()
    masks = (~keep & ~is_object, keep & ~is_object, keep & is_object, ~keep & is_object)
    box = zoom_box(x, y, masks[3] if masks[3].any() else is_object)
    width, height = scene_size(x, y, width=15.0, extra_height=1.8, panels=2)
    fig, axes = plt.subplots(1, 2, figsize=(width, height), layout="constrained")
    handles = []
    for k, (mask, (name, style)) in enumerate(zip(masks, FILTER_SCENE_KINDS, strict=True)):
        zorder = REMOVED_OBJECTS_ZORDER if k == len(masks) - 1 else k + 1
        for ax in axes:
            ax.scatter(x[mask], y[mask], zorder=zorder, label=name, **style)
        # The legend's markers all of one readable size, whatever the size drawn.
        edge = {"markeredgecolor": style["edgecolors"]} if "edgecolors" in style else {}
        handles.append(
            Line2D(
                [],
                [],
                linestyle="",
                color=style["c"],
                marker=style["marker"],
                markersize=8 if edge else 6,
                label=f"{name}: {int(mask.sum()):,}",
                **edge,
            )
        )
    overview, zoom = axes
    overview.set(xlabel="x (m, FCS)", ylabel="y (m, FCS)", aspect="equal", title="the whole sequence")
    if box is not None:
        (x0, x1), (y0, y1) = box
        overview.add_patch(
            Rectangle(
                (x0, y0),
                x1 - x0,
                y1 - y0,
                fill=False,
                edgecolor="black",
                linestyle="--",
                linewidth=1.2,
                zorder=REMOVED_OBJECTS_ZORDER + 1,
            )
        )
        zoom.set(xlim=(x0, x1), ylim=(y0, y1))
    zoom.set(xlabel="x (m, FCS)", aspect="equal", title="zoom on the removed road-user detections (dashed box)")
    fig.suptitle(
        f"what the filter removes: test sequence {drawn.id}, FCS, eta_1 = {CHOSEN[0]:.2f} m/s, d_xy = {CHOSEN[1]:.1f} m"
    )
    fig.legend(handles=handles, loc="outside lower center", ncol=4, fontsize=10, frameon=False)
    return fig


def zoom_box(x, y, mask):
    """``((x0, x1), (y0, y1))``, m: a square around ``mask``'s detections (margin, smallest side); None without any."""
    if not mask.any():
        return None
    centre = np.array([(x[mask].min() + x[mask].max()) / 2, (y[mask].min() + y[mask].max()) / 2])
    side = max(float(np.ptp(x[mask])), float(np.ptp(y[mask]))) + 2 * ZOOM_MARGIN
    half = max(side, ZOOM_MIN_SIDE) / 2
    return (centre[0] - half, centre[0] + half), (centre[1] - half, centre[1] + half)


SECTION = Section("filter", markdown, figures)
