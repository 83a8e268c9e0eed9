"""Doppler-based full 2-D velocity estimation of a cluster (Kellner et al. 2013 via Scheiner et al. 2019)."""

import numpy as np
import pytest

from sklearn_radar.cluster._velocity import estimate_velocities, estimate_velocity

#: RadarScenes front sensors (front-right, front-left), m, car frame (x forward, y left).
SENSORS = np.array([[3.8, -0.7], [3.8, 0.7]])
#: Half length and half width of a car-like object, m.
HALF_SIZE = np.array([2.25, 0.9])


def _los(points, sensors):
    """Line-of-sight direction, rad, from each detection's sensor to the detection."""
    d = np.asarray(points, dtype=float) - np.asarray(sensors, dtype=float)
    return np.arctan2(d[:, 1], d[:, 0])


def _radial(velocity, theta):
    return velocity[0] * np.cos(theta) + velocity[1] * np.sin(theta)


# ---------------------------------------------------------------------------
# Exact recovery
# ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "velocity",
    [(10.0, 0.0), (-8.0, 0.0), (0.0, 5.0), (0.0, -12.0), (3.0, -4.0), (-6.5, 6.5), (0.3, 0.2)],
)
def test_exact_recovery_two_sensors_car_outline(velocity):
    velocity = np.array(velocity)
    # Rear face and right side of a car centred 20 m ahead, seen by both front sensors.
    points = np.array(
        [[21.75, y] for y in (-0.9, -0.45, 0.0, 0.45, 0.9)] + [[x, -0.9] for x in (22.5, 23.5, 24.5)], dtype=float
    )
    sensor_id = np.arange(len(points)) % 2
    theta = _los(points, SENSORS[sensor_id])
    vx, vy, n_inliers = estimate_velocity(_radial(velocity, theta), theta)
    np.testing.assert_allclose([vx, vy], velocity, atol=1e-9)
    assert n_inliers == len(points)


def test_lateral_motion_of_a_point_like_object_needs_two_sensors():
    """Purely lateral motion: v_r ~ 0 near boresight; solvable from the sensors' different viewpoints."""
    velocity = np.array([0.0, 8.0])
    # Three reflections from (almost) one spot 20 m ahead of the sensors' midpoint.
    points = np.array([[23.8, 0.0], [23.8, 0.02], [23.8, -0.02]] * 2)
    sensor_id = np.repeat([0, 1], 3)
    theta = _los(points, SENSORS[sensor_id])
    v_r = _radial(velocity, theta)
    assert np.all(np.abs(v_r) < 0.3 * np.linalg.norm(velocity))  # the premise: little Doppler
    vx, vy, n_inliers = estimate_velocity(v_r, theta)
    np.testing.assert_allclose([vx, vy], velocity, atol=1e-9)
    assert n_inliers == 6
    # The front-right sensor alone sees the spot within 0.002 rad: unknown.
    one = sensor_id == 0
    vx1, vy1, _ = estimate_velocity(v_r[one], theta[one])
    assert np.isnan(vx1) and np.isnan(vy1)


def test_sign_convention_approaching_object_has_negative_radial_velocity():
    # An object 30 m ahead driving towards the car at 7 m/s.
    points = np.array([[33.8, y] for y in np.linspace(-0.9, 0.9, 6)])
    sensor_id = np.arange(6) % 2
    theta = _los(points, SENSORS[sensor_id])
    v_r = _radial((-7.0, 0.0), theta)
    assert np.all(v_r < 0)
    vx, vy, _ = estimate_velocity(v_r, theta)
    assert vx == pytest.approx(-7.0, abs=1e-9) and vy == pytest.approx(0.0, abs=1e-9)


