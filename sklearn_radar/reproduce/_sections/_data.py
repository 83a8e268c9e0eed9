"""The data the run used: the statistics of the simulated (or loaded) detections."""

from __future__ import annotations

from ... import LABELS
from ...classification import CLASS_OF_LABEL, ROAD_USER_CLASSES
from .._results import RunResults
from ._base import Section


def markdown(results: RunResults) -> list[str]:
    """The statistics of the data, as ``sklearn-radar stats`` prints them; [] when they were not measured."""
    statistics = results.statistics
    if statistics is None:
        return []
    return [
        "",
        "## The data",
        "",
        "Statistics of all sequences (both halves), as `sklearn-radar stats --data FOLDER` prints them. "
        "'static share' is the share of detections that belong to no moving road user (the target's background, "
        "label -1); the table "
        "gives the mean number of detections of one object in one scan in which it is seen, by class and by the "
        "object's range in m. Few detections per object per scan make the filter's error windows "
        "(Table I) and split clusters more likely. The paper used a pre-release of RadarScenes (real data); "
        "absolute scores are comparable only as far as these statistics are.",
        "",
        "```",
        *statistics.text.splitlines(),
        "```",
        "",
        class_names_line(),
    ]


def class_names_line():
    """How the library's road-user classes, the names the classification section uses, group the data's labels."""
    grouped = "; ".join(
        f"{name}: {', '.join(LABELS[label] for label, code in CLASS_OF_LABEL.items() if code == class_code)}"
        for class_code, name in ROAD_USER_CLASSES.items()
    )
    return (
        "The table names the RadarScenes labels; the classification section names the library's road-user classes "
        f"(`sklearn_radar.classification`), which group them: {grouped}."
    )


SECTION = Section("data", markdown)
