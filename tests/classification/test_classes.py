"""The road-user classes and their mapping from RadarScenes label_id, against the devkit's own mapping."""

import re

import numpy as np
import pytest
from radar_scenes.labels import ClassificationLabel, Label

from sklearn_radar import LABELS
from sklearn_radar.classification import (
    BACKGROUND,
    CLASS_OF_LABEL,
    DEVKIT_CLASS_INDEX,
    DEVKIT_CLASS_NAMES,
    IGNORED,
    ROAD_USER_CLASSES,
    ClusterClassifier,
    devkit_class_index,
    road_user_class,
)


def test_mapping_is_the_devkits_translation():
    # Every RadarScenes label goes where the devkit's ClassificationLabel.translation_dict sends it: the devkit's
    # class name of our code, and None (left out) exactly for our "ignored" code.
    translation = ClassificationLabel.translation_dict()
    assert set(CLASS_OF_LABEL) == {label.value for label in Label} == set(LABELS)
    for label, devkit_class in translation.items():
        code = CLASS_OF_LABEL[label.value]
        if devkit_class is None:
            assert code == IGNORED, label
        else:
            assert DEVKIT_CLASS_NAMES[code] == devkit_class.name, label


def test_devkit_class_index_is_the_value_of_the_devkits_class_of_that_name():
    assert set(DEVKIT_CLASS_INDEX) == set(DEVKIT_CLASS_NAMES) == {*ROAD_USER_CLASSES, BACKGROUND}
    for code, index in DEVKIT_CLASS_INDEX.items():
        assert ClassificationLabel(index).name == DEVKIT_CLASS_NAMES[code], code
    assert DEVKIT_CLASS_INDEX[BACKGROUND] == ClassificationLabel.STATIC.value
    # Every label_id lands on the devkit's index of its class (through our code).
    for label, devkit_class in ClassificationLabel.translation_dict().items():
        if devkit_class is not None:
            assert DEVKIT_CLASS_INDEX[CLASS_OF_LABEL[label.value]] == devkit_class.value, label


def test_the_devkits_none_classes_are_animal_and_other():
    ignored = {label.name for label, value in ClassificationLabel.translation_dict().items() if value is None}
    assert ignored == {"ANIMAL", "OTHER"}
    assert {LABELS[label] for label, code in CLASS_OF_LABEL.items() if code == IGNORED} == ignored


def test_codes_are_the_five_road_user_classes_and_background():
    assert ROAD_USER_CLASSES == {0: "car", 1: "large vehicle", 2: "two-wheeler", 3: "pedestrian", 4: "pedestrian group"}
    assert set(CLASS_OF_LABEL.values()) == {*ROAD_USER_CLASSES, BACKGROUND, IGNORED}
    assert CLASS_OF_LABEL[11] == BACKGROUND == -1 and IGNORED == -2
    assert set(DEVKIT_CLASS_NAMES) == {*ROAD_USER_CLASSES, BACKGROUND}


def test_road_user_class_by_hand():
    label_id = np.array([0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11])
    expected = [0, 1, 1, 1, 1, 2, 2, 3, 4, -2, -2, -1]
    assert road_user_class(label_id).tolist() == expected
    assert road_user_class(label_id.astype(np.float64)).tolist() == expected  # integral floats are integers
    assert road_user_class([]).shape == (0,)
    assert road_user_class(np.array([7, 7], dtype=np.uint8)).dtype == np.int64


@pytest.mark.parametrize("bad", [[12], [-1], [0.5], ["CAR"], [np.nan]])
def test_road_user_class_refuses_values_that_are_no_label_id(bad):
    with pytest.raises(ValueError, match="label_id"):
        road_user_class(bad)


def test_devkit_class_index_of_every_label_is_the_devkits_class():
    # Reference: the devkit's own enum and translation (radar_scenes.labels), label by label.
    labels = [label for label, devkit_class in ClassificationLabel.translation_dict().items() if devkit_class]
    expected = [ClassificationLabel.translation_dict()[label].value for label in labels]
    codes = road_user_class([label.value for label in labels])
    assert devkit_class_index(codes).tolist() == expected
    assert devkit_class_index(codes.astype(np.float64)).dtype == np.int64
    assert devkit_class_index([]).shape == (0,)


@pytest.mark.parametrize("bad", [[-2], [5], [0.5], ["CAR"]])
def test_devkit_class_index_refuses_codes_it_cannot_map(bad):
    with pytest.raises(ValueError, match="class codes -1 to 4"):
        devkit_class_index(bad)


#: A row of the code table of ClusterClassifier's docstring: code, class name, devkit name and value (or "none").
_TABLE_ROW = re.compile(r"^\s*(-?\d)\s{2,}([a-z][a-z -]*?)\s{2,}(?:([A-Z_]+) (\d)|none \(ANIMAL, OTHER\))\s*$")


def test_the_class_docstring_shows_each_code_with_the_devkits_class():
    rows = [match.groups() for match in map(_TABLE_ROW.match, ClusterClassifier.__doc__.splitlines()) if match]
    shown = {int(code): (name, devkit, value) for code, name, devkit, value in rows}
    assert len(rows) == len(shown) == 7, rows
    assert shown.pop(IGNORED) == ("ignored", None, None)
    for code, (name, devkit, value) in shown.items():
        assert name == {**ROAD_USER_CLASSES, BACKGROUND: "background"}[code]
        assert ClassificationLabel[devkit].value == int(value), code
        assert [ClassificationLabel(int(value)).name] == [DEVKIT_CLASS_NAMES[code]]
    # Every class the devkit translates a label into is in the table under the code of that label.
    for label, devkit_class in ClassificationLabel.translation_dict().items():
        if devkit_class is not None:
            assert shown[CLASS_OF_LABEL[label.value]][1] == devkit_class.name, label
