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
from scipy.spatial import cKDTree
from sklearn.utils import Bunch, check_random_state
from sklearn.utils._param_validation import Interval, StrOptions, validate_params

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
from ._scenario import (
    ROAD_USER_CLASSES,
    add_occlusions,
    add_stops,
    aspect_rcs,
    make_dense_traffic,
    make_road,
    make_road_users,
    make_static_world,
    simulate_ego,
)

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
CLUTTER_PER_SCAN = 6.0  # false alarms per scan
GHOST_RATE = 0.04  # multipath ghosts per object detection
DIFFUSE_SHARE = 0.3  # object detections spread over the outline rather than from a scattering centre
NEW_TRACK_GAP = 0.5  # s, RadarScenes: a new track id after longer absence
SCAN_BLOCK = 48  # scans processed together for the static world
VEHICLE_LABELS = (0, 1, 2, 3)  # car, large vehicle, truck, bus: the road users that throw up spray
STRONG_RCS = 10.0  # dBsm: detections this strong show sidelobes and multipath mirrors

#: The knobs of the simulator's phenomena and their values in the two ``difficulty`` presets.  "easy" turns
#: every phenomenon off and is the simulator of sklearn-radar 0.x; "realistic" sets each to a physically argued
#: value (see :func:`make_scenes` and the user guide's "Simulated data" page for the arguments and the
#: calibration against published figures).
DIFFICULTY_PRESETS = {
    "easy": {
        "odometry_speed_scale": 0.0,
        "odometry_speed_noise": 0.0,
        "odometry_yaw_rate_bias": 0.0,
        "odometry_yaw_rate_noise": 0.0,
        "mounting_error": 0.0,
        "time_offset": 0.0,
        "multipath": 0.0,
        "second_bounce": 0.0,
        "rain": 0.0,
        "spray": 0.0,
        "sidelobes": 0.0,
        "traffic": 0.0,
        "occlusion": 0.0,
        "detection_range": np.inf,
        "object_detection_probability": 1.0,
        "angular_noise_range": np.inf,
        "rcs_fluctuation": False,
        "rcs_object_spread": 0.0,
        "rcs_aspect": 0.0,
        "wheel_micro_doppler": 0.0,
        "road_user_share": 1.0,
        "stop_and_go": 0.0,
        "annotation_margin": np.inf,
        "glint": 0.0,
    },
    "realistic": {
        "odometry_speed_scale": 0.005,
        "odometry_speed_noise": 0.04,
        "odometry_yaw_rate_bias": 0.002,
        "odometry_yaw_rate_noise": 0.003,
        "mounting_error": float(np.deg2rad(0.5)),
        "time_offset": 0.005,
        "multipath": 0.05,
        "second_bounce": 0.02,
        "rain": 1.0,
        "spray": 0.05,
        "sidelobes": 0.2,
        "traffic": 12.0,
        "occlusion": 0.3,
        "detection_range": 100.0,
        "object_detection_probability": 0.5,
        "angular_noise_range": 40.0,
        "rcs_fluctuation": True,
        "rcs_object_spread": 3.0,
        "rcs_aspect": 1.0,
        "wheel_micro_doppler": 0.25,
        "road_user_share": 1.0,
        "stop_and_go": 0.0,
        "annotation_margin": np.inf,
        "glint": 0.0,
    },
}
#: The radarscenes preset: the realistic one with RadarScenes' traffic (fewer, longer-lived road users; see the user
#: guide's "Towards RadarScenes' statistics") and road users that stop and start.
DIFFICULTY_PRESETS["radarscenes"] = {
    **DIFFICULTY_PRESETS["realistic"],
    "traffic": 4.0,
    "occlusion": 0.1,
    "object_detection_probability": 0.9,
    "road_user_share": 0.6,
    "stop_and_go": 0.3,
    "glint": 0.75,
}
#: The knobs of the radarscenes preset: off in "easy" and in "realistic" (so both stay as they were); "radarscenes"
#: turns on all but ``annotation_margin``, whose box labels drop the glinted detections (see the simulator guide).
RADARSCENES_KNOBS = ("road_user_share", "stop_and_go", "annotation_margin", "glint")
#: The knobs that are shares or probabilities, in [0, 1].
UNIT_INTERVAL_KNOBS = ("object_detection_probability", "wheel_micro_doppler", "road_user_share", "stop_and_go", "glint")


