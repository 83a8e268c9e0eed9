"""ScanStream: RadarDBSCAN (Eqs. 2-5) scan by scan, each new radar scan labelled from the last ``eps_t``.

The scan-by-scan state of stage 1: :meth:`RadarDBSCAN.partial_fit
<sklearn_radar.cluster.RadarDBSCAN.partial_fit>` and the online pipeline
(:class:`~sklearn_radar.online.OnlinePipeline`) both stream through
:class:`ScanStream`.
"""

from __future__ import annotations

import numpy as np

from ._radar_dbscan_kernels import Points, update_window

STREAM_GATE_ERROR = (
    "RadarDBSCAN: cluster_vr_min judges whole clusters, which a stream never has; "
    "use fit (offline) or set cluster_vr_min=None for partial_fit and ScanStream"
)


class ScanStream:
    """Real-time RadarDBSCAN: label each new radar scan from the last ``eps_t`` seconds.

    The low-overhead twin of :meth:`RadarDBSCAN.partial_fit` for use on a
    vehicle: it takes plain arrays, keeps per sequence only the detections of
    the last ``eps_t`` and gives every new detection the label the offline
    ``causal=True`` mode gives it.  A cluster that continues keeps its id;
    when clusters meet the older (smaller) id wins; ids are never reused.

    Read more in the :ref:`User Guide <user-guide-radar-dbscan>`.

    Parameters
    ----------
    clusterer : RadarDBSCAN
        Its parameters (read once, at construction) define the clustering.
        Its ``cluster_vr_min`` must be None (the gate needs whole clusters):
        a ValueError otherwise.

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_radar.cluster import RadarDBSCAN, ScanStream
    >>> stream = ScanStream(RadarDBSCAN(metric="xy", min_samples=2, vr_min=0.0))
    >>> stream.update(x=[0.0, 0.3], y=[0.0, 0.0], v_r=[5.0, 5.0], t=0.0)
    array([0, 0])
    >>> stream.update(x=[0.5], y=[0.0], v_r=[5.0], t=0.06)
    array([0])
    """

    def __init__(self, clusterer):
        clusterer._validate_params()
        if clusterer.cluster_vr_min is not None:
            raise ValueError(STREAM_GATE_ERROR)
        self.clusterer = clusterer
        self._windows = {}
        self._next_id = 0
        self._criterion = clusterer._kernel_criterion()  # the headings of future scans are unknown: the rotated box
        self._meetings = []  # (absorbed ids, surviving ids) of the clusters that met in the last call

    def update(self, x, y, v_r, t, *, sequence=0, keep=None, range_sc=None, heading=None):
        """Labels of one or more new scans (-1: noise), in the order given.

        Parameters
        ----------
        x, y : array-like of float, m
            Working coordinates (see :class:`FrameTransform`).
        v_r : array-like of float, m/s
            Ego-motion-compensated radial velocity.
        t : float or array-like of float, s
            Scan time(s); never older than what was passed for the sequence.
        sequence : int or array-like, default=0
            Sequence of each detection; each sequence has its own window.
        keep : array-like of bool, default=None
            False marks detections removed by the filter.
        range_sc : array-like of float, m, default=None
            Needed when ``alpha_r > 0``.
        heading : array-like of float, rad, default=None
            Car heading for the box criterion.

        Returns
        -------
        labels : ndarray of int64
        """
        x = np.asarray(x, dtype=np.float64).ravel()
        n = len(x)

        def column(values, name):
            if values is None:
                return None
            values = np.asarray(values, dtype=np.float64)
            values = np.full(n, values) if values.ndim == 0 else values.ravel()
            if len(values) != n or not np.isfinite(values).all():
                raise ValueError(f"ScanStream.update: {name!r} must hold {n} finite values")
            return values

        given = dict(x=x, y=y, v_r=v_r, t=t, sequence=sequence, keep=keep, range_sc=range_sc, heading=heading)
        c = {name: column(values, name) for name, values in given.items()}
        return self._label(c)

    def _label(self, c, one_scan=None):
        """Labels of the rows of the read columns ``c``; ``one_scan``: True when the caller checked that they are
        one scan of one sequence (the online pipeline), None to find out."""
        self._meetings = []
        active, min_points, can_be_core = self.clusterer._point_rules(c)
        n = len(c["x"])
        labels = np.full(n, -1, dtype=np.int64)
        sequence = np.zeros(n) if c["sequence"] is None else c["sequence"]
        heading = np.zeros(n) if c["heading"] is None else c["heading"]
        if one_scan is None:
            one_scan = n > 0 and np.all(sequence == sequence[0]) and np.all(c["t"] == c["t"][0])
        if one_scan:
            groups = [np.flatnonzero(active)]  # the active rows only
        else:
            order = np.lexsort((c["t"], sequence))
            cut = np.flatnonzero((np.diff(sequence[order]) != 0) | (np.diff(c["t"][order]) != 0)) + 1
            groups = [scan[active[scan]] for scan in np.split(order, cut)]
        for scan in groups:
            if len(scan) == 0:
                continue
            key = float(sequence[scan[0]])
            window = self._windows.get(key) or self._windows.setdefault(key, _Window())
            if c["t"][scan[0]] < window.last_time:
                raise ValueError(
                    f"RadarDBSCAN stream: column 't' goes back in time ({c['t'][scan[0]]} s after "
                    f"{window.last_time} s in sequence {sequence[scan[0]]:g}); pass scans in time order"
                )
            window.append(c, scan, heading, min_points, can_be_core, self._criterion.eps_t)
            before = window.cluster[: window.first_new].copy()
            self._next_id = update_window(
                points=window.points,
                min_points=window.min_points,
                can_be_core=window.can_be_core,
                core=window.core,
                cluster=window.cluster,
                first_new=window.first_new,
                next_id=self._next_id,
                criterion=self._criterion,
            )
            labels[scan] = window.cluster[window.first_new :]
            relabelled = np.flatnonzero(before != window.cluster[: window.first_new])
            if len(relabelled):  # clusters met: the window's rows of the newer ones now carry the older id
                self._meetings.append((before[relabelled], window.cluster[relabelled]))
        return labels