def test_exact_recovery_across_the_angle_branch_cut():
    """Lines of sight around +-pi (an object behind the sensor), given wrapped and unwrapped."""
    velocity = np.array([4.0, -2.0])
    unwrapped = np.pi + np.linspace(-0.15, 0.15, 7)
    wrapped = np.mod(unwrapped + np.pi, 2 * np.pi) - np.pi
    assert wrapped.min() < -3 and wrapped.max() > 3
    for theta in (unwrapped, wrapped):
        vx, vy, n_inliers = estimate_velocity(_radial(velocity, theta), theta)
        np.testing.assert_allclose([vx, vy], velocity, atol=1e-9)
        assert n_inliers == 7


def test_matches_least_squares_on_the_true_inliers_with_noise():
    rng = np.random.default_rng(7)
    velocity = np.array([-5.0, 9.0])
    theta = rng.uniform(-0.4, 0.4, 12)
    v_r = _radial(velocity, theta) + rng.normal(0, 0.05, 12)
    vx, vy, n_inliers = estimate_velocity(v_r, theta)
    design = np.column_stack((np.cos(theta), np.sin(theta)))
    expected = np.linalg.lstsq(design, v_r, rcond=None)[0]
    np.testing.assert_allclose([vx, vy], expected, rtol=0, atol=1e-10)
    assert n_inliers == 12


def _reference_all_pairs(v_r, theta, min_detections=3, min_spread=0.05, threshold=0.25):
    """Loop-based transcription of the documented algorithm for the all-pairs regime (n(n-1)/2 <= 60)."""
    n = len(v_r)
    design = np.column_stack((np.cos(theta), np.sin(theta)))
    best = None
    for i in range(n):
        for j in range(i + 1, n):
            if abs(np.sin(theta[j] - theta[i])) < 1e-3:
                continue
            hypothesis = np.linalg.solve(design[[i, j]], v_r[[i, j]])
            residual = v_r - design @ hypothesis
            inlier = np.abs(residual) < threshold
            key = (-int(inlier.sum()), float(np.sum(residual[inlier] ** 2)))
            if best is None or key < best[0]:
                best = (key, inlier)
    if best is None:
        return np.nan, np.nan, 0
    inlier = best[1]
    velocity = np.linalg.lstsq(design[inlier], v_r[inlier], rcond=None)[0]
    reselected = np.abs(v_r - design @ velocity) < threshold
    if reselected.sum() >= 2:
        inlier = reselected
        velocity = np.linalg.lstsq(design[inlier], v_r[inlier], rcond=None)[0]
    lines = np.sort(np.mod(theta[inlier], np.pi))  # directions as lines: spread = pi - largest gap
    gaps = np.diff(np.concatenate((lines, [lines[0] + np.pi])))
    spread = np.pi - gaps.max()
    if inlier.sum() < min_detections or spread < min_spread:
        return np.nan, np.nan, int(inlier.sum())
    return velocity[0], velocity[1], int(inlier.sum())


