"""OnlinePipeline: the whole framework (frame transform, filter, stage 1, stage 2) one radar scan at a time."""

from __future__ import annotations

import copy
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from sklearn.base import clone
from sklearn.pipeline import Pipeline

from .._schema import RAW_LAYOUT
from ..cluster import ClusterMerger, LinkClustering, RadarDBSCAN, ScanStream
from ..experiments._saved import load_params, setting_pipeline
from ..preprocessing import DopplerDensityFilter, FrameTransform
from ._filter import FilterWindow
from ._learned_stream import LearnedIds, LearnedStream, check_learned, learned_update
from ._merger import MergeWindow
from ._objects import ObjectIds, ObjectList, ObjectTable, empty_object_list, object_figures
from ._tracker import Tracker, followed_ids, sequence_frame

#: The raw columns a scan must hold (the detection table's, see :mod:`sklearn_radar._schema`).
SCAN_COLUMNS = tuple(name for name in RAW_LAYOUT.columns if name != "sequence")


@dataclass
class ScanResult:
    """What :meth:`OnlinePipeline.update` returns for one scan.

    Parameters
    ----------
    labels : ndarray of int64, shape (n_detections,)
        Stage-1 cluster of each detection (-1: noise), as the offline causal stage 1 gives it.
    object_ids : ndarray of int64, shape (n_detections,)
        Persistent object id of each detection (-1: noise), after the merges decided at this scan.
    confirmed : ndarray of bool, shape (n_detections,)
        Whether the detection's object has at least ClusterMerger's ``min_cluster_size`` detections so far (this
        scan's and the merges decided at it included): the track confirmation rule.  ``object_ids >= 0`` when
        ``min_cluster_size`` is 1 or there is no stage 2.
    keep : ndarray of bool, shape (n_detections,)
        False where the filter (Eq. 1) removed the detection; True for every row without a filter.
    objects : ObjectList
        The live objects of the scan's sequence.
    aliases : list of (int, int, int, str)
        The merges decided at this scan: (timestamp us, surviving id, merged id, ``"stage1"``, ``"stage2"``
        or, with the learned grouping, ``"learned"``);
        from now on the merged id is an alias of the surviving one.  A merge of clusters that are one
        object already (through other merges) makes no alias.
    merges : list of (int, int)
        The stage-2 pairs (A, B) accepted at this scan, as stage-1 labels: the offline ``ClusterMerger``'s
        ``merges_``, decided here.
    joins : list of (int, int)
        The pairs of stage-1 labels that stage 2 made one object at this scan: ``merges`` when
        ``min_samples`` is 1; with a larger one the joins of the DBSCAN over clusters (core partners, a
        non-core cluster with its first core partner), each as soon as it is certain.
    track_id : ndarray of int64, shape (n_detections,), or None
        With a ``tracker``: the :class:`Tracker`'s confirmed track of each
        detection (-1: none); ids are unique within a sequence.  None
        without one.
    """

    labels: np.ndarray
    object_ids: np.ndarray
    confirmed: np.ndarray
    keep: np.ndarray
    objects: ObjectList
    aliases: list
    merges: list
    joins: list
    track_id: np.ndarray | None = None


class _Sequence:
    """The windows of one sequence (recording): filter, stage 2, its tracker and the last times seen."""

    def __init__(self, filter_, merger, eps_t, tracker=None):
        self.tracker = None if tracker is None else tracker.fresh()
        self.filter = None if filter_ is None else FilterWindow(filter_)
        self.merge = MergeWindow(merger, eps_t)
        self.objects = ObjectTable()
        self.last_us = None
        self.sensor_us = {}


