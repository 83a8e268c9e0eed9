"""DopplerDensityFilter: the paper's Eq. 1, removing static background by Doppler and density."""

from __future__ import annotations

from numbers import Integral, Real
from typing import ClassVar

import numpy as np
from joblib import Parallel, delayed
from sklearn.base import BaseEstimator, TransformerMixin, _fit_context
from sklearn.utils._param_validation import Interval, validate_params
from sklearn.utils.validation import check_is_fitted

from .._neighbors import build_grid, count_neighbors
from .._schema import FILTER_READS
from .._validation import check_filter_rule, read_columns, sequence_slices, write_columns
from ._doppler_density_kernels import removed_by_eq1, speed_limits
from ._output_names import feature_names_out, work_array_width


@validate_params(
    {
        "v_r": ["array-like"],
        "n_neighbors": ["array-like"],
        "vr_threshold": [Interval(Real, 0, None, closed="left")],
        "threshold_ratios": ["array-like"],
        "min_neighbors": ["array-like"],
    },
    prefer_skip_nested_validation=True,
)
def doppler_density_keep(
    v_r, n_neighbors, vr_threshold=0.10, threshold_ratios=(1, 5, 10, 50), min_neighbors=(2, 3, 4, 10)
):
    """Eq. 1: which detections survive the Doppler-density filter.

    A detection is removed when it has no neighbour, or when for any i its
    absolute compensated radial velocity is below ``eta_i = vr_threshold /
    threshold_ratios[i]`` while it has fewer than ``min_neighbors[i]``
    neighbours::

        N < 1  or  any_i (|v_r| < eta_i and N < N_i),
        eta_1 = 5 eta_2 = 10 eta_3 = 50 eta_4,  N = (2, 3, 4, 10).

    Read more in the :ref:`User Guide <user-guide-filter>`.

    Parameters
    ----------
    v_r : array-like of shape (n_detections,)
        Ego-motion-compensated radial velocity, m/s.
    n_neighbors : array-like of shape (n_detections,)
        Neighbour count N (the detection itself excluded); counts capped at
        ``max(min_neighbors)`` give the same result.
    vr_threshold : float, default=0.10
        eta_1, m/s, >= 0.
    threshold_ratios : array-like of float, default=(1, 5, 10, 50)
        eta_1 / eta_i for each i, each > 0.
    min_neighbors : array-like of int, default=(2, 3, 4, 10)
        N_i for each i, each >= 1; as many as ``threshold_ratios``.

    Returns
    -------
    keep : ndarray of bool, shape (n_detections,)
        False where Eq. 1 removes the detection.

    Raises
    ------
    ValueError
        If ``v_r`` and ``n_neighbors`` differ in shape, or
        ``threshold_ratios`` and ``min_neighbors`` in length.

    See Also
    --------
    neighbor_counts : the neighbour counts N.
    DopplerDensityFilter : the filter as a transformer.

    Examples
    --------
    >>> from sklearn_radar.preprocessing import doppler_density_keep
    >>> doppler_density_keep([0.0, 0.0, 0.5, 0.0], [0, 1, 1, 10]).tolist()
    [False, False, True, True]
    """
    v_r = np.asarray(v_r, dtype=np.float64)
    n_neighbors = np.asarray(n_neighbors)
    if v_r.shape != n_neighbors.shape:
        raise ValueError(f"v_r and n_neighbors must have equal shapes, got {v_r.shape} and {n_neighbors.shape}")
    ratios, n_min = check_filter_rule(threshold_ratios, min_neighbors)
    return _doppler_density_keep(v_r, n_neighbors, vr_threshold, ratios, n_min)


def _doppler_density_keep(v_r, n_neighbors, vr_threshold, threshold_ratios, min_neighbors):
    """:func:`doppler_density_keep` without its validation, for callers inside the package.

    ``threshold_ratios`` and ``min_neighbors`` as returned by
    :func:`~sklearn_radar._validation.check_filter_rule`.
    """
    speed = np.abs(np.asarray(v_r, dtype=np.float64))
    limits = speed_limits(vr_threshold, threshold_ratios)
    if len(limits) != len(min_neighbors):
        raise ValueError(
            f"threshold_ratios and min_neighbors must be of equal length, got {len(limits)} and {len(min_neighbors)}"
        )
    return ~removed_by_eq1(speed, np.asarray(n_neighbors), limits, min_neighbors)


