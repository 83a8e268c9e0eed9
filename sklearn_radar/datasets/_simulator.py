"""Scene simulator: realistic radar recordings in the RadarScenes layout.

:func:`make_scenes` takes the ground truth (ego drive, road, static world,
road users) from :mod:`._scenario`, the sensors from :mod:`._sensor_model`,
the true detections from :mod:`._detections` and :mod:`._phenomena`, the
labels from :mod:`._annotation`, and returns the detection table of
:mod:`sklearn_radar._schema`.  Read more in the
:ref:`User Guide <user-guide-simulator>`.
"""

from __future__ import annotations

import numbers

import numpy as np
import pandas as pd
from sklearn.utils import check_random_state
from sklearn.utils._param_validation import Interval, StrOptions, validate_params

from .._schema import (
    ODOMETRY_COLUMNS,
    RADAR_DATA_COLUMNS,
    RADARSCENES_MOUNTING,
    attach_context,
    make_frame,
    nearest_odometry_index,
)
from ._annotation import _box_annotation, _track_ids, _uuids
from ._bunch import data_bunch
from ._detections import _clutter, _ghosts, _object_detections, _static_detections
from ._phenomena import _phenomena
from ._presets import DIFFICULTY_PRESETS, _check_knobs, _overrides
from ._scenario import (
    add_occlusions,
    add_stops,
    make_dense_traffic,
    make_road,
    make_road_users,
    make_static_world,
    simulate_ego,
)
from ._sensor_model import (
    MAX_RANGE,
    _measure,
    _odometry,
    _odometry_errors,
    _scan_schedule,
    _sensor_errors,
    _sensor_states,
)


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

    Read more in the :ref:`User Guide <user-guide-simulator>`.

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
        Preset of the knobs below.  "easy" turns every phenomenon off (the
        simulator described above); "realistic" turns each on
        (``sklearn_radar.datasets._presets.DIFFICULTY_PRESETS``);
        "radarscenes" is "realistic" with RadarScenes' traffic statistics
        (fewer, longer-lived road users), road users that stop and start and
        angle glint (:ref:`User Guide <simulator-radarscenes-statistics>`).
        Equal seeds give the same drive, road, static world and base road
        users in all presets ("radarscenes" keeps a share of them).
    knobs : dict, default=None
        Values that override single knobs of the preset, all seeded by
        ``random_state``.  The value of "realistic" is in brackets; what each
        knob models and why it has that value is in the
        :ref:`User Guide <simulator-knobs>`.

        * ``odometry_speed_scale``: standard deviation of the relative
          wheel-speed scale error, one draw per sequence (0.005).
        * ``odometry_speed_noise``: m/s, white noise of the 50 Hz odometry
          speed (0.04).
        * ``odometry_yaw_rate_bias``: rad/s, standard deviation of the gyro
          bias per sequence (0.002).
        * ``odometry_yaw_rate_noise``: rad/s, white noise of the yaw rate
          (0.003).
          The reported pose is dead-reckoned from the erroneous speed and
          yaw rate; ``vr_compensated`` uses them, so static Doppler spreads.
        * ``mounting_error``: rad, standard deviation of each sensor's yaw
          error per sequence (0.5 deg).
        * ``time_offset``: s, standard deviation of each sensor's time-stamp
          offset per sequence (0.005).
        * ``multipath``: ghosts per object detection and per strong static
          detection (>= 10 dBsm) mirrored at the wall or guard rail nearer to
          the reflector (0.05); a moving object's ghost moves and carries the
          mirrored Doppler.
        * ``second_bounce``: ghosts per object detection at twice the range
          and twice the radial velocity (0.02).
        * ``rain``: rain and spray clutter per scan, mostly at short range,
          with a radial velocity of its own, s.d. 0.8 m/s (1.0).
        * ``spray``: spray detections per vehicle detection, behind the rear
          wheels, moving with 30-90 % of the vehicle's velocity (0.05).
        * ``sidelobes``: sidelobe detections per detection of >= 10 dBsm,
          2-6 deg beside it at its range and Doppler, 15-25 dB weaker (0.2).
        * ``traffic``: close situations of dense urban traffic per minute
          (12): turning vehicles, convoys 1.5-4 m apart, a pedestrian beside
          a pedestrian group, pedestrians and cyclists passing parked cars
          0.3-0.7 m away.
        * ``occlusion``: mean number of 1-4 s occlusions per road user (0.3).
        * ``detection_range``: m, range at which a 10 dBsm Swerling-1 target
          is detected with probability 0.5 (100); object detections are
          thinned by ``exp(-ln 2 (r / r_50)^4)`` with ``r_50`` scaled by the
          object's RCS as ``10^((rcs - 10) / 40)``.  ``inf``: no thinning.
        * ``object_detection_probability``: in [0, 1], probability that a
          road user's scattering point in view is detected in a scan at
          close range (0.5).
        * ``angular_noise_range``: m, beyond it the azimuth noise grows with
          the square of the range, up to 2.5 times its value (40).  ``inf``:
          no growth.
        * ``rcs_fluctuation``: bool, Swerling-1 fluctuation (exponential
          power) on top of the aspect noise of the RCS (True).
        * ``rcs_object_spread``: dB, standard deviation of a road user's own
          offset of its class's mean RCS, one draw per object (3).
        * ``rcs_aspect``: >= 0, scale of the classes' aspect dependence of
          the RCS (1: the amplitudes ``rcs_side`` and ``rcs_oblique`` of
          ``_scenario.ROAD_USER_CLASSES``; see ``_scenario.aspect_rcs``).
          ``detection_range``'s ``r_50`` follows the object's offset and
          aspect.
        * ``wheel_micro_doppler``: in [0, 1], the share of the detections of a
          car, truck, bus or bicycle seen broadside that come from its wheels
          (0.25); ``|sin aspect|`` times that share from other aspects.  A
          wheel detection at rim angle ``phi`` moves at ``v (1 + sin phi)``,
          between 0 at the road and ``2 v`` at the top.
        * ``road_user_share``: in [0, 1], the share of the base road users
          (``n_objects``) kept, each drawn alone (1; "radarscenes" 0.6).
        * ``stop_and_go``: in [0, 1], the share of the road users keeping to
          a lane or a pavement that brake to a standstill at 1-2 m/s^2 near
          the time they are closest to the ego car, stand for 2-8 s and start
          again (0; "radarscenes" 0.3).  A standing road user's detections
          are static background; it is annotated again as it starts.
        * ``annotation_margin``: m, >= 0, the labels of a box annotator:
          in each scan in which a road user has a detection, the detections
          *measured* within its box enlarged by this margin are its own, and
          only those (``inf``, the simulation's truth, in every preset).
        * ``glint``: in [0, 1], the share of a road user's detections whose
          azimuth estimate is off by a normal error with a standard deviation
          of half the object's angular extent, ``hypot(length, width) / (2 r)``
          rad; range, Doppler and whether the detection is seen stay as they
          were (0; "radarscenes" 0.75).

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
    return data_bunch(data, odometry, RADARSCENES_MOUNTING, numbers, ["train"] * len(numbers), description)


def _check_n_objects(n_objects):
    if (
        len(n_objects) != 2
        or not all(isinstance(v, numbers.Integral) for v in n_objects)
        or not 0 <= n_objects[0] <= n_objects[1]
    ):
        raise ValueError(f"n_objects must be a pair (low, high) of integers with 0 <= low <= high, got {n_objects!r}")
    return int(n_objects[0]), int(n_objects[1])


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