class OnlinePipeline:
    """The framework's pipeline on a live stream: each radar scan labelled when it arrives, using only the past.

    Built from an offline pipeline of :class:`~sklearn_radar.FrameTransform`,
    an optional :class:`~sklearn_radar.DopplerDensityFilter` (or
    ``"passthrough"``) and :class:`~sklearn_radar.RadarDBSCAN` or
    :class:`~sklearn_radar.ClusterMerger` (either mode), configured or
    fitted, or from a ``params.json`` (:meth:`from_params`).  Each stage is
    causal exactly as the offline pipeline with ``causal=True`` on the
    filter and on stage 1 (:meth:`causal_pipeline`):

    * the frame transform uses each scan's own odometry and mounting;
    * the filter (Eq. 1) counts neighbours within the past ``dt`` only;
    * stage 1 is :class:`~sklearn_radar.cluster.ScanStream` (the last ``eps_t``);
    * stage 2 decides a pair (A, B) at ``tau = min(end of B, s_B + eps_t2)``
      from the detections at or before tau, as soon as they have all arrived
      (at the latest ``eps_t`` after B's last detection); with ClusterMerger's
      ``min_samples`` above 1 a join of the DBSCAN over clusters is made as
      soon as it is certain (:attr:`ScanResult.joins`), which for a non-core
      cluster can be later: when the partner counts it depends on are final.

    The stage-1 labels equal the causal pipeline's detection for detection,
    and the object ids resolved through the stage-2 aliases give its merged
    clusters.  Memory is bounded: every window keeps a fixed span of time.

    **Confirmation.**  With ClusterMerger's ``min_cluster_size`` above 1 a
    detection is :attr:`ScanResult.confirmed` once its object has that many
    detections so far, and the object list holds confirmed objects only.
    The count is what is known at the scan (object ids, so stage-1
    meetings included): a stage-2 merge decided later adds the merged
    cluster's past detections only from then on.  The causal pipeline
    (``merge__causal_min_size=True``) applies the same rule to its final clusters:
    the stage-1 labels resolved through the stage-2 joins, with that rule,
    equal its labels.

    **Object ids.**  A new stage-1 cluster is a new object whose id is its
    stage-1 id; ids are never reused.  When clusters merge (stage-1 clusters
    meet, or stage 2 merges them) the older (smaller) id survives and the
    merge is reported as an alias (:attr:`ScanResult.aliases`); detections
    reported before the merge keep the id they were given.  **Occlusion**:
    an object unseen for more than ``eps_t`` ends as a stage-1 cluster; when
    it comes back it is a new stage-1 cluster with a new id, which the
    stage-2 merge makes an alias of the old one if the gap is shorter than
    ``eps_t2`` and the merge criterion accepts the pair; otherwise (or
    without stage 2) the old id is retired and never given again.

    Not a scikit-learn estimator: like :class:`~sklearn_radar.cluster.ScanStream`
    it is the state of one stream (windows, ids), fed scan by scan with raw
    columns and odometry, and nothing is fitted; the estimator is the
    offline pipeline it is built from, which keeps the parameters and
    passes the scikit-learn checks.

    Read more in the :ref:`User Guide <user-guide-online>`.

    Parameters
    ----------
    pipeline : sklearn.pipeline.Pipeline
        The offline pipeline; read once, at construction.  Stage 1's
        ``eps_t`` must be set (the window) and ``cluster_vr_min`` of both
        stages None (the gate judges whole clusters): a ValueError otherwise.
        Or a fitted pipeline ending in a :class:`~sklearn_radar.cluster.LinkClustering`
        with ``causal=True`` (the learned grouping, in place of both stages:
        :ref:`online-learned`).
    tracker : Tracker or None, default=None
        Tracks the objects from scan to scan (a fresh copy per sequence):
        :attr:`ScanResult.track_id` gives its track ids, from the object ids
        of every scan (in the sequence frame; with the learned grouping, of
        its confirmed clusters only).  None: no tracking.

    Attributes
    ----------
    experiment : int, str or None
        The saved experiment :meth:`from_params` built it from (its number,
        or ``"objects"``); None when built from a pipeline.

    See Also
    --------
    iter_scans : the scans of a detection table, in the order to feed them.

    Examples
    --------
    >>> from sklearn_radar.datasets import make_scenes
    >>> from sklearn_radar.experiments import experiment_pipeline
    >>> from sklearn_radar.online import OnlinePipeline, iter_scans
    >>> scenes = make_scenes(n_sequences=1, duration=2.0, random_state=0)
    >>> online = OnlinePipeline(experiment_pipeline(1))
    >>> online
    OnlinePipeline(pipeline=Pipeline(steps=[('frame', FrameTransform(frame='car')),
                                            ('filter', DopplerDensityFilter()),
                                            ('cluster', RadarDBSCAN())]))
    >>> for scan in iter_scans(scenes.data):
    ...     result = online.update(scan)
    >>> result.labels.shape == (len(scan),)
    True
    """

    def __init__(self, pipeline, tracker=None):
        if tracker is not None and not isinstance(tracker, Tracker):
            raise ValueError(f"OnlinePipeline: tracker must be a Tracker or None, got {type(tracker).__name__}")
        self.pipeline = pipeline
        self.tracker = tracker
        self.experiment = None
        frame, filter_, stage1, merger = _stages(pipeline)
        self._frame = frame
        self._filter_params = filter_
        self._learned = self._learned_ids = None
        if isinstance(stage1, LinkClustering):  # the learned grouping in place of both stages
            self._learned = LearnedStream(stage1)
            self._learned_ids = LearnedIds(float(stage1.pair_window))
            stage1, merger = None, None
            self._min_size = int(self._learned.model.min_cluster_size_)
        else:
            self._min_size = 1 if merger is None else int(merger.min_cluster_size)
        self._merger = merger
        self._stage1 = None if stage1 is None else ScanStream(stage1)
        self._eps_t = float(self._learned.span if stage1 is None else stage1.eps_t)
        self._sequences = {}
        self._ids = ObjectIds()

    @classmethod
    def from_params(cls, path, experiment=None, tracker=None):
        """The online form of the pipeline saved in a reproduce run's ``params.json``.

        Parameters
        ----------
        path : str or path-like
            ``params.json`` written by ``sklearn-radar reproduce``.
        experiment : int, "objects" or "learned", default=None
            Which saved experiment (``"learned"``: its causal model); None: the one ``sklearn-radar
            reproduce`` marked as the run's best.
        tracker : Tracker or None, default=None
            The tracking stage, as for :class:`OnlinePipeline`.

        Returns
        -------
        online : OnlinePipeline
            Its :attr:`experiment` is the experiment taken (the best's
            number when ``experiment`` is None).
        """
        setting = load_params(path, experiment)
        online = cls(setting_pipeline(setting, path), tracker=tracker)
        online.experiment = setting["experiment"]
        return online

    def __repr__(self):
        """``OnlinePipeline(pipeline=...)`` with the pipeline's repr, as scikit-learn shows an estimator."""
        head = f"{type(self).__name__}(pipeline="
        tail = "" if self.tracker is None else f", tracker={self.tracker!r}"
        return head + repr(self.pipeline).replace("\n", "\n" + " " * len(head)) + tail + ")"

    @property
    def learned(self):
        """bool: Whether the grouping is the learned one (a fitted causal LinkClustering)."""
        return self._learned is not None

    @property
    def min_cluster_size(self):
        """int: The confirmation count, stage 2's ``min_cluster_size`` (1 without stage 2; the learned grouping's)."""
        return self._min_size

    def causal_pipeline(self):
        """The offline pipeline whose labels this stream gives: every stage causal (stage 2: ``causal_min_size=True``).

        With the learned grouping: a copy of the fitted pipeline with the filter causal, whose ``predict``
        gives the labels (the stream's ids resolved through the aliases, where confirmed).

        Returns
        -------
        pipeline : sklearn.pipeline.Pipeline
            An unfitted clone (with the learned grouping: a fitted copy).
        """
        if self._learned is not None:  # the fitted model as it is, the filter causal
            causal = copy.deepcopy(self.pipeline)
            for name, step in causal.steps:
                if isinstance(step, DopplerDensityFilter):
                    causal.set_params(**{f"{name}__causal": True})
            return causal
        causal = clone(self.pipeline)
        for name, step in causal.steps:
            if isinstance(step, DopplerDensityFilter | RadarDBSCAN):
                causal.set_params(**{f"{name}__causal": True})
            elif isinstance(step, ClusterMerger):
                stage1 = clone(step.stage1) if step.stage1 is not None else RadarDBSCAN()
                causal.set_params(
                    **{f"{name}__stage1": stage1.set_params(causal=True), f"{name}__causal_min_size": True}
                )
        return causal

    def update(self, scan, objects=True):
        """Label one radar scan.

        Parameters
        ----------
        scan : DataFrame or mapping of str to array-like
            The detections of one scan (one ``timestamp`` of one
            ``sequence``; sensors that measured at the same time go
            together, since the causal stages count detections of the same
            time as the past of each other) with the raw columns of the
            detection table: ``range_sc`` (m), ``azimuth_sc`` (rad), ``vr``
            (m/s), ``timestamp`` (us), the mounting ``sensor_x``,
            ``sensor_y`` (m), ``sensor_yaw`` (rad) and the odometry
            ``ego_x_seq``, ``ego_y_seq`` (m), ``ego_yaw_seq`` (rad),
            ``ego_vx`` (m/s), ``ego_yaw_rate`` (rad/s); optionally
            ``sequence`` and ``sensor_id`` (default 0).  Scans must come in
            time order within a sequence (the sensors interleaved); there is
            no buffering.
        objects : bool, default=True
            Whether to compute the object list (the velocity estimate is
            most of its cost).

        Returns
        -------
        result : ScanResult

        Raises
        ------
        ValueError
            If a column is missing or not finite, the rows are not one
            scan, or the scan is not newer than the last one of its
            sequence (which includes its own sensors' last scans).
        """
        c = _read_scan(scan, ("rcs",) if self._learned is not None and self._learned.needs_rcs else ())
        n = len(c["timestamp"])
        if n == 0:
            result = _empty_result([], [], [])
            result.track_id = None if self.tracker is None else np.zeros(0, dtype=np.int64)
            return result
        sequence, us = int(c["sequence"][0]), int(c["timestamp"][0])
        state = self._sequences.get(sequence)
        if state is None:
            state = self._sequences[sequence] = _Sequence(self._filter_params, self._merger, self._eps_t, self.tracker)
        _check_order(state, sequence, sorted(set(c["sensor_id"].tolist())), us)
        work = self._frame._working_columns(c)
        x, y, v_r, t, heading = work["x"], work["y"], work["v_r"], work["t"], work["heading"]
        keep = np.ones(n, dtype=bool) if state.filter is None else state.filter.keep(x, y, t, v_r)
        if self._learned is not None:
            return learned_update(self, state, sequence, us, c, work, keep, objects)
        stage1_columns = {"x": x, "y": y, "v_r": v_r, "t": t, "sequence": np.full(n, float(sequence))}
        stage1_columns.update(keep=keep, range_sc=c["range_sc"], heading=heading)
        labels = self._stage1._label(stage1_columns, one_scan=True)
        los = c["azimuth_sc"] + c["sensor_yaw"] + heading
        self._ids.add(state.merge.add(labels, t, x, y, v_r, los, us), us)
        aliases = []
        for absorbed, survivor in self._stage1._meetings:
            state.merge.absorbed.update(absorbed.tolist())
            for a, s in sorted(set(zip(absorbed.tolist(), survivor.tolist(), strict=True))):
                aliases.append(self._ids.merge(s, a, us, "stage1"))
        window = self._stage1._windows.get(float(sequence))
        window_start = np.inf if window is None or len(window.points.t) == 0 else float(window.points.t[0])
        merges, joins = state.merge.decide(float(t[0]), window_start)
        for a, b in joins:
            aliases.append(self._ids.merge(a, b, us, "stage2"))
        object_ids = self._ids.of(labels)
        self._ids.count(object_ids)
        result = ScanResult(
            labels=labels,
            object_ids=object_ids,
            confirmed=self._ids.confirmed(object_ids, self._min_size),
            keep=keep,
            objects=self._objects(state, sequence, us, float(t[0]), labels, aliases)
            if objects
            else empty_object_list(),
            aliases=[alias for alias in aliases if alias is not None],
            merges=merges,
            joins=joins,
        )
        if state.tracker is not None:
            x_seq, y_seq, los_seq = sequence_frame(c, x, y, self._frame.frame)
            followed = followed_ids(object_ids, result.confirmed, learned=False)
            result.track_id = state.tracker.update(x_seq, y_seq, v_r, los_seq, t[0], followed)
        self._ids.forget(state.merge.gone)
        return result

    def finish(self):
        """End the stream: decide every pending stage-2 pair (as offline at the end of each sequence).

        Returns
        -------
        result : ScanResult
            Without detections; its ``aliases`` and ``merges`` are those decided now, the aliases stamped
            with the last time of their sequence.
        """
        aliases, merges, joins = [], [], []
        for state in self._sequences.values():
            decided, joined = state.merge.decide(np.inf, None)
            merges += decided
            joins += joined
            aliases += [self._ids.merge(a, b, state.last_us, "stage2") for a, b in joined]
        return _empty_result([alias for alias in aliases if alias is not None], merges, joins)

    def _objects(self, state, sequence, now_us, now, labels, aliases):
        """The scan's object list: the objects it updated (detected or merged) get new figures."""
        updated = set(self._ids.of(labels[labels >= 0]).tolist())
        updated |= {alias[1] for alias in aliases if alias is not None}
        gone = [alias[2] for alias in aliases if alias is not None]
        if updated:
            rows = state.merge.recent(now - self._eps_t)
            ids = self._ids.of(rows["label"])
            mine = np.isin(ids, np.fromiter(updated, dtype=np.int64))
            found, figures = object_figures(
                ids[mine], rows["x"][mine], rows["y"][mine], rows["v_r"][mine], rows["los"][mine], rows["us"][mine]
            )
            state.objects.update(found, figures, gone)
        else:
            state.objects.update(np.zeros(0, dtype=np.int64), {}, gone)
        oldest_us = now_us - round(self._eps_t * 1e6)
        size, min_size = self._ids.size, self._min_size
        listable = None if min_size <= 1 else (lambda object_id: size.get(object_id, 0) >= min_size)
        return state.objects.listed(sequence, now_us, oldest_us, self._ids.first_us, listable)


