"""The report of a reproduce run: ``report.md`` and its figures, built from the sections of :mod:`._sections`."""

from __future__ import annotations

from pathlib import Path

from .._files import atomic_write_text
from ._context import RunContext
from ._results import RunResults
from ._sections import SECTIONS


def write_figures(out, results: RunResults, context: RunContext, sections=SECTIONS):
    """Draw every section's figures into ``out`` (none without matplotlib); return ``results.figures``."""
    out = Path(out)
    try:
        import matplotlib

        matplotlib.use("Agg")
    except ImportError:
        results.figures.missing = "matplotlib is not installed"
        return results.figures
    for section in sections:
        if section.figures is not None:
            results.figures.drawn.update(section.figures(out, results, context))
    return results.figures


def report_markdown(results: RunResults, sections=SECTIONS):
    """The text of ``report.md``: every section's lines, in order."""
    lines = []
    for section in sections:
        lines += section.markdown(results)
    return "\n".join(lines) + "\n"


def write_report(out, results: RunResults, context: RunContext | None = None, sections=SECTIONS):
    """Write ``report.md`` into ``out`` atomically, figures first with ``context``; return its path."""
    out = Path(out)
    if context is not None:
        write_figures(out, results, context, sections)
    path = out / "report.md"
    atomic_write_text(path, report_markdown(results, sections))
    return path
