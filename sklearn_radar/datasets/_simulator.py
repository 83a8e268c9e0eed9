"""Scene simulator: realistic radar recordings in the RadarScenes layout.

The ground truth (ego drive, road, static world, road users) comes from
:mod:`._scenario`; this module turns it into radar detections of four
unsynchronised sensors with the RadarScenes mounting, adds measurement
noise, clutter and multipath ghosts, and writes the detection table of
:mod:`sklearn_radar._schema`.
"""

from __future__ import annotations

import numbers

import numpy as np
import pandas as pd
from sklearn.utils import Bunch, check_random_state
from sklearn.utils._param_validation import Interval, validate_params

from .._schema import (
    ODOMETRY_COLUMNS,
    RADAR_DATA_COLUMNS,
    RADARSCENES_MOUNTING,
    STATIC_LABEL,
    attach_context,
    instance_target,
    make_frame,
    nearest_odometry_index,
)
from ._scenario import ROAD_USER_CLASSES, make_road, make_road_users, make_static_world, simulate_ego

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
CLUTTER_PER_SCAN = 6.0  # false alarms per scan
GHOST_RATE = 0.04  # multipath ghosts per object detection
DIFFUSE_SHARE = 0.3  # object detections spread over the outline rather than from a scattering centre
NEW_TRACK_GAP = 0.5  # s, RadarScenes: a new track id after longer absence
SCAN_BLOCK = 48  # scans processed together for the static world


@validate_params(
    {
        "n_sequences": [Interval(numbers.Integral, 1, None, closed="left")],
        "duration": [Interval(numbers.Real, 0.5, None, closed="left")],
        "random_state": ["random_state"],
        "n_objects": [tuple],
        "static_density": [Interval(numbers.Real, 0, None, closed="neither")],
        "first_sequence": [Interval(numbers.Integral, 1, None, closed="left")],
    },
    prefer_skip_nested_validation=True,
)
def make_scenes(
    n_sequences=4,
    duration=30.0,
    random_state=None,
    *,
    n_objects=(3, 12),
    static_density=1.0,
    first_sequence=1,
):
    """Simulate radar recordings of an urban drive, in the RadarScenes layout.

    An ego car with the four RadarScenes radars drives a curving road,
    changes speed and stops (every sequence of 10 s or more stops once).
    The radars are not synchronised (about 60 ms cycle with jitter each),
    cover +-60 deg and 100 m, and measure range, azimuth (noisier at the
    edge of the field of view), Doppler and RCS.  Most detections are static
    background: walls, parked cars, poles, vegetation, buildings, clutter
    and multipath ghosts.  Between ``n_objects`` moving road users per
    sequence (cars, trucks, buses, cyclists, pedestrians with micro-Doppler,
    pedestrian groups) drive with, against and across the traffic, overtake,
    pass within 1-2 m and vanish for 0.3-1.5 s.  Their detections lie on the
    visible outline and their mean count per scan falls with range and grows
    with size.  Coordinates and Doppler obey the formulas of
    :mod:`sklearn_radar._schema` exactly.

    Parameters
    ----------
    n_sequences : int, default=4
        Number of recordings, >= 1.
    duration : float, default=30.0
        Length of each recording, s, >= 0.5.
    random_state : int, RandomState instance or None, default=None
        Seed; equal seeds give identical data sets.
    n_objects : tuple of (int, int), default=(3, 12)
        Inclusive range ``(low, high)``, ``0 <= low <= high``, of the number
        of moving road users per sequence.
    static_density : float, default=1.0
        Scales the number of static scatterers and clutter (1.0: urban
        street), > 0.
    first_sequence : int, default=1
        Number N >= 1 of the first sequence (folder ``sequence_N``).

    Returns
    -------
    data : :class:`~sklearn.utils.Bunch`
        ``data`` (the detection table), ``target`` (instance id per
        detection, -1 for background), ``groups`` (sequence number per
        detection), ``odometry``, ``sensors`` (mounting), ``sequences``
        (number, name, category) and ``DESCR``.

    Examples
    --------
    >>> from sklearn_radar.datasets import make_scenes
    >>> scenes = make_scenes(n_sequences=1, duration=2.0, random_state=0)
    >>> len(scenes.data) == len(scenes.target) == len(scenes.groups)
    True
    """
    low, high = _check_n_objects(n_objects)
    rng = check_random_state(random_state)
    seeds = rng.randint(0, 2**31 - 1, size=n_sequences)
    data, odometry = [], []
    for i, seed in enumerate(seeds):
        number = first_sequence + i
        det, odo = _simulate_sequence(number, duration, (low, high), static_density, np.random.default_rng(seed))
        data.append(det)
        odometry.append(odo)
    data = pd.concat(data, ignore_index=True)
    odometry = pd.concat(odometry, ignore_index=True)
    numbers_ = np.arange(first_sequence, first_sequence + n_sequences, dtype=np.int64)
    return Bunch(
        data=data,
        target=instance_target(data["track_id"], data["sequence"]),
        groups=data["sequence"].to_numpy(dtype=np.int64),
        odometry=odometry,
        sensors=mounting_frame(RADARSCENES_MOUNTING),
        sequences=pd.DataFrame(
            {
                "sequence": numbers_,
                "name": pd.array([f"sequence_{n}" for n in numbers_], dtype="str"),
                "category": pd.array(["train"] * n_sequences, dtype="str"),
            }
        ),
        DESCR=f"Simulated RadarScenes-layout data: {n_sequences} sequence(s) of {duration:g} s "
        f"(sklearn_radar.datasets.make_scenes, random_state={random_state!r}).",
    )


