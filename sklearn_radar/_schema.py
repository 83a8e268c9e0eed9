"""The detection table: columns, units, frames and sign conventions.

This module is the one place where the data layout of sklearn-radar is
defined.  Everything else (simulator, RadarScenes reader and writer, the
estimators) builds and checks tables through it.

Detections travel as **one** :class:`pandas.DataFrame`, one row per radar
detection.  Its first 14 columns are the RadarScenes ``radar_data`` fields
under their RadarScenes names; ``sequence`` and eight *context* columns
follow.  The context columns carry, on every row, the ego odometry of the
detection's scan and the mounting of the detection's sensor.  Estimators
therefore reach odometry and mounting as ordinary columns of ``X``: they
survive any row subset (cross-validation splits, sequence filters), travel
through a :class:`~sklearn.pipeline.Pipeline` and work with every search
object, without metadata routing.  The whole-sequence odometry and the
mounting table are kept beside the table in the data :class:`~sklearn.utils.Bunch`
as well, because the RadarScenes writer needs them.

Coordinate frames and sign conventions
--------------------------------------
* **Sensor frame (sc)**: polar, ``range_sc`` (m) and ``azimuth_sc`` (rad),
  azimuth positive counter-clockwise, i.e. to the left of boresight.
* **Car frame (cc)**: origin at the centre of the rear axle, x forward,
  y to the left, yaw counter-clockwise.  A sensor mounted at
  ``(sensor_x, sensor_y)`` with yaw ``sensor_yaw`` sees a detection at
  ``x_cc = sensor_x + range_sc * cos(azimuth_sc + sensor_yaw)`` and
  ``y_cc = sensor_y + range_sc * sin(azimuth_sc + sensor_yaw)``.
* **Sequence frame (seq)**: a fixed world frame per recording with an
  arbitrary origin.  With the ego pose ``(ego_x_seq, ego_y_seq, ego_yaw_seq)``
  of the scan, ``x_seq = ego_x_seq + c * x_cc - s * y_cc`` and
  ``y_seq = ego_y_seq + s * x_cc + c * y_cc`` (``c, s = cos, sin(ego_yaw_seq)``).
* **Radial velocity**: ``vr`` is the measured Doppler velocity, the rate of
  change of range, so **negative means approaching**.  ``vr_compensated``
  removes the ego motion: ``vr = vr_compensated - v_s . u`` with the
  line-of-sight unit vector ``u = (cos(azimuth_sc + sensor_yaw),
  sin(azimuth_sc + sensor_yaw))`` and the sensor velocity over ground in
  the car frame ``v_s = (ego_vx - ego_yaw_rate * sensor_y,
  ego_yaw_rate * sensor_x)``.  Static targets have ``vr_compensated``
  close to 0.
* **Time**: ``timestamp`` is in microseconds with an arbitrary origin per
  sequence; one scan (one sensor's measurement cycle) shares one timestamp.

Physical plausibility
---------------------
Every column an estimator or the RadarScenes reader reads has physical
limits here (:data:`PLAUSIBLE_VALUES`, and :class:`ScanSpacing` for the
spacing of scan times), each with its argument: a value beyond one is a
wrong unit, sign or column order, and raises a ValueError naming column,
value and likely cause.  ``sklearn_radar.set_config(check_plausibility=False)``
turns the checks off.

Labels
------
``label_id`` uses the RadarScenes classes (:data:`LABELS`); 11 (STATIC) is
background.  ``track_id`` is the instance id: a non-empty string for
moving road users, ``""`` for background.  A new track id starts after more
than 0.5 s of absence.  The learning target ``y`` is derived from it by
:func:`instance_target`: one integer per instance, -1 for background.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from sklearn.utils._param_validation import validate_params

from ._labels import rank_by_first_appearance


@dataclass(frozen=True)
class Column:
    """One column of a table: name, in-memory dtype, unit and meaning."""

    name: str
    dtype: str
    unit: str
    description: str


#: The 14 fields of a RadarScenes ``radar_data`` row, in file order.
RADAR_DATA_COLUMNS = (
    Column("timestamp", "int64", "µs", "scan time; equals the RadarScenes scene key"),
    Column("sensor_id", "int64", "-", "radar 1..4 (1 front-right side, 4 front-left side)"),
    Column("range_sc", "float32", "m", "radial distance from the sensor"),
    Column("azimuth_sc", "float32", "rad", "azimuth in the sensor frame, positive to the left"),
    Column("rcs", "float32", "dBsm", "radar cross section"),
    Column("vr", "float32", "m/s", "measured radial velocity, negative = approaching"),
    Column("vr_compensated", "float32", "m/s", "radial velocity over ground (ego motion removed)"),
    Column("x_cc", "float32", "m", "x in the car frame of the scan (forward)"),
    Column("y_cc", "float32", "m", "y in the car frame of the scan (left)"),
    Column("x_seq", "float32", "m", "x in the sequence (world) frame"),
    Column("y_seq", "float32", "m", "y in the sequence (world) frame"),
    Column("uuid", "str", "-", "unique detection id"),
    Column("track_id", "str", "-", "instance id of a moving road user, '' for background"),
    Column("label_id", "int64", "-", "RadarScenes class, 11 = STATIC (see LABELS)"),
)

#: Columns that sklearn-radar adds to every detection row.
CONTEXT_COLUMNS = (
    Column("sequence", "int64", "-", "recording number N of the folder sequence_N"),
    Column("ego_x_seq", "float32", "m", "ego x in the sequence frame at this scan's odometry row"),
    Column("ego_y_seq", "float32", "m", "ego y in the sequence frame at this scan's odometry row"),
    Column("ego_yaw_seq", "float32", "rad", "ego yaw in the sequence frame, counter-clockwise"),
    Column("ego_vx", "float32", "m/s", "ego speed along the car x axis"),
    Column("ego_yaw_rate", "float32", "rad/s", "ego yaw rate, counter-clockwise"),
    Column("sensor_x", "float32", "m", "sensor mounting x in the car frame"),
    Column("sensor_y", "float32", "m", "sensor mounting y in the car frame"),
    Column("sensor_yaw", "float32", "rad", "sensor boresight yaw in the car frame"),
)

DETECTION_COLUMNS = RADAR_DATA_COLUMNS + CONTEXT_COLUMNS

#: Fields of a RadarScenes ``odometry`` row, plus ``sequence`` in memory.
ODOMETRY_COLUMNS = (
    Column("sequence", "int64", "-", "recording number N of the folder sequence_N"),
    Column("timestamp", "int64", "µs", "odometry sample time (about 50 Hz)"),
    Column("x_seq", "float32", "m", "ego x in the sequence frame"),
    Column("y_seq", "float32", "m", "ego y in the sequence frame"),
    Column("yaw_seq", "float32", "rad", "ego yaw in the sequence frame"),
    Column("vx", "float32", "m/s", "ego speed along the car x axis"),
    Column("yaw_rate", "float32", "rad/s", "ego yaw rate"),
)

#: Sensor mounting table: index ``sensor_id``.
SENSOR_COLUMNS = (
    Column("x", "float64", "m", "mounting x in the car frame"),
    Column("y", "float64", "m", "mounting y in the car frame"),
    Column("yaw", "float64", "rad", "boresight yaw in the car frame"),
)

#: The RadarScenes mounting (``sensors.json`` of the dataset, devkit default).
RADARSCENES_MOUNTING = {
    1: {"x": 3.663, "y": -0.873, "yaw": -1.48418552},
    2: {"x": 3.86, "y": -0.70, "yaw": -0.436185662},
    3: {"x": 3.86, "y": 0.70, "yaw": 0.436},
    4: {"x": 3.663, "y": 0.873, "yaw": 1.484},
}

#: RadarScenes ``label_id`` values.
LABELS = {
    0: "CAR",
    1: "LARGE_VEHICLE",
    2: "TRUCK",
    3: "BUS",
    4: "TRAIN",
    5: "BICYCLE",
    6: "MOTORIZED_TWO_WHEELER",
    7: "PEDESTRIAN",
    8: "PEDESTRIAN_GROUP",
    9: "ANIMAL",
    10: "OTHER",
    11: "STATIC",
}
STATIC_LABEL = 11

#: Odometry fields copied onto every detection row, as (odometry, detection) names.
EGO_FIELDS = (
    ("x_seq", "ego_x_seq"),
    ("y_seq", "ego_y_seq"),
    ("yaw_seq", "ego_yaw_seq"),
    ("vx", "ego_vx"),
    ("yaw_rate", "ego_yaw_rate"),
)
#: Mounting fields copied onto every detection row, as (mounting, detection) names.
MOUNTING_FIELDS = (("x", "sensor_x"), ("y", "sensor_y"), ("yaw", "sensor_yaw"))


@dataclass(frozen=True)
class ArrayLayout:
    """The positions of the columns in plain-array input, and which may be absent.

    A DataFrame is read by column name; a plain numeric array (scikit-learn's
    common checks, quick experiments) by position in :attr:`columns`.  An
    array may be narrower than the layout.  An absent trailing column that
    has a neutral value in :attr:`neutral` takes it (one sequence, every
    detection kept, car axes, ...); any other absent column is *missing*:
    an estimator that needs it raises a ValueError naming it, and one that
    does not need it never reads it.  No measured quantity (a range, an
    angle) is ever made up.

    Parameters
    ----------
    name : str
        Used in error messages.
    columns : tuple of str
        Column names in positional order.
    neutral : mapping of str to float
        The value of each column that may be left out of an array.
    """

    name: str
    columns: tuple
    neutral: dict

    def position(self, name: str) -> int:
        """Position of column ``name`` in an array of this layout."""
        return self.columns.index(name)


@dataclass(frozen=True)
class ColumnsRead:
    """The columns one estimator reads: those it always needs and those it uses when present.

    Parameters
    ----------
    required : tuple of str
        A DataFrame must hold them; an array must hold them or their layout
        must give them a neutral value.
    optional : tuple of str
        Read when present; absent ones are None, or their neutral value in
        an array.
    layout : ArrayLayout
        How a plain array holds them.
    """

    required: tuple
    optional: tuple
    layout: ArrayLayout

    @property
    def names(self) -> tuple:
        """Every column read, required first."""
        return self.required + self.optional


#: Raw detections as FrameTransform reads them from an array: the measurement,
#: then mounting and odometry.  Left out, mounting and odometry are 0 (sensor
#: at the car origin looking forward, the car at rest at the frame origin),
#: azimuth 0 (boresight), Doppler 0, timestamp 0 (one scan) and sequence 0.
RAW_LAYOUT = ArrayLayout(
    name="raw detection array",
    columns=(
        "range_sc",
        "azimuth_sc",
        "vr",
        "timestamp",
        "sensor_x",
        "sensor_y",
        "sensor_yaw",
        "ego_x_seq",
        "ego_y_seq",
        "ego_yaw_seq",
        "ego_vx",
        "ego_yaw_rate",
        "sequence",
    ),
    neutral={
        "azimuth_sc": 0.0,
        "vr": 0.0,
        "timestamp": 0.0,
        "sensor_x": 0.0,
        "sensor_y": 0.0,
        "sensor_yaw": 0.0,
        "ego_x_seq": 0.0,
        "ego_y_seq": 0.0,
        "ego_yaw_seq": 0.0,
        "ego_vx": 0.0,
        "ego_yaw_rate": 0.0,
        "sequence": 0.0,
    },
)

#: Working detections as FrameTransform writes them to an array and every later
#: stage reads them.  Left out, y, v_r and t are 0 (points in one plane, no
#: Doppler, one scan), sequence 0, keep 1 (every detection kept) and heading 0
#: (the car axes are the x-y axes).  ``range_sc`` (Eq. 2), ``azimuth_sc`` and
#: ``sensor_yaw`` (line of sight, Eq. 6) have no neutral value: a parameter
#: that needs them raises when they are missing.
WORK_LAYOUT = ArrayLayout(
    name="working detection array",
    columns=("x", "y", "v_r", "t", "sequence", "keep", "range_sc", "heading", "azimuth_sc", "sensor_yaw"),
    neutral={"y": 0.0, "v_r": 0.0, "t": 0.0, "sequence": 0.0, "keep": 1.0, "heading": 0.0},
)

_WORK = ("x", "y", "v_r", "t")

#: FrameTransform (stage 0).
FRAME_TRANSFORM_READS = ColumnsRead(
    required=tuple(name for name in RAW_LAYOUT.columns if name != "sequence"),
    optional=("sequence",),
    layout=RAW_LAYOUT,
)
#: DopplerDensityFilter (Eq. 1).
FILTER_READS = ColumnsRead(required=_WORK, optional=("sequence",), layout=WORK_LAYOUT)
#: RadarDBSCAN (Eqs. 2-5); ``range_sc`` is needed when ``alpha_r > 0``.
STAGE1_READS = ColumnsRead(required=_WORK, optional=("sequence", "keep", "range_sc", "heading"), layout=WORK_LAYOUT)
#: ClusterMerger (stage 2); ``azimuth_sc`` and ``sensor_yaw`` are needed by ``mode="velocity"``.
MERGER_READS = ColumnsRead(
    required=_WORK,
    optional=(*STAGE1_READS.optional, "azimuth_sc", "sensor_yaw"),
    layout=WORK_LAYOUT,
)
#: The scikit-learn baselines per time window.
WINDOWED_READS = ColumnsRead(required=_WORK, optional=("sequence", "keep"), layout=WORK_LAYOUT)

#: Working detections with the two measurements the road-user classifiers read besides the working layout:
#: ``rcs`` (dBsm) and ``sensor_id``.  Both are measurements without a neutral value: features that need an
#: absent one are left out, never made up.
CLASSIFIER_LAYOUT = ArrayLayout(
    name="classifier detection array",
    columns=(*WORK_LAYOUT.columns, "rcs", "sensor_id"),
    neutral=dict(WORK_LAYOUT.neutral),
)
#: The cluster features (:func:`~sklearn_radar.classification.cluster_features`) and ClusterClassifier.
CLUSTER_FEATURE_READS = ColumnsRead(
    required=_WORK,
    optional=("sequence", "keep", "range_sc", "heading", "azimuth_sc", "sensor_yaw", "rcs", "sensor_id"),
    layout=CLASSIFIER_LAYOUT,
)
#: PointClassifier: per-detection features.
POINT_FEATURE_READS = ColumnsRead(
    required=_WORK,
    optional=("sequence", "keep", "range_sc", "azimuth_sc", "sensor_yaw", "rcs"),
    layout=CLASSIFIER_LAYOUT,
)


# --------------------------------------------------------------------------
# Physical plausibility: the one place where the bounds live
# --------------------------------------------------------------------------
#
# Each limit below is a property of the world (a car, a radar, the Earth), not of a data set, with a margin so
# that no real recording comes near it; a value beyond it means a wrong unit, sign or column order.  The checks
# that apply them are in sklearn_radar._validation; sklearn_radar.set_config(check_plausibility=False) skips them.

#: m.  The farthest automotive radars see about 300 m (long-range sensors; RadarScenes: 100 m); 1000 m is more
#: than three times that.  A range in mm (100 m -> 1e5) or cm (1e4) is beyond it.
MAX_RANGE = 1000.0
#: rad.  An azimuth is an angle about the boresight, wrapped to (-pi, pi] (RadarScenes sensors see +-60 deg);
#: the margin covers float32 rounding of pi.  Degrees exceed it as soon as one detection lies 3.2 deg off boresight.
MAX_AZIMUTH = np.pi + 1e-5
#: rad.  A mounting yaw, in (-pi, pi] or [0, 2 pi) (both conventions occur); degrees exceed 2 pi above 6.3 deg.
MAX_SENSOR_YAW = 2 * np.pi + 1e-5
#: m.  Mounting x from the rear-axle centre: the longest road vehicles (articulated buses, truck-trailers, 25 m)
#: hold every sensor within 25 m of an axle; 30 m is beyond any.  A mounting in cm (3.66 m -> 366) or mm is not.
MAX_SENSOR_X = 30.0
#: m.  Mounting y from the centre line: road vehicles are at most 2.6 m wide (EU and US limits), so a sensor sits
#: within 1.3 m (1.6 m with mirrors); 5 m is beyond any.  A mounting in cm (0.87 m -> 87) or mm is not.
MAX_SENSOR_Y = 5.0
#: m/s.  The fastest road cars reach about 490 km/h (136 m/s); 150 m/s (540 km/h) is faster than any.  Speeds in
#: km/h exceed it above 150 km/h only, so a km/h ego speed is caught on a motorway, not in town.
MAX_EGO_SPEED = 150.0
#: m/s.  Reverse gears are geared low (cars reverse at at most about 60 km/h, 17 m/s); -30 m/s (108 km/h
#: backwards) is beyond any car, and more negative values mean a car x axis that points backwards.
MIN_EGO_SPEED = -30.0
#: rad/s.  A car at full lock circles about 10 m at walking pace (about 1 rad/s); even a car that spins out
#: turns slower than half a revolution per second (pi rad/s = 180 deg/s).  A yaw rate in deg/s exceeds pi in
#: any turn faster than 3.2 deg/s.
MAX_YAW_RATE = np.pi
#: m/s.  A Doppler velocity is the range rate between a sensor and a target, both road vehicles (<= 150 m/s
#: each, head-on: 300 m/s), and automotive radars resolve at most about +-110 m/s (-400/+200 km/h); a
#: compensated velocity (over ground) is smaller still.  300 m/s bounds both; km/h exceeds it above 300 km/h only.
MAX_DOPPLER = 300.0
#: m.  A position in a sequence (world) frame: no place on Earth is farther than its circumference (4.0e7 m)
#: from any origin on Earth, even in UTM or ECEF coordinates.  A microsecond timestamp (1.6e11) read as a
#: position is far beyond.
MAX_POSITION = 4.0e7
#: m.  A position in the car frame is a detection seen by a sensor mounted on the car.
MAX_CAR_POSITION = MAX_RANGE + MAX_SENSOR_X


@dataclass(frozen=True)
class PlausibleRange:
    """The physically plausible values of one column, and what a value beyond them usually means.

    Parameters
    ----------
    column : str
        Column name.
    unit : str
        Its unit.
    low, high : float
        Smallest and largest plausible value, in ``unit``.
    too_low, too_high : str
        The likely cause of a value below ``low`` / above ``high``, for the error message.
    argument : str
        Why these limits (documentation).
    """

    column: str
    unit: str
    low: float
    high: float
    too_low: str
    too_high: str
    argument: str


def _symmetric(column, unit, limit, cause, argument):
    return PlausibleRange(column, unit, -limit, limit, cause, cause, argument)


_DEGREES = "it looks like degrees; sklearn-radar (as RadarScenes) uses rad"
_RANGE_TOO_FAR = "it looks like mm or cm; sklearn-radar (as RadarScenes) uses m"
_DOPPLER_TOO_FAST = "it looks like km/h; sklearn-radar (as RadarScenes) uses m/s"
_POSITION_TOO_FAR = "it looks like mm, or another column (e.g. a µs timestamp) read as a position; positions are in m"
_CAR_POSITION_TOO_FAR = "it looks like mm or cm; car-frame positions are in m"
_MOUNTING_OUTSIDE = "the sensor would be mounted outside the car: it looks like cm or mm; mountings are in m"

#: {column: PlausibleRange} of every bounded column any estimator or the RadarScenes reader reads.  Not bounded:
#: ``ego_yaw_seq`` and ``heading`` (a heading may be unwrapped over a sequence, so any value is an angle;
#: degrees there cannot be told from a car that turned many times), ``timestamp`` and ``t`` (any origin; their
#: *spacing* is checked, :data:`SCAN_SPACING`), ``sequence``, ``keep``, ``rcs``, ids and labels.
PLAUSIBLE_VALUES = {
    bound.column: bound
    for bound in (
        PlausibleRange(
            "range_sc",
            "m",
            0.0,
            MAX_RANGE,
            "a range is a distance and cannot be negative (a sign flip, an offset, or another column read as range_sc)",
            _RANGE_TOO_FAR,
            "0 to MAX_RANGE (1000 m): a distance, and no automotive radar sees beyond about 300 m",
        ),
        _symmetric("azimuth_sc", "rad", MAX_AZIMUTH, _DEGREES, "+-pi: an angle about the boresight"),
        _symmetric("sensor_yaw", "rad", MAX_SENSOR_YAW, _DEGREES, "+-2 pi: (-pi, pi] and [0, 2 pi) both occur"),
        _symmetric("sensor_x", "m", MAX_SENSOR_X, _MOUNTING_OUTSIDE, "+-30 m: within the longest road vehicle"),
        _symmetric("sensor_y", "m", MAX_SENSOR_Y, _MOUNTING_OUTSIDE, "+-5 m: within the widest road vehicle"),
        PlausibleRange(
            "ego_vx",
            "m/s",
            MIN_EGO_SPEED,
            MAX_EGO_SPEED,
            "no car reverses that fast: the car x axis may point backwards, or the speed is in km/h",
            _DOPPLER_TOO_FAST,
            "-30 to 150 m/s: no car reverses faster than about 17 m/s or drives faster than 136 m/s",
        ),
        _symmetric(
            "ego_yaw_rate",
            "rad/s",
            MAX_YAW_RATE,
            "it looks like deg/s; sklearn-radar (as RadarScenes) uses rad/s",
            "+-pi rad/s: no car turns faster than half a revolution per second",
        ),
        _symmetric("vr", "m/s", MAX_DOPPLER, _DOPPLER_TOO_FAST, "+-300 m/s: two road vehicles head-on"),
        _symmetric("vr_compensated", "m/s", MAX_DOPPLER, _DOPPLER_TOO_FAST, "+-300 m/s, as vr"),
        _symmetric("v_r", "m/s", MAX_DOPPLER, _DOPPLER_TOO_FAST, "+-300 m/s, as vr"),
        _symmetric("x_cc", "m", MAX_CAR_POSITION, _CAR_POSITION_TOO_FAR, "+-1030 m: radar reach plus mounting"),
        _symmetric("y_cc", "m", MAX_CAR_POSITION, _CAR_POSITION_TOO_FAR, "+-1030 m: radar reach plus mounting"),
        _symmetric("x_seq", "m", MAX_POSITION, _POSITION_TOO_FAR, "+-4e7 m: the Earth's circumference"),
        _symmetric("y_seq", "m", MAX_POSITION, _POSITION_TOO_FAR, "+-4e7 m: the Earth's circumference"),
        _symmetric("ego_x_seq", "m", MAX_POSITION, _POSITION_TOO_FAR, "+-4e7 m: the Earth's circumference"),
        _symmetric("ego_y_seq", "m", MAX_POSITION, _POSITION_TOO_FAR, "+-4e7 m: the Earth's circumference"),
        _symmetric("x", "m", MAX_POSITION, _POSITION_TOO_FAR, "+-4e7 m: the Earth's circumference"),
        _symmetric("y", "m", MAX_POSITION, _POSITION_TOO_FAR, "+-4e7 m: the Earth's circumference"),
    )
}


#: s.  A radar network delivers scans at a rate set by its cycle time: RadarScenes' four unsynchronised sensors
#: each cycle in about 60 ms, so distinct scan times are about 15 ms apart in a sequence and 60 ms apart per
#: sensor.  The *median* spacing per sequence (or per sensor of it, where the sensor is known) is robust to two
#: sensors that scan almost at once and to gaps.  Even 64 unsynchronised sensors cycling every 10 ms would be
#: 0.16 ms apart: a median below 0.1 ms is no radar.  Timestamps in s or ms instead of µs are far below it.
MIN_SCAN_SPACING = 1e-4
#: s.  No radar cycles slower than 5 s, and a recording subsampled to one scan per second is still within;
#: ``t`` in ms (15-60 "s") or µs (1.5e4) instead of s, or timestamps in ns, are above it.
MAX_SCAN_SPACING = 5.0
#: The spacing is judged only over at least this many distinct scan times of one sequence (or sensor): over a
#: few hand-made rows, or a sparse subset such as one object's detections, a median says little.
MIN_SCANS_FOR_SPACING = 10
#: A scan is one measurement of many detections at one time (RadarScenes: tens to hundreds, the simulator about
#: 35).  A group whose rows are on average fewer than 2 per distinct time is not scan-structured (synthetic
#: data with a time per detection, per-detection times of some sensors): its spacing says nothing about a scan
#: rate and is not judged.
MIN_DETECTIONS_PER_SCAN = 2
#: s, the typical spacing per sequence (4 sensors of about 60 ms) and per sensor: the unit whose typical
#: spacing is nearest (in ratio) to the one seen is named as the likely unit.
TYPICAL_SCAN_SPACING = 0.015
TYPICAL_SENSOR_SCAN_SPACING = 0.06
#: The units a time column is found in, as seconds per unit, and their names.
TIME_UNITS = {"ns": 1e-9, "µs": 1e-6, "ms": 1e-3, "s": 1.0}
TIME_UNIT_NAMES = {"ns": "nanoseconds", "µs": "microseconds", "ms": "milliseconds", "s": "seconds"}


@dataclass(frozen=True)
class ScanSpacing:
    """The plausible median spacing of the distinct scan times of a recording, in a time column's unit.

    The limits are :data:`MIN_SCAN_SPACING` and :data:`MAX_SCAN_SPACING` (s),
    converted to the column's unit.

    Parameters
    ----------
    column : str
        ``"timestamp"`` or ``"t"``.
    unit : str
        The column's unit, a key of :data:`TIME_UNITS`.
    convention : str
        The right unit, as the error message states it.
    too_dense : str
        The likely cause of a spacing below the limit that no other unit explains.
    """

    column: str
    unit: str
    convention: str
    too_dense: str = "no radar scans at that rate"

    @property
    def low(self) -> float:
        """Smallest plausible median spacing, in the column's unit."""
        return MIN_SCAN_SPACING / TIME_UNITS[self.unit]

    @property
    def high(self) -> float:
        """Largest plausible median spacing, in the column's unit."""
        return MAX_SCAN_SPACING / TIME_UNITS[self.unit]

    def likely_unit(self, spacing: float, per_sensor: bool) -> str:
        """The unit in which ``spacing`` (a number read from the column) would be the typical spacing."""
        typical = TYPICAL_SENSOR_SCAN_SPACING if per_sensor else TYPICAL_SCAN_SPACING
        return min(TIME_UNITS, key=lambda unit: abs(np.log(max(spacing, 1e-300) * TIME_UNITS[unit] / typical)))


