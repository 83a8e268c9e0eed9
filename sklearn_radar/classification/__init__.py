"""Road-user classification: the stage after clustering (semantic instance segmentation).

The RadarScenes road-user classes and their mapping from ``label_id``
(:func:`road_user_class`) and to the devkit's numbering (:func:`devkit_class_index`),
the features of a cluster (:func:`cluster_features`), the classifier of clusters
(:class:`ClusterClassifier`) and its road users in a pipeline
(:func:`predict_instances`), its files
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
    devkit_class_index,
    road_user_class,
)
from ._cluster_classifier import ClusterClassifier
from ._features import CLUSTER_FEATURES, cluster_features
from ._instances import predict_instances
from ._persist import ClassifierVersionWarning, load_classifier, save_classifier
from ._point_classifier import NEIGHBOURHOOD_FEATURES, POINT_FEATURES, PointClassifier

__all__ = [
    "BACKGROUND",
    "CLASS_OF_LABEL",
    "CLUSTER_FEATURES",
    "DEVKIT_CLASS_INDEX",
    "DEVKIT_CLASS_NAMES",
    "IGNORED",
    "NEIGHBOURHOOD_FEATURES",
    "POINT_FEATURES",
    "ROAD_USER_CLASSES",
    "ClassifierVersionWarning",
    "ClusterClassifier",
    "PointClassifier",
    "cluster_features",
    "devkit_class_index",
    "load_classifier",
    "predict_instances",
    "road_user_class",
    "save_classifier",
]