def mounting_frame(mounting) -> pd.DataFrame:
    """The sensor mounting as a DataFrame indexed by ``sensor_id`` (columns x, y in m, yaw in rad)."""
    ids = sorted(int(k) for k in mounting)
    frame = pd.DataFrame(
        {field: np.array([float(mounting[k][field]) for k in ids]) for field in ("x", "y", "yaw")},
        index=pd.Index(np.array(ids, dtype=np.int64), name="sensor_id"),
    )
    return frame


def _check_n_objects(n_objects):
    if (
        len(n_objects) != 2
        or not all(isinstance(v, numbers.Integral) for v in n_objects)
        or not 0 <= n_objects[0] <= n_objects[1]
    ):
        raise ValueError(f"n_objects must be a pair (low, high) of integers with 0 <= low <= high, got {n_objects!r}")
    return int(n_objects[0]), int(n_objects[1])


def _simulate_sequence(number, duration, n_objects, density, rng):
    """Detection table and odometry of one sequence."""
    t0_us = 156_000_000_000 + 1_000_000_000 * number
    ego = simulate_ego(duration, rng)
    road = make_road(ego)
    odometry = _odometry(ego, duration, t0_us, rng)
    scans = _scan_schedule(duration, t0_us, rng)
    sensor = _sensor_states(ego, scans)

    static = make_static_world(
        road, sensor["s"].min() - MAX_RANGE - 10, sensor["s"].max() + MAX_RANGE + 10, rng, density
    )
    users = make_road_users(ego, road, duration, rng.integers(n_objects[0], n_objects[1] + 1), rng)
    parts = [_static_detections(static, sensor, rng), _clutter(sensor, density, rng)]
    objects = _object_detections(users, sensor, rng)
    parts += [objects, _ghosts(objects, rng)]
    truth = {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}

    scans["odometry_index"] = nearest_odometry_index(scans["timestamp"], odometry["timestamp"].to_numpy())
    measured = _measure(truth, scans, odometry, rng)
    track_id = _track_ids(truth["object"], scans["t"][truth["scan"]], number)
    order = np.lexsort((measured["range_sc"], truth["scan"]))
    radar = {key: value[order] for key, value in measured.items()}
    radar["timestamp"] = scans["timestamp"][truth["scan"]][order]
    radar["sensor_id"] = scans["sensor_id"][truth["scan"]][order]
    radar["label_id"] = truth["label"][order]
    radar["track_id"] = track_id[order]
    radar["uuid"] = _uuids(len(order), rng)
    radar = make_frame(radar, RADAR_DATA_COLUMNS, table=f"sequence_{number}")
    odometry_index = scans["odometry_index"][truth["scan"]][order]
    data = attach_context(radar, number, odometry_index, odometry, RADARSCENES_MOUNTING)
    odometry.insert(0, "sequence", number)
    return data, make_frame(odometry, ODOMETRY_COLUMNS, table=f"sequence_{number} odometry")


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


