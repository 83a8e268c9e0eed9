"""Ground truth of a simulated drive: ego motion, road, static world, road users.

Everything here is in the sequence (world) frame, in m, s, rad.  The road
follows the ego path: positions along it are given in road coordinates
``(s, d)`` (arclength along the ego path, lateral offset to the left).
Measurement (what a radar sees of this world) lives in ``_simulator``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Integration step of the ego motion, s.
EGO_DT = 0.005
MAX_ACCEL = 2.5  # m/s^2, ego acceleration and braking limit
MAX_LATERAL_ACCEL = 2.5  # m/s^2, bounds the curvature at speed
MAX_CURVATURE = 0.04  # 1/m, road radius of at least 25 m

# Road layout (lateral offsets d in m, positive to the left, ego lane at 0).
OVERTAKING_LANE = 3.5
ONCOMING_LANE = 7.0
BIKE_LANE = -2.6
RIGHT_SIDEWALK = -7.0
LEFT_SIDEWALK = 10.5


@dataclass
class EgoMotion:
    """Ego trajectory sampled every :data:`EGO_DT` seconds from ``t[0]``."""

    t: np.ndarray  # s
    x: np.ndarray  # m
    y: np.ndarray  # m
    yaw: np.ndarray  # rad
    vx: np.ndarray  # m/s
    yaw_rate: np.ndarray  # rad/s
    s: np.ndarray  # m, distance driven

    def at(self, times):
        """Pose and velocity (x, y, yaw, vx, yaw_rate, s) at ``times`` (s), linear interpolation."""
        return tuple(np.interp(times, self.t, v) for v in (self.x, self.y, self.yaw, self.vx, self.yaw_rate, self.s))


@dataclass
class Road:
    """The ego path as a function of arclength, extended straight at both ends."""

    s: np.ndarray
    x: np.ndarray
    y: np.ndarray
    heading: np.ndarray

    def to_world(self, s, d):
        """World x, y of road coordinates (s along the path, d to the left), in m."""
        x = np.interp(s, self.s, self.x)
        y = np.interp(s, self.s, self.y)
        heading = np.interp(s, self.s, self.heading)
        return x - d * np.sin(heading), y + d * np.cos(heading)

    def heading_at(self, s):
        return np.interp(s, self.s, self.heading)


@dataclass
class StaticScatterers:
    """Persistent static reflection points."""

    x: np.ndarray  # m
    y: np.ndarray  # m
    s: np.ndarray  # m, road arclength (for culling)
    p_detect: np.ndarray  # detection probability at close range
    rcs_mean: np.ndarray  # dBsm
    walls: tuple = ()  # lateral offsets d (m) of the wall or guard-rail lines: the multipath mirrors


#: Road-user classes: RadarScenes label, size (length, width) ranges in m,
#: mean detections per scan at 10 m range, micro-Doppler amplitude, RCS in dBsm.
#: The class signatures of the realistic preset (off in "easy", see
#: ``_simulator.DIFFICULTY_PRESETS``): ``rcs_side`` and ``rcs_oblique`` (dB) shape
#: the aspect dependence of the RCS (:func:`aspect_rcs`), ``axles`` are the
#: positions of the wheel axles along the body, as fractions of half the length
#: (a car's wheelbase is about 60 % of its length; no wheels: empty).
ROAD_USER_CLASSES = {
    "car": dict(
        label=0, length=(4.0, 5.0), width=(1.7, 1.95), det_10m=6.0, micro=0.0, rcs=5.0,
        rcs_side=6.0, rcs_oblique=6.0, axles=(-0.6, 0.6),
    ),
    "truck": dict(
        label=2, length=(7.0, 12.0), width=(2.4, 2.55), det_10m=10.0, micro=0.0, rcs=12.0,
        rcs_side=8.0, rcs_oblique=8.0, axles=(-0.75, -0.55, 0.65),
    ),
    "bus": dict(
        label=3, length=(11.0, 13.0), width=(2.5, 2.55), det_10m=11.0, micro=0.0, rcs=12.0,
        rcs_side=8.0, rcs_oblique=8.0, axles=(-0.45, 0.6),
    ),
    "bicycle": dict(
        label=5, length=(1.6, 1.9), width=(0.5, 0.7), det_10m=2.5, micro=0.35, rcs=-3.0,
        rcs_side=10.0, rcs_oblique=0.0, axles=(-0.6, 0.6),
    ),
    "pedestrian": dict(
        label=7, length=(0.4, 0.6), width=(0.5, 0.7), det_10m=1.8, micro=0.9, rcs=-8.0,
        rcs_side=0.0, rcs_oblique=0.0, axles=(),
    ),
    "pedestrian_group": dict(
        label=8, length=(0.8, 1.4), width=(1.4, 3.0), det_10m=3.5, micro=0.9, rcs=-5.0,
        rcs_side=0.0, rcs_oblique=0.0, axles=(),
    ),
}  # fmt: skip


def aspect_rcs(params, cos_aspect, sin_aspect):
    """Aspect dependence of a road user's RCS, dB, zero on average over all aspects.

    ``cos_aspect`` and ``sin_aspect`` are the cosine and sine of the aspect
    angle: the angle between the body's forward axis and the line from the
    body to the sensor (0: seen head-on from ahead, pi/2: broadside).  Two
    terms, both of mean 0 over uniformly distributed aspects::

        rcs_side * (sin^2 - 1/2) + rcs_oblique * (|cos 2 aspect| - 2 / pi)

    The first makes the long side stronger than the ends (a larger flat
    surface; a bicycle's frame and wheels broadside against its narrow front),
    the second makes the principal aspects (head-on, tail-on and broadside,
    where flat panels face the radar and reflect specularly) stronger than the
    oblique ones.  A car (6 dB, 6 dB) is about 5 dB above its average
    broadside, 1 dB below it head-on and 4 dB below it at 45 deg.
    """
    cos_2 = cos_aspect**2 - sin_aspect**2
    return params["rcs_side"] * (sin_aspect**2 - 0.5) + params["rcs_oblique"] * (np.abs(cos_2) - 2 / np.pi)


@dataclass
class RoadUser:
    """A moving object with a trajectory ``position(t)`` in the world frame."""

    kind: str
    length: float  # m
    width: float  # m
    road: Road
    s0: float  # m, road arclength at t = 0 (or of the crossing point)
    speed: float  # m/s along the road (negative: oncoming) or across it
    d0: float  # m, lateral offset (or start offset of a crossing)
    crossing: bool = False
    follow_ego: EgoMotion | None = None  # leader: s(t) = s_ego(t + lag) + gap
    lag: float = 0.0
    gap: float = 0.0
    t_cross: float = 0.0
    absences: tuple = ()  # (start, end) intervals, s, without any detection
    gait_hz: float = 0.0
    centres: np.ndarray | None = None  # (K, 4): scattering centres (along, across) and outward normals, m
    path: tuple | None = None  # (arclength, x, y) of a world-frame path driven at ``speed`` from ``s0`` (m)
    stop: tuple | None = None  # (brake, halt, start, cruise) times, s: one stop (:func:`add_stops`)

    @property
    def params(self):
        return ROAD_USER_CLASSES[self.kind]

    def position(self, t):
        """World position of the object centre at times ``t`` (s), in m."""
        t = np.asarray(t, dtype=float)
        if self.path is not None:
            along, px, py = self.path
            s = self.s0 + self.speed * self.travel_time(t)
            return np.interp(s, along, px), np.interp(s, along, py)
        if self.follow_ego is not None:
            return self.road.to_world(self._leader_s(t), np.zeros_like(t))
        if self.crossing:
            d = self.d0 + self.speed * (t - self.t_cross)
            return self.road.to_world(np.full_like(t, self.s0), d)
        return self.road.to_world(self.s0 + self.speed * self.travel_time(t), np.full_like(t, self.d0))

    def travel_time(self, t):
        """Time ``t`` (s) less the time lost to the stop: the object has moved as far as at constant speed by then.

        Without a stop it is ``t``.  With ``stop = (brake, halt, start, cruise)`` the speed falls linearly from
        ``speed`` at ``brake`` to 0 at ``halt`` (constant deceleration), stays 0 until ``start`` and rises
        linearly back to ``speed`` at ``cruise``.
        """
        t = np.asarray(t, dtype=float)
        if self.stop is None:
            return t
        return t - _lost_time(t, *self.stop)

    def standing(self, t):
        """True at the times ``t`` (s) at which the object stands still (between ``halt`` and ``start``)."""
        t = np.asarray(t, dtype=float)
        if self.stop is None:
            return np.zeros(t.shape, dtype=bool)
        return (t >= self.stop[1]) & (t < self.stop[2])

    def kinematics(self, t, h=0.01):
        """Centre (x, y), velocity (vx, vy), heading and yaw rate at times ``t``.

        Derivatives are central differences of :meth:`position` with step
        ``h`` (s), so every trajectory type shares one definition of velocity.
        """
        t = np.asarray(t, dtype=float)
        x, y = self.position(t)
        x1, y1 = self.position(t + h)
        x0, y0 = self.position(t - h)
        vx, vy = (x1 - x0) / (2 * h), (y1 - y0) / (2 * h)
        heading = self._heading(t, h)
        yaw_rate = _wrap(self._heading(t + h, h) - self._heading(t - h, h)) / (2 * h)
        return x, y, vx, vy, heading, yaw_rate

    def _leader_s(self, t):
        return np.interp(t + self.lag, self.follow_ego.t, self.follow_ego.s) + self.gap

    def _heading(self, t, h):
        """Direction of motion; the road direction while (nearly) standing."""
        x1, y1 = self.position(t + h)
        x0, y0 = self.position(t - h)
        moving = np.hypot(x1 - x0, y1 - y0) > 0.2 * 2 * h  # faster than 0.2 m/s
        if self.path is not None:
            rest = np.zeros_like(t)  # a path is driven at a constant speed > 0.2 m/s
        elif self.follow_ego is not None:
            rest = self.road.heading_at(self._leader_s(t))
        elif self.crossing:
            rest = self.road.heading_at(np.full_like(t, self.s0)) + np.pi / 2 * np.sign(self.speed)
        else:
            rest = self.road.heading_at(self.s0 + self.speed * self.travel_time(t)) + np.pi * (self.speed < 0)
        return np.where(moving, np.arctan2(y1 - y0, x1 - x0), rest)

    def absent(self, t):
        t = np.asarray(t, dtype=float)
        out = np.zeros(t.shape, dtype=bool)
        for start, end in self.absences:
            out |= (t >= start) & (t < end)
        return out


def _lost_time(t, brake, halt, start, cruise):
    """Integral from -inf to ``t`` of ``1 - v(t') / v`` for the stop's speed profile (s): a trapezoid in time."""
    ramp_down = np.clip(t, brake, halt) - brake
    lost = ramp_down**2 / (2 * max(halt - brake, 1e-9))
    lost += np.clip(t, halt, start) - halt
    ramp_up = np.clip(t, start, cruise) - start
    lost += ramp_up - ramp_up**2 / (2 * max(cruise - start, 1e-9))
    return lost


def _wrap(angle):
    return (angle + np.pi) % (2 * np.pi) - np.pi


def simulate_ego(duration, rng) -> EgoMotion:
    """Ego drive with speed changes, at least one stop (if >= 10 s) and curves."""
    t = np.arange(-1.0, duration + 1.0 + EGO_DT, EGO_DT)
    target_speed = _piecewise(t, rng, lambda: rng.choice([4.0, 8.0, 11.0, 14.0]), (3.0, 7.0))
    initial_speed = rng.uniform(5.0, 12.0)
    if duration >= 10.0:
        # Brake to a standstill, then stand for 2-4 s (a traffic light).
        stop_start = rng.uniform(0.2, 0.5) * duration
        speed = _rate_limited(target_speed, initial_speed, MAX_ACCEL * EGO_DT)
        braking = np.interp(stop_start, t, speed) / MAX_ACCEL
        target_speed[(t >= stop_start) & (t < stop_start + braking + rng.uniform(2.0, 4.0))] = 0.0
    speed = _rate_limited(target_speed, initial_speed, MAX_ACCEL * EGO_DT)
    curvature = _piecewise(t, rng, lambda: 0.0 if rng.random() < 0.4 else rng.normal(0.0, 0.025), (2.0, 6.0))
    curvature = _rate_limited(curvature, 0.0, 0.02 * EGO_DT)  # clothoid-like transitions
    max_curvature = np.minimum(MAX_CURVATURE, MAX_LATERAL_ACCEL / np.maximum(speed, 1.0) ** 2)
    curvature = np.clip(curvature, -max_curvature, max_curvature)
    yaw_rate = curvature * speed
    yaw = rng.uniform(-np.pi, np.pi) + np.concatenate([[0.0], np.cumsum(yaw_rate[:-1] * EGO_DT)])
    x = rng.uniform(-50, 50) + np.concatenate([[0.0], np.cumsum(speed[:-1] * np.cos(yaw[:-1]) * EGO_DT)])
    y = rng.uniform(-50, 50) + np.concatenate([[0.0], np.cumsum(speed[:-1] * np.sin(yaw[:-1]) * EGO_DT)])
    s = np.concatenate([[0.0], np.cumsum(speed[:-1] * EGO_DT)])
    return EgoMotion(t=t, x=x, y=y, yaw=yaw, vx=speed, yaw_rate=yaw_rate, s=s)


def _piecewise(t, rng, draw, segment_range):
    """A piecewise-constant signal with random segment lengths (s) and values."""
    out = np.empty_like(t)
    start = t[0]
    while start <= t[-1]:
        end = start + rng.uniform(*segment_range)
        out[(t >= start) & (t < end)] = draw()
        start = end
    return out


def _rate_limited(target, initial, max_step):
    """Follow ``target`` with at most ``max_step`` change per sample."""
    out = np.empty_like(target)
    value = initial
    for i, goal in enumerate(target):
        value += min(max(goal - value, -max_step), max_step)
        out[i] = value
    return out


def make_road(ego: EgoMotion, margin=300.0) -> Road:
    """The ego path by arclength, with straight extensions of ``margin`` m."""
    keep = np.concatenate([[True], np.diff(ego.s) > 1e-6])
    s, x, y, heading = ego.s[keep], ego.x[keep], ego.y[keep], ego.yaw[keep]
    ext = np.linspace(5.0, margin, 60)
    s_before, s_after = s[0] - ext[::-1], s[-1] + ext
    x_before = x[0] - ext[::-1] * np.cos(heading[0])
    y_before = y[0] - ext[::-1] * np.sin(heading[0])
    x_after = x[-1] + ext * np.cos(heading[-1])
    y_after = y[-1] + ext * np.sin(heading[-1])
    return Road(
        s=np.concatenate([s_before, s, s_after]),
        x=np.concatenate([x_before, x, x_after]),
        y=np.concatenate([y_before, y, y_after]),
        heading=np.concatenate([np.full(60, heading[0]), heading, np.full(60, heading[-1])]),
    )


def make_static_world(road: Road, s_min, s_max, rng, density=1.0) -> StaticScatterers:
    """Walls or guard rails, parked cars, poles, vegetation and buildings along the road.

    ``density`` scales the number of scatterers (1.0 is an urban street).
    """
    parts, walls = [], []
    for side, base in ((-1, -9.0), (1, 13.0)):
        offset = base + side * rng.uniform(0.0, 3.0)
        walls.append(offset)
        parts.append(_line_feature(road, s_min, s_max, offset, 0.4, rng, 0.18, 0.0, gaps=0.3))
        parts.append(
            _line_feature(road, s_min, s_max, offset + side * rng.uniform(8, 20), 1.5, rng, 0.10, 3.0, gaps=0.5)
        )
        parts.append(_points_feature(road, s_min, s_max, offset - side * 1.0, 25.0, rng, 0.6, 12.0))
        parts.append(_clumps_feature(road, s_min, s_max, offset + side * 2.5, 12.0, rng, 0.06, -8.0))
    parts.append(_parked_cars(road, s_min, s_max, -4.5, rng))
    x, y, s, p, rcs = (np.concatenate(v) for v in zip(*parts, strict=True))
    if density != 1.0:
        keep = rng.random(len(x)) < min(density, 1.0)
        p = p * max(density, 1.0)
        x, y, s, p, rcs = x[keep], y[keep], s[keep], p[keep], rcs[keep]
    order = np.argsort(s, kind="stable")
    return StaticScatterers(x[order], y[order], s[order], np.clip(p[order], 0, 0.95), rcs[order], tuple(walls))


def _line_feature(road, s_min, s_max, d, spacing, rng, p, rcs, gaps=0.0):
    s = np.arange(s_min, s_max, spacing) + rng.uniform(0, spacing)
    segment = np.floor(s / 20.0)
    present = rng.random(int(segment.max() - segment.min()) + 1) >= gaps
    s = s[present[(segment - segment.min()).astype(int)]]
    dd = d + rng.normal(0.0, 0.1, len(s))
    x, y = road.to_world(s, dd)
    return x, y, s, np.full(len(s), p) * rng.uniform(0.5, 1.5, len(s)), rcs + rng.normal(0, 4, len(s))


def _points_feature(road, s_min, s_max, d, spacing, rng, p, rcs):
    s = np.arange(s_min, s_max, spacing)
    s = s + rng.uniform(-0.1, 0.1, len(s)) * spacing
    x, y = road.to_world(s, np.full(len(s), d))
    return x, y, s, np.full(len(s), p), rcs + rng.normal(0, 3, len(s))


def _clumps_feature(road, s_min, s_max, d, spacing, rng, p, rcs):
    centres = np.arange(s_min, s_max, spacing)
    n_each = rng.integers(4, 16, len(centres))
    s = np.repeat(centres, n_each) + rng.normal(0, 1.2, n_each.sum())
    dd = d + np.sign(d) * np.abs(rng.normal(0, 1.5, n_each.sum()))
    x, y = road.to_world(s, dd)
    return x, y, s, np.full(len(s), p), rcs + rng.normal(0, 5, len(s))


def _parked_cars(road, s_min, s_max, d, rng):
    """Outlines of parked cars along the right kerb (0.5 m scatterer spacing)."""
    xs, ys, ss = [], [], []
    s = s_min
    while s < s_max:
        s += rng.uniform(5.5, 30.0)
        if rng.random() < 0.5:
            continue
        length, width = rng.uniform(4.0, 5.0), rng.uniform(1.7, 1.9)
        along, across = _rectangle_outline(length, width, 0.5)
        heading = road.heading_at(s)
        cx, cy = road.to_world(np.array([s]), np.array([d]))
        xs.append(cx + along * np.cos(heading) - across * np.sin(heading))
        ys.append(cy + along * np.sin(heading) + across * np.cos(heading))
        ss.append(np.full(len(along), s))
    if not xs:
        empty = np.zeros(0)
        return empty, empty, empty, empty, empty
    x, y, s_all = np.concatenate(xs), np.concatenate(ys), np.concatenate(ss)
    return x, y, s_all, np.full(len(x), 0.2), 5.0 + rng.normal(0, 5, len(x))


def _rectangle_outline(length, width, spacing):
    """Points along the outline of a centred rectangle, (along, across) in m."""
    along_edge = np.arange(-length / 2, length / 2 + 1e-9, spacing)
    across_edge = np.arange(-width / 2, width / 2 + 1e-9, spacing)
    along = np.concatenate(
        [along_edge, along_edge, np.full(len(across_edge), -length / 2), np.full(len(across_edge), length / 2)]
    )
    across = np.concatenate(
        [np.full(len(along_edge), -width / 2), np.full(len(along_edge), width / 2), across_edge, across_edge]
    )
    return along, across


def make_road_users(ego: EgoMotion, road: Road, duration, n_objects, rng) -> list[RoadUser]:
    """``n_objects`` road users in typical urban situations near the ego."""
    kinds = ["leader", "same", "oncoming", "bike", "walker", "crosser"]
    weights = np.array([0.08, 0.2, 0.24, 0.14, 0.2, 0.14])
    users = []
    has_leader = False
    stops = _stop_times(ego, duration)
    for _ in range(n_objects):
        kind = rng.choice(kinds, p=weights)
        if kind == "leader" and has_leader:
            kind = "same"
        has_leader |= kind == "leader"
        users.append(_road_user(kind, ego, road, duration, stops, rng))
    return users


def _stop_times(ego, duration):
    inside = (ego.t >= 0) & (ego.t <= duration)
    return ego.t[inside & (ego.vx < 0.05)]


def _road_user(kind, ego, road, duration, stops, rng) -> RoadUser:
    t_meet = rng.uniform(0.1, 0.9) * duration
    s_meet = np.interp(t_meet, ego.t, ego.s)
    if kind == "leader":
        cls = "car"
        user = dict(s0=0.0, speed=0.0, d0=0.0, follow_ego=ego, lag=rng.uniform(0.8, 2.0), gap=rng.uniform(7.0, 12.0))
    elif kind == "same":
        cls = rng.choice(["car", "car", "car", "truck", "bus"])
        speed = max(np.mean(ego.vx) + rng.uniform(-5.0, 5.0), 3.0)
        user = dict(s0=s_meet + rng.uniform(-10, 25) - speed * t_meet, speed=speed, d0=OVERTAKING_LANE)
    elif kind == "oncoming":
        cls = rng.choice(["car", "car", "car", "truck", "bus", "bicycle"])
        speed = -rng.uniform(4.0, 7.0) if cls == "bicycle" else -rng.uniform(7.0, 15.0)
        user = dict(s0=s_meet + rng.uniform(0, 20) - speed * t_meet, speed=speed, d0=ONCOMING_LANE)
    elif kind == "bike":
        cls = "bicycle"
        speed = rng.uniform(3.0, 7.0)
        user = dict(s0=s_meet + rng.uniform(-5, 30) - speed * t_meet, speed=speed, d0=BIKE_LANE)
    elif kind == "walker":
        cls = rng.choice(["pedestrian", "pedestrian", "pedestrian_group"])
        speed = rng.choice([-1.0, 1.0]) * rng.uniform(0.8, 1.6)
        side = rng.choice([RIGHT_SIDEWALK, LEFT_SIDEWALK])
        user = dict(s0=s_meet + rng.uniform(5, 35) - speed * t_meet, speed=speed, d0=side + rng.normal(0, 0.4))
    else:  # crosser: crosses the road ahead, preferably while the ego waits
        cls = rng.choice(["pedestrian", "pedestrian", "pedestrian_group", "bicycle", "car"])
        speed = {"car": 8.0, "bicycle": 4.0}.get(cls, 1.4) * rng.uniform(0.7, 1.3) * rng.choice([-1.0, 1.0])
        t_cross = rng.choice(stops) if len(stops) else t_meet
        ahead = rng.uniform(8.0, 20.0) if len(stops) else rng.uniform(40.0, 70.0)
        half_road = 5.5  # m, half the crossing distance around the road centre line
        user = dict(
            s0=np.interp(t_cross, ego.t, ego.s) + ahead,
            speed=speed,
            d0=1.75 - np.sign(speed) * half_road,
            crossing=True,
            t_cross=t_cross - half_road / abs(speed),
        )
    return _new_user(cls, road, duration, rng, **user)


def scattering_centres(length, width, rng, spacing=1.5):
    """Persistent reflection points on the outline of a length x width box (m).

    Real targets reflect mostly from a few spots (wheel houses, corners,
    mirrors, a pedestrian's torso and legs), so successive scans see them at
    the same places.  Returns an array (K, 4): position (along, across) in the
    object frame and the outward normal of its edge.
    """
    perimeter = 2 * (length + width)
    k = max(2, round(float(perimeter / spacing)))
    u = np.sort(rng.uniform(0.0, perimeter, k))
    half_l, half_w = length / 2, width / 2
    edges = np.cumsum([0.0, length, width, length])  # right side, front, left side, back
    edge = np.searchsorted(edges, u, side="right") - 1
    offset = u - edges[edge]
    along = np.select(
        [edge == 0, edge == 1, edge == 2], [-half_l + offset, np.full(k, half_l), half_l - offset], -half_l
    )
    across = np.select(
        [edge == 0, edge == 1, edge == 2], [np.full(k, -half_w), -half_w + offset, np.full(k, half_w)], half_w - offset
    )
    normal_along = np.select([edge == 1, edge == 3], [np.ones(k), -np.ones(k)], 0.0)
    normal_across = np.select([edge == 0, edge == 2], [-np.ones(k), np.ones(k)], 0.0)
    return np.column_stack([along, across, normal_along, normal_across])


def _absences(duration, rng):
    """0-2 intervals of 0.3-1.5 s in which the object gives no detection."""
    out = []
    for _ in range(rng.choice([0, 1, 1, 2])):
        start = rng.uniform(0, duration)
        out.append((start, start + rng.uniform(0.3, 1.5)))
    return tuple(out)


# ----------------------------------------------------------------------------
# Dense traffic (the "realistic" difficulty): close situations, turns, occlusions
# ----------------------------------------------------------------------------
#: Situations of dense urban traffic and their relative frequencies.
DENSE_SITUATIONS = {"turning": 0.3, "convoy": 0.2, "group_and_walker": 0.2, "kerb_walker": 0.15, "kerb_cyclist": 0.15}
PARKED_CARS_LANE = -4.5  # m, centre line of the parked cars of :func:`make_static_world`
TURN_APPROACH = 40.0  # m of straight lane before the turn


def make_dense_traffic(ego: EgoMotion, road: Road, duration, rate, rng) -> list[RoadUser]:
    """Road users in the close situations of dense urban traffic, ``rate`` situations per minute on average.

    * ``turning``: a car, truck, bus or cyclist turns off the road or into it
      (radius 6-12 m, 3-7 m/s); its yaw rate makes the Doppler vary across
      the body.
    * ``convoy``: two vehicles in one lane, 1.5-4 m bumper to bumper.
    * ``group_and_walker``: a pedestrian group and a pedestrian walking
      1.0-1.8 m beside it at the same pace (two instances, RadarScenes labels
      the group as one instance of its own class).
    * ``kerb_walker``: a pedestrian between the parked cars and the kerb,
      0.3-0.7 m from their bodies.
    * ``kerb_cyclist``: a cyclist passing the parked cars 0.3-0.7 m from them.
    """
    kinds = list(DENSE_SITUATIONS)
    weights = np.array(list(DENSE_SITUATIONS.values()))
    users = []
    for _ in range(rng.poisson(rate * duration / 60.0)):
        kind = kinds[rng.choice(len(kinds), p=weights / weights.sum())]
        users.extend(_dense_situation(kind, ego, road, duration, rng))
    return users


def _new_user(cls, road, duration, rng, **trajectory) -> RoadUser:
    params = ROAD_USER_CLASSES[cls]
    length, width = rng.uniform(*params["length"]), rng.uniform(*params["width"])
    return RoadUser(
        kind=cls,
        length=length,
        width=width,
        centres=scattering_centres(length, width, rng),
        road=road,
        absences=_absences(duration, rng),
        gait_hz=rng.uniform(1.5, 2.2) if params["micro"] > 0 else 0.0,
        **trajectory,
    )


def _dense_situation(kind, ego, road, duration, rng):
    t_meet = rng.uniform(0.1, 0.9) * duration
    s_meet = np.interp(t_meet, ego.t, ego.s)
    if kind == "turning":
        cls = str(rng.choice(["car", "car", "car", "truck", "bus", "bicycle"]))
        speed = rng.uniform(3.0, 5.0) if cls == "bicycle" else rng.uniform(3.5, 7.0)
        radius = rng.uniform(6.0, 12.0)
        # (lane, side of the turn, reversed): out of the overtaking lane to the left, in from the left into the
        # oncoming lane, out of the ego lane to the right.
        lane, side, backwards = [(OVERTAKING_LANE, 1.0, False), (ONCOMING_LANE, 1.0, True), (0.0, -1.0, False)][
            rng.integers(3)
        ]
        s_turn = s_meet + rng.uniform(12.0, 40.0)
        path, arc_start = _turn_path(road, s_turn, lane, side, radius, TURN_APPROACH + speed * duration, backwards)
        # The turn starts at t_meet.
        return [_new_user(cls, road, duration, rng, s0=arc_start - speed * t_meet, speed=speed, d0=0.0, path=path)]
    if kind == "convoy":
        oncoming = rng.random() < 0.5
        speed = -rng.uniform(7.0, 13.0) if oncoming else max(np.mean(ego.vx) + rng.uniform(-3.0, 3.0), 4.0)
        lane = ONCOMING_LANE if oncoming else OVERTAKING_LANE
        s0 = s_meet + rng.uniform(0, 20) - speed * t_meet
        first = _new_user(str(rng.choice(["car", "car", "truck"])), road, duration, rng, s0=s0, speed=speed, d0=lane)
        second = _new_user("car", road, duration, rng, s0=0.0, speed=speed, d0=lane + rng.normal(0, 0.2))
        gap = (first.length + second.length) / 2 + rng.uniform(1.5, 4.0)
        second.s0 = s0 - np.sign(speed) * gap
        return [first, second]
    if kind == "group_and_walker":
        speed = rng.choice([-1.0, 1.0]) * rng.uniform(0.8, 1.5)
        side = RIGHT_SIDEWALK if rng.random() < 0.5 else LEFT_SIDEWALK
        s0 = s_meet + rng.uniform(5, 35) - speed * t_meet
        group = _new_user("pedestrian_group", road, duration, rng, s0=s0, speed=speed, d0=side)
        walker = _new_user(
            "pedestrian",
            road,
            duration,
            rng,
            s0=s0 + rng.normal(0.0, 0.8),
            speed=speed + rng.normal(0.0, 0.1),
            d0=side + rng.choice([-1.0, 1.0]) * (group.width / 2 + rng.uniform(1.0, 1.8) - 0.3),
        )
        return [group, walker]
    # kerb_walker, kerb_cyclist: beside the parked cars (their bodies are 1.7-1.9 m wide)
    cls = "pedestrian" if kind == "kerb_walker" else "bicycle"
    speed = rng.choice([-1.0, 1.0]) * (rng.uniform(0.8, 1.6) if cls == "pedestrian" else rng.uniform(3.0, 6.0))
    clearance = 0.9 + rng.uniform(0.3, 0.7) + ROAD_USER_CLASSES[cls]["width"][1] / 2
    d0 = PARKED_CARS_LANE + (-clearance if cls == "pedestrian" else clearance)
    return [_new_user(cls, road, duration, rng, s0=s_meet + rng.uniform(0, 30) - speed * t_meet, speed=speed, d0=d0)]


def _turn_path(road, s_turn, lane, side, radius, straight, backwards):
    """A lane, a quarter circle of ``radius`` (m) to the left (side=1) or right (-1) and a side street.

    Returns the path (arclength, x, y) in the world frame, starting on the lane (in the side street when
    ``backwards``), and the arclength (m) at which the arc starts.
    """
    u_lane = np.linspace(-straight, 0.0, max(int(straight / 2.0), 2))
    phi = np.linspace(0.0, np.pi / 2, 24)[1:]
    u_arc, w_arc = radius * np.sin(phi), lane + side * radius * (1 - np.cos(phi))
    w_street = lane + side * (radius + np.linspace(0.0, straight, max(int(straight / 2.0), 2))[1:])
    u = np.concatenate([u_lane, u_arc, np.full(len(w_street), radius)])
    w = np.concatenate([np.full(len(u_lane), lane), w_arc, w_street])
    first_arc = len(u_lane) - 1
    if backwards:
        u, w = u[::-1], w[::-1]
        first_arc = len(w_street)
    x, y = road.to_world(s_turn + u, w)
    along = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    return (along, x, y), float(along[first_arc])


#: m/s^2, the deceleration and acceleration of a road user that stops and starts: moderate braking of a car
#: at a light (about 2 m/s^2), a cyclist's (1.5), a pedestrian who stops and walks on within a step or two (1).
STOP_DECELERATION = {"car": 2.0, "truck": 1.5, "bus": 1.5, "bicycle": 1.5, "pedestrian": 1.0, "pedestrian_group": 1.0}
#: s, how long a road user that stops stands still: a pedestrian waiting to cross, a car at a light or behind a
#: turning one, a cyclist at a junction.
STAND_DURATION = (2.0, 8.0)


def add_stops(users, ego, share, rng):
    """Let a ``share`` of the road users that keep to a lane or a pavement stop once and start again.

    Each chosen user (drawn with probability ``share``; followers of the ego
    car, crossers and turning vehicles keep their motion) brakes at constant
    deceleration (:data:`STOP_DECELERATION`) to a standstill near the time at
    which it is closest to the ego car (+-3 s), stands for
    :data:`STAND_DURATION` and starts again at the same rate.  While standing
    it is not a moving road user, which RadarScenes does not annotate; while
    braking and starting its Doppler is low.
    """
    for user in users:
        if user.follow_ego is not None or user.crossing or user.path is not None:
            continue
        if rng.random() >= share:
            continue
        ramp = abs(user.speed) / STOP_DECELERATION[user.kind]
        halt = _closest_time(user, ego) + rng.uniform(-3.0, 3.0)
        start = halt + rng.uniform(*STAND_DURATION)
        user.stop = (halt - ramp, halt, start, start + ramp)
    return users


def _closest_time(user, ego):
    """Time (s) of the ego drive at which the user, moving at constant speed, is nearest to the ego car."""
    x, y = user.position(ego.t)
    return float(ego.t[np.argmin(np.hypot(x - ego.x, y - ego.y))])


def add_occlusions(users, duration, rate, rng):
    """Give each road user ``Poisson(rate)`` extra intervals of 1-4 s without detections (occluded)."""
    for user in users:
        extra = []
        for _ in range(rng.poisson(rate)):
            start = rng.uniform(0, duration)
            extra.append((start, start + rng.uniform(1.0, 4.0)))
        user.absences = tuple(user.absences) + tuple(extra)
    return users