#: {column: ScanSpacing} of the time columns.
SCAN_SPACING = {
    "timestamp": ScanSpacing("timestamp", "µs", "RadarScenes uses µs"),
    "t": ScanSpacing(
        "t",
        "s",
        "t is in s (FrameTransform writes t = timestamp * 1e-6 s)",
        too_dense="the timestamps it came from look like seconds (FrameTransform's t = timestamp * 1e-6 needs µs)",
    ),
}


#: The ego speed must agree with the ego's path: odometry dead-reckons the pose from the same wheel speed
#: (RadarScenes, and the simulator), so over a sequence the speed integrated over time and the path of the pose
#: differ by wheel slip and sampling only (a few %).  Their ratio is judged between consecutive scans at most
#: SPEED_PATH_MAX_GAP apart (over longer gaps a chord cuts a curve short) and only over a path of at least
#: SPEED_PATH_MIN_PATH (a car at rest says nothing).  A speed in km/h gives 3.6, in mph 2.24, a time column in the
#: wrong unit a factor of 1000: all beyond these limits, while a km/h speed in town stays within MAX_EGO_SPEED.
SPEED_PATH_RATIO = (0.6, 1.7)
#: m.
SPEED_PATH_MIN_PATH = 20.0
#: s.
SPEED_PATH_MAX_GAP = 0.5
#: Units an ego speed is found in, as their value for 1 m/s, for naming the likely one.
SPEED_UNITS = {"km/h": 3.6, "mph": 2.23694}

