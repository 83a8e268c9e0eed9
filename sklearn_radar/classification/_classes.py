"""The road-user classes and their mapping from the RadarScenes ``label_id``.

RadarScenes annotates 12 classes (:data:`~sklearn_radar.LABELS`).  Its devkit
(``radar_scenes.labels.ClassificationLabel.translation_dict``, radar-scenes
1.0.4) reduces them to the five road-user classes used for classification,
plus STATIC, and omits ANIMAL and OTHER from training and evaluation.  This
module follows that mapping exactly; only the codes differ (the devkit numbers
CAR 0, PEDESTRIAN 1, PEDESTRIAN_GROUP 2, TWO_WHEELER 3, LARGE_VEHICLE 4,
STATIC 5; :data:`DEVKIT_CLASS_NAMES` gives the devkit's name of each code):

==========  ===================  =========================================
code        class                RadarScenes ``label_id`` (name)
==========  ===================  =========================================
0           car                  0 (CAR)
1           large vehicle        1 (LARGE_VEHICLE), 2 (TRUCK), 3 (BUS),
                                 4 (TRAIN)
2           two-wheeler          5 (BICYCLE), 6 (MOTORIZED_TWO_WHEELER)
3           pedestrian           7 (PEDESTRIAN)
4           pedestrian group     8 (PEDESTRIAN_GROUP)
-1          background           11 (STATIC)
-2          ignored              9 (ANIMAL), 10 (OTHER)
==========  ===================  =========================================

Ignored detections (-2) are what the devkit maps to ``None``: they are left
out of training (a cluster matched to an ANIMAL or OTHER instance teaches the
classifiers nothing) and must be left out of evaluation as well; the
classifiers never predict -2.
"""

from __future__ import annotations

import numpy as np
from sklearn.utils._param_validation import validate_params

from .._schema import LABELS

__all__ = [
    "BACKGROUND",
    "CLASS_OF_LABEL",
    "DEVKIT_CLASS_INDEX",
    "DEVKIT_CLASS_NAMES",
    "IGNORED",
    "ROAD_USER_CLASSES",
    "devkit_class_index",
    "road_user_class",
]

#: Code of static background (RadarScenes STATIC) and of detections that no road user explains.
BACKGROUND = -1
#: Code of the RadarScenes classes the devkit omits from training and evaluation (ANIMAL, OTHER).
IGNORED = -2

#: ``{code: name}`` of the five road-user classes.
ROAD_USER_CLASSES = {0: "car", 1: "large vehicle", 2: "two-wheeler", 3: "pedestrian", 4: "pedestrian group"}

#: ``{RadarScenes label_id: code}``, the devkit's ``ClassificationLabel.translation_dict``.
CLASS_OF_LABEL = {
    0: 0,  # CAR
    1: 1,  # LARGE_VEHICLE
    2: 1,  # TRUCK
    3: 1,  # BUS
    4: 1,  # TRAIN
    5: 2,  # BICYCLE
    6: 2,  # MOTORIZED_TWO_WHEELER
    7: 3,  # PEDESTRIAN
    8: 4,  # PEDESTRIAN_GROUP
    9: IGNORED,  # ANIMAL: None in the devkit
    10: IGNORED,  # OTHER: None in the devkit
    11: BACKGROUND,  # STATIC
}
assert set(CLASS_OF_LABEL) == set(LABELS)

#: ``{code: devkit ClassificationLabel name}``, for writing predictions in the devkit's terms.
DEVKIT_CLASS_NAMES = {
    0: "CAR",
    1: "LARGE_VEHICLE",
    2: "TWO_WHEELER",
    3: "PEDESTRIAN",
    4: "PEDESTRIAN_GROUP",
    BACKGROUND: "STATIC",
}

#: ``{code: devkit ClassificationLabel value}``: the class index a predictions file of the devkit holds (CAR 0,
#: PEDESTRIAN 1, PEDESTRIAN_GROUP 2, TWO_WHEELER 3, LARGE_VEHICLE 4, STATIC 5).  Background, and noise, is STATIC:
#: the devkit's own class of every detection that is no road user (it has no "unclassified" class).
DEVKIT_CLASS_INDEX = {0: 0, 1: 4, 2: 3, 3: 1, 4: 2, BACKGROUND: 5}