@validate_params(
    {
        "x": ["array-like"],
        "y": ["array-like"],
        "t": ["array-like"],
        "sequence": ["array-like", None],
        "d_xy": [Interval(Real, 0, None, closed="neither")],
        "dt": [Interval(Real, 0, None, closed="left")],
        "causal": ["boolean"],
        "cap": [Interval(Integral, 1, None, closed="left")],
        "n_jobs": [Integral, None],
    },
    prefer_skip_nested_validation=True,
)
def neighbor_counts(x, y, t, sequence, d_xy, dt, causal=False, cap=10, n_jobs=None):
    """Neighbours within ``d_xy`` (m) and ``dt`` (s) in the same sequence, capped at ``cap``.

    The neighbour count N of Eq. 1: for each detection, the number of other
    detections of its sequence within ``d_xy`` in x-y (Euclidean,
    inclusive) and within ``dt`` in time (inclusive).  Work is linear in the
    number of detections: a grid of cell ``d_xy`` limits the candidates and
    counting stops at ``cap``.

    Read more in the :ref:`User Guide <user-guide-filter>`.

    Parameters
    ----------
    x, y : array-like of float, shape (n_detections,)
        Position, m (the ``x`` and ``y`` columns of
        :class:`~sklearn_radar.FrameTransform`).
    t : array-like of float, shape (n_detections,)
        Detection time, s.
    sequence : array-like of shape (n_detections,) or None
        Sequence of each detection; detections of different sequences are
        never neighbours.  None: one sequence.
    d_xy : float
        Spatial radius, m, > 0.
    dt : float
        Time window, s, >= 0.
    causal : bool, default=False
        If True, only detections at or before a detection's time count.
    cap : int, default=10
        Counting stops at this many neighbours, >= 1; Eq. 1 needs no more
        than ``max(min_neighbors)``.
    n_jobs : int, default=None
        Sequences processed in parallel (joblib threads; the count kernel
        releases the GIL).  None means 1.

    Returns
    -------
    counts : ndarray of int64, shape (n_detections,)
        Neighbours of each detection (itself excluded), at most ``cap``.

    Raises
    ------
    ValueError
        If the arrays differ in length.

    See Also
    --------
    doppler_density_keep : Eq. 1 applied to the counts.

    Examples
    --------
    >>> from sklearn_radar.preprocessing import neighbor_counts
    >>> neighbor_counts([0.0, 1.0, 5.0], [0.0, 0.0, 0.0], [0.0, 0.1, 0.0], None, d_xy=1.4, dt=0.25).tolist()
    [1, 1, 0]
    """
    x, y, t = (np.asarray(values, dtype=np.float64) for values in (x, y, t))
    shapes = {x.shape, y.shape, t.shape} | ({np.shape(sequence)} if sequence is not None else set())
    if len(shapes) != 1 or x.ndim != 1:
        raise ValueError(f"x, y, t and sequence must be 1-D of equal length, got shapes {sorted(shapes)}")
    return _neighbor_counts(x, y, t, sequence, d_xy, dt, causal, cap, n_jobs)


def _neighbor_counts(x, y, t, sequence, d_xy, dt, causal=False, cap=10, n_jobs=None):
    """:func:`neighbor_counts` without its validation: float64 arrays, for callers inside the package."""
    counts = np.empty(len(x), dtype=np.int64)
    slices = sequence_slices(sequence)

    def count(rows):
        times = t[rows] - t[rows].min() if len(t[rows]) else t[rows]  # small numbers: exact window edges
        grid = build_grid(x[rows], y[rows], times, d_xy)
        return rows, count_neighbors(grid, d_xy, dt, 0.0 if causal else dt, cap)

    jobs = Parallel(n_jobs=n_jobs, prefer="threads")(delayed(count)(rows) for rows in slices)
    for rows, result in jobs:
        counts[rows] = result
    return counts


