"""FrameTransform against hand-computed geometry, rigid-body kinematics and the official devkit."""

import numpy as np
import pandas as pd
import pytest
from radar_scenes.coordinate_transformation import transform_detections_sequence_to_car

from sklearn_radar import FrameTransform
from sklearn_radar.datasets import make_scenes


@pytest.fixture(scope="module")
def scenes():
    return make_scenes(n_sequences=2, duration=6.0, random_state=11)


def _detection(**values):
    row = dict(
        range_sc=0.0,
        azimuth_sc=0.0,
        vr=0.0,
        timestamp=0,
        sensor_x=0.0,
        sensor_y=0.0,
        sensor_yaw=0.0,
        ego_x_seq=0.0,
        ego_y_seq=0.0,
        ego_yaw_seq=0.0,
        ego_vx=0.0,
        ego_yaw_rate=0.0,
        sequence=1,
    )
    row.update(values)
    return row


def test_hand_computed_car_and_frame_coordinates():
    # Sensor 1 m ahead of the rear axle looking left; target 2 m along its boresight.
    X = pd.DataFrame(
        [
            _detection(
                range_sc=2.0, sensor_x=1.0, sensor_yaw=np.pi / 2, ego_x_seq=10.0, ego_y_seq=5.0, ego_yaw_seq=np.pi / 2
            )
        ]
    )
    car = FrameTransform(frame="car").fit_transform(X)
    np.testing.assert_allclose(car[["x", "y"]].to_numpy(), [[1.0, 2.0]], atol=1e-12)
    # Car heading along world +y: car x -> world +y, car y -> world -x.
    frame = FrameTransform(frame="frame").fit_transform(X)
    np.testing.assert_allclose(frame[["x", "y"]].to_numpy(), [[8.0, 6.0]], atol=1e-12)
    # The box of RadarDBSCAN follows the car's x axis: pi/2 in the frame system, 0 in the car's own.
    assert frame["heading"].tolist() == [np.pi / 2] and car["heading"].tolist() == [0.0]


def test_doppler_of_a_static_target_is_compensated_to_zero():
    # Ego at 10 m/s, forward-looking sensor, static target straight ahead: vr = -10 m/s (approaching).
    X = pd.DataFrame([_detection(range_sc=20.0, vr=-10.0, sensor_x=3.8, ego_vx=10.0, timestamp=2_500_000)])
    Xt = FrameTransform().fit_transform(X)
    assert Xt["v_r"].iloc[0] == pytest.approx(0.0, abs=1e-12)
    assert Xt["t"].iloc[0] == pytest.approx(2.5)


def test_yaw_rate_moves_a_sensor_mounted_off_the_rear_axle():
    # Turning on the spot at 0.5 rad/s: a sensor 4 m ahead moves left at 2 m/s.
    # A static target to its left (sensor yaw pi/2) approaches at 2 m/s: vr = -2.
    X = pd.DataFrame([_detection(range_sc=10.0, vr=-2.0, sensor_x=4.0, sensor_yaw=np.pi / 2, ego_yaw_rate=0.5)])
    assert FrameTransform().fit_transform(X)["v_r"].iloc[0] == pytest.approx(0.0, abs=1e-12)


def test_yaw_rate_with_a_laterally_mounted_sensor_by_hand():
    # Sensor on the right (sensor_x, sensor_y) = (3.0, -0.8); car at 10 m/s turning left at 0.5 rad/s.
    # v_s = (ego_vx - yaw_rate * sensor_y, yaw_rate * sensor_x) = (10 + 0.4, 1.5) = (10.4, 1.5) m/s.
    # Line of sight u = (0.6, -0.8) (sensor_yaw -0.5 plus azimuth): v_s . u = 6.24 - 1.2 = 5.04 m/s.
    # A target receding over ground at 2.0 m/s is measured at vr = 2.0 - 5.04 = -3.04 m/s.
    # Range 10 m: x = 3.0 + 10 * 0.6 = 9.0, y = -0.8 - 10 * 0.8 = -8.8.
    sensor_yaw = -0.5
    azimuth = np.arctan2(-0.8, 0.6) - sensor_yaw
    X = pd.DataFrame(
        [
            _detection(
                range_sc=10.0,
                azimuth_sc=azimuth,
                vr=-3.04,
                sensor_x=3.0,
                sensor_y=-0.8,
                sensor_yaw=sensor_yaw,
                ego_vx=10.0,
                ego_yaw_rate=0.5,
            )
        ]
    )
    Xt = FrameTransform(frame="car").fit_transform(X)
    assert Xt["v_r"].iloc[0] == pytest.approx(2.0, abs=1e-12)
    np.testing.assert_allclose(Xt[["x", "y"]].to_numpy(), [[9.0, -8.8]], atol=1e-12)