def _empty_result(aliases, merges, joins):
    """A ScanResult without detections."""
    none, no = np.zeros(0, dtype=np.int64), np.zeros(0, dtype=bool)
    return ScanResult(none, none, no, no, empty_object_list(), aliases, merges, joins)


def _stages(pipeline):
    """(FrameTransform, DopplerDensityFilter or None, stage-1 RadarDBSCAN, ClusterMerger or None), checked."""
    if not isinstance(pipeline, Pipeline):
        raise ValueError(f"OnlinePipeline: pipeline must be a scikit-learn Pipeline, got {type(pipeline).__name__}")
    steps = [step for _, step in pipeline.steps if step not in (None, "passthrough")]
    kinds = [FrameTransform, DopplerDensityFilter, RadarDBSCAN | ClusterMerger | LinkClustering]
    if not (
        len(steps) in (2, 3)
        and isinstance(steps[0], kinds[0])
        and isinstance(steps[-1], kinds[2])
        and (len(steps) == 2 or isinstance(steps[1], kinds[1]))
    ):
        names = [type(step).__name__ for step in steps]
        raise ValueError(
            "OnlinePipeline: pipeline must be FrameTransform, an optional DopplerDensityFilter, then RadarDBSCAN, "
            f"ClusterMerger or a fitted causal LinkClustering; got {names}"
        )
    for step in steps:
        step._validate_params()
    frame, final = steps[0], steps[-1]
    filter_ = steps[1] if len(steps) == 3 else None
    if isinstance(final, LinkClustering):
        check_learned(final)
        return frame, filter_, final, None
    merger = final if isinstance(final, ClusterMerger) else None
    stage1 = final if merger is None else (merger.stage1 if merger.stage1 is not None else RadarDBSCAN())
    if not isinstance(stage1, RadarDBSCAN):
        raise ValueError(f"OnlinePipeline: ClusterMerger's stage1 must be a RadarDBSCAN, got {type(stage1).__name__}")
    stage1._validate_params()
    if stage1.eps_t is None:
        raise ValueError("OnlinePipeline: RadarDBSCAN's eps_t must be set (None keeps every past detection)")
    if merger is not None:
        if merger.cluster_vr_min is not None:
            raise ValueError("OnlinePipeline: ClusterMerger's cluster_vr_min judges whole clusters; set it to None")
    return frame, filter_, stage1, merger