@pytest.mark.parametrize("seed", range(40))
def test_matches_a_loop_based_transcription_of_the_algorithm(seed):
    """Noise comparable to the threshold, so that tie-breaks and the re-selection matter."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 12))  # at most 55 pairs: all are tried
    theta = rng.uniform(-np.pi, np.pi) + rng.uniform(-0.25, 0.25, n)
    v_r = _radial(rng.uniform(-15, 15, 2), theta) + rng.normal(0, 0.12, n)
    wild = rng.random(n) < 0.2
    v_r[wild] += rng.uniform(0.5, 3, wild.sum()) * rng.choice([-1, 1], wild.sum())
    expected = _reference_all_pairs(v_r, theta)
    vx, vy, n_inliers = estimate_velocity(v_r, theta)
    assert n_inliers == expected[2]
    np.testing.assert_allclose([vx, vy], expected[:2], rtol=0, atol=1e-9)


# ---------------------------------------------------------------------------
# Degenerate geometry
# ---------------------------------------------------------------------------


def test_one_detection_is_unknown():
    assert _is_unknown(estimate_velocity([3.0], [0.2]), n_inliers=0)
    assert _is_unknown(estimate_velocity([3.0], [0.2], min_detections=2), n_inliers=0)


def test_no_detection_is_unknown():
    assert _is_unknown(estimate_velocity([], []), n_inliers=0)


def test_two_detections_are_unknown_by_default_but_exact_with_min_detections_2():
    theta = np.array([0.1, 0.5])
    v_r = _radial((6.0, -1.0), theta)
    assert _is_unknown(estimate_velocity(v_r, theta), n_inliers=0)
    vx, vy, n_inliers = estimate_velocity(v_r, theta, min_detections=2)
    np.testing.assert_allclose([vx, vy], [6.0, -1.0], atol=1e-9)
    assert n_inliers == 2


def test_identical_lines_of_sight_are_unknown():
    theta = np.full(6, 0.3)
    v_r = np.full(6, 2.0)
    assert _is_unknown(estimate_velocity(v_r, theta), n_inliers=0)  # no pair is solvable


def test_opposite_lines_of_sight_are_one_line_and_unknown():
    """theta and theta + pi constrain the same velocity component: no lateral information."""
    exactly_opposite = np.array([0.3, 0.3 + np.pi, 0.3, 0.3 + np.pi, 0.3])
    v_r = _radial((2.0, 1.0), exactly_opposite)
    assert _is_unknown(estimate_velocity(v_r, exactly_opposite), n_inliers=0)  # no pair is solvable
    # Nearly opposite: pairs are solvable, but as lines the directions span only 0.02 rad.
    near = 0.3 + np.array([0.0, 0.01, 0.02, np.pi, np.pi + 0.01, np.pi + 0.02])
    v_r = _radial((2.0, 1.0), near)
    assert _is_unknown(estimate_velocity(v_r, near), n_inliers=6)
    vx, vy, _ = estimate_velocity(v_r, near, min_spread=0.01)
    np.testing.assert_allclose([vx, vy], [2.0, 1.0], atol=1e-6)


def test_spread_below_min_spread_is_unknown_and_gated_only_by_the_spread():
    theta = 0.2 + np.linspace(0.0, 0.04, 8)  # spread 0.04 rad < 0.05
    v_r = _radial((5.0, 3.0), theta)
    vx, vy, n_inliers = estimate_velocity(v_r, theta)
    assert np.isnan(vx) and np.isnan(vy)
    assert n_inliers == 8  # consistent detections, only too narrow
    vx, vy, _ = estimate_velocity(v_r, theta, min_spread=0.03)
    np.testing.assert_allclose([vx, vy], [5.0, 3.0], atol=1e-8)


def test_spread_is_measured_across_the_branch_cut():
    """Lines of sight straddling +-pi within 0.04 rad: narrow, not 2 pi wide."""
    theta = np.mod(np.pi + np.linspace(-0.02, 0.02, 8) + np.pi, 2 * np.pi) - np.pi
    assert theta.max() - theta.min() > 6  # naive max - min would call this wide
    v_r = _radial((5.0, 3.0), theta)
    vx, vy, n_inliers = estimate_velocity(v_r, theta)
    assert np.isnan(vx) and np.isnan(vy) and n_inliers == 8
    vx, vy, _ = estimate_velocity(v_r, theta, min_spread=0.03)
    np.testing.assert_allclose([vx, vy], [5.0, 3.0], atol=1e-8)


def test_too_few_inliers_is_unknown():
    # Two consistent detections plus three mutually inconsistent ones.
    theta = np.array([0.0, 0.4, 0.1, 0.2, 0.3])
    v_r = _radial((5.0, 0.0), theta)
    v_r[2:] += [2.0, -1.5, 3.0]
    vx, vy, n_inliers = estimate_velocity(v_r, theta, min_detections=4)
    assert np.isnan(vx) and np.isnan(vy)
    assert 2 <= n_inliers < 4


def test_non_finite_detections_are_ignored():
    theta = np.array([0.0, 0.2, np.nan, 0.4, 0.3])
    v_r = np.array([1.0, 2.0, 3.0, np.inf, 4.0])
    keep = np.isfinite(theta) & np.isfinite(v_r)
    v_r[keep] = _radial((4.0, 2.0), theta[keep])
    vx, vy, n_inliers = estimate_velocity(v_r, theta)
    np.testing.assert_allclose([vx, vy], [4.0, 2.0], atol=1e-9)
    assert n_inliers == 3


def _is_unknown(result, n_inliers):
    vx, vy, count = result
    return np.isnan(vx) and np.isnan(vy) and count == n_inliers


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(min_detections=1),
        dict(min_detections=2.5),
        dict(min_spread=-0.1),
        dict(inlier_threshold=0.0),
        dict(max_trials=0),
    ],
)
def test_invalid_parameters_raise(kwargs):
    with pytest.raises(ValueError):
        estimate_velocity([1.0, 2.0, 3.0], [0.0, 0.1, 0.2], **kwargs)


def test_mismatched_shapes_raise():
    with pytest.raises(ValueError):
        estimate_velocity([1.0, 2.0], [0.0, 0.1, 0.2])
    with pytest.raises(ValueError):
        estimate_velocities([1.0, 2.0], [0.0, 0.1], [0, 0, 1])


# ---------------------------------------------------------------------------
# Outlier rejection
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("n", [10, 20])  # 45 pairs (all tried) and 190 pairs (60 drawn)
@pytest.mark.parametrize("seed", range(10))
def test_thirty_percent_gross_outliers_are_rejected(n, seed):
    rng = np.random.default_rng(seed)
    speed, direction = rng.uniform(3, 15), rng.uniform(-np.pi, np.pi)
    velocity = speed * np.array([np.cos(direction), np.sin(direction)])
    theta = rng.uniform(-0.3, 0.3, n)
    v_r = _radial(velocity, theta) + rng.normal(0, 0.05, n)
    outlier = np.zeros(n, dtype=bool)
    outlier[rng.choice(n, round(0.3 * n), replace=False)] = True
    v_r[outlier] += rng.choice([-1.0, 1.0], outlier.sum()) * rng.uniform(1.0, 3.0, outlier.sum())

    vx, vy, n_inliers = estimate_velocity(v_r, theta)
    assert n_inliers == n - outlier.sum()
    # The final fit is least squares on exactly the true inliers ...
    design = np.column_stack((np.cos(theta), np.sin(theta)))[~outlier]
    expected = np.linalg.lstsq(design, v_r[~outlier], rcond=None)[0]
    np.testing.assert_allclose([vx, vy], expected, rtol=0, atol=1e-9)
    # ... hence within 4 standard deviations of the truth (covariance sigma^2 (A^T A)^-1).
    error = np.array([vx, vy]) - velocity
    mahalanobis2 = error @ (design.T @ design) @ error / 0.05**2
    assert mahalanobis2 < 16.0


def test_least_squares_without_ransac_would_fail_on_these_outliers():
    """Guard for the test above: the outliers do bias a plain least-squares fit."""
    rng = np.random.default_rng(3)
    theta = rng.uniform(-0.3, 0.3, 20)
    v_r = _radial((8.0, 2.0), theta) + rng.normal(0, 0.05, 20)
    v_r[:6] += np.array([2.5, -2.0, 3.0, 1.5, -2.8, 2.2])
    plain = np.linalg.lstsq(np.column_stack((np.cos(theta), np.sin(theta))), v_r, rcond=None)[0]
    assert np.linalg.norm(plain - [8.0, 2.0]) > 1.0
    vx, vy, n_inliers = estimate_velocity(v_r, theta)
    assert np.linalg.norm([vx - 8.0, vy - 2.0]) < 0.5 and n_inliers == 14


# ---------------------------------------------------------------------------
# Monte Carlo: a car seen by one or two front sensors
# ---------------------------------------------------------------------------

SIGMA_VR = 0.05  # m/s
OUTLIER_RATE = 0.15
MC_TRIALS = 300


def _outline_detections(center, heading, sensor, count, rng):
    """``count`` points on the edges of the car outline facing ``sensor``, by apparent edge size."""
    c, s = np.cos(heading), np.sin(heading)
    rotation = np.array([[c, -s], [s, c]])
    lx, ly = HALF_SIZE
    # (midpoint, half edge vector, outward normal) in the object frame: front, rear, left, right.
    local = np.array(
        [
            [[lx, 0], [0, ly], [1, 0]],
            [[-lx, 0], [0, ly], [-1, 0]],
            [[0, ly], [lx, 0], [0, 1]],
            [[0, -ly], [lx, 0], [0, -1]],
        ],
        dtype=float,
    )
    world = local @ rotation.T
    midpoint, half_edge, normal = center + world[:, 0], world[:, 1], world[:, 2]
    to_sensor = sensor - midpoint
    facing = np.einsum("ij,ij->i", normal, to_sensor) / np.linalg.norm(to_sensor, axis=1)
    apparent = np.clip(facing, 0.0, None) * np.linalg.norm(half_edge, axis=1)
    edge = rng.choice(4, size=count, p=apparent / apparent.sum())
    return midpoint[edge] + rng.uniform(-1.0, 1.0, count)[:, None] * half_edge[edge]


def _simulate(rng, n_sensors):
    """One car 10-40 m ahead (bearing +-30 deg, in both sensors' fields of view), 5-15 detections."""
    distance, bearing = rng.uniform(10.0, 40.0), rng.uniform(-np.radians(30), np.radians(30))
    center = np.array([3.8, 0.0]) + distance * np.array([np.cos(bearing), np.sin(bearing)])
    speed, heading = rng.uniform(3.0, 15.0), rng.uniform(-np.pi, np.pi)
    velocity = speed * np.array([np.cos(heading), np.sin(heading)])
    n = int(rng.integers(5, 16))
    if n_sensors == 1:
        sensor_id = np.full(n, rng.integers(2))
    else:
        sensor_id = rng.permutation(np.arange(n) % 2)
    points = np.empty((n, 2))
    for k in (0, 1):
        mine = sensor_id == k
        if mine.any():
            points[mine] = _outline_detections(center, heading, SENSORS[k], int(mine.sum()), rng)
    theta = _los(points, SENSORS[sensor_id])
    v_r = _radial(velocity, theta) + rng.normal(0.0, SIGMA_VR, n)
    outlier = rng.random(n) < OUTLIER_RATE
    v_r[outlier] += rng.choice([-1.0, 1.0], outlier.sum()) * rng.uniform(1.0, 3.0, outlier.sum())
    return velocity, theta, v_r, outlier


def _monte_carlo(n_sensors, seed):
    rng = np.random.default_rng(seed)
    rows = []
    for _ in range(MC_TRIALS):
        velocity, theta, v_r, outlier = _simulate(rng, n_sensors)
        vx, vy, n_inliers = estimate_velocity(v_r, theta)
        if np.isnan(vx):
            rows.append((1.0, np.nan, np.nan, np.nan, np.nan))
            continue
        estimate = np.array([vx, vy])
        speed_error = abs(np.linalg.norm(estimate) - np.linalg.norm(velocity))
        heading_error = abs(
            np.degrees(np.angle(np.exp(1j * (np.arctan2(vy, vx) - np.arctan2(velocity[1], velocity[0])))))
        )
        # Error relative to the ideal fit's covariance sigma^2 (A^T A)^-1 on the true inliers
        # (squared Mahalanobis distance; chi-square with 2 degrees of freedom for an ideal estimator).
        design = np.column_stack((np.cos(theta), np.sin(theta)))[~outlier]
        error = estimate - velocity
        mahalanobis2 = error @ (design.T @ design) @ error / SIGMA_VR**2
        rows.append((0.0, speed_error, heading_error, mahalanobis2, float(n_inliers == (~outlier).sum())))
    return np.array(rows)


@pytest.fixture(scope="module")
def monte_carlo():
    results = {n_sensors: _monte_carlo(n_sensors, seed=100 + n_sensors) for n_sensors in (1, 2)}
    print()
    print(
        f"Doppler velocity estimate, car 10-40 m, 5-15 detections, sigma {SIGMA_VR} m/s, "
        f"{OUTLIER_RATE:.0%} outliers, {MC_TRIALS} trials"
    )
    print(
        "sensors  unknown  speed err m/s (med / p90)  heading err deg (med / p90)  "
        "Mahalanobis^2 (med / p90)  exact inlier set"
    )
    for n_sensors, rows in results.items():
        known = rows[rows[:, 0] == 0]
        print(
            f"{n_sensors:7d}  {rows[:, 0].mean():6.1%}  "
            f"{np.median(known[:, 1]):10.3f} / {np.percentile(known[:, 1], 90):5.3f}      "
            f"{np.median(known[:, 2]):13.2f} / {np.percentile(known[:, 2], 90):5.2f}       "
            f"{np.median(known[:, 3]):10.2f} / {np.percentile(known[:, 3], 90):5.2f}        "
            f"{known[:, 4].mean():6.1%}"
        )
    print("(ideal, chi-square 2 dof: Mahalanobis^2 median 1.39, p90 4.61)")
    return results


# Bounds.  The lateral velocity component (across the lines of sight) has a
# standard deviation of about sigma / (sqrt(n) * std(theta)).  A 4.5 m x 1.8 m
# car at 10-40 m subtends 0.045-0.45 rad from one sensor (1.8 m nose-on at
# 40 m up to ~4.8 m diagonal at 10 m); the two sensors' 1.4 m baseline adds
# only 0.035-0.14 rad, so two sensors help little.  Typical case: 25 m,
# ~3 m apparent extent -> std(theta) ~ 0.12 / sqrt(12) = 0.035 rad, with ~8
# inliers sigma_lat ~ 0.05 / (2.8 * 0.035) ~ 0.5 m/s, while the radial
# component is ~ 0.05 / 2.8 ~ 0.02 m/s.  The speed error is the projection
# onto the (random) heading, so its median is a fraction of sigma_lat:
# below 0.2 m/s with two sensors, 0.25 m/s with one (fewer trials reach the
# best geometry).  The heading error is ~ sigma_lat * cos / speed: ~0.5 m/s
# at 3-15 m/s gives a few degrees typically; the 90th percentile (far,
# nose-on, slow, laterally moving) below 10 deg with two sensors and 15 deg
# with one.  Unknown (spread < 0.05 rad): one sensor only when the car is
# nearly nose/tail-on beyond ~30 m or has very few inliers -> < 10 %;
# with two sensors the baseline widens the spread -> < 5 %.
#
# Calibration against the ideal fit: with the 15 % outliers 1-3 m/s off and
# the noise 0.05 m/s, the 0.25 m/s threshold should separate them (>= 95 %
# of trials with the exact inlier set) and the error should follow the
# least-squares covariance on the true inliers: Mahalanobis^2 ~ chi2(2),
# median 1.39 and 90th percentile 4.61.  With 300 trials the sampling
# standard error of the median is ~0.12 and of the p90 ~0.35, so the bounds
# 1.8 and 6.0 allow ~3.5-4 standard errors and fail if the estimator is
# markedly worse than least squares on the true inliers.
BOUNDS = {
    # sensors: (median speed error, p90 heading error, unknown share)
    1: (0.25, 15.0, 0.10),
    2: (0.20, 10.0, 0.05),
}


@pytest.mark.parametrize("n_sensors", [1, 2])
def test_monte_carlo_car_accuracy(monte_carlo, n_sensors):
    rows = monte_carlo[n_sensors]
    known = rows[rows[:, 0] == 0]
    median_speed, p90_heading, unknown_share = BOUNDS[n_sensors]
    assert rows[:, 0].mean() < unknown_share
    assert np.median(known[:, 1]) < median_speed
    assert np.percentile(known[:, 2], 90) < p90_heading


@pytest.mark.parametrize("n_sensors", [1, 2])
def test_monte_carlo_car_is_as_good_as_least_squares_on_the_true_inliers(monte_carlo, n_sensors):
    rows = monte_carlo[n_sensors]
    known = rows[rows[:, 0] == 0]
    assert known[:, 4].mean() >= 0.95
    assert np.median(known[:, 3]) < 1.8
    assert np.percentile(known[:, 3], 90) < 6.0


# ---------------------------------------------------------------------------
# Batched estimation
# ---------------------------------------------------------------------------


def _random_groups(rng, n_groups, labels):
    sizes = rng.integers(1, 21, n_groups)  # includes groups too small to estimate
    group = np.repeat(labels, sizes)
    velocity = rng.uniform(-15, 15, (n_groups, 2))
    theta = rng.uniform(-np.pi, np.pi, n_groups)[np.repeat(np.arange(n_groups), sizes)]
    theta += rng.uniform(-0.3, 0.3, theta.shape)
    index = np.repeat(np.arange(n_groups), sizes)
    v_r = _radial(velocity[index].T, theta) + rng.normal(0, 0.05, theta.shape)
    wild = rng.random(theta.shape) < 0.15
    v_r[wild] += rng.uniform(1, 3, wild.sum()) * rng.choice([-1, 1], wild.sum())
    order = rng.permutation(theta.shape[0])  # rows of a group scattered, groups in any order
    return v_r[order], theta[order], group[order]


def test_estimate_velocities_equals_estimate_velocity_per_group():
    rng = np.random.default_rng(11)
    labels = rng.choice(100_000, 2000, replace=False)  # unsorted, non-contiguous labels
    v_r, theta, group = _random_groups(rng, 2000, labels)
    v_r[rng.choice(v_r.shape[0], 30, replace=False)] = np.nan  # some unusable detections
    vx, vy, n_inliers, unique = estimate_velocities(v_r, theta, group)
    np.testing.assert_array_equal(unique, np.sort(labels))
    expected = np.array([estimate_velocity(v_r[group == g], theta[group == g]) for g in unique])
    np.testing.assert_array_equal(vx, expected[:, 0])
    np.testing.assert_array_equal(vy, expected[:, 1])
    np.testing.assert_array_equal(n_inliers, expected[:, 2].astype(np.int64))
    assert np.isnan(vx).any() and np.isfinite(vx).mean() > 0.8  # both outcomes exercised


def test_estimate_velocities_with_string_labels_and_options():
    rng = np.random.default_rng(5)
    labels = np.array([f"track_{k:03d}" for k in rng.permutation(300)])
    v_r, theta, group = _random_groups(rng, 300, labels)
    options = dict(min_detections=4, min_spread=0.1, inlier_threshold=0.2, max_trials=25, random_state=9)
    vx, vy, n_inliers, unique = estimate_velocities(v_r, theta, group, **options)
    assert list(unique) == sorted(labels)
    for k, g in enumerate(unique):
        rows = group == g
        assert (vx[k], vy[k], n_inliers[k]) == pytest.approx(
            estimate_velocity(v_r[rows], theta[rows], **options), nan_ok=True, abs=0
        )


def test_estimate_velocities_ten_thousand_groups():
    """10,000 clusters of 5-20 detections in one call (vectorised; well under a second)."""
    rng = np.random.default_rng(2)
    n_groups = 10_000
    sizes = rng.integers(5, 21, n_groups)
    index = np.repeat(np.arange(n_groups), sizes)
    velocity = rng.uniform(-15, 15, (n_groups, 2))
    theta = rng.uniform(-1.0, 1.0, n_groups)[index] + rng.uniform(-0.25, 0.25, index.shape)
    v_r = _radial(velocity[index].T, theta) + rng.normal(0, 0.05, index.shape)
    vx, vy, n_inliers, unique = estimate_velocities(v_r, theta, index)
    np.testing.assert_array_equal(unique, np.arange(n_groups))
    known = np.isfinite(vx)
    assert known.mean() > 0.9
    assert np.median(np.hypot(vx - velocity[:, 0], vy - velocity[:, 1])[known]) < 0.5
    for g in range(0, n_groups, 500):
        assert (vx[g], vy[g], n_inliers[g]) == pytest.approx(
            estimate_velocity(v_r[index == g], theta[index == g]), nan_ok=True, abs=0
        )


def test_estimate_velocities_with_a_shared_generator():
    rng = np.random.default_rng(8)
    group = np.repeat(np.arange(50), 30)  # 435 pairs per group: drawn from the shared generator
    velocity = rng.uniform(-10, 10, (50, 2))
    theta = rng.uniform(-1, 1, 50)[group] + rng.uniform(-0.3, 0.3, group.shape)
    v_r = _radial(velocity[group].T, theta) + rng.normal(0, 0.05, group.shape)
    v_r[rng.random(group.shape) < 0.2] += 2.0
    vx, vy, _, _ = estimate_velocities(v_r, theta, group, random_state=np.random.default_rng(0))
    assert np.all(np.hypot(vx - velocity[:, 0], vy - velocity[:, 1]) < 1.0)


def test_estimate_velocities_empty_input():
    vx, vy, n_inliers, unique = estimate_velocities([], [], np.array([], dtype=int))
    assert vx.shape == vy.shape == n_inliers.shape == unique.shape == (0,)


# ---------------------------------------------------------------------------
# Determinism
# ---------------------------------------------------------------------------


def test_deterministic_with_random_pairs():
    rng = np.random.default_rng(4)
    theta = rng.uniform(-0.5, 0.5, 40)  # 780 pairs > max_trials: pairs are drawn
    v_r = _radial((6.0, -3.0), theta) + rng.normal(0, 0.05, 40)
    v_r[:12] += rng.uniform(1, 3, 12)
    before = (v_r.copy(), theta.copy())
    first = estimate_velocity(v_r, theta)
    second = estimate_velocity(v_r, theta)
    assert first == second
    assert np.isfinite(first[0]) and first[2] == 28
    np.testing.assert_array_equal(v_r, before[0])  # inputs untouched
    np.testing.assert_array_equal(theta, before[1])

    group = np.repeat([3, 1], 20)
    a = estimate_velocities(v_r, theta, group)
    b = estimate_velocities(v_r, theta, group)
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x, y)


