"""Scores and targets for radar clustering.

The radar V-measure and the pre-clustered target of Scheiner et al. 2019 (Sec. "Parameter Optimization"), and
object-level scores per time window: panoptic quality, coverage, the share of background-only clusters and the
missed and false segments by cause; and
the tracking quality of object ids over windows: ID switches, MOTA, IDF1 and HOTA; and the semantic scores of
classified road users: class-aware panoptic quality, mAP, point-wise macro-F1 and coverage, and where the
class-aware panoptic quality goes (a confusion matrix of matched segments).
"""

from ._class_errors import class_errors
from ._errors import instance_errors
from ._hota import hota_scores
from ._instance import (
    background_share,
    instance_coverage,
    instance_scores,
    make_instance_scorer,
    panoptic_quality,
    panoptic_quality_scorer,
)
from ._semantic import (
    class_panoptic_quality,
    make_semantic_scorer,
    mean_average_precision,
    pointwise_macro_f1,
    semantic_scores,
)
from ._target import precluster_target
from ._tracking import tracking_scores
from ._v_measure import radar_homogeneity_completeness_v_measure, radar_v_measure, radar_v_measure_scorer

__all__ = [
    "background_share",
    "class_errors",
    "class_panoptic_quality",
    "hota_scores",
    "instance_coverage",
    "instance_errors",
    "instance_scores",
    "make_instance_scorer",
    "make_semantic_scorer",
    "mean_average_precision",
    "panoptic_quality",
    "panoptic_quality_scorer",
    "pointwise_macro_f1",
    "precluster_target",
    "radar_homogeneity_completeness_v_measure",
    "radar_v_measure",
    "radar_v_measure_scorer",
    "semantic_scores",
    "tracking_scores",
]