#: The Doppler ``vr`` of the static world against the ego motion: a raw table is mostly static (RadarScenes and the
#: simulator: 80-95 % of the detections), and a static target's ``vr`` is ``-v_s . u`` (see "Radial velocity"
#: above), known from ``ego_vx``, ``ego_yaw_rate``, the mounting and ``azimuth_sc``.  Judged over the detections
#: whose predicted ``|vr|`` is at least DOPPLER_MIN_PREDICTED (the ego moves), taken from at most DOPPLER_SAMPLE
#: evenly spaced rows, when at least DOPPLER_MIN_DETECTIONS: when DOPPLER_STATIC_SHARE of them or more have ``vr``
#: within DOPPLER_BAND (relative) of a speed unit's multiple of the prediction (km/h: 3.6), ``vr`` is in that unit.
#: In m/s these detections sit at 1 (simulated: 78-84 % of them), in km/h at 3.6 (< 1 % in m/s).
DOPPLER_MIN_PREDICTED = 2.0
DOPPLER_SAMPLE = 2**14
DOPPLER_MIN_DETECTIONS = 100
DOPPLER_BAND = 0.15
DOPPLER_STATIC_SHARE = 0.5

#: The ego yaw must follow its rate: odometry integrates ``yaw_seq`` from the yaw rate (RadarScenes, the simulator),
#: so between consecutive scans at most SPEED_PATH_MAX_GAP apart the change of ``ego_yaw_seq`` (wrapped to
#: (-pi, pi]) equals ``ego_yaw_rate`` integrated over time.  Their least-squares slope per sequence (jitter in the yaw
#: averages out) is about 1 (simulated: 1.03-1.06); a yaw in degrees gives 57.3.  Judged over at least YAW_MIN_STEPS
#: steps and an integrated turn of at least YAW_MIN_TURN rad (a car driving straight says nothing), when the two
#: correlate (YAW_MIN_CORRELATION; simulated: 0.9), so that a yaw that does not follow the rate at all is not blamed
#: on a unit; a slope above YAW_MAX_SLOPE is implausible.
YAW_MIN_STEPS = 50
YAW_MIN_TURN = 0.05
YAW_MIN_CORRELATION = 0.5
YAW_MAX_SLOPE = 5.0
#: Units an angle is found in, as their value for 1 rad, for naming the likely one.
ANGLE_UNITS = {"degrees": 180.0 / np.pi}


