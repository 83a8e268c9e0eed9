"""The simulator's true detections: static world, clutter, road users' outlines and wheels, multipath ghosts.

Each part is a *truth dict* (:func:`_truth`): per detection its scan, true range (m), azimuth (rad), radial
velocity (m/s), RCS (dBsm), label and object index.  Read more in the :ref:`User Guide <user-guide-simulator>`.
"""

from __future__ import annotations

import numpy as np

from .._schema import STATIC_LABEL
from ._presets import DIFFICULTY_PRESETS
from ._scenario import ROAD_USER_CLASSES, aspect_rcs
from ._sensor_model import FOV, MAX_RANGE, _polar, _static_vr, _visibility

CLUTTER_PER_SCAN = 6.0  # false alarms per scan
GHOST_RATE = 0.04  # multipath ghosts per object detection
DIFFUSE_SHARE = 0.3  # object detections spread over the outline rather than from a scattering centre
SCAN_BLOCK = 48  # scans processed together for the static world


def _truth(scan, r, azimuth, vr, rcs, label, obj):
    return {"scan": scan, "range": r, "azimuth": azimuth, "vr": vr, "rcs": rcs, "label": label, "object": obj}


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


def _object_detections(users, sensor, rng, knobs=None, extra=None, signature=None):
    """Detections on the visible outline of each road user, and their world-frame geometry.

    Returns the truth dict and ``world``: per detection the reflecting
    point's position and velocity (``x``, ``y``, ``vx``, ``vy``, m and m/s)
    and the object's centre velocity, heading, length and width, which the
    realistic phenomena (ghosts, spray) start from.
    """
    knobs = DIFFICULTY_PRESETS["easy"] if knobs is None else knobs
    parts = [_one_object(i, user, sensor, rng, knobs, extra, signature) for i, user in enumerate(users)]
    empty = np.zeros(0)
    parts.append(
        (
            _truth(*(np.zeros(0, dtype=dt) for dt in (int, float, float, float, float, int, int))),
            {key: empty for key in _WORLD_KEYS},
        )
    )
    truth = {key: np.concatenate([p[0][key] for p in parts]) for key in parts[0][0]}
    world = {key: np.concatenate([p[1][key] for p in parts]) for key in _WORLD_KEYS}
    return truth, world


_WORLD_KEYS = ("x", "y", "vx", "vy", "cx", "cy", "cvx", "cvy", "heading", "length", "width")


def _one_object(index, user, sensor, rng, knobs=None, extra=None, signature=None):
    knobs = DIFFICULTY_PRESETS["easy"] if knobs is None else knobs
    params = ROAD_USER_CLASSES[user.kind]
    # The object's own mean RCS: its shape, size and material (one draw per object; 0 dB when the knob is off).
    rcs_offset = signature.normal(0.0, knobs["rcs_object_spread"]) if knobs["rcs_object_spread"] > 0 else 0.0
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
    cos_aspect, sin_aspect = _aspect(sensor, scan, cx, cy, heading)
    if knobs["wheel_micro_doppler"] > 0 and params["axles"]:
        px, py, pvx, pvy = _wheel_reflections(
            user, scan, (cx, cy, vx, vy, heading, yaw_rate), (px, py, pvx, pvy), sin_aspect, knobs, signature
        )
    r, azimuth = _polar(sensor, scan, px, py)
    angle = azimuth + sensor["boresight"][scan]
    vr = (pvx - sensor["vx"][scan]) * np.cos(angle) + (pvy - sensor["vy"][scan]) * np.sin(angle)
    rcs = params["rcs"] + rng.normal(0.0, 4.0, len(scan))
    mean_rcs = params["rcs"]
    if knobs["rcs_object_spread"] > 0 or knobs["rcs_aspect"] > 0:
        # The mean RCS of this object from this aspect, dBsm: what the detection threshold sees.
        mean_rcs = params["rcs"] + rcs_offset + knobs["rcs_aspect"] * aspect_rcs(params, cos_aspect, sin_aspect)
        rcs = rcs + (mean_rcs - params["rcs"])
    keep = _visibility(r, azimuth) > 0
    if np.isfinite(knobs["detection_range"]) or knobs["object_detection_probability"] < 1:
        # Radar equation with a Swerling-1 target: P_d = exp(-ln 2 (r / r_50)^4), r_50 growing as RCS^(1/4).
        r_50 = knobs["detection_range"] * 10 ** ((mean_rcs - 10.0) / 40.0)
        p_d = knobs["object_detection_probability"] * np.exp(-np.log(2.0) * (r / r_50) ** 4)
        keep &= extra.random(len(scan)) < p_d
    label = np.full(len(scan), params["label"])
    obj = np.full(len(scan), index)
    if user.stop is not None:
        # RadarScenes annotates moving road users only: a standing one is static background, without a track id.
        standing = user.standing(t[scan])
        label, obj = np.where(standing, STATIC_LABEL, label), np.where(standing, -1, obj)
    if knobs["glint"] > 0:
        # Last: glint moves the angle estimate, not the reflecting point, its Doppler or whether it is seen.
        azimuth = _glint(azimuth, r, user, knobs["glint"], signature)
    truth = _truth(scan[keep], r[keep], azimuth[keep], vr[keep], rcs[keep], label[keep], obj[keep])
    n = int(keep.sum())
    world = {
        "x": px[keep],
        "y": py[keep],
        "vx": pvx[keep],
        "vy": pvy[keep],
        "cx": cx[scan][keep],
        "cy": cy[scan][keep],
        "cvx": vx[scan][keep],
        "cvy": vy[scan][keep],
        "heading": heading[scan][keep],
        "length": np.full(n, user.length),
        "width": np.full(n, user.width),
    }
    return truth, world


