"""Road-user classification: the stage after clustering (semantic instance segmentation).

The RadarScenes road-user classes and their mapping from ``label_id``
(:func:`road_user_class`), the features of a cluster (:func:`cluster_features`),
the classifier of clusters (:class:`ClusterClassifier`), its files
(:func:`save_classifier`, :func:`load_classifier`) and the baseline that
classifies single detections instead (:class:`PointClassifier`).
"""

from ._classes import (
    BACKGROUND,
    CLASS_OF_LABEL,
    DEVKIT_CLASS_INDEX,
    DEVKIT_CLASS_NAMES,
    IGNORED,
    ROAD_USER_CLASSES,
    road_user_class,
)
from ._cluster_classifier import ClusterClassifier
from ._features import CLUSTER_FEATURES, cluster_features
from ._persist import ClassifierVersionWarning, load_classifier, save_classifier
from ._point_classifier import POINT_FEATURES, PointClassifier

__all__ = [
    "BACKGROUND",
    "CLASS_OF_LABEL",
    "CLUSTER_FEATURES",
    "DEVKIT_CLASS_INDEX",
    "DEVKIT_CLASS_NAMES",
    "IGNORED",
    "POINT_FEATURES",
    "ROAD_USER_CLASSES",
    "ClassifierVersionWarning",
    "ClusterClassifier",
    "PointClassifier",
    "cluster_features",
    "load_classifier",
    "road_user_class",
    "save_classifier",
]