def test_a_static_point_stays_in_place_in_the_frame_system_but_moves_in_the_car_system():
    # The ego drives along world x at 10 m/s; a static point at world (30, 4) is seen from three scans 0.1 s apart.
    rows = []
    for k in range(3):
        ego_x = 1.0 * k
        dx, dy = 30.0 - ego_x, 4.0
        rows.append(
            _detection(
                range_sc=np.hypot(dx, dy),
                azimuth_sc=np.arctan2(dy, dx),
                ego_x_seq=ego_x,
                ego_vx=10.0,
                timestamp=100_000 * k,
            )
        )
    X = pd.DataFrame(rows)
    frame = FrameTransform(frame="frame").fit_transform(X)
    np.testing.assert_allclose(frame[["x", "y"]].to_numpy(), [[30.0, 4.0]] * 3, atol=1e-9)
    car = FrameTransform(frame="car").fit_transform(X)
    np.testing.assert_allclose(np.diff(car["x"]), [-1.0, -1.0], atol=1e-9)


def _rigid_body_detections(n, seed):
    """Detections made from world geometry alone, with what each must give.

    A car drives at ego_vx along its heading and turns at ego_yaw_rate (its rear axle on a circle); a
    sensor is mounted on it at (sensor_x, sensor_y, sensor_yaw); a target moves in a straight line.  The
    measured vr is the rate of change of the sensor-target distance, taken by a central difference of
    positions -- none of FrameTransform's formulas is used.  Expected: the target's world (sequence)
    position, its position in the car frame, and its velocity over ground along the line of sight.
    """
    rng = np.random.default_rng(seed)
    psi0 = rng.uniform(-np.pi, np.pi, n)
    omega = rng.choice([-1.0, 1.0], n) * rng.uniform(0.05, 1.0, n)
    speed = rng.uniform(0.0, 20.0, n)
    ego0 = rng.uniform(-50.0, 50.0, (n, 2))
    mount = np.c_[rng.uniform(-1.0, 4.0, n), rng.uniform(-1.0, 1.0, n)]
    sensor_yaw = rng.uniform(-np.pi, np.pi, n)
    target0 = (
        ego0 + rng.uniform(3.0, 60.0, n)[:, None] * np.c_[np.cos(angle := rng.uniform(-np.pi, np.pi, n)), np.sin(angle)]
    )
    target_velocity = rng.uniform(-15.0, 15.0, (n, 2))

    def sensor(t):
        psi = psi0 + omega * t
        ego = ego0 + (speed / omega)[:, None] * np.c_[np.sin(psi) - np.sin(psi0), np.cos(psi0) - np.cos(psi)]
        c, s = np.cos(psi), np.sin(psi)
        return ego + np.c_[c * mount[:, 0] - s * mount[:, 1], s * mount[:, 0] + c * mount[:, 1]]

    def distance(t):
        return np.linalg.norm(target0 + target_velocity * t - sensor(t), axis=1)

    h = 1e-5
    sight = target0 - sensor(0.0)
    azimuth = np.mod(np.arctan2(sight[:, 1], sight[:, 0]) - psi0 - sensor_yaw + np.pi, 2 * np.pi) - np.pi
    timestamp = rng.integers(0, 10**9, n)
    X = pd.DataFrame(
        {
            "range_sc": distance(0.0),
            "azimuth_sc": azimuth,
            "vr": (distance(h) - distance(-h)) / (2 * h),
            "timestamp": timestamp,
            "sensor_x": mount[:, 0],
            "sensor_y": mount[:, 1],
            "sensor_yaw": sensor_yaw,
            "ego_x_seq": ego0[:, 0],
            "ego_y_seq": ego0[:, 1],
            "ego_yaw_seq": psi0,
            "ego_vx": speed,
            "ego_yaw_rate": omega,
            "sequence": np.arange(1, n + 1),  # each row its own car and recording: no ego path across rows
        }
    )
    relative = target0 - ego0
    c, s = np.cos(psi0), np.sin(psi0)
    car = np.c_[c * relative[:, 0] + s * relative[:, 1], -s * relative[:, 0] + c * relative[:, 1]]
    over_ground = np.sum(target_velocity * sight, axis=1) / np.linalg.norm(sight, axis=1)
    return X, target0, car, over_ground, timestamp * 1e-6


