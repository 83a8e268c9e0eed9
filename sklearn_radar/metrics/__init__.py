"""Scores and targets for radar clustering (Scheiner et al. 2019, Sec. "Parameter Optimization")."""

from ._target import precluster_target
from ._v_measure import radar_homogeneity_completeness_v_measure, radar_v_measure, radar_v_measure_scorer

__all__ = [
    "precluster_target",
    "radar_homogeneity_completeness_v_measure",
    "radar_v_measure",
    "radar_v_measure_scorer",
]