@validate_params(
    {
        "n_sequences": [Interval(numbers.Integral, 1, None, closed="left")],
        "duration": [Interval(numbers.Real, 0.5, None, closed="left")],
        "random_state": ["random_state"],
        "n_objects": [tuple],
        "static_density": [Interval(numbers.Real, 0, None, closed="neither")],
        "first_sequence": [Interval(numbers.Integral, 1, None, closed="left")],
        "difficulty": [StrOptions(set(DIFFICULTY_PRESETS))],
        "knobs": [dict, None],
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
    difficulty="realistic",
    knobs=None,
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
        of moving road users per sequence; the ``traffic`` knob of the
        realistic preset adds the road users of its close situations.
    static_density : float, default=1.0
        Scales the number of static scatterers and clutter (1.0: urban
        street), > 0.
    first_sequence : int, default=1
        Number N >= 1 of the first sequence (folder ``sequence_N``).
    difficulty : {"easy", "realistic", "radarscenes"}, default="realistic"
        Preset of the phenomena that make real radar data hard.  "easy" turns
        them all off (the simulator described above); "realistic" turns each
        on at a physically argued value
        (``sklearn_radar.datasets._simulator.DIFFICULTY_PRESETS``);
        "radarscenes" is "realistic" with RadarScenes' traffic statistics
        (about 31 road users per minute with about 470 annotated detections
        each, instead of about 83 with 240), road users that stop and start
        and box annotation (:ref:`User Guide <simulator-radarscenes-statistics>`).
        Equal seeds give the same drive, road, static world
        and base road users in all presets ("radarscenes" keeps a share of
        them).
    knobs : dict, default=None
        Values that override single knobs of the preset (all seedable
        through ``random_state``):

        * ``odometry_speed_scale``: standard deviation of the relative
          wheel-speed scale error, one draw per sequence (realistic 0.005:
          tyre circumference within +-1 %).
        * ``odometry_speed_noise``: m/s, white noise of the 50 Hz odometry
          speed (0.04: wheel-tick quantisation).
        * ``odometry_yaw_rate_bias``: rad/s, standard deviation of the gyro
          bias per sequence (0.002: about 0.1 deg/s after offset learning).
        * ``odometry_yaw_rate_noise``: rad/s, white noise of the yaw rate
          (0.003).
          The reported pose is dead-reckoned from the erroneous speed and
          yaw rate; ``vr_compensated`` uses them, so static Doppler spreads.
        * ``mounting_error``: rad, standard deviation of each sensor's yaw
          error per sequence (0.5 deg: alignment tolerance of series
          radars); it smears static structure between sensors in FCS.
        * ``time_offset``: s, standard deviation of each sensor's time-stamp
          offset per sequence (0.005: CAN latency of unsynchronised sensors).
        * ``multipath``: ghosts per object detection and per strong static
          detection (>= 10 dBsm) mirrored at the wall or guard rail nearer to
          the reflector (0.05); a moving object's ghost moves and carries the
          mirrored Doppler.
        * ``second_bounce``: ghosts per object detection at twice the range
          and twice the radial velocity (the path sensor-object-car-object,
          0.02).
        * ``rain``: rain and spray clutter per scan, mostly at short range,
          with a radial velocity of its own (1.0; s.d. 0.8 m/s of wind).
        * ``spray``: spray detections per vehicle detection, behind the rear
          wheels, moving with 30-90 % of the vehicle's velocity (0.05).
        * ``sidelobes``: sidelobe detections per detection of >= 10 dBsm,
          2-6 deg beside it at its range and Doppler, 15-25 dB weaker (0.2).
        * ``traffic``: close situations of dense urban traffic per minute
          (12, about 40 road users per minute in all; RadarScenes averages
          at most 31 over its 4 h, quieter stretches included): turning
          vehicles (their Doppler varies across the body), convoys
          1.5-4 m apart, a pedestrian beside a pedestrian group, pedestrians
          and cyclists passing parked cars 0.3-0.7 m away.
        * ``occlusion``: mean number of 1-4 s occlusions per road user (0.3).
        * ``detection_range``: m, range at which a 10 dBsm Swerling-1 target
          is detected with probability 0.5 (100, the sensors' specified
          range; a 5 dBsm car: 84 m, a -8 dBsm pedestrian: 36 m); object detections are
          thinned by ``exp(-ln 2 (r / r_50)^4)`` with ``r_50`` scaled by the
          class RCS as ``10^((rcs - 10) / 40)`` (radar equation), which
          leaves lone detections at range.  ``inf``: no thinning.
        * ``object_detection_probability``: probability, in [0, 1], that a
          road user's scattering point in view is detected in a scan at
          close range (0.5); calibrated to the published RadarScenes figure
          of about 4 million annotated detections in 4 h of 4 sensors, about
          4 per scan.
        * ``angular_noise_range``: m, beyond it the azimuth noise grows with
          the square of the range (SNR falls with r^4), up to 2.5 times its
          value near the detection threshold (40).  ``inf``: no growth.
        * ``rcs_fluctuation``: bool, Swerling-1 fluctuation (exponential
          power, 5.6 dB spread) on top of the aspect noise of the RCS (True).
        * ``rcs_object_spread``: dB, standard deviation of a road user's own
          offset of its mean RCS, one draw per object (3): objects of one
          class differ in shape, size and material (a small hatchback and a
          van, a child and an adult, clothing), and measured 77 GHz RCS
          distributions differ from vehicle to vehicle and person to person
          (Lee et al., "Radar cross section measurement with 77 GHz
          automotive FMCW radar", PIMRC 2016, four people and four vehicles;
          Fortuny-Guasch and Chareau, JRC report EUR 25762, 2013, people and
          dummies at 24 and 77 GHz).  Without it every object of a class has
          the same mean RCS and the mean RCS is an unrealistically clean
          class feature.
        * ``rcs_aspect``: scale, >= 0, of the classes' aspect dependence of
          the RCS (1: the amplitudes ``rcs_side`` and ``rcs_oblique`` of
          ``_scenario.ROAD_USER_CLASSES``; see ``_scenario.aspect_rcs``).  Flat
          panels reflect specularly: a vehicle is strongest broadside and
          head- or tail-on and weakest at oblique aspects (a car about 5 dB
          above its average broadside, 4 dB below it at 45 deg), a bicycle's
          frame and wheels are strong broadside and thin from ahead (+-5 dB);
          a pedestrian looks alike from all sides (0).  The detection
          threshold sees this RCS: ``detection_range``'s ``r_50`` follows the
          object's offset and aspect.
        * ``wheel_micro_doppler``: in [0, 1], the share of the detections of a
          car, truck, bus or bicycle seen broadside that come from its wheels
          (0.25); a share ``|sin aspect|`` of that from other aspects, none
          head-on, where the body hides the wheels.  A rolling wheel's rim
          point moves at ``v (1 + sin phi)``, from 0 at the road to ``2 v`` at
          the top, so wheel detections spread the object's Doppler over
          ``[0, 2 v]`` times the line-of-sight projection (Kellner et al.,
          "Wheel extraction based on micro Doppler distribution using
          high-resolution radar", ICMIM 2015).  Pedestrians' limbs already
          swing every detection's velocity over 0.1-1.9 times the body's (in
          both presets).
        * ``road_user_share``: in [0, 1], the share of the base road users
          (``n_objects``) kept, each drawn alone (1 in "realistic", 0.6 in
          "radarscenes"): the simulated sequences are 20-30 s of busy urban
          streets, while RadarScenes' mean of at most 31 road users per minute
          (7,500 in more than 4 h) includes quieter stretches.
        * ``stop_and_go``: in [0, 1], the share of the road users that keep
          to a lane or a pavement which brake to a standstill near the time
          they are closest to the ego car, stand for 2-8 s and start again
          (0.3 in "radarscenes"): pedestrians waiting to cross, cars at a
          light, cyclists at a junction, at 1-2 m/s^2.  RadarScenes annotates
          moving road users only and gives a new track id after more than
          500 ms of standstill (radar-scenes.com): a standing road user's
          detections are static background, and it is annotated again, with
          low Doppler, as it starts.
        * ``annotation_margin``: m, >= 0, the labels of a box annotator:
          in each scan in which a road user has a detection, the detections
          *measured* within its box enlarged by this margin are its own, and
          only those (``inf``: the simulation's truth).
          RadarScenes' labels come from a semi-automatic process that selects
          a road user's detections by its extent (Schumann et al.,
          "RadarScenes", FUSION 2021), so an own detection that the azimuth
          noise pushed out of the box (0.1-0.5 m across at 20-50 m) is
          background, and a ghost, spray or clutter detection inside it
          belongs to the object.  Off (``inf``) in every preset: with
          ``glint`` it drops about half of the annotated detections, far below
          RadarScenes' 530 per road user (the simulator guide).
        * ``glint``: in [0, 1], the share of a road user's detections whose
          azimuth estimate wanders by about the object's angular extent
          (0.75 in "radarscenes"): several scattering centres of one object
          in one range-Doppler cell interfere, and the cell's angle estimate
          leaves the line of any of them (angle glint of extended targets;
          Skolnik, "Introduction to Radar Systems", 3rd ed.).  The error is
          normal with a standard deviation of half the extent,
          ``hypot(length, width) / (2 r)`` rad; range, Doppler and whether
          the detection is seen stay as they were.

        Unknown names raise a ValueError.

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
    knobs = _check_knobs(difficulty, knobs)
    numbers_ = np.arange(first_sequence, first_sequence + n_sequences, dtype=np.int64)
    description = (
        f"Simulated RadarScenes-layout data: {n_sequences} sequence(s) of {duration:g} s "
        f"(sklearn_radar.datasets.make_scenes, random_state={random_state!r}, difficulty={difficulty!r}"
        + (f", knobs={dict(sorted(_overrides(difficulty, knobs).items()))!r}" if _overrides(difficulty, knobs) else "")
        + ")."
    )
    seeds = sequence_seeds(random_state, n_sequences)
    return simulate_sequences(numbers_, seeds, duration, (low, high), static_density, knobs, description)


def sequence_seeds(random_state, n_sequences):
    """The seed of each sequence of :func:`make_scenes` (drawn first: any sequence can be simulated alone)."""
    return check_random_state(random_state).randint(0, 2**31 - 1, size=n_sequences)


def simulate_sequences(numbers, seeds, duration, n_objects, static_density, knobs, description):
    """The sequences ``numbers`` with their ``seeds`` (:func:`sequence_seeds`): :func:`make_scenes`'s Bunch of them.

    ``knobs`` are checked ones (``_check_knobs``); ``n_objects`` is
    ``(low, high)``.  A sequence's rows do not depend on the others
    simulated with it; its instances are numbered from 0 in the Bunch.
    """
    data, odometry = [], []
    for number, seed in zip(numbers, seeds, strict=True):
        # The phenomena draw from a stream of their own, so that both presets share the world of a seed; the
        # class signatures from a third and the road users' traffic and behaviour (the radarscenes knobs) from a
        # fourth, so that each leaves the others' draws alone.
        det, odo = _simulate_sequence(
            int(number),
            duration,
            n_objects,
            static_density,
            np.random.default_rng(seed),
            knobs,
            np.random.default_rng([int(seed), 13]),
            np.random.default_rng([int(seed), 31]),
            np.random.default_rng([int(seed), 32]),
        )
        data.append(det)
        odometry.append(odo)
    data = pd.concat(data, ignore_index=True)
    odometry = pd.concat(odometry, ignore_index=True)
    numbers = np.asarray(numbers, dtype=np.int64)
    return Bunch(
        data=data,
        target=instance_target(data["track_id"], data["sequence"]),
        groups=data["sequence"].to_numpy(dtype=np.int64),
        odometry=odometry,
        sensors=mounting_frame(RADARSCENES_MOUNTING),
        sequences=pd.DataFrame(
            {
                "sequence": numbers,
                "name": pd.array([f"sequence_{n}" for n in numbers], dtype="str"),
                "category": pd.array(["train"] * len(numbers), dtype="str"),
            }
        ),
        DESCR=description,
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


def _check_knobs(difficulty, knobs):
    """The preset's knob values with ``knobs`` applied; ValueError names an unknown or invalid knob."""
    values = dict(DIFFICULTY_PRESETS[difficulty])
    for name, value in (knobs or {}).items():
        if name not in values:
            raise ValueError(f"knobs: unknown knob {name!r}; the knobs are {', '.join(sorted(values))}")
        if name in UNIT_INTERVAL_KNOBS and not (
            isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_)) and 0 <= value <= 1
        ):
            raise ValueError(f"knobs: {name} must be in [0, 1], got {value!r}")
        if name == "rcs_fluctuation":
            if not isinstance(value, (bool, np.bool_)):
                raise ValueError(f"knobs: rcs_fluctuation must be a bool, got {value!r}")
        elif (
            not isinstance(value, numbers.Real)
            or isinstance(value, (bool, np.bool_))
            or np.isnan(value)
            or value < 0
            or (name in ("detection_range", "angular_noise_range") and value == 0)
            or (np.isinf(value) and name not in ("detection_range", "angular_noise_range", "annotation_margin"))
        ):
            rule = {"detection_range": "> 0 (inf: off)", "angular_noise_range": "> 0 (inf: off)"}.get(
                name, ">= 0 (inf: off)" if name == "annotation_margin" else "finite and >= 0"
            )
            raise ValueError(f"knobs: {name} must be a real number {rule}, got {value!r}")
        values[name] = value
    return values


def _overrides(difficulty, knobs):
    preset = DIFFICULTY_PRESETS[difficulty]
    return {k: v for k, v in (knobs or {}).items() if v != preset[k]}


def _simulate_sequence(
    number, duration, n_objects, density, rng, knobs=None, extra=None, signature=None, behaviour=None
):
    """Detection table and odometry of one sequence.

    ``rng`` draws the world and the easy simulator's measurements; ``extra``
    draws everything the realistic phenomena (``knobs``) add, and nothing
    else, so that with every knob off the data are those of the easy preset;
    ``signature`` draws what the class-signature knobs (``rcs_object_spread``,
    ``wheel_micro_doppler``) add, ``behaviour`` what ``road_user_share`` and
    ``stop_and_go`` do.
    """
    knobs = DIFFICULTY_PRESETS["easy"] if knobs is None else knobs
    t0_us = 156_000_000_000 + 1_000_000_000 * number
    ego = simulate_ego(duration, rng)
    road = make_road(ego)
    odometry = _odometry(ego, duration, t0_us, rng)
    odometry = _odometry_errors(odometry, knobs, extra)
    scans = _scan_schedule(duration, t0_us, rng)
    sensor = _sensor_states(ego, scans, _sensor_errors(knobs, extra))

    static = make_static_world(
        road, sensor["s"].min() - MAX_RANGE - 10, sensor["s"].max() + MAX_RANGE + 10, rng, density
    )
    users = make_road_users(ego, road, duration, rng.integers(n_objects[0], n_objects[1] + 1), rng)
    if knobs["road_user_share"] < 1:
        # Drawn after the base users, so that the world stream is that of the other presets.
        users = [user for user in users if behaviour.random() < knobs["road_user_share"]]
    if knobs["traffic"] > 0:
        users += make_dense_traffic(ego, road, duration, knobs["traffic"], extra)
    if knobs["occlusion"] > 0:
        add_occlusions(users, duration, knobs["occlusion"], extra)
    if knobs["stop_and_go"] > 0:
        add_stops(users, ego, knobs["stop_and_go"], behaviour)
    static_part = _static_detections(static, sensor, rng)
    parts = [static_part, _clutter(sensor, density, rng)]
    objects, world = _object_detections(users, sensor, rng, knobs, extra, signature)
    parts += [objects, _ghosts(objects, rng)]
    parts += _phenomena(static_part, objects, world, static, road, sensor, knobs, extra)
    truth = {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}
    if knobs["rcs_fluctuation"]:
        # Swerling 1: exponentially distributed power, 10 log10 of it (5.6 dB spread), mean power kept.
        truth["rcs"] = truth["rcs"] + 10 * np.log10(extra.exponential(1.0, len(truth["rcs"])))

    scans["odometry_index"] = nearest_odometry_index(scans["timestamp"], odometry["timestamp"].to_numpy())
    measured = _measure(truth, scans, odometry, rng, angular_noise_range=knobs["angular_noise_range"])
    if np.isfinite(knobs["annotation_margin"]):
        truth = _box_annotation(truth, measured, users, sensor, knobs["annotation_margin"])
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

    Where several scattering centres of one object fall into the same range-Doppler cell, their echoes interfere
    and the angle estimate of the cell leaves the line of any of them, by up to the object's angular extent and
    beyond (glint; Skolnik, "Introduction to Radar Systems", 3rd ed., sec. 4.4).  The error is normal, its
    standard deviation half the angular extent ``hypot(length, width) / r`` (rad).
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
    from 0 at the bottom to ``2 v`` at the top.  The wheels are seen from
    the side only (the body hides them from ahead and behind), so a
    detection lies on a wheel of the visible side with probability
    ``wheel_micro_doppler * |sin aspect|``; it keeps its scan and gets a
    uniform ``phi``, an axle of the class (``ROAD_USER_CLASSES[...]["axles"]``)
    and the velocity of that rim point.  Kellner et al., "Wheel extraction
    based on micro Doppler distribution using high-resolution radar"
    (ICMIM 2015), find a car's wheels in 77 GHz radar data by exactly this
    spread of Doppler about the body's; cyclist models carry scatterers on
    the rims and spokes (Stolz et al., "Multi-target reflection point model
    of cyclists for automotive radar", EuRAD 2017).
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


def _box_annotation(truth, measured, users, sensor, margin):
    """The labels of an annotator who marks each road user, scan by scan, by its box enlarged by ``margin`` (m).

    RadarScenes' labels come from a semi-automatic process in which the
    detections of a road user are selected by its extent (Schumann et al.,
    "RadarScenes", FUSION 2021, section III).  Such a label follows where a
    detection was *measured*, not what reflected it: an own detection that
    the azimuth noise (0.1-0.5 m across at 20-50 m) pushed beyond the box
    becomes background, and a background detection measured inside the box
    (a ghost, spray, clutter, a kerb or a parked car beside a pedestrian)
    joins the object.  Only scans in which the object has a detection of its
    own are marked, and never while it stands (it is not a moving road user).
    """
    scan = truth["scan"]
    angle = measured["azimuth_sc"].astype(float) + sensor["boresight"][scan]
    r = measured["range_sc"].astype(float)
    px, py = sensor["x"][scan] + r * np.cos(angle), sensor["y"][scan] + r * np.sin(angle)
    label, obj = truth["label"].copy(), truth["object"].copy()
    n_scans = len(sensor["t"])
    for index, user in enumerate(users):
        own = truth["object"] == index
        if not own.any():
            continue
        marked = (np.bincount(scan[own], minlength=n_scans) > 0) & ~user.standing(sensor["t"])
        cx, cy, _, _, heading, _ = user.kinematics(sensor["t"])
        c, s = np.cos(heading[scan]), np.sin(heading[scan])
        dx, dy = px - cx[scan], py - cy[scan]
        inside = (
            marked[scan]
            & (np.abs(c * dx + s * dy) <= user.length / 2 + margin)
            & (np.abs(-s * dx + c * dy) <= user.width / 2 + margin)
        )
        leave, join = own & ~inside, inside & (truth["object"] == -1)
        label[leave], obj[leave] = STATIC_LABEL, -1
        label[join], obj[join] = ROAD_USER_CLASSES[user.kind]["label"], index
    return {**truth, "label": label, "object": obj}


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
