"""Tables I and II: the Doppler-density filter's errors and background removal, and the Table I heatmap."""

from __future__ import annotations

from pathlib import Path

from .._constants import FRAMES
from .._context import RunContext
from .._results import RunResults
from ._base import Section, frame_name, grid_markdown, percent, save_figure

#: The heatmap's file in the output folder.
HEATMAP = "table1_heatmap.png"


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
    lines += ["", f"![Table I as a heatmap]({HEATMAP})"]
    return lines


def figures(out: Path, results: RunResults, context: RunContext) -> dict[str, str]:
    """Table I's error counts as heatmaps, FCS beside CCS."""
    if context.filter_grids is None:
        return {}
    import matplotlib.pyplot as plt

    from ...evaluation import plot_filter_errors

    fig, axes = plt.subplots(1, 2, figsize=(12, 5))
    for ax, frame in zip(axes, FRAMES, strict=True):
        plot_filter_errors(context.filter_grids[frame].errors, ax=ax)
        ax.set_title(f"Table I errors, {frame_name(frame)}")
    save_figure(fig, out / HEATMAP)
    return {"table1_heatmap": HEATMAP}


SECTION = Section("filter", markdown, figures)
