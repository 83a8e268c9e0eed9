"""The simulator's difficulty presets: the knobs of its phenomena, their values per preset, and their checks.

Read more in the :ref:`User Guide <simulator-knobs>`.
"""

from __future__ import annotations

import numbers

import numpy as np

#: The knobs of the simulator's phenomena and their values in the ``difficulty`` presets.  "easy" turns every
#: phenomenon off; "realistic" sets each to a physically argued value (see :func:`make_scenes`, and the user
#: guide's "Simulated data" page for the arguments and the calibration against published figures).
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
