"""Tests of the class signatures of the simulator (issue 31 item 6): object RCS, aspect RCS, wheel micro-Doppler."""

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sklearn_radar import FrameTransform
from sklearn_radar.classification import cluster_features
from sklearn_radar.datasets import make_scenes
from sklearn_radar.datasets._presets import DIFFICULTY_PRESETS
from sklearn_radar.datasets._scenario import ROAD_USER_CLASSES, aspect_rcs

from .test_preset_pins import digest

SIGNATURES_OFF = {"rcs_object_spread": 0.0, "rcs_aspect": 0.0, "wheel_micro_doppler": 0.0}
CAR, BICYCLE, PEDESTRIAN = 0, 5, 7

#: ``make_scenes(n_sequences=2, duration=6.0, random_state=7)`` of the realistic preset before these knobs
#: (main at 8bc7dbf): rows and digest of test_preset_pins.
REALISTIC_BEFORE_SIGNATURES = (27671, "6cf9478f0366a3ce1ccc57d9653a020d0e5aeed342d6236901446ed2c2eacb29")


def _scenes(knobs=None, difficulty="easy", seed=2, n=2, duration=10.0):
    return make_scenes(n_sequences=n, duration=duration, random_state=seed, difficulty=difficulty, knobs=knobs)


def test_the_realistic_preset_turns_the_signatures_on_and_easy_leaves_them_off():
    assert {k: DIFFICULTY_PRESETS["easy"][k] for k in SIGNATURES_OFF} == SIGNATURES_OFF
    assert all(DIFFICULTY_PRESETS["realistic"][k] > 0 for k in SIGNATURES_OFF)


def test_realistic_with_the_signatures_off_is_the_realistic_preset_before_them():
    scenes = make_scenes(n_sequences=2, duration=6.0, random_state=7, knobs=SIGNATURES_OFF)
    assert (len(scenes.data), digest(scenes)) == REALISTIC_BEFORE_SIGNATURES


@pytest.mark.parametrize(
    "knobs, match",
    [
        ({"rcs_object_spread": -1.0}, "rcs_object_spread"),
        ({"rcs_object_spread": np.inf}, "rcs_object_spread"),
        ({"rcs_aspect": np.nan}, "rcs_aspect"),
        ({"rcs_aspect": True}, "rcs_aspect"),
        ({"wheel_micro_doppler": 1.5}, "wheel_micro_doppler"),
        ({"wheel_micro_doppler": -0.1}, "wheel_micro_doppler"),
        ({"wheel_micro_doppler": "some"}, "wheel_micro_doppler"),
    ],
)
def test_bad_signature_knobs_raise_a_value_error_naming_the_knob(knobs, match):
    with pytest.raises(ValueError, match=match):
        make_scenes(n_sequences=1, duration=1.0, random_state=0, knobs=knobs)


def test_aspect_rcs_of_a_car_by_hand():
    car = ROAD_USER_CLASSES["car"]  # rcs_side 6 dB, rcs_oblique 6 dB
    broadside, head_on, oblique = np.pi / 2, 0.0, np.pi / 4
    angles = np.array([broadside, head_on, oblique, np.pi])
    expected = [
        3.0 + 6.0 * (1 - 2 / np.pi),
        -3.0 + 6.0 * (1 - 2 / np.pi),
        -6.0 * 2 / np.pi,
        -3.0 + 6.0 * (1 - 2 / np.pi),
    ]
    np.testing.assert_allclose(aspect_rcs(car, np.cos(angles), np.sin(angles)), expected, atol=1e-12)
    assert np.all(aspect_rcs(ROAD_USER_CLASSES["pedestrian"], np.cos(angles), np.sin(angles)) == 0)