def _sensor_states(ego, scans):
    """True pose and velocity over ground of the scanning sensor, per scan."""
    x, y, yaw, vx, yaw_rate, s = ego.at(scans["t"])
    mount = np.array([[RADARSCENES_MOUNTING[k][f] for f in ("x", "y", "yaw")] for k in scans["sensor_id"]])
    mx, my, myaw = mount.T
    c, si = np.cos(yaw), np.sin(yaw)
    vsx_car, vsy_car = vx - yaw_rate * my, yaw_rate * mx
    return {
        "x": x + c * mx - si * my,
        "y": y + si * mx + c * my,
        "boresight": yaw + myaw,
        "vx": c * vsx_car - si * vsy_car,
        "vy": si * vsx_car + c * vsy_car,
        "s": s,
        "t": scans["t"],
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


def _truth(scan, r, azimuth, vr, rcs, label, obj):
    return {"scan": scan, "range": r, "azimuth": azimuth, "vr": vr, "rcs": rcs, "label": label, "object": obj}


def _static_vr(sensor, scan, azimuth):
    """True radial velocity of a static target: minus the sensor velocity along the line of sight."""
    angle = azimuth + sensor["boresight"][scan]
    return -(sensor["vx"][scan] * np.cos(angle) + sensor["vy"][scan] * np.sin(angle))


def _static_detections(static, sensor, rng):
    """Detections of the persistent static scatterers, processed in blocks of scans."""
    found = []
    n_scans = len(sensor["s"])
    for start in range(0, n_scans, SCAN_BLOCK):
        scans = np.arange(start, min(start + SCAN_BLOCK, n_scans))
        s_lo = sensor["s"][scans].min() - MAX_RANGE - 5
        s_hi = sensor["s"][scans].max() + MAX_RANGE + 5
        lo, hi = np.searchsorted(static.s, [s_lo, s_hi])
        points = np.arange(lo, hi)
        dx = static.x[points][None, :] - sensor["x"][scans][:, None]
        dy = static.y[points][None, :] - sensor["y"][scans][:, None]
        cos_b, sin_b = np.cos(sensor["boresight"][scans])[:, None], np.sin(sensor["boresight"][scans])[:, None]
        along, across = dx * cos_b + dy * sin_b, dy * cos_b - dx * sin_b
        # Cheap field-of-view and range test first; angles only for what passes.
        seen_scan, seen_point = np.nonzero(
            (np.abs(across) < np.tan(FOV) * along) & (along * along + across * across < MAX_RANGE**2)
        )
        along, across = along[seen_scan, seen_point], across[seen_scan, seen_point]
        scan, point = scans[seen_scan], points[seen_point]
        r, azimuth = np.hypot(along, across), np.arctan2(across, along)
        p = static.p_detect[point] * _visibility(r, azimuth) / (1.0 + (r / 30.0) ** 2)
        hit = rng.random(len(p)) < p
        found.append((scan[hit], point[hit], r[hit], azimuth[hit]))
    scan, point, r, azimuth = (np.concatenate(v) for v in zip(*found, strict=True))
    rcs = static.rcs_mean[point] + rng.normal(0.0, 3.0, len(point))
    vr = _static_vr(sensor, scan, azimuth)
    return _truth(scan, r, azimuth, vr, rcs, np.full(len(scan), STATIC_LABEL), np.full(len(scan), -1))


def _clutter(sensor, density, rng):
    """False alarms: uniform in the field of view; most static, some with random Doppler."""
    n_scans = len(sensor["s"])
    counts = rng.poisson(CLUTTER_PER_SCAN * density, n_scans)
    scan = np.repeat(np.arange(n_scans), counts)
    r = rng.uniform(1.0, MAX_RANGE, len(scan))
    azimuth = rng.uniform(-FOV, FOV, len(scan))
    vr = _static_vr(sensor, scan, azimuth)
    moving = rng.random(len(scan)) < 0.15
    vr[moving] += rng.uniform(-10.0, 10.0, moving.sum())
    rcs = rng.normal(-15.0, 4.0, len(scan))
    return _truth(scan, r, azimuth, vr, rcs, np.full(len(scan), STATIC_LABEL), np.full(len(scan), -1))


def _object_detections(users, sensor, rng):
    """Detections on the visible outline of each road user."""
    parts = [_one_object(i, user, sensor, rng) for i, user in enumerate(users)]
    parts.append(_truth(*(np.zeros(0, dtype=dt) for dt in (int, float, float, float, float, int, int))))
    return {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}


def _one_object(index, user, sensor, rng):
    params = ROAD_USER_CLASSES[user.kind]
    t = sensor["t"]
    cx, cy, vx, vy, heading, yaw_rate = user.kinematics(t)
    r_centre, az_centre = _polar(sensor, np.arange(len(t)), cx, cy)
    mean_count = params["det_10m"] * np.clip((12.0 / np.maximum(r_centre, 1.0)) ** 0.6, 0.3, 1.5)
    mean_count *= _visibility(r_centre, az_centre) * ~user.absent(t) * (r_centre > 1.5)
    scan = np.repeat(np.arange(len(t)), rng.poisson(mean_count))
    along, across = _outline_points(user, sensor, scan, cx, cy, heading, rng)
    c, s = np.cos(heading[scan]), np.sin(heading[scan])
    px = cx[scan] + c * along - s * across
    py = cy[scan] + s * along + c * across
    # Rigid-body velocity of the reflecting point, plus limb/pedal micro-Doppler.
    pvx = vx[scan] - yaw_rate[scan] * (py - cy[scan])
    pvy = vy[scan] + yaw_rate[scan] * (px - cx[scan])
    if params["micro"] > 0:
        swing = 1.0 + params["micro"] * np.sin(
            2 * np.pi * user.gait_hz * t[scan] + rng.uniform(0, 2 * np.pi, len(scan))
        )
        pvx, pvy = pvx * swing, pvy * swing
    r, azimuth = _polar(sensor, scan, px, py)
    angle = azimuth + sensor["boresight"][scan]
    vr = (pvx - sensor["vx"][scan]) * np.cos(angle) + (pvy - sensor["vy"][scan]) * np.sin(angle)
    rcs = params["rcs"] + rng.normal(0.0, 4.0, len(scan))
    keep = _visibility(r, azimuth) > 0
    label = np.full(len(scan), params["label"])
    return _truth(scan[keep], r[keep], azimuth[keep], vr[keep], rcs[keep], label[keep], np.full(keep.sum(), index))


def _outline_points(user, sensor, scan, cx, cy, heading, rng):
    """Reflection points on the outline edges that face the sensor, in the object frame (m).

    Most detections come from the object's persistent scattering centres
    (weighted by how squarely their edge faces the sensor); the rest are
    spread uniformly over the visible edges by apparent length.
    """
    half_length, half_width = user.length / 2, user.width / 2
    dx, dy = sensor["x"][scan] - cx[scan], sensor["y"][scan] - cy[scan]
    c, s = np.cos(heading[scan]), np.sin(heading[scan])
    q_along, q_across = c * dx + s * dy, -s * dx + c * dy
    distance = np.maximum(np.hypot(q_along, q_across), 1e-6)
    # An edge is visible when the sensor lies beyond it; weight = length * cos(incidence).
    w_end = (np.abs(q_along) > half_length) * user.width * np.abs(q_along) / distance
    w_side = (np.abs(q_across) > half_width) * user.length * np.abs(q_across) / distance
    on_end = rng.random(len(scan)) * (w_end + w_side + 1e-12) < w_end
    along = np.where(on_end, np.sign(q_along) * half_length, rng.uniform(-half_length, half_length, len(scan)))
    across = np.where(on_end, rng.uniform(-half_width, half_width, len(scan)), np.sign(q_across) * half_width)

    centres = user.centres
    to_sensor_along = q_along[:, None] - centres[None, :, 0]
    to_sensor_across = q_across[:, None] - centres[None, :, 1]
    facing = (centres[None, :, 2] * to_sensor_along + centres[None, :, 3] * to_sensor_across) / np.maximum(
        np.hypot(to_sensor_along, to_sensor_across), 1e-6
    )
    weight = np.clip(facing, 0.0, None)
    total = weight.sum(axis=1)
    use_centre = (rng.random(len(scan)) >= DIFFUSE_SHARE) & (total > 0)
    pick = (np.cumsum(weight, axis=1) < (rng.random(len(scan)) * total)[:, None]).sum(axis=1)
    pick = np.minimum(pick, len(centres) - 1)
    along = np.where(use_centre, centres[pick, 0], along)
    across = np.where(use_centre, centres[pick, 1], across)
    return along + rng.normal(0, 0.08, len(scan)), across + rng.normal(0, 0.08, len(scan))


def _ghosts(objects, rng):
    """Multipath ghosts: a copy of an object detection farther along the same ray, labelled static."""
    pick = rng.random(len(objects["scan"])) < GHOST_RATE
    n = pick.sum()
    return _truth(
        objects["scan"][pick],
        objects["range"][pick] + rng.uniform(2.0, 8.0, n),
        objects["azimuth"][pick] + rng.normal(0.0, 0.02, n),
        objects["vr"][pick],
        objects["rcs"][pick] - rng.uniform(5.0, 15.0, n),
        np.full(n, STATIC_LABEL),
        np.full(n, -1),
    )


def _measure(truth, scans, odometry, rng):
    """Noisy measurements and the derived RadarScenes fields, as float32."""
    n = len(truth["scan"])
    scan = truth["scan"]
    edge = (np.abs(truth["azimuth"]) / FOV) ** 2
    az_sigma = AZIMUTH_NOISE_BORESIGHT + (AZIMUTH_NOISE_EDGE - AZIMUTH_NOISE_BORESIGHT) * edge
    r = np.maximum(truth["range"] + rng.normal(0.0, RANGE_NOISE, n), 0.2).astype(np.float32)
    azimuth = (truth["azimuth"] + rng.normal(0.0, 1.0, n) * az_sigma).astype(np.float32)
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


def _track_ids(obj, t, sequence):
    """RadarScenes-style track ids: a new id after more than 0.5 s without detection."""
    track = np.full(len(obj), "", dtype=object)
    for index in np.unique(obj[obj >= 0]):
        rows = np.flatnonzero(obj == index)
        rows = rows[np.argsort(t[rows], kind="stable")]
        segment = np.concatenate([[0], np.cumsum(np.diff(t[rows]) > NEW_TRACK_GAP)])
        track[rows] = [f"{sequence:08x}{index:08x}{k:016x}" for k in segment]
    return track


_HEX = np.frombuffer(b"0123456789abcdef", dtype=np.uint8)


def _uuids(n, rng):
    """``n`` random 32-character hexadecimal detection ids, deterministic for ``rng``."""
    words = rng.integers(0, 2**32, size=(n, 4), dtype=np.uint64)
    shifts = np.arange(28, -1, -4, dtype=np.uint64)
    nibbles = (words[:, :, None] >> shifts) & np.uint64(0xF)
    chars = _HEX[nibbles.reshape(n, 32)]
    return np.ascontiguousarray(chars).view("S32").ravel()
