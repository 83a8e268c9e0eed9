"""sklearn-radar: multi-stage clustering of automotive radar detections.

An implementation of Scheiner, Appenrodt, Dickmann and Sick, "A Multi-Stage
Clustering Framework for Automotive Radar Data" (ITSC 2019) as scikit-learn
estimators, with a RadarScenes reader/writer and a scene simulator.
The detection table is described in :mod:`sklearn_radar._schema`.
"""

from ._schema import LABELS, RADARSCENES_MOUNTING, describe_columns, instance_target
from .cluster import ClusterMerger, RadarDBSCAN
from .preprocessing import DopplerDensityFilter, FrameTransform

__version__ = "0.1.0.dev0"

__all__ = [
    "LABELS",
    "RADARSCENES_MOUNTING",
    "ClusterMerger",
    "DopplerDensityFilter",
    "FrameTransform",
    "RadarDBSCAN",
    "__version__",
    "describe_columns",
    "instance_target",
]