class _Window:
    """The detections of one sequence within the last eps_t, for the stream.

    The columns live in buffers with room for more scans: the float columns
    in one (7, capacity) block, the six rows of :class:`Points` (x, y in m,
    v in m/s, t in s, cos and sin of the heading) then N_min, and the flags
    and ids beside it.  The window is the span ``[lo, hi)``: a scan drops
    the old detections by moving ``lo`` and writes its rows at ``hi``; the
    live span is moved to the front only when the buffer is full (and the
    buffer doubled when the span needs it), so that a scan costs a few row
    writes instead of concatenations of the whole window.  ``points``,
    ``min_points``, ``can_be_core``, ``core`` and ``cluster`` are
    contiguous views of the span (the kernel writes ``core`` and
    ``cluster`` in place).
    """

    def __init__(self, capacity=1024):
        self._block = np.zeros((7, capacity))
        self._can_be_core = np.zeros(capacity, dtype=bool)
        self._core = np.zeros(capacity, dtype=bool)
        self._cluster = np.full(capacity, -1, dtype=np.int64)
        self.lo = self.hi = 0
        self.first_new = 0
        self.last_time = -np.inf
        self._set_views()

    def _set_views(self):
        lo, hi = self.lo, self.hi
        self.points = Points(*(self._block[row, lo:hi] for row in range(6)))
        self.min_points = self._block[6, lo:hi]
        self.can_be_core = self._can_be_core[lo:hi]
        self.core = self._core[lo:hi]
        self.cluster = self._cluster[lo:hi]

    def _make_room(self, first_kept, n_new):
        """Move the kept span ``[first_kept, hi)`` to the front (in a larger buffer if ``n_new`` rows do not fit)."""
        live = self.hi - first_kept
        capacity = self._block.shape[1]
        if live + n_new > capacity // 2:  # keep the moves rare: at most every capacity / 2 rows
            capacity = 2 * (live + n_new)
        block, can_be_core = np.zeros((7, capacity)), np.zeros(capacity, dtype=bool)
        core, cluster = np.zeros(capacity, dtype=bool), np.full(capacity, -1, dtype=np.int64)
        block[:, :live] = self._block[:, first_kept : self.hi]
        can_be_core[:live] = self._can_be_core[first_kept : self.hi]
        core[:live] = self._core[first_kept : self.hi]
        cluster[:live] = self._cluster[first_kept : self.hi]
        self._block, self._can_be_core, self._core, self._cluster = block, can_be_core, core, cluster
        self.lo, self.hi = 0, live

    def append(self, c, scan, heading, min_points, can_be_core, eps_t):
        """Drop what is older than ``eps_t`` (s) before the scan, then add the scan."""
        now = c["t"][scan[0]]
        first_kept = self.lo + int(np.searchsorted(self.points.t, now - eps_t, side="left"))  # time-sorted
        n_new = len(scan)
        if self.hi + n_new > self._block.shape[1]:
            self._make_room(first_kept, n_new)
        else:
            self.lo = first_kept
        start, stop = self.hi, self.hi + n_new
        block = self._block
        block[0, start:stop] = c["x"][scan]
        block[1, start:stop] = c["y"][scan]
        block[2, start:stop] = c["v_r"][scan]
        block[3, start:stop] = c["t"][scan]
        scan_heading = heading[scan]
        if scan_heading.any():  # as points_of: no trigonometry for a heading of 0
            block[4, start:stop] = np.cos(scan_heading)
            block[5, start:stop] = np.sin(scan_heading)
        else:
            block[4, start:stop] = 1.0
            block[5, start:stop] = 0.0
        block[6, start:stop] = min_points[scan]
        self._can_be_core[start:stop] = can_be_core[scan]
        self._core[start:stop] = False
        self._cluster[start:stop] = -1
        self.hi = stop
        self.first_new = stop - n_new - self.lo
        self._set_views()
        self.last_time = now