def _read_scan(scan, extra=()):
    """The scan's columns (and the ``extra`` ones) as float64 arrays (``sequence`` and ``sensor_id`` as given)."""
    required = SCAN_COLUMNS + tuple(extra)
    if not isinstance(scan, Mapping) and not hasattr(scan, "columns"):
        raise ValueError(f"OnlinePipeline.update: scan must be a DataFrame or a mapping, got {type(scan).__name__}")
    names = scan.columns if hasattr(scan, "columns") else scan.keys()
    missing = [name for name in required if name not in names]
    if missing:
        raise ValueError(f"OnlinePipeline.update: the scan lacks the column(s) {missing}")
    try:  # the columns as given: one conversion (and one finiteness test below) for all
        block = np.array([scan[name] for name in required], dtype=np.float64)
    except (ValueError, TypeError):
        block = None
    if block is None or block.ndim != 2:  # not 1-D columns of one length: flatten, and name a bad one
        columns = [np.ravel(scan[name]) for name in required]
        n = len(columns[0])
        lengths = [len(values) for values in columns]
        if min(lengths) != n or max(lengths) != n:
            name = required[next(i for i, length in enumerate(lengths) if length != n)]
            raise ValueError(f"OnlinePipeline.update: column {name!r} has another length than 'range_sc' ({n})")
        block = np.array(columns, dtype=np.float64)
    n = block.shape[1]
    with np.errstate(over="ignore", invalid="ignore"):
        total = float(block.sum())  # finite unless a value is not (or the sum of large ones overflows)
    if not np.isfinite(total):
        finite = np.isfinite(block).all(axis=1)
        if not finite.all():
            bad = required[int(np.flatnonzero(~finite)[0])]
            raise ValueError(f"OnlinePipeline.update: column {bad!r} holds values that are not finite")
    c = dict(zip(required, block, strict=True))
    for name in ("sequence", "sensor_id"):
        values = np.ravel(scan[name]) if name in names else np.zeros(n, dtype=np.int64)
        if len(values) != n:
            raise ValueError(f"OnlinePipeline.update: column {name!r} has another length than 'range_sc' ({n})")
        c[name] = values
    for name in ("timestamp", "sequence"):
        if n and (c[name] != c[name][0]).any():
            raise ValueError(f"OnlinePipeline.update: the rows are not one scan (column {name!r} differs)")
    return c


def _check_order(state, sequence, sensors, us):
    """ValueError for a scan not newer than its sequence's last one (its sensors' last ones included)."""
    if state.last_us is not None and us <= state.last_us:
        late = [sensor for sensor in sensors if state.sensor_us.get(sensor, -np.inf) >= us]
        which = (
            f"its sensor {late[0]}'s last scan at {state.sensor_us[late[0]]} us"
            if late
            else f"the last scan of sequence {sequence} at {state.last_us} us"
        )
        if us == state.last_us:
            raise ValueError(
                f"OnlinePipeline.update: the scan at {us} us has the time of {which}; pass the detections of one "
                "time of a sequence (all its sensors) in one update, as the causal stages count them together"
            )
        raise ValueError(
            f"OnlinePipeline.update: the scan at {us} us is older than {which}; pass the scans of a sequence in "
            "time order (the stages are causal: a late scan cannot be labelled after later ones)"
        )
    state.last_us = us
    for sensor in sensors:
        state.sensor_us[sensor] = us
