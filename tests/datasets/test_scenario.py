"""Tests of the simulator's ground truth: ego motion, road users and their situations."""

import numpy as np
import pytest

from sklearn_radar.datasets._scenario import (
    EGO_DT,
    MAX_ACCEL,
    ROAD_USER_CLASSES,
    make_road,
    make_road_users,
    simulate_ego,
)


def _users(seed, duration=30.0, n=12):
    rng = np.random.default_rng(seed)
    ego = simulate_ego(duration, rng)
    return ego, make_road_users(ego, make_road(ego), duration, n, rng)


@pytest.fixture(scope="module")
def many_users():
    return [_users(seed) for seed in range(6)]


def test_ego_respects_its_acceleration_limit_and_integrates_consistently():
    ego = simulate_ego(30.0, np.random.default_rng(0))
    assert np.abs(np.diff(ego.vx)).max() <= MAX_ACCEL * EGO_DT + 1e-12
    step = np.hypot(np.diff(ego.x), np.diff(ego.y))
    np.testing.assert_allclose(step, ego.vx[:-1] * EGO_DT, atol=1e-9)
    np.testing.assert_allclose(np.diff(ego.yaw), ego.yaw_rate[:-1] * EGO_DT, atol=1e-12)


def test_road_user_sizes_and_speeds_are_realistic(many_users):
    t = np.linspace(0, 30, 301)
    for _, users in many_users:
        for user in users:
            low, high = ROAD_USER_CLASSES[user.kind]["length"]
            assert low <= user.length <= high
            _, _, vx, vy, _, _ = user.kinematics(t)
            top_speed = {"pedestrian": 2.5, "pedestrian_group": 2.5, "bicycle": 9.0}.get(user.kind, 25.0)
            assert np.hypot(vx, vy).max() <= top_speed, user.kind


def test_some_road_users_cross_the_road_laterally(many_users):
    crossing = [u for _, users in many_users for u in users if u.crossing]
    assert crossing
    for user in crossing:
        heading = user._heading(np.array([user.t_cross]), 0.01)[0]
        road = user.road.heading_at(np.array([user.s0]))[0]
        assert abs(np.cos(heading - road)) < 0.05  # perpendicular to the road


def test_road_users_pass_each_other_within_one_to_two_metres(many_users):
    t = np.linspace(0, 30, 601)
    closest_gaps = []
    for _, users in many_users:
        centres = [np.stack(u.position(t)) for u in users]
        for i in range(len(users)):
            for j in range(i + 1, len(users)):
                distance = np.hypot(*(centres[i] - centres[j]))
                gap = distance - (users[i].width + users[j].width) / 2
                closest_gaps.append(gap.min())
    closest_gaps = np.array(closest_gaps)
    assert np.any((closest_gaps > 1.0) & (closest_gaps < 2.0))


def test_absences_last_between_0_3_and_1_5_s(many_users):
    absences = [a for _, users in many_users for u in users for a in u.absences]
    assert absences
    lengths = np.array([end - start for start, end in absences])
    assert lengths.min() >= 0.3 and lengths.max() <= 1.5


def test_leader_never_runs_into_the_ego():
    for seed in range(10):
        ego, users = _users(seed)
        for user in (u for u in users if u.follow_ego is not None):
            t = np.linspace(0, 30, 601)
            ahead = user._leader_s(t) - np.interp(t, ego.t, ego.s)
            assert ahead.min() >= user.gap - 1e-9 and user.gap > 5.0