def _glint(azimuth, r, user, share, rng):
    """Angle glint: a ``share`` of the detections' azimuths wander by about the object's angular extent.

    The error is normal, its standard deviation half the angular extent ``hypot(length, width) / r`` (rad); see
    ``glint`` in the :ref:`User Guide <simulator-knobs>`.
    """
    hit = rng.random(len(azimuth)) < share
    extent = np.hypot(user.length, user.width) / np.maximum(r[hit], 1.0)
    out = azimuth.copy()
    out[hit] += rng.normal(0.0, 0.5, int(hit.sum())) * extent
    return out


def _aspect(sensor, scan, cx, cy, heading):
    """Cosine and sine of the aspect angle of each detection's scan: body axis against the line body-sensor."""
    dx, dy = sensor["x"][scan] - cx[scan], sensor["y"][scan] - cy[scan]
    c, s = np.cos(heading[scan]), np.sin(heading[scan])
    q_along, q_across = c * dx + s * dy, -s * dx + c * dy
    distance = np.maximum(np.hypot(q_along, q_across), 1e-6)
    return q_along / distance, q_across / distance


#: m, radius of the wheels of the wheeled road users (a car tyre of 0.6-0.7 m diameter, a 28-inch bicycle wheel).
WHEEL_RADIUS = 0.33


def _wheel_reflections(user, scan, motion, points, sin_aspect, knobs, rng):
    """Move a share of a wheeled road user's detections onto its wheels, with the wheels' micro-Doppler.

    A wheel rolling without slip at hub velocity ``v`` turns about its
    contact point: the rim point at angle ``phi`` (``R cos phi`` ahead of the
    hub, ``R sin phi`` above it) moves horizontally at ``v (1 + sin phi)``,
    from 0 at the bottom to ``2 v`` at the top.  A detection lies on a wheel
    of the visible side with probability ``wheel_micro_doppler * |sin aspect|``;
    it keeps its scan and gets a uniform ``phi``, an axle of the class
    (``ROAD_USER_CLASSES[...]["axles"]``) and the velocity of that rim point.
    Read more in the :ref:`User Guide <simulator-knobs>`.
    """
    cx, cy, vx, vy, heading, yaw_rate = motion
    px, py, pvx, pvy = points
    n = len(scan)
    on_wheel = rng.random(n) < knobs["wheel_micro_doppler"] * np.abs(sin_aspect)
    axles = np.asarray(ROAD_USER_CLASSES[user.kind]["axles"]) * user.length / 2
    axle = axles[rng.integers(len(axles), size=n)]
    phi = rng.uniform(0.0, 2 * np.pi, n)
    along = axle + WHEEL_RADIUS * np.cos(phi)
    across = np.sign(sin_aspect) * user.width / 2
    c, s = np.cos(heading[scan]), np.sin(heading[scan])
    wx = cx[scan] + c * along - s * across
    wy = cy[scan] + s * along + c * across
    roll = 1.0 + np.sin(phi)
    hub_vx = vx[scan] - yaw_rate[scan] * (wy - cy[scan])
    hub_vy = vy[scan] + yaw_rate[scan] * (wx - cx[scan])
    return (
        np.where(on_wheel, wx, px),
        np.where(on_wheel, wy, py),
        np.where(on_wheel, hub_vx * roll, pvx),
        np.where(on_wheel, hub_vy * roll, pvy),
    )


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
