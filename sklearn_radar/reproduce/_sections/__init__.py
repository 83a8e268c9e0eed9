"""The sections of ``report.md``, one module each, in the order they appear.

Each module defines ``SECTION``, a :class:`Section`: a name, a
``markdown(results) -> list[str]`` function and optionally a
``figures(out, results, context) -> dict[str, str]`` function.  Sections
read the typed :class:`~sklearn_radar.reproduce._results.RunResults`, never
raw dictionaries.  To add a section (a metric, a data preset, a figure):
write a module here with its ``SECTION`` and add it to :data:`SECTIONS`.
"""

from . import (
    _baselines,
    _classification,
    _comparison,
    _data,
    _figures,
    _filter,
    _filter_effect,
    _header,
    _instance,
    _learned,
    _objects,
    _stage1,
    _stage2,
    _summary,
    _tracking,
)
from ._base import Section

#: The report's sections, in order.  Figures are drawn in this order too, before any markdown is written.
SECTIONS: tuple[Section, ...] = (
    _header.SECTION,
    _summary.SECTION,
    _data.SECTION,
    _filter.SECTION,
    _stage1.SECTION,
    _stage2.SECTION,
    _filter_effect.SECTION,
    _baselines.SECTION,
    _instance.SECTION,
    _objects.SECTION,
    _learned.SECTION,
    _tracking.SECTION,
    _classification.SECTION,
    _figures.SECTION,
    _comparison.SECTION,
)

__all__ = ["SECTIONS", "Section"]