@settings(max_examples=50, deadline=None)
@given(side=st.floats(0, 20), oblique=st.floats(0, 20), angle=st.floats(-np.pi, np.pi))
def test_aspect_rcs_averages_to_zero_and_is_symmetric(side, oblique, angle):
    params = {"rcs_side": side, "rcs_oblique": oblique}
    grid = np.linspace(-np.pi, np.pi, 4000, endpoint=False)  # uniform aspects: the mean of each term is 0
    assert abs(np.mean(aspect_rcs(params, np.cos(grid), np.sin(grid)))) < 1e-3 * (1 + side + oblique)
    # Left and right, front and back look alike.
    value = aspect_rcs(params, np.cos(angle), np.sin(angle))
    for mirrored in (-angle, np.pi - angle):
        assert aspect_rcs(params, np.cos(mirrored), np.sin(mirrored)) == pytest.approx(value, abs=1e-9)


@pytest.fixture(scope="module")
def easy():
    return _scenes()


def _rows(scenes, label):
    d = scenes.data
    return d[d["label_id"] == label].reset_index(drop=True)


def test_aspect_rcs_changes_the_rcs_of_each_detection_within_the_class_band(easy):
    # The aspect term draws nothing: on the easy data only the RCS of the road users' detections change.
    other = _scenes({"rcs_aspect": 1.0})
    pd.testing.assert_frame_equal(other.data.drop(columns="rcs"), easy.data.drop(columns="rcs"))
    for label, (low, high) in {CAR: (-6 * 2 / np.pi, 3 + 6 * (1 - 2 / np.pi)), BICYCLE: (-5.0, 5.0)}.items():
        change = (_rows(other, label)["rcs"] - _rows(easy, label)["rcs"]).to_numpy(float)
        assert low - 1e-4 <= change.min() < -1.0 and 1.0 < change.max() <= high + 1e-4
    changed = (other.data["rcs"] != easy.data["rcs"]).to_numpy()
    assert not changed[np.isin(easy.data["label_id"], [7, 8])].any()  # pedestrians look alike from all sides
    # Background changes only through the multipath ghosts of the road users (GHOST_RATE, 4 % of them).
    assert changed[easy.target == -1].sum() < 0.1 * changed[easy.target >= 0].sum()


def _object_rcs_spread(scenes, label, min_detections=30):
    d = scenes.data[(scenes.target >= 0) & (scenes.data["label_id"] == label)]
    per_object = d.groupby(scenes.target[d.index])["rcs"].agg(["mean", "size"])
    return per_object.loc[per_object["size"] >= min_detections, "mean"].std()


def test_objects_of_a_class_differ_in_mean_rcs_by_a_few_db():
    # Cars' mean RCS over their detections: with one offset per object (s.d. 3 dB) they spread by a few dB,
    # without it only by the sampling noise of a mean of >= 30 detections of 6.8 dB s.d. (about 1 dB).
    knobs = {"rcs_aspect": 0.0, "wheel_micro_doppler": 0.0}
    on = _object_rcs_spread(_scenes(knobs, difficulty="realistic", n=4, duration=15.0), CAR)
    off = _object_rcs_spread(_scenes({**knobs, "rcs_object_spread": 0.0}, "realistic", n=4, duration=15.0), CAR)
    assert off < 1.5
    assert 2.0 < on < 5.0


def _median_frame_doppler_spread(scenes, label):
    X = FrameTransform().fit_transform(scenes.data)
    labels = np.where(scenes.data["label_id"].to_numpy() == label, scenes.target, -1)
    frames = cluster_features(X, labels, window=0.5)
    return frames.loc[frames["n_detections"] >= 3, "vr_std"].median()


def test_wheel_micro_doppler_broadens_the_doppler_of_cars_and_leaves_pedestrians_alone(easy):
    other = _scenes({"wheel_micro_doppler": 0.25})
    assert _median_frame_doppler_spread(other, CAR) > 2 * _median_frame_doppler_spread(easy, CAR)
    # Pedestrians have no wheels: only the measurement noise moves (a moved wheel point can leave the field of
    # view, which shifts the noise draws of every later detection).
    pedestrians = [_median_frame_doppler_spread(s, PEDESTRIAN) for s in (other, easy)]
    assert pedestrians[0] == pytest.approx(pedestrians[1], rel=0.1)


def test_the_signatures_are_seeded():
    a, b = (_scenes(dict(SIGNATURES_OFF, rcs_object_spread=3.0, wheel_micro_doppler=0.3), n=1) for _ in range(2))
    pd.testing.assert_frame_equal(a.data, b.data)