class DopplerDensityFilter(TransformerMixin, BaseEstimator):
    """Mark static background by Doppler and neighbour density (Eq. 1).

    For each detection, N counts the other detections of the same sequence
    within ``d_xy`` in x-y and within ``dt`` in time.  The detection is
    marked as removed (``keep = False``) when ``N < 1``, or when
    ``|v_r| < eta_i`` and ``N < N_i`` for any i, with ``eta_i = vr_threshold
    / threshold_ratios[i]`` and ``N_i = min_neighbors[i]`` (the paper:
    eta_1 = 5 eta_2 = 10 eta_3 = 50 eta_4 and N = (2, 3, 4, 10)).  The fewer
    the neighbours, the faster a detection must move to stay.  Rows are never
    dropped: the later stages treat ``keep = False`` as noise.

    Read more in the :ref:`User Guide <user-guide-filter>`.

    Parameters
    ----------
    vr_threshold : float, default=0.10
        eta_1, the largest Doppler threshold, m/s.  The paper's chosen
        setting; tuned with ``d_xy``.
    d_xy : float, default=1.4
        Spatial neighbour radius, m (Euclidean in x-y, inclusive).
    dt : float, default=0.25
        Time window, s (inclusive), the sliding window of the later stages.
    threshold_ratios : array-like of float, default=(1, 5, 10, 50)
        eta_1 / eta_i.
    min_neighbors : array-like of int, default=(2, 3, 4, 10)
        N_i, one per ratio.
    causal : bool, default=False
        If True, only detections at or before a detection's time are its
        neighbours (no look-ahead, usable on a live stream).  The default is
        the paper's symmetric window "around each point", which sees up to
        ``dt`` into the future and so removes less of a road user that has
        just appeared.
    n_jobs : int, default=None
        Sequences processed in parallel (joblib threads).

    Attributes
    ----------
    n_features_in_ : int
    feature_names_in_ : ndarray of str
        When X is a DataFrame.

    Notes
    -----
    Reads the columns ``x``, ``y`` (m), ``v_r`` (m/s), ``t`` (s) written by
    :class:`FrameTransform`, and ``sequence`` if present.  Returns X with a
    boolean column ``keep``.  A plain array is read by position
    ``[x, y, v_r, t, sequence]`` of :data:`~sklearn_radar._schema.WORK_LAYOUT`
    (absent columns: y = v_r = t = sequence = 0) and the result carries
    ``keep`` (1.0 or 0.0) at its position there, 5.

    Output containers follow scikit-learn's ``set_output`` API as for
    :class:`FrameTransform`: under ``"default"`` a DataFrame comes back as a
    DataFrame (``keep`` boolean) and an array as an array (``keep`` 1.0 or
    0.0); under ``"pandas"`` an array result becomes a DataFrame with the
    columns of :meth:`get_feature_names_out` and a ``RangeIndex``.

    Examples
    --------
    >>> from sklearn.pipeline import make_pipeline
    >>> from sklearn_radar import DopplerDensityFilter, FrameTransform
    >>> from sklearn_radar.datasets import make_scenes
    >>> scenes = make_scenes(n_sequences=1, duration=5.0, random_state=0)
    >>> Xt = make_pipeline(FrameTransform(), DopplerDensityFilter()).fit_transform(scenes.data)
    >>> len(Xt) == len(scenes.data)
    True
    """

    _parameter_constraints: ClassVar[dict] = {
        "vr_threshold": [Interval(Real, 0, None, closed="left")],
        "d_xy": [Interval(Real, 0, None, closed="neither")],
        "dt": [Interval(Real, 0, None, closed="left")],
        "threshold_ratios": ["array-like"],
        "min_neighbors": ["array-like"],
        "causal": ["boolean"],
        "n_jobs": [None, Integral],
    }

    def __init__(
        self,
        vr_threshold=0.10,
        d_xy=1.4,
        dt=0.25,
        threshold_ratios=(1, 5, 10, 50),
        min_neighbors=(2, 3, 4, 10),
        causal=False,
        n_jobs=None,
    ):
        self.vr_threshold = vr_threshold
        self.d_xy = d_xy
        self.dt = dt
        self.threshold_ratios = threshold_ratios
        self.min_neighbors = min_neighbors
        self.causal = causal
        self.n_jobs = n_jobs

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y=None):
        """Check the parameters and the input columns; nothing is learned.

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections (the output of :class:`FrameTransform`), or an array in the order
            of :data:`~sklearn_radar._schema.WORK_LAYOUT`.
        y : None
            Ignored.

        Returns
        -------
        self : DopplerDensityFilter
        """
        self._rule()
        read_columns(self, X, FILTER_READS, reset=True)
        return self

    def transform(self, X):
        """Add the boolean column ``keep`` (False: removed by Eq. 1).

        Parameters
        ----------
        X : DataFrame or array-like of shape (n_detections, n_columns)
            Working detections (the output of :class:`FrameTransform`), or an array in the order
            of :data:`~sklearn_radar._schema.WORK_LAYOUT`.

        Returns
        -------
        Xt : DataFrame or ndarray
            X with ``keep``; same rows in the same order.
        """
        check_is_fitted(self)
        ratios, min_neighbors = self._rule()
        X, c = read_columns(self, X, FILTER_READS, reset=False)
        counts = _neighbor_counts(
            c["x"],
            c["y"],
            c["t"],
            c["sequence"],
            self.d_xy,
            self.dt,
            self.causal,
            int(min_neighbors.max()),
            self.n_jobs,
        )
        keep = _doppler_density_keep(c["v_r"], counts, self.vr_threshold, ratios, min_neighbors)
        return write_columns(X, {"keep": keep if hasattr(X, "columns") else keep.astype(np.float64)})

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
            Fitted on a DataFrame: its columns, then ``keep`` if it did not
            hold one.  Fitted on an array: the names of
            :data:`~sklearn_radar._schema.WORK_LAYOUT` up to the output width
            (at least 6, to ``keep``; a column beyond the layout keeps its
            name from ``input_features``).
        """
        check_is_fitted(self)
        width = work_array_width(self.n_features_in_, ("keep",))
        return feature_names_out(self, input_features, added=("keep",), array_width=width)

    def _rule(self):
        """The thresholds of Eq. 1 as arrays, validated."""
        return check_filter_rule(self.threshold_ratios, self.min_neighbors)

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.transformer_tags.preserves_dtype = []
        return tags