def test_the_internal_defaults_are_the_public_ones():
    """ClusterMerger calls the estimate's kernel with _VELOCITY_DEFAULTS: they must be estimate_velocities' defaults."""
    import inspect

    from sklearn_radar.cluster._velocity import _VELOCITY_DEFAULTS

    signature = inspect.signature(estimate_velocities)
    names = ("min_detections", "min_spread", "inlier_threshold", "max_trials", "random_state")
    assert tuple(signature.parameters[name].default for name in names) == _VELOCITY_DEFAULTS


def test_velocities_and_residuals_equal_the_per_group_estimate_and_a_loop():
    # The batched form the cluster features use: per group, estimate_velocity's result and the RMS residual of
    # all the group's detections against it.
    from sklearn_radar.cluster._velocity import _velocities_and_residuals

    rng = np.random.default_rng(5)
    sizes = rng.integers(1, 30, 40)
    group = np.repeat(np.arange(len(sizes)), sizes)
    theta = rng.uniform(-1.5, 1.5, len(group))
    velocity = rng.normal(0, 5, (len(sizes), 2))
    v_r = _radial(velocity[group].T, theta) + rng.normal(0, 0.1, len(group)) + (rng.random(len(group)) < 0.2) * 3.0
    vx, vy, residual = _velocities_and_residuals(v_r, theta, group, len(sizes))
    for g in range(len(sizes)):
        mine = group == g
        ex, ey, _ = estimate_velocity(v_r[mine], theta[mine])
        np.testing.assert_allclose([vx[g], vy[g]], [ex, ey], rtol=1e-12, atol=1e-12)
        expected = np.sqrt(np.mean((v_r[mine] - (ex * np.cos(theta[mine]) + ey * np.sin(theta[mine]))) ** 2))
        np.testing.assert_allclose(residual[g], expected, rtol=1e-12, atol=1e-12)
    assert np.isnan(vx).any() and np.isfinite(vx).any()  # groups too small for an estimate, and others