_LOOKUP = np.array([CLASS_OF_LABEL[label] for label in range(len(LABELS))], dtype=np.int64)
#: DEVKIT_CLASS_INDEX as a lookup indexed by ``code - BACKGROUND``.
_DEVKIT_LOOKUP = np.array([DEVKIT_CLASS_INDEX[code] for code in range(BACKGROUND, len(ROAD_USER_CLASSES))])


@validate_params({"label_id": ["array-like"]}, prefer_skip_nested_validation=True)
def road_user_class(label_id):
    """Road-user class code of each RadarScenes ``label_id`` (the devkit's mapping).

    Read more in the :ref:`User Guide <user-guide-classification>`.

    Parameters
    ----------
    label_id : array-like of int, shape (n_detections,)
        RadarScenes class of each detection, 0-11 (:data:`~sklearn_radar.LABELS`).

    Returns
    -------
    classes : ndarray of int64, shape (n_detections,)
        0 car, 1 large vehicle (also truck, bus, train), 2 two-wheeler
        (bicycle, motorised two-wheeler), 3 pedestrian, 4 pedestrian group,
        -1 background (STATIC), -2 ignored (ANIMAL, OTHER: left out of
        training and evaluation, as the devkit maps them to None).

    Raises
    ------
    ValueError
        If a value is not an integer label id 0-11.

    Examples
    --------
    >>> from sklearn_radar.classification import road_user_class
    >>> road_user_class([0, 2, 5, 7, 8, 9, 11]).tolist()
    [0, 1, 2, 3, 4, -2, -1]
    """
    values = np.asarray(label_id)
    if values.dtype.kind == "f" and np.all(np.isfinite(values)) and np.all(values == np.round(values)):
        values = values.astype(np.int64)
    if values.dtype.kind not in "iu":
        raise ValueError(
            f"label_id must hold integer RadarScenes label ids 0-{len(LABELS) - 1}, got dtype {values.dtype}"
        )
    bad = (values < 0) | (values >= len(LABELS))
    if bad.any():
        raise ValueError(
            f"label_id must hold RadarScenes label ids 0-{len(LABELS) - 1}, got {values[bad][0]!r} "
            f"({int(bad.sum())} value(s) out of range)"
        )
    return _LOOKUP[values.astype(np.int64, copy=False)]


@validate_params({"classes": ["array-like"]}, prefer_skip_nested_validation=True)
def devkit_class_index(classes):
    """The RadarScenes devkit's ``ClassificationLabel`` value of each road-user class code.

    The classifiers predict the codes of :func:`road_user_class`; the devkit
    numbers the same classes otherwise (:data:`DEVKIT_CLASS_INDEX`; the table
    of both is in :class:`ClusterClassifier`'s description).

    Read more in the :ref:`User Guide <user-guide-classification>`.

    Parameters
    ----------
    classes : array-like of int, shape (n_detections,)
        Road-user class codes, -1 (background and noise) to 4, as
        :meth:`ClusterClassifier.predict` returns them.

    Returns
    -------
    devkit_classes : ndarray of int64, shape (n_detections,)
        The devkit's class index of each: background is STATIC (5), the
        devkit's class of every detection that is no road user.

    Raises
    ------
    ValueError
        If a value is not a code -1 to 4 (ignored, -2, has no devkit class:
        the devkit maps ANIMAL and OTHER to None).

    Examples
    --------
    >>> from sklearn_radar.classification import devkit_class_index
    >>> devkit_class_index([0, 1, 2, 3, 4, -1]).tolist()
    [0, 4, 3, 1, 2, 5]
    """
    values = np.asarray(classes)
    if values.dtype.kind == "f" and np.all(np.isfinite(values)) and np.all(values == np.round(values)):
        values = values.astype(np.int64)
    if values.dtype.kind not in "iu":
        raise ValueError(f"classes must hold integer road-user class codes -1 to 4, got dtype {values.dtype}")
    bad = (values < BACKGROUND) | (values >= len(ROAD_USER_CLASSES))
    if bad.any():
        raise ValueError(
            f"classes must hold road-user class codes -1 to 4, got {values[bad][0]!r} ({int(bad.sum())} value(s); "
            "ignored detections, -2, have no devkit class)"
        )
    return _DEVKIT_LOOKUP[values.astype(np.int64, copy=False) - BACKGROUND]
