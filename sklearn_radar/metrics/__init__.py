"""Scores and targets for radar clustering.

The radar V-measure and the pre-clustered target of Scheiner et al. 2019 (Sec. "Parameter Optimization"), and
object-level scores per time frame: panoptic quality, coverage and the share of background-only clusters; and
the tracking quality of object ids over frames: ID switches, MOTA and IDF1.
"""

from ._instance import (
    background_share,
    instance_coverage,
    instance_scores,
    make_instance_scorer,
    panoptic_quality,
    panoptic_quality_scorer,
)
from ._target import precluster_target
from ._tracking import tracking_scores
from ._v_measure import radar_homogeneity_completeness_v_measure, radar_v_measure, radar_v_measure_scorer

__all__ = [
    "background_share",
    "instance_coverage",
    "instance_scores",
    "make_instance_scorer",
    "panoptic_quality",
    "panoptic_quality_scorer",
    "precluster_target",
    "radar_homogeneity_completeness_v_measure",
    "radar_v_measure",
    "radar_v_measure_scorer",
    "tracking_scores",
]
