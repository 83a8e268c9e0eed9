"""The "radarscenes" preset and the knobs of issue 32: road_user_share, stop_and_go, annotation_margin, glint."""

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sklearn_radar._schema import STATIC_LABEL
from sklearn_radar.datasets import make_scenes
from sklearn_radar.datasets._detections import _object_detections
from sklearn_radar.datasets._presets import DIFFICULTY_PRESETS, RADARSCENES_KNOBS
from sklearn_radar.datasets._scenario import (
    OVERTAKING_LANE,
    STOP_DECELERATION,
    Road,
    RoadUser,
    _lost_time,
    _new_user,
    add_stops,
    make_road,
    simulate_ego,
)
from sklearn_radar.datasets._sensor_model import _scan_schedule, _sensor_states

EASY = DIFFICULTY_PRESETS["easy"]
RADARSCENES = DIFFICULTY_PRESETS["radarscenes"]


def _easy(knobs=None, seed=4, n=2, duration=10.0):
    return make_scenes(n_sequences=n, duration=duration, random_state=seed, difficulty="easy", knobs=knobs)


def test_radarscenes_is_realistic_with_fewer_longer_lived_road_users_and_the_new_knobs():
    realistic = DIFFICULTY_PRESETS["realistic"]
    changed = {name for name in realistic if realistic[name] != RADARSCENES[name]}
    on = set(RADARSCENES_KNOBS) - {"annotation_margin"}
    assert changed == {"traffic", "occlusion", "object_detection_probability", *on}
    assert RADARSCENES["traffic"] < realistic["traffic"] and RADARSCENES["occlusion"] < realistic["occlusion"]
    assert RADARSCENES["road_user_share"] < 1 and RADARSCENES["stop_and_go"] > 0 and RADARSCENES["glint"] > 0
    # The box annotator stays off: with glint it would drop a third of the annotated detections.
    assert not np.isfinite(RADARSCENES["annotation_margin"]) and not np.isfinite(EASY["annotation_margin"])


def test_radarscenes_preset_is_seeded():
    a = make_scenes(n_sequences=1, duration=4.0, random_state=3, difficulty="radarscenes")
    b = make_scenes(n_sequences=1, duration=4.0, random_state=3, difficulty="radarscenes")
    pd.testing.assert_frame_equal(a.data, b.data)
    assert "difficulty='radarscenes'" in a.DESCR


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("road_user_share", 1.5),
        ("road_user_share", -0.1),
        ("stop_and_go", 2.0),
        ("stop_and_go", True),
        ("annotation_margin", -0.2),
        ("annotation_margin", float("nan")),
        ("annotation_margin", "0.2"),
        ("glint", 1.5),
        ("glint", -0.5),
        ("glint", False),
    ],
)
def test_invalid_issue_32_knobs_raise_a_value_error_naming_the_knob(name, value):
    with pytest.raises(ValueError, match=name):
        make_scenes(n_sequences=1, duration=1.0, random_state=0, difficulty="radarscenes", knobs={name: value})


# ---------------------------------------------------------------------------------------------------------------
# road_user_share
# ---------------------------------------------------------------------------------------------------------------
def test_no_base_road_user_left_means_no_annotated_detection_in_the_same_drive():
    base, empty = _easy(), _easy({"road_user_share": 0.0})
    assert (base.target >= 0).any() and not (empty.target >= 0).any()
    pd.testing.assert_frame_equal(empty.odometry, base.odometry)


def test_a_share_of_the_road_users_keeps_fewer_instances():
    def objects(scenes):
        return scenes.data.loc[scenes.target >= 0, "track_id"].str[:16].nunique()

    assert 0 < objects(_easy({"road_user_share": 0.4})) < objects(_easy())


# ---------------------------------------------------------------------------------------------------------------
# stop_and_go
# ---------------------------------------------------------------------------------------------------------------
def _speed_profile(t, brake, halt, start, cruise):
    """The stop's speed as a fraction of the cruising speed, from its definition (linear ramps, 0 standing)."""
    return np.interp(t, [brake, halt, start, cruise], [1.0, 0.0, 0.0, 1.0])


@settings(max_examples=40, deadline=None)
@given(
    brake=st.floats(-5.0, 5.0),
    ramp_down=st.floats(0.1, 6.0),
    stand=st.floats(0.0, 8.0),
    ramp_up=st.floats(0.1, 6.0),
)
def test_the_time_lost_to_a_stop_is_the_integral_of_the_missing_speed(brake, ramp_down, stand, ramp_up):
    halt, start = brake + ramp_down, brake + ramp_down + stand
    cruise = start + ramp_up
    t = np.linspace(brake - 2.0, cruise + 2.0, 4001)
    missing = 1.0 - _speed_profile(t, brake, halt, start, cruise)
    numeric = np.concatenate([[0.0], np.cumsum(0.5 * (missing[1:] + missing[:-1]) * np.diff(t))])
    np.testing.assert_allclose(_lost_time(t, brake, halt, start, cruise), numeric, atol=1e-4)
    # After the stop the object is ramp_down / 2 + stand + ramp_up / 2 behind: hand-computed.
    assert _lost_time(cruise + 1.0, brake, halt, start, cruise) == pytest.approx(ramp_down / 2 + stand + ramp_up / 2)


def _straight_road():
    s = np.linspace(-200.0, 200.0, 401)
    return Road(s=s, x=s.copy(), y=np.zeros_like(s), heading=np.zeros_like(s))