def column_names(columns):
    """Names of a tuple of :class:`Column`."""
    return [column.name for column in columns]


def _cast_column(values, column: Column, table: str):
    values = np.asarray(values)
    if column.dtype == "str":
        if values.dtype.kind == "S":
            values = np.char.decode(values, "ascii")
        if values.dtype.kind not in "OUT":
            raise ValueError(f"{table}: column {column.name!r} must hold strings, got dtype {values.dtype}")
        return pd.array(values.astype(str), dtype="str")
    kind = np.dtype(column.dtype).kind
    if values.dtype.kind not in "biuf":
        raise ValueError(f"{table}: column {column.name!r} must be numeric ({column.dtype}), got dtype {values.dtype}")
    if kind in "iu" and values.dtype.kind == "f":
        if not np.all(np.isfinite(values)) or np.any(values != np.round(values)):
            raise ValueError(f"{table}: column {column.name!r} must hold integers, found non-integer values")
        inexact = inexact_integers(np.max(np.abs(values), initial=0.0), values.dtype, column.name, column.unit)
        if inexact:
            raise ValueError(f"{table}: {inexact}")
    return values.astype(column.dtype, copy=False)


def inexact_integers(largest, dtype, name, unit):
    """Why a float ``dtype`` cannot hold integers up to ``largest`` exactly (column ``name``), or None.

    A float of ``p`` mantissa bits holds every integer up to ``2**p`` (float32: 16 777 216, float64: 9e15); beyond,
    values are rounded to steps of a power of two.  Integer types are exact.
    """
    dtype = np.dtype(getattr(dtype, "numpy_dtype", dtype))
    if dtype.kind != "f":
        return None
    exact = 2.0 ** (np.finfo(dtype).nmant + 1)
    if not largest > exact:  # NaN is refused elsewhere
        return None
    step = 2.0 ** (np.floor(np.log2(largest)) - np.finfo(dtype).nmant)
    return (
        f"column {name!r} is {dtype}, which holds integers exactly only up to {exact:.0f}; its values reach "
        f"{largest:.6g} {unit}, where {dtype} steps by {step:.0f} {unit}, so they have been rounded (distinct scans "
        f"merge). Keep {name} as int64 (as RadarScenes) or float64"
    )


