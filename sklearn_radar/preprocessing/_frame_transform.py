"""FrameTransform: working coordinates in the car frame (CCS) or a fixed frame (FCS)."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from sklearn.base import BaseEstimator, TransformerMixin, _fit_context
from sklearn.utils._param_validation import StrOptions
from sklearn.utils.validation import check_is_fitted

from .._schema import FRAME_TRANSFORM_READS
from .._validation import read_columns, write_columns
from ._output_names import feature_names_out, work_array_width

#: The working columns added to a DataFrame, in the order they are appended.
WORKING_COLUMNS = ("x", "y", "v_r", "t", "heading")
#: Raw columns copied into the working-layout array (Eq. 2 needs the range, Eq. 6 the line of sight).
_LINE_OF_SIGHT = ("range_sc", "azimuth_sc", "sensor_yaw")
#: The columns written into the working-layout array returned for an array.
_ARRAY_COLUMNS = (*WORKING_COLUMNS, "sequence", *_LINE_OF_SIGHT)


class FrameTransform(TransformerMixin, BaseEstimator):
    """Give every detection working coordinates x, y (m), v_r (m/s), t (s) and heading (rad).

    The first stage of the framework (Sec. "Detection Filtering" of Scheiner
    et al. 2019).  Positions come from each detection's polar measurement
    (``range_sc``, ``azimuth_sc``) and its sensor's mounting:

    * ``frame="car"`` (CCS): the car frame of the detection's own scan,
      ``x = sensor_x + range_sc cos(azimuth_sc + sensor_yaw)`` (likewise y).
      Nothing compensates the ego motion between scans, so a static wall
      smears along the driving direction within a time window.
    * ``frame="frame"`` (FCS): the car-frame position carried into the fixed
      sequence frame with the odometry pose of the scan,
      ``x = ego_x_seq + cos(ego_yaw_seq) x_cc - sin(ego_yaw_seq) y_cc``
      (likewise y).  Distances between detections of different scans are then
      free of ego motion: a static wall stays in place while the car moves.

    ``v_r`` is the ego-motion-compensated radial velocity,
    ``vr + (ego_vx - ego_yaw_rate sensor_y) cos(a) + ego_yaw_rate sensor_x sin(a)``
    with ``a = azimuth_sc + sensor_yaw``: about 0 for static targets, negative
    for targets that approach the sensor.  ``t = timestamp * 1e-6``.
    ``heading`` is the direction of the car's x axis in the x-y axes
    (``ego_yaw_seq`` in FCS, 0 in CCS); the box criterion of
    :class:`RadarDBSCAN` uses it to keep its box aligned with the car.
    On RadarScenes data the results equal ``x_cc``/``y_cc`` (CCS),
    ``x_seq``/``y_seq`` (FCS) and ``vr_compensated``.

    Rows are never dropped or reordered.

    Read more in the :ref:`User Guide <user-guide-data>`.

    Parameters
    ----------
    frame : {"frame", "car"}, default="frame"
        Coordinate system of ``x`` and ``y``: "frame" (FCS, ego-motion
        compensated, the paper's preferred choice) or "car" (CCS).

    Attributes
    ----------
    n_features_in_ : int
        Number of columns seen in :meth:`fit`.
    feature_names_in_ : ndarray of str
        Column names seen in :meth:`fit`, when X is a DataFrame.

    Notes
    -----
    X is the detection table of :mod:`sklearn_radar._schema` (a DataFrame);
    :meth:`transform` returns a copy with the columns ``x``, ``y``, ``v_r``,
    ``t`` and ``heading`` added (overwritten if present).  A plain array is read by
    position in the order ``range_sc, azimuth_sc, vr, timestamp, sensor_x,
    sensor_y, sensor_yaw, ego_x_seq, ego_y_seq, ego_yaw_seq, ego_vx,
    ego_yaw_rate, sequence`` (:data:`~sklearn_radar._schema.RAW_LAYOUT`;
    absent trailing columns are 0: sensor at the car origin, car at rest, one
    scan), and the result is the array ``[x, y, v_r, t, sequence, keep,
    range_sc, heading, azimuth_sc, sensor_yaw]`` (keep = 1) that the later
    stages read by position (:data:`~sklearn_radar._schema.WORK_LAYOUT`).

    The output container follows scikit-learn's ``set_output`` API.  Under
    ``"default"`` (also when nothing is set) the result is what
    :meth:`transform` makes: a DataFrame for a DataFrame, an array for an
    array.  ``set_output(transform="pandas")``, or
    ``sklearn.set_config(transform_output="pandas")``, also returns the array
    result as a DataFrame, with the columns of :meth:`get_feature_names_out`
    and a ``RangeIndex``; the later stages read it by name.  A DataFrame
    result is the same under both settings.  ``"polars"`` needs polars
    (without it, scikit-learn raises an ImportError); the later stages read
    pandas DataFrames by name and refuse other tables.  Fit and transform
    the same kind of container: :meth:`get_feature_names_out` names the
    result of the kind seen in :meth:`fit`, and the pandas wrapper raises a
    ValueError when the widths differ.

    Examples
    --------
    >>> from sklearn_radar import FrameTransform
    >>> from sklearn_radar.datasets import make_scenes
    >>> X = make_scenes(n_sequences=1, duration=2.0, random_state=0).data
    >>> Xt = FrameTransform(frame="frame").fit_transform(X)
    >>> bool(abs(Xt["x"] - X["x_seq"]).max() < 1e-3)
    True

    A plain array comes back as a DataFrame of the working columns under
    pandas output:

    >>> import numpy as np
    >>> raw = np.array([[10.0, 0.0, -1.0, 0.0], [20.0, 0.5, 2.0, 60_000.0]])
    >>> ft = FrameTransform().set_output(transform="pandas")
    >>> ft.fit_transform(raw).columns.tolist()
    ['x', 'y', 'v_r', 't', 'sequence', 'keep', 'range_sc', 'heading', 'azimuth_sc', 'sensor_yaw']
    """

    _parameter_constraints: ClassVar[dict] = {"frame": [StrOptions({"frame", "car"})]}

    def __init__(self, frame="frame"):
        self.frame = frame

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y=None):
        """Check the input columns; nothing is learned.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Raw detections: the detection table of :mod:`sklearn_radar._schema`, or an array in the
            order of :data:`~sklearn_radar._schema.RAW_LAYOUT`.
        y : None
            Ignored.

        Returns
        -------
        self : FrameTransform
        """
        read_columns(self, X, FRAME_TRANSFORM_READS, reset=True)
        return self

    @_fit_context(prefer_skip_nested_validation=True)
    def fit_transform(self, X, y=None):
        """:meth:`fit`, then :meth:`transform`, reading and checking the input once.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Raw detections, as for :meth:`fit`.
        y : None
            Ignored.

        Returns
        -------
        Xt : DataFrame or ndarray
            As :meth:`transform` returns it.
        """
        return self._transformed(*read_columns(self, X, FRAME_TRANSFORM_READS, reset=True))

    def transform(self, X):
        """Add the working columns ``x``, ``y`` (m), ``v_r`` (m/s), ``t`` (s) and ``heading`` (rad).

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Raw detections: the detection table of :mod:`sklearn_radar._schema`, or an array in the
            order of :data:`~sklearn_radar._schema.RAW_LAYOUT`.

        Returns
        -------
        Xt : DataFrame or ndarray
            A DataFrame with the columns added, or the array
            ``[x, y, v_r, t, sequence, keep, range_sc, heading, azimuth_sc, sensor_yaw]``
            of shape (n_detections, 10) (:data:`~sklearn_radar._schema.WORK_LAYOUT`).
        """
        check_is_fitted(self)
        return self._transformed(*read_columns(self, X, FRAME_TRANSFORM_READS, reset=False))

    def get_feature_names_out(self, input_features=None):
        """Names of the columns :meth:`transform` returns, as ``set_output`` uses them.

        Parameters
        ----------
        input_features : array-like of str or None, default=None
            The input columns.  None: those seen in :meth:`fit`
            (``feature_names_in_``), or ``x0, x1, ...`` for an array.  If
            given, they must equal ``feature_names_in_`` (DataFrame fit) or
            number ``n_features_in_`` (array fit).

        Returns
        -------
        feature_names_out : ndarray of str objects
            Fitted on a DataFrame: its columns, then those of ``x, y, v_r, t,
            heading`` it did not hold.  Fitted on an array:
            :data:`~sklearn_radar._schema.WORK_LAYOUT`, ``x, y, v_r, t,
            sequence, keep, range_sc, heading, azimuth_sc, sensor_yaw``,
            whatever ``input_features`` are.
        """
        check_is_fitted(self)
        return feature_names_out(
            self, input_features, added=WORKING_COLUMNS, array_width=work_array_width(0, _ARRAY_COLUMNS)
        )

    def _transformed(self, X, c):
        """The working columns from the read raw columns ``c``, written into ``X``'s kind of container."""
        with np.errstate(over="ignore", invalid="ignore"):
            work = self._working_columns(c)
        _check_finite(work, c)
        if hasattr(X, "columns"):
            return write_columns(X, {name: work[name] for name in WORKING_COLUMNS})
        sequence = c["sequence"] if c["sequence"] is not None else np.zeros(len(work["x"]))
        line_of_sight = {name: c[name] for name in _LINE_OF_SIGHT}
        return write_columns(np.empty((len(work["x"]), 0)), {**work, "sequence": sequence, **line_of_sight})

    def _working_columns(self, c):
        """x, y (m), v_r (m/s), t (s) and heading (rad) from the raw columns ``c``."""
        angle = c["azimuth_sc"] + c["sensor_yaw"]
        cos_a, sin_a = np.cos(angle), np.sin(angle)
        x = c["sensor_x"] + c["range_sc"] * cos_a
        y = c["sensor_y"] + c["range_sc"] * sin_a
        if self.frame == "frame":
            cos_e, sin_e = np.cos(c["ego_yaw_seq"]), np.sin(c["ego_yaw_seq"])
            x, y = c["ego_x_seq"] + cos_e * x - sin_e * y, c["ego_y_seq"] + sin_e * x + cos_e * y
        sensor_vx = c["ego_vx"] - c["ego_yaw_rate"] * c["sensor_y"]
        sensor_vy = c["ego_yaw_rate"] * c["sensor_x"]
        work = {
            "x": x,
            "y": y,
            "v_r": c["vr"] + sensor_vx * cos_a + sensor_vy * sin_a,
            "t": c["timestamp"] * 1e-6,
            "heading": c["ego_yaw_seq"] if self.frame == "frame" else np.zeros(len(x)),
        }
        return work

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.transformer_tags.preserves_dtype = []
        return tags


#: The raw columns each working column is computed from, to name them when a result overflows.
_SOURCES = {
    "x": ("range_sc", "azimuth_sc", "sensor_x", "sensor_y", "sensor_yaw", "ego_x_seq", "ego_y_seq", "ego_yaw_seq"),
    "y": ("range_sc", "azimuth_sc", "sensor_x", "sensor_y", "sensor_yaw", "ego_x_seq", "ego_y_seq", "ego_yaw_seq"),
    "v_r": ("vr", "azimuth_sc", "sensor_yaw", "sensor_x", "sensor_y", "ego_vx", "ego_yaw_rate"),
    "t": ("timestamp",),
    "heading": ("ego_yaw_seq",),
}


def _check_finite(work, c):
    """ValueError naming the largest raw value behind the first working column that overflowed."""
    for name, values in work.items():
        bad = np.flatnonzero(~np.isfinite(values))
        if len(bad):
            row = int(bad[0])
            source = max(_SOURCES[name], key=lambda column: abs(c[column][row]))
            raise ValueError(
                f"FrameTransform: column {source!r} holds {c[source][row]:.3g} at row {row}, which makes the "
                f"working column {name!r} overflow; check its unit and magnitude"
            )