def test_a_stopping_road_user_brakes_stands_and_starts_with_its_speed_profile():
    user = RoadUser(kind="car", length=4.5, width=1.8, road=_straight_road(), s0=0.0, speed=10.0, d0=3.5)
    user.stop = (2.0, 7.0, 10.0, 15.0)  # 2 m/s^2 both ways
    t = np.array([1.0, 4.5, 8.0, 12.5, 16.0])
    _, _, vx, vy, heading, _ = user.kinematics(t)
    np.testing.assert_allclose(vx, 10.0 * _speed_profile(t, *user.stop), atol=1e-6)
    np.testing.assert_allclose(vy, 0.0, atol=1e-9)
    np.testing.assert_allclose(heading, 0.0, atol=1e-9)  # standing, it keeps the road's direction
    np.testing.assert_array_equal(user.standing(t), [False, False, True, False, False])
    x, _ = user.position(np.array([7.0, 9.9]))
    assert x[0] == pytest.approx(x[1]) == pytest.approx(10.0 * (7.0 - 2.5))


def test_add_stops_leaves_followers_crossers_and_turning_users_alone_and_stops_near_the_ego():
    rng = np.random.default_rng(0)
    ego = simulate_ego(20.0, rng)
    road = make_road(ego)
    lane = _new_user("car", road, 20.0, rng, s0=-50.0, speed=9.0, d0=OVERTAKING_LANE)
    crosser = _new_user("pedestrian", road, 20.0, rng, s0=30.0, speed=1.4, d0=-4.0, crossing=True, t_cross=5.0)
    follower = _new_user("car", road, 20.0, rng, s0=0.0, speed=0.0, d0=0.0, follow_ego=ego, lag=1.0, gap=9.0)
    add_stops([lane, crosser, follower], ego, 1.0, np.random.default_rng(1))
    assert crosser.stop is None and follower.stop is None
    brake, halt, start, cruise = lane.stop
    assert halt - brake == pytest.approx(9.0 / STOP_DECELERATION["car"]) == pytest.approx(cruise - start)
    assert 2.0 <= start - halt <= 8.0
    x, y = RoadUser(**{**vars(lane), "stop": None}).position(ego.t)
    closest = ego.t[np.argmin(np.hypot(x - ego.x, y - ego.y))]
    assert abs(halt - closest) <= 3.0


def test_a_standing_road_users_detections_are_static_background_with_the_static_doppler():
    rng = np.random.default_rng(5)
    ego = simulate_ego(12.0, rng)
    road = make_road(ego)
    scans = _scan_schedule(12.0, 0, rng)
    sensor = _sensor_states(ego, scans)
    # A car in the overtaking lane that stands from 4 s to 8 s (after 3.5 s of driving) 15 m ahead of where the
    # ego car is at 8 s: in view while it stands.
    speed = 8.0
    s_stand = float(np.interp(8.0, ego.t, ego.s)) + 15.0
    user = _new_user("car", road, 12.0, rng, s0=s_stand - 3.5 * speed, speed=speed, d0=OVERTAKING_LANE)
    user.absences = ()
    user.stop = (3.0, 4.0, 8.0, 9.0)
    truth, _ = _object_detections([user], sensor, rng, EASY)
    t = sensor["t"][truth["scan"]]
    standing = (t >= 4.0) & (t < 8.0)
    assert standing.sum() > 20 and (~standing).sum() > 20
    assert (truth["label"][standing] == STATIC_LABEL).all() and (truth["object"][standing] == -1).all()
    assert (truth["label"][~standing] == 0).all() and (truth["object"][~standing] == 0).all()
    # Its true radial velocity is that of the static world: minus the sensor's velocity along the line of sight.
    angle = truth["azimuth"] + sensor["boresight"][truth["scan"]]
    static_vr = -(sensor["vx"][truth["scan"]] * np.cos(angle) + sensor["vy"][truth["scan"]] * np.sin(angle))
    np.testing.assert_allclose(truth["vr"][standing], static_vr[standing], atol=1e-6)


def test_stopping_road_users_give_fewer_annotated_and_more_still_background_detections():
    base, stopping = _easy(seed=6), _easy({"stop_and_go": 1.0}, seed=6)
    assert (stopping.target >= 0).sum() < (base.target >= 0).sum()

    def still_background(scenes):
        return int(((scenes.target == -1) & (scenes.data["vr_compensated"].abs() < 0.2)).sum())

    assert still_background(stopping) > still_background(base)


# ---------------------------------------------------------------------------------------------------------------
# annotation_margin
# ---------------------------------------------------------------------------------------------------------------


def test_box_annotation_changes_labels_only_both_ways():
    truth, boxed = _easy(seed=8), _easy({"annotation_margin": 0.2}, seed=8)
    labels = ["label_id", "track_id"]
    pd.testing.assert_frame_equal(truth.data.drop(columns=labels), boxed.data.drop(columns=labels))
    was, now = truth.target >= 0, boxed.target >= 0
    assert (was & ~now).sum() > 0  # own detections measured outside the box became background
    assert (~was & now).sum() > 0  # background measured inside a box joined its object
    assert (boxed.data["label_id"][~now] == STATIC_LABEL).all()


# ---------------------------------------------------------------------------------------------------------------
# glint
# ---------------------------------------------------------------------------------------------------------------


def test_glint_moves_the_object_azimuths_and_nothing_else():
    plain, glinted = _easy(), _easy({"glint": 1.0})
    same = ["timestamp", "sensor_id", "range_sc", "vr", "rcs", "label_id", "track_id"]
    pd.testing.assert_frame_equal(plain.data[same], glinted.data[same])
    annotated = plain.target >= 0
    moved = plain.data["azimuth_sc"].to_numpy() != glinted.data["azimuth_sc"].to_numpy()
    assert moved[annotated].mean() > 0.99
    # Background moves only where it copies an object detection's ray: the multipath ghosts (4 % of them).
    assert moved[~annotated].sum() < 0.1 * annotated.sum()