def make_frame(data, columns, table: str) -> pd.DataFrame:
    """Build a DataFrame with exactly ``columns``, in order and in their dtypes.

    Parameters
    ----------
    data : mapping or DataFrame
        Column name to values.  Extra keys are ignored.
    columns : tuple of Column
        The schema, e.g. :data:`DETECTION_COLUMNS`.
    table : str
        Name used in error messages (a file name or ``"detections"``).

    Raises
    ------
    ValueError
        Naming the table and the first missing or ill-typed column.
    """
    missing = [c.name for c in columns if c.name not in data]
    if missing:
        raise ValueError(f"{table}: missing column(s) {missing}")
    return pd.DataFrame({c.name: _cast_column(data[c.name], c, table) for c in columns})


def check_columns(X, required, where: str = "X") -> None:
    """Raise a ValueError naming the columns of ``required`` that ``X`` lacks.

    ``X`` must be a DataFrame; estimators that read named columns call this
    before touching them.
    """
    if not isinstance(X, pd.DataFrame):
        raise ValueError(
            f"{where} must be a pandas DataFrame with the columns {list(required)}, got {type(X).__name__}"
        )
    missing = [name for name in required if name not in X.columns]
    if missing:
        raise ValueError(f"{where} is missing the column(s) {missing}")