@pytest.mark.parametrize("seed", range(3))
def test_results_agree_with_rigid_body_geometry(seed):
    X, world, car_position, over_ground, t = _rigid_body_detections(300, seed)
    car = FrameTransform(frame="car").fit_transform(X)
    frame = FrameTransform(frame="frame").fit_transform(X)
    np.testing.assert_allclose(car[["x", "y"]].to_numpy(), car_position, atol=1e-9)
    np.testing.assert_allclose(frame[["x", "y"]].to_numpy(), world, atol=1e-9)
    np.testing.assert_allclose(frame["v_r"], over_ground, atol=1e-5)  # the central difference's error is ~1e-9
    np.testing.assert_allclose(car["v_r"], over_ground, atol=1e-5)  # v_r does not depend on the frame
    np.testing.assert_allclose(frame["t"], t)


def test_frame_coordinates_map_back_to_car_coordinates_with_the_devkit(scenes):
    X = scenes.data
    car = FrameTransform(frame="car").fit_transform(X)
    frame = FrameTransform(frame="frame").fit_transform(X)
    for _, scan in X.groupby(["sequence", "timestamp"]).groups.items():
        pose = np.array(
            [tuple(X.loc[scan[0], ["ego_x_seq", "ego_y_seq", "ego_yaw_seq"]])],
            dtype=[("x_seq", "f8"), ("y_seq", "f8"), ("yaw_seq", "f8")],
        )[0]
        x_cc, y_cc = transform_detections_sequence_to_car(
            frame.loc[scan, "x"].to_numpy(), frame.loc[scan, "y"].to_numpy(), pose
        )
        np.testing.assert_allclose(x_cc, car.loc[scan, "x"], atol=1e-6)
        np.testing.assert_allclose(y_cc, car.loc[scan, "y"], atol=1e-6)


def test_rows_index_and_input_are_preserved(scenes):
    X = scenes.data.iloc[::-3].copy()  # reversed, strided index
    before = X.copy()
    Xt = FrameTransform().fit_transform(X)
    pd.testing.assert_frame_equal(X, before)
    assert Xt.index.equals(X.index)
    pd.testing.assert_frame_equal(Xt[X.columns], X)
    assert list(Xt.columns[-5:]) == ["x", "y", "v_r", "t", "heading"]
    np.testing.assert_array_equal(Xt["heading"], X["ego_yaw_seq"])


def test_sequences_are_transformed_independently(scenes):
    X = scenes.data
    together = FrameTransform().fit_transform(X)
    apart = pd.concat([FrameTransform().fit_transform(part) for _, part in X.groupby("sequence")])
    pd.testing.assert_frame_equal(together, apart.loc[together.index])


def test_plain_array_is_read_by_position():
    r, az = np.array([1.0, 2.0]), np.array([0.0, np.pi / 2])
    Xt = FrameTransform().fit_transform(np.c_[r, az])
    # [x, y, v_r, t, sequence, keep, range_sc, heading, azimuth_sc, sensor_yaw]
    expected = [
        [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0],
        [0.0, 2.0, 0.0, 0.0, 0.0, 1.0, 2.0, 0.0, np.pi / 2, 0.0],
    ]
    np.testing.assert_allclose(Xt, expected, atol=1e-12)


def test_missing_column_or_odometry_is_a_clear_error(scenes):
    with pytest.raises(ValueError, match=r"missing the column\(s\) \['ego_yaw_seq'\]"):
        FrameTransform().fit(scenes.data.drop(columns="ego_yaw_seq"))
    bad = scenes.data.copy()
    bad.loc[3, "ego_vx"] = np.nan
    with pytest.raises(ValueError, match="'ego_vx' contains NaN"):
        FrameTransform().fit(bad)
    with pytest.raises(ValueError, match="frame"):
        FrameTransform(frame="world").fit(scenes.data)
