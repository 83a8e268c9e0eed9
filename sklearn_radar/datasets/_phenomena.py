"""The background detections of the simulator's realistic phenomena: mirror and second-bounce ghosts, rain, spray
and sidelobes.

Read more in the :ref:`User Guide <simulator-knobs>`.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .._schema import STATIC_LABEL
from ._detections import _truth
from ._sensor_model import FOV, MAX_RANGE, _polar, _static_vr, _visibility

VEHICLE_LABELS = (0, 1, 2, 3)  # car, large vehicle, truck, bus: the road users that throw up spray
STRONG_RCS = 10.0  # dBsm: detections this strong show sidelobes and multipath mirrors


def _phenomena(static_part, objects, world, static, road, sensor, knobs, rng):
    """The background detections of the realistic phenomena: mirrored and second-bounce ghosts, rain, spray and
    sidelobes.  Each is a truth dict (label static, no object); none is drawn for a knob of 0."""
    parts = []
    if knobs["multipath"] > 0:
        parts.append(_mirror_ghosts(static_part, objects, world, static, road, sensor, knobs["multipath"], rng))
    if knobs["second_bounce"] > 0:
        parts.append(_second_bounce(objects, knobs["second_bounce"], rng))
    if knobs["rain"] > 0:
        parts.append(_rain(sensor, knobs["rain"], rng))
    if knobs["spray"] > 0:
        parts.append(_spray(objects, world, sensor, knobs["spray"], rng))
    if knobs["sidelobes"] > 0:
        parts.append(_sidelobes([static_part, objects, *parts], knobs["sidelobes"], rng))
    return parts


def _background(scan, r, azimuth, vr, rcs):
    n = len(scan)
    return _truth(scan, r, azimuth, vr, rcs, np.full(n, STATIC_LABEL), np.full(n, -1))


def _seen(sensor, scan, x, y, vx, vy, rcs):
    """Background detections of world points with velocities, where the sensor sees them."""
    r, azimuth = _polar(sensor, scan, x, y)
    angle = azimuth + sensor["boresight"][scan]
    vr = (vx - sensor["vx"][scan]) * np.cos(angle) + (vy - sensor["vy"][scan]) * np.sin(angle)
    keep = _visibility(r, azimuth) > 0
    return _background(scan[keep], r[keep], azimuth[keep], vr[keep], rcs[keep])


def _mirror_ghosts(static_part, objects, world, static, road, sensor, rate, rng):
    """Multipath: the reflector seen in the mirror of the wall or guard rail nearer to it.

    The path sensor-wall-reflector is as long as the line from the sensor to
    the mirror image, and its length changes as the mirror image moves: a
    ghost sits at the image's position with the image's (mirrored) velocity.
    """
    walls = np.sort(np.asarray(static.walls, dtype=float))
    pick = np.flatnonzero(rng.random(len(objects["scan"])) < rate)
    scan, x, y = objects["scan"][pick], world["x"][pick], world["y"][pick]
    vx, vy, rcs = world["vx"][pick], world["vy"][pick], objects["rcs"][pick]
    strong = np.flatnonzero(static_part["rcs"] >= STRONG_RCS)
    strong = strong[rng.random(len(strong)) < rate]
    s_scan = static_part["scan"][strong]
    angle = static_part["azimuth"][strong] + sensor["boresight"][s_scan]
    s_x = sensor["x"][s_scan] + static_part["range"][strong] * np.cos(angle)
    s_y = sensor["y"][s_scan] + static_part["range"][strong] * np.sin(angle)
    scan, x, y = np.concatenate([scan, s_scan]), np.concatenate([x, s_x]), np.concatenate([y, s_y])
    vx, vy = np.concatenate([vx, np.zeros(len(strong))]), np.concatenate([vy, np.zeros(len(strong))])
    rcs = np.concatenate([rcs, static_part["rcs"][strong]])
    if len(walls) < 2 or len(scan) == 0:
        return _background(*(np.zeros(0, dtype=dt) for dt in (int, float, float, float, float)))
    # Road coordinates of the reflector: the nearest point of the road polyline, its normal to the left.
    _, nearest = cKDTree(np.c_[road.x, road.y]).query(np.c_[x, y])
    nx, ny = -np.sin(road.heading[nearest]), np.cos(road.heading[nearest])
    d = (x - road.x[nearest]) * nx + (y - road.y[nearest]) * ny
    inside = (d > walls[0]) & (d < walls[-1])
    wall = np.where(d - walls[0] < walls[-1] - d, walls[0], walls[-1])
    shift = 2 * (wall - d)
    v_normal = vx * nx + vy * ny
    ghost = _seen(
        sensor,
        scan[inside],
        (x + shift * nx)[inside],
        (y + shift * ny)[inside],
        (vx - 2 * v_normal * nx)[inside],
        (vy - 2 * v_normal * ny)[inside],
        rcs[inside] - rng.uniform(6.0, 12.0, int(inside.sum())),
    )
    return ghost


def _second_bounce(objects, rate, rng):
    """Ghosts of the path sensor-object-car-object-sensor: twice the range and twice the radial velocity."""
    pick = rng.random(len(objects["scan"])) < rate
    r = 2 * objects["range"][pick]
    seen = r < MAX_RANGE
    n = int(seen.sum())
    return _background(
        objects["scan"][pick][seen],
        r[seen] + rng.normal(0.0, 0.1, n),
        objects["azimuth"][pick][seen],
        2 * objects["vr"][pick][seen],
        objects["rcs"][pick][seen] - rng.uniform(10.0, 15.0, n),
    )


def _rain(sensor, rate, rng):
    """Rain and road-spray clutter: mostly within 10 m, radial velocity of wind-blown drops (s.d. 0.8 m/s)."""
    n_scans = len(sensor["s"])
    scan = np.repeat(np.arange(n_scans), rng.poisson(rate, n_scans))
    r = 1.0 + rng.exponential(8.0, len(scan))
    keep = r < MAX_RANGE
    scan, r = scan[keep], r[keep]
    azimuth = rng.uniform(-FOV, FOV, len(scan))
    vr = _static_vr(sensor, scan, azimuth) + rng.normal(0.0, 0.8, len(scan))
    return _background(scan, r, azimuth, vr, rng.normal(-25.0, 3.0, len(scan)))


def _spray(objects, world, sensor, rate, rng):
    """Spray thrown up behind the rear wheels of vehicles, moving with 30-90 % of the vehicle's velocity."""
    vehicle = np.isin(objects["label"], VEHICLE_LABELS)
    pick = np.flatnonzero(vehicle & (rng.random(len(vehicle)) < rate))
    n = len(pick)
    along = -world["length"][pick] / 2 - rng.uniform(0.0, 1.5, n)
    across = rng.choice([-1.0, 1.0], n) * (world["width"][pick] / 2 - 0.2) + rng.normal(0.0, 0.3, n)
    c, s = np.cos(world["heading"][pick]), np.sin(world["heading"][pick])
    x = world["cx"][pick] + c * along - s * across
    y = world["cy"][pick] + s * along + c * across
    share = rng.uniform(0.3, 0.9, n)
    return _seen(
        sensor,
        objects["scan"][pick],
        x,
        y,
        world["cvx"][pick] * share,
        world["cvy"][pick] * share,
        rng.normal(-20.0, 4.0, n),
    )


def _sidelobes(parts, rate, rng):
    """Sidelobes of strong detections: 2-6 deg beside them, at their range and radial velocity, 15-25 dB weaker."""
    scan, r, azimuth, vr, rcs = (
        np.concatenate([p[key] for p in parts]) for key in ("scan", "range", "azimuth", "vr", "rcs")
    )
    pick = (rcs >= STRONG_RCS) & (rng.random(len(rcs)) < rate)
    n = int(pick.sum())
    side = azimuth[pick] + rng.choice([-1.0, 1.0], n) * np.deg2rad(rng.uniform(2.0, 6.0, n))
    keep = np.abs(side) < FOV
    return _background(
        scan[pick][keep],
        r[pick][keep] + rng.normal(0.0, 0.05, int(keep.sum())),
        side[keep],
        vr[pick][keep],
        rcs[pick][keep] - rng.uniform(15.0, 25.0, int(keep.sum())),
    )