@validate_params(
    {"track_id": ["array-like"], "sequence": ["array-like", None]},
    prefer_skip_nested_validation=True,
)
def instance_target(track_id, sequence=None) -> np.ndarray:
    """Integer instance label per detection, -1 for background.

    Instances are numbered 0, 1, ... in order of first appearance.  When
    ``sequence`` is given, equal track ids in different sequences are
    different instances.

    Parameters
    ----------
    track_id : array-like of str, shape (n_detections,)
        RadarScenes track ids, ``""`` for background.
    sequence : array-like of int, shape (n_detections,), default=None
        Sequence number of each detection.  None: all detections belong to
        one sequence.

    Returns
    -------
    target : ndarray of int64, shape (n_detections,)
        Instance of each detection, -1 for background.

    Raises
    ------
    ValueError
        If ``track_id`` is not one-dimensional (e.g. the whole detection
        table), or ``sequence`` does not have its shape.

    Examples
    --------
    >>> from sklearn_radar import instance_target
    >>> instance_target(["", "b", "a", "b"]).tolist()
    [-1, 0, 1, 0]
    >>> instance_target(["a", "a"], sequence=[1, 2]).tolist()
    [0, 1]
    """
    kind = "a DataFrame" if isinstance(track_id, pd.DataFrame) else f"a {type(track_id).__name__}"
    track_id = np.asarray(track_id, dtype=object)
    if track_id.ndim != 1:
        raise ValueError(
            f"instance_target expects track_id as one id per detection (1-D, e.g. data['track_id'] of the detection "
            f"table), got {kind} of shape "
            f"{track_id.shape}; for the table use instance_target(data['track_id'], data['sequence'])"
        )
    track_id = track_id.astype(str)
    target = np.full(track_id.shape, -1, dtype=np.int64)
    is_object = track_id != ""
    keys = track_id[is_object]
    if sequence is not None:
        sequence = np.asarray(sequence)
        if sequence.shape != track_id.shape:
            raise ValueError(f"sequence must have the shape of track_id {track_id.shape}, got {sequence.shape}")
        keys = np.char.add(sequence[is_object].astype(str), np.char.add(":", keys))
    target[is_object] = rank_by_first_appearance(keys)
    return target


