"""The simulator's sensor model: scan schedule, sensor poses, odometry as the car reports it, noisy measurements.

Distances are in m, angles in rad, velocities in m/s, times in s (time stamps in µs).  Read more in the
:ref:`User Guide <user-guide-simulator>`.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from .._schema import RADARSCENES_MOUNTING

# Sensor model (RadarScenes sensors: 0.15 m range resolution, 0.1 km/h
# Doppler resolution, 0.5 deg azimuth resolution at boresight, 2 deg at the edge).
MAX_RANGE = 100.0  # m
FOV = np.deg2rad(60.0)  # rad, half opening angle
CYCLE = 0.060  # s, mean measurement cycle per sensor
CYCLE_JITTER = 0.003  # s, standard deviation of the cycle time
ODOMETRY_PERIOD = 0.020  # s (50 Hz)
RANGE_NOISE = 0.05  # m
DOPPLER_NOISE = 0.04  # m/s
DOPPLER_OUTLIER_RATE = 0.02
AZIMUTH_NOISE_BORESIGHT = np.deg2rad(0.15)  # rad, about 0.3 x the resolution
AZIMUTH_NOISE_EDGE = np.deg2rad(0.6)  # rad
AZIMUTH_MARGIN = np.deg2rad(2.0)  # rad, beyond the field of view that an azimuth estimate can reach (realistic)
AZIMUTH_NOISE_GROWTH = 2.5  # at most this factor more azimuth noise at range: 8 dB less SNR, the detection threshold


def _odometry(ego, duration, t0_us, rng) -> pd.DataFrame:
    """Ego odometry at about 50 Hz, covering the whole recording."""
    t = np.arange(-0.1, duration + 0.1, ODOMETRY_PERIOD)
    t = np.sort(t + rng.normal(0.0, 0.0005, len(t)))
    timestamp = t0_us + np.round(t * 1e6).astype(np.int64)
    x, y, yaw, vx, yaw_rate, _ = ego.at((timestamp - t0_us) * 1e-6)
    return pd.DataFrame(
        {
            "timestamp": timestamp,
            "x_seq": x.astype(np.float32),
            "y_seq": y.astype(np.float32),
            "yaw_seq": np.mod(yaw + np.pi, 2 * np.pi).astype(np.float32) - np.float32(np.pi),
            "vx": vx.astype(np.float32),
            "yaw_rate": yaw_rate.astype(np.float32),
        }
    )


def _odometry_errors(odometry, knobs, rng):
    """Odometry as the car reports it: speed scale error and noise, gyro bias and noise, dead-reckoned pose.

    Returns ``odometry`` itself when every odometry knob is 0 (no draw).
    """
    names = ("odometry_speed_scale", "odometry_speed_noise", "odometry_yaw_rate_bias", "odometry_yaw_rate_noise")
    if not any(knobs[name] > 0 for name in names):
        return odometry
    n = len(odometry)
    vx = odometry["vx"].to_numpy(dtype=float)
    yaw_rate = odometry["yaw_rate"].to_numpy(dtype=float)
    scale = 1.0 + rng.normal(0.0, 1.0) * knobs["odometry_speed_scale"]
    # A standing wheel gives no ticks: the speed noise vanishes at standstill.
    vx = np.where(vx > 0.01, vx * scale + rng.normal(0.0, 1.0, n) * knobs["odometry_speed_noise"], vx)
    yaw_rate = (
        yaw_rate
        + rng.normal(0.0, 1.0) * knobs["odometry_yaw_rate_bias"]
        + rng.normal(0.0, 1.0, n) * knobs["odometry_yaw_rate_noise"]
    )
    t = (odometry["timestamp"].to_numpy() - odometry["timestamp"].iloc[0]) * 1e-6
    dt = np.diff(t)
    yaw = float(odometry["yaw_seq"].iloc[0]) + np.concatenate(
        [[0.0], np.cumsum(0.5 * (yaw_rate[1:] + yaw_rate[:-1]) * dt)]
    )
    heading = 0.5 * (yaw[1:] + yaw[:-1])
    step = 0.5 * (vx[1:] + vx[:-1]) * dt
    x = float(odometry["x_seq"].iloc[0]) + np.concatenate([[0.0], np.cumsum(step * np.cos(heading))])
    y = float(odometry["y_seq"].iloc[0]) + np.concatenate([[0.0], np.cumsum(step * np.sin(heading))])
    return odometry.assign(
        x_seq=x.astype(np.float32),
        y_seq=y.astype(np.float32),
        yaw_seq=(np.mod(yaw + np.pi, 2 * np.pi) - np.pi).astype(np.float32),
        vx=vx.astype(np.float32),
        yaw_rate=yaw_rate.astype(np.float32),
    )


def _sensor_errors(knobs, rng):
    """Per-sensor yaw error (rad) and time-stamp offset (s) of one sequence; None when both knobs are 0."""
    if not (knobs["mounting_error"] > 0 or knobs["time_offset"] > 0):
        return None
    ids = sorted(RADARSCENES_MOUNTING)
    yaw = rng.normal(0.0, 1.0, len(ids)) * knobs["mounting_error"]
    offset = rng.normal(0.0, 1.0, len(ids)) * knobs["time_offset"]
    return {"yaw": dict(zip(ids, yaw, strict=True)), "offset": dict(zip(ids, offset, strict=True))}


def _scan_schedule(duration, t0_us, rng):
    """Unsynchronised scans of the four sensors, sorted by unique µs timestamps."""
    times, sensors = [], []
    for sensor_id in RADARSCENES_MOUNTING:
        n = int(duration / CYCLE) + 5
        cycle = np.clip(rng.normal(CYCLE, CYCLE_JITTER, n), CYCLE - 0.01, CYCLE + 0.01)
        t = rng.uniform(0.0, CYCLE) + np.concatenate([[0.0], np.cumsum(cycle[:-1])])
        t = t[t < duration]
        times.append(t)
        sensors.append(np.full(len(t), sensor_id, dtype=np.int64))
    timestamp = t0_us + np.round(np.concatenate(times) * 1e6).astype(np.int64)
    sensor_id = np.concatenate(sensors)
    order = np.argsort(timestamp, kind="stable")
    timestamp, sensor_id = timestamp[order], sensor_id[order]
    # Scene keys are timestamps: two sensors never share one.
    for i in range(1, len(timestamp)):
        if timestamp[i] <= timestamp[i - 1]:
            timestamp[i] = timestamp[i - 1] + 1
    return {"timestamp": timestamp, "sensor_id": sensor_id, "t": (timestamp - t0_us) * 1e-6}


def _sensor_states(ego, scans, errors=None):
    """True pose and velocity over ground of the scanning sensor, per scan.

    ``errors`` (:func:`_sensor_errors`) turns each sensor by its yaw error
    and measures at its time stamp minus its offset: ``t`` is then the true
    time of the measurement, which the time stamp no longer is.
    """
    t = scans["t"]
    mount = np.array([[RADARSCENES_MOUNTING[k][f] for f in ("x", "y", "yaw")] for k in scans["sensor_id"]])
    mx, my, myaw = mount.T
    if errors is not None:
        t = t - np.array([errors["offset"][k] for k in scans["sensor_id"]])
        myaw = myaw + np.array([errors["yaw"][k] for k in scans["sensor_id"]])
    x, y, yaw, vx, yaw_rate, s = ego.at(t)
    c, si = np.cos(yaw), np.sin(yaw)
    vsx_car, vsy_car = vx - yaw_rate * my, yaw_rate * mx
    return {
        "x": x + c * mx - si * my,
        "y": y + si * mx + c * my,
        "boresight": yaw + myaw,
        "vx": c * vsx_car - si * vsy_car,
        "vy": si * vsx_car + c * vsy_car,
        "s": s,
        "t": t,
    }


def _polar(sensor, scan, x, y):
    """Range (m) and azimuth (rad) of world points seen from the scanning sensor."""
    dx, dy = x - sensor["x"][scan], y - sensor["y"][scan]
    azimuth = np.mod(np.arctan2(dy, dx) - sensor["boresight"][scan] + np.pi, 2 * np.pi) - np.pi
    return np.hypot(dx, dy), azimuth


def _visibility(r, azimuth):
    """Detection probability factor of the field-of-view edge and the range limit."""
    inside = (r > 0.5) & (r < MAX_RANGE) & (np.abs(azimuth) < FOV)
    return inside * (1.0 - 0.6 * (np.abs(azimuth) / FOV) ** 4)


def _static_vr(sensor, scan, azimuth):
    """True radial velocity of a static target: minus the sensor velocity along the line of sight."""
    angle = azimuth + sensor["boresight"][scan]
    return -(sensor["vx"][scan] * np.cos(angle) + sensor["vy"][scan] * np.sin(angle))


def _measure(truth, scans, odometry, rng, angular_noise_range=np.inf):
    """Noisy measurements and the derived RadarScenes fields, as float32.

    Beyond ``angular_noise_range`` (m) the azimuth noise grows with the
    square of the range (its variance with 1/SNR, SNR with r^-4), up to
    :data:`AZIMUTH_NOISE_GROWTH` times its value: the SNR of a detection
    cannot fall below the detection threshold.
    """
    n = len(truth["scan"])
    scan = truth["scan"]
    edge = (np.abs(truth["azimuth"]) / FOV) ** 2
    az_sigma = AZIMUTH_NOISE_BORESIGHT + (AZIMUTH_NOISE_EDGE - AZIMUTH_NOISE_BORESIGHT) * edge
    limit = None
    if np.isfinite(angular_noise_range):
        growth = np.clip(truth["range"] / angular_noise_range, 1.0, np.sqrt(AZIMUTH_NOISE_GROWTH)) ** 2
        az_sigma = az_sigma * growth
        limit = FOV + AZIMUTH_MARGIN  # the angle estimator's grid ends a little beyond the field of view
    r = np.maximum(truth["range"] + rng.normal(0.0, RANGE_NOISE, n), 0.2).astype(np.float32)
    azimuth = truth["azimuth"] + rng.normal(0.0, 1.0, n) * az_sigma
    azimuth = (azimuth if limit is None else np.clip(azimuth, -limit, limit)).astype(np.float32)
    vr = truth["vr"] + rng.normal(0.0, DOPPLER_NOISE, n)
    outlier = rng.random(n) < DOPPLER_OUTLIER_RATE
    vr[outlier] += rng.normal(0.0, 0.5, outlier.sum())
    vr = vr.astype(np.float32)

    row = scans["odometry_index"][scan]
    mount = np.array([[RADARSCENES_MOUNTING[k][f] for f in ("x", "y", "yaw")] for k in (1, 2, 3, 4)])
    mx, my, myaw = (mount[scans["sensor_id"][scan] - 1, i].astype(np.float32).astype(float) for i in range(3))
    angle = azimuth.astype(float) + myaw
    x_cc = mx + r * np.cos(angle)
    y_cc = my + r * np.sin(angle)
    ego = {
        name: odometry[name].to_numpy().astype(float)[row] for name in ("x_seq", "y_seq", "yaw_seq", "vx", "yaw_rate")
    }
    c, s = np.cos(ego["yaw_seq"]), np.sin(ego["yaw_seq"])
    sensor_vx, sensor_vy = ego["vx"] - ego["yaw_rate"] * my, ego["yaw_rate"] * mx
    vr_compensated = vr + sensor_vx * np.cos(angle) + sensor_vy * np.sin(angle)
    return {
        "range_sc": r,
        "azimuth_sc": azimuth,
        "rcs": truth["rcs"].astype(np.float32),
        "vr": vr,
        "vr_compensated": vr_compensated.astype(np.float32),
        "x_cc": x_cc.astype(np.float32),
        "y_cc": y_cc.astype(np.float32),
        "x_seq": (ego["x_seq"] + c * x_cc - s * y_cc).astype(np.float32),
        "y_seq": (ego["y_seq"] + s * x_cc + c * y_cc).astype(np.float32),
    }
