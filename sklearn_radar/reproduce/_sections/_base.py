"""What every report section is, and the formatting that several sections share."""

from __future__ import annotations

import io
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._constants import FRAME_NAMES
from .._context import RunContext
from .._io import atomic_write
from .._results import ExperimentResult, GridTable, RunResults

#: Markdown of a section: its lines, each starting a new line of report.md; [] leaves the section out.
Markdown = Callable[[RunResults], list[str]]

#: Figures of a section: draw them into the output folder, return {figure name: file name} of those drawn.
Figures = Callable[[Path, RunResults, RunContext], dict[str, str]]


@dataclass(frozen=True)
class Section:
    """One section of ``report.md``.

    Attributes
    ----------
    name : str
        Short name, e.g. ``"filter"``.
    markdown : callable
        ``markdown(results: RunResults) -> list[str]``: the section's lines
        (typically a blank line and a heading first); ``[]`` when there is
        nothing to report, e.g. a step that did not run.
    figures : callable or None, default=None
        ``figures(out: Path, results: RunResults, context: RunContext) ->
        dict[str, str]``: draw the section's figures into ``out`` (with
        :func:`save_figure`) and return ``{figure name: file name}`` of those
        drawn; they are recorded in ``results.figures`` before any markdown
        is written.  Called only when matplotlib is installed, with the
        Agg backend selected.
    """

    name: str
    markdown: Markdown
    figures: Figures | None = None


def format_params(params):
    """``{"cluster__eps_xy": 0.6, ...}`` -> ``"eps_xy=0.6, ..."``: what the experiment sets, 3 significant digits.

    Parameters
    ----------
    params : dict or None
        Pipeline parameters.

    Returns
    -------
    text : str
        Without ``eps_t``, ``n_jobs``, ``mode`` and ``metric``, which every
        setting of a method shares.
    """
    shown = []
    for key, value in (params or {}).items():
        name = key.split("__")[-1]
        if name in ("eps_t", "n_jobs", "mode", "metric"):
            continue
        if isinstance(value, (int, float)):
            shown.append(f"{_SHORT.get(name, name)}={value:.3g}")
        else:
            shown.append(f"{name}={value}")
    return ", ".join(shown)


_SHORT = {"eps_phi": "eps_phi (rad)"}


def percent(value):
    """A share 0-1 as ``"71.55 %"``; ``"-"`` for None or NaN."""
    return "-" if value is None or (isinstance(value, float) and np.isnan(value)) else f"{100 * value:.2f} %"


def frame_name(frame):
    """``"frame"`` -> ``"FCS"``, ``"car"`` -> ``"CCS"``."""
    return FRAME_NAMES[frame]


def grid_markdown(table: GridTable):
    """A table of Table I as a markdown table."""
    frame = table.to_frame()
    header = "| eta_1 (m/s) \\ d_xy (m) | " + " | ".join(f"{c:.1f}" for c in frame.columns) + " |"
    rule = "|---|" + "---|" * len(frame.columns)
    rows = [f"| {i:.2f} | " + " | ".join(f"{v:g}" for v in frame.loc[i]) + " |" for i in frame.index]
    return "\n".join([header, rule, *rows])


def experiment_table(title, rows: list[ExperimentResult]):
    """A heading and the table of Tables III and IV, one row per experiment, by number.

    Parameters
    ----------
    title : str
        The heading's text.
    rows : list of ExperimentResult

    Returns
    -------
    lines : list of str
    """
    lines = [
        "",
        f"## {title}",
        "",
        "| # | method | CS | filtered | V1 (ours) | V1 (paper) | our parameters | paper's parameters |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for e in sorted(rows, key=lambda e: e.number):
        lines.append(experiment_row(e))
    return lines


def experiment_row(e: ExperimentResult):
    """One experiment's row of Table III or IV."""
    cells = (
        e.number,
        e.method,
        frame_name(e.frame),
        "yes" if e.filtered else "no",
        percent(e.v1_test),
        f"{e.paper_v1_percent:.2f} %",
        format_params(e.params),
        format_params(e.paper_params),
    )
    return "| " + " | ".join(str(cell) for cell in cells) + " |"


def save_figure(fig, path):
    """Lay out ``fig``, write it to ``path`` as PNG (90 dpi) atomically, and close it."""
    import matplotlib.pyplot as plt

    buffer = io.BytesIO()
    fig.tight_layout()
    fig.savefig(buffer, format="png", dpi=90)
    plt.close(fig)
    atomic_write(path, lambda stream: stream.write(buffer.getvalue()))


__all__ = [
    "Figures",
    "Markdown",
    "Section",
    "experiment_row",
    "experiment_table",
    "format_params",
    "frame_name",
    "grid_markdown",
    "percent",
    "save_figure",
]