def attach_context(radar_data: pd.DataFrame, sequence: int, odometry_index, odometry, mounting):
    """Add ``sequence``, ego-pose and mounting columns to one sequence's radar data.

    Parameters
    ----------
    radar_data : DataFrame
        The 14 RadarScenes fields of one sequence.
    sequence : int
        The sequence number.
    odometry_index : ndarray of int, shape (n_detections,)
        Row of ``odometry`` that belongs to each detection's scan.
    odometry : DataFrame
        That sequence's odometry with columns ``x_seq ... yaw_rate``.
    mounting : mapping
        ``{sensor_id: {"x": m, "y": m, "yaw": rad}}``.
    """
    table = {name: radar_data[name].to_numpy() for name in radar_data.columns}
    table["sequence"] = np.full(len(radar_data), sequence, dtype=np.int64)
    for odo_name, det_name in EGO_FIELDS:
        table[det_name] = odometry[odo_name].to_numpy()[odometry_index]
    sensor_id = radar_data["sensor_id"].to_numpy()
    unknown = sorted(set(np.unique(sensor_id).tolist()) - set(int(k) for k in mounting))
    if unknown:
        raise ValueError(f"sensor_id {unknown} has no mounting (sensors.json)")
    for field, det_name in MOUNTING_FIELDS:
        lookup = np.zeros(max(int(k) for k in mounting) + 1)
        for sensor, mount in mounting.items():
            lookup[int(sensor)] = mount[field]
        table[det_name] = lookup[sensor_id]
    return make_frame(table, DETECTION_COLUMNS, table="detections")


@validate_params({"columns": [tuple, list]}, prefer_skip_nested_validation=True)
def describe_columns(columns=DETECTION_COLUMNS) -> str:
    """The column table as reStructuredText-like plain text, for docs and ``--help``.

    Parameters
    ----------
    columns : tuple or list of Column, default=DETECTION_COLUMNS
        The columns to describe, e.g. :data:`RADAR_DATA_COLUMNS` or
        :data:`ODOMETRY_COLUMNS`.

    Returns
    -------
    text : str
        A header line, then one line per column: name, dtype, unit and
        meaning, aligned.

    Examples
    --------
    >>> from sklearn_radar import describe_columns
    >>> print("\\n".join(describe_columns().splitlines()[:2]))
    column          dtype    unit   meaning
    timestamp       int64    µs     scan time; equals the RadarScenes scene key
    """
    width = max((len(c.name) for c in columns), default=len("column"))
    lines = [f"{'column':<{width}}  {'dtype':<7}  {'unit':<5}  meaning"]
    lines += [f"{c.name:<{width}}  {c.dtype:<7}  {c.unit:<5}  {c.description}" for c in columns]
    return "\n".join(lines)


def nearest_odometry_index(scan_timestamps, odometry_timestamps) -> np.ndarray:
    """Index of the odometry row nearest in time to each scan (ties: the earlier row).

    This is how a RadarScenes scene chooses its ``odometry_index``; the
    simulator and the writer both use it, so that ego columns round-trip.

    Parameters
    ----------
    scan_timestamps : array-like of int, µs
    odometry_timestamps : array-like of int, µs, sorted ascending, non-empty
    """
    scan = np.asarray(scan_timestamps, dtype=np.int64)
    odo = np.asarray(odometry_timestamps, dtype=np.int64)
    after = np.clip(np.searchsorted(odo, scan, side="left"), 1, len(odo) - 1) if len(odo) > 1 else None
    if after is None:
        return np.zeros(len(scan), dtype=np.int64)
    before = after - 1
    take_after = np.abs(odo[after] - scan) < np.abs(scan - odo[before])
    return np.where(take_after, after, before).astype(np.int64)
