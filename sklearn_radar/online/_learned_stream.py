"""The learned grouping (a fitted causal LinkClustering) scan by scan, for OnlinePipeline.

Per sequence, a window of the recent kept detections (the longer of the
neighbourhood window and the pair window) holds what the new scan's
features and pairs need: its detections are sorted as the estimator sorts
a sequence (time first), their causal features computed against the
window (:func:`~sklearn_radar.cluster._causal_link_features.causal_detection_features`),
their objectness, their candidate pairs to the window and within the scan,
the pairs' link probabilities (with ``cluster_window``, from the context of
the clusters so far too: :func:`~sklearn_radar.cluster._cluster_context.context_features`),
and one step of the causal agglomeration
(:func:`~sklearn_radar.cluster._causal_agglomeration.step`).  The code is
the estimator's, on the same numbers, so the clusters are those of the
offline ``predict``.
"""

from __future__ import annotations

import numpy as np
from sklearn.utils.validation import check_is_fitted

from ..cluster._causal_agglomeration import new_state, step
from ..cluster._causal_link_features import causal_detection_features, causal_pair_features, causal_pairs
from ..cluster._cluster_context import context_features
from ..cluster._link_clustering import _SORT_KEY
from ..cluster._link_features import (
    DETECTION_FEATURES,
    LOCAL_WINDOW,
    Detections,
    LocalMotion,
)
from ..cluster._link_training import positive_proba
from ..cluster._tree_walk import boosting_proba, compile_boosting
from ._objects import empty_object_list, object_figures

#: The buffered float columns of each kept detection (rows of one array): the measurements, then what the pairs
#: reuse; and the integer ones (node: 1 when above the objectness threshold).
_FLOATS = (*Detections._fields, "vx", "vy", "count", "spread", "objectness")
_INTS = ("node", "number", "cluster", "us")
_F = {name: k for k, name in enumerate(_FLOATS)}
_I = {name: k for k, name in enumerate(_INTS)}
#: The measurements that a model fitted without their columns does not see (NaN, as offline).
_OPTIONAL = {"rcs": "rcs", "range": "range_sc", "sensor": "sensor_id", "ego": "ego_vx"}


def check_learned(model):
    """ValueError unless ``model`` is a fitted LinkClustering with ``causal=True``."""
    if not model.causal:
        raise ValueError(
            "OnlinePipeline: LinkClustering must have causal=True to run scan by scan (causal=False decides from "
            "the future too); fit it with causal=True"
        )
    try:
        check_is_fitted(model, "link_classifier_")
    except Exception as error:
        raise ValueError(
            "OnlinePipeline: the causal LinkClustering is not fitted; fit it (on labelled sequences) first"
        ) from error


class _Window:
    """One sequence's recent kept detections (a row per column, time order) and its agglomeration state."""

    def __init__(self):
        self.floats = np.zeros((len(_FLOATS), 0))
        self.ints = np.zeros((len(_INTS), 0), dtype=np.int64)
        self.state = new_state()
        self.n_kept = 0  # kept detections so far: the next one's number


class LearnedStream:
    """The causal LinkClustering of every sequence of a stream: per scan, the cluster of each detection.

    Parameters
    ----------
    model : LinkClustering
        Fitted, ``causal=True``.
    """

    def __init__(self, model):
        check_learned(model)
        self.model = model
        self._detection_columns = np.flatnonzero(np.isin(list(DETECTION_FEATURES), model.detection_feature_names_))
        self._pair_columns = model._pair_columns()
        self._context_columns = model._context_columns()
        self._objectness = _fast(model.objectness_classifier_)
        self._links = _fast(model.link_classifier_)
        names = getattr(model, "feature_names_in_", None)
        self._absent = (
            set()
            if names is None
            else {field for field, column in _OPTIONAL.items() if column not in set(names.tolist())}
        )
        if names is not None and not {"azimuth_sc", "sensor_yaw"} <= set(names.tolist()):
            self._absent.add("los")
        self.span = max(LOCAL_WINDOW, float(model.pair_window), float(model.cluster_window or 0.0))
        self._windows = {}

    @property
    def needs_rcs(self):
        """bool: Whether the model reads ``rcs`` (the scans must then hold it)."""
        return "rcs" not in self._absent

    def update(self, sequence, columns, keep):
        """Cluster one scan of one sequence.

        Parameters
        ----------
        sequence : int
            Its sequence.
        columns : dict
            The scan's working and raw columns: ``x``, ``y`` (m), ``t`` (s, one value), ``v_r`` (m/s), ``los``
            (rad), ``rcs`` (dBsm), ``range_sc`` (m), ``sensor_id``, ``ego_vx`` (m/s), and ``us`` (its time, us).
        keep : ndarray of bool
            The filter's verdict.

        Returns
        -------
        clusters : ndarray of int64
            Cluster of each row (its oldest detection's number in the sequence), -1 for the detections that
            are not nodes (dropped, or at or below the objectness threshold).
        sizes : ndarray of int64
            Detections of that cluster so far (0 for the others).
        merges : list of (int, int)
            (survivor, merged) of the merges of clusters that existed before this scan, in order.
        """
        model = self.model
        window = self._windows.get(sequence)
        if window is None:
            window = self._windows[sequence] = _Window()
        n = len(keep)
        clusters = np.full(n, -1, dtype=np.int64)
        sizes = np.zeros(n, dtype=np.int64)
        rows = np.flatnonzero(keep)
        now = float(columns["t"][0])
        recent = now - window.floats[_F["t"]] <= self.span
        if not recent.all():
            first = int(np.argmax(recent)) if recent.any() else len(recent)  # the window is in time order
            window.floats, window.ints = window.floats[:, first:], window.ints[:, first:]
        if len(rows) == 0:
            return clusters, sizes, []
        new = np.full((len(_FLOATS), len(rows)), np.nan)
        for name, column in (("x", "x"), ("y", "y"), ("t", "t"), ("v", "v_r"), ("los", "los"), *_OPTIONAL.items()):
            if name not in self._absent:
                new[_F[name]] = columns[column][rows]
        order = np.lexsort(new[[_F[name] for name in reversed(_SORT_KEY)]])
        rows, new = rows[order], new[:, order]
        start = window.floats.shape[1]
        floats = np.concatenate([window.floats, new], axis=1)
        detections = Detections(*floats[: len(Detections._fields)])
        features, local = causal_detection_features(detections, start)
        X = features[:, self._detection_columns]
        objectness = self._proba(self._objectness, model.objectness_classifier_, X)
        floats[_F["vx"], start:], floats[_F["vy"], start:] = local.vx, local.vy
        floats[_F["count"], start:], floats[_F["spread"], start:] = local.count, local.spread
        floats[_F["objectness"], start:] = objectness
        node = objectness > model.objectness_threshold_
        numbers = window.n_kept + np.arange(len(rows))
        window.n_kept += len(rows)
        ints = np.empty((len(_INTS), len(rows)), dtype=np.int64)
        ints[_I["node"]], ints[_I["number"]] = node, numbers
        ints[_I["cluster"]], ints[_I["us"]] = np.where(node, numbers, -1), int(columns["us"])
        window.floats, window.ints = floats, np.concatenate([window.ints, ints], axis=1)
        if not node.any():
            return clusters, sizes, []
        flags = window.ints[_I["node"]].astype(bool)
        i, j = causal_pairs(
            detections.x,
            detections.y,
            detections.t,
            flags,
            start,
            model.pair_radius,
            model.pair_window,
            model.max_links_per_detection,
        )
        links = np.zeros(0)
        if len(i):
            motion = LocalMotion(*(floats[_F[name]] for name in LocalMotion._fields))
            X = causal_pair_features(detections, motion, floats[_F["objectness"]], i, j)[:, self._pair_columns]
            if model.cluster_window is not None:
                X = np.hstack([X, self._context(detections, flags, window.ints[_I["cluster"]], start, i, j, now)])
            links = self._proba(self._links, model.link_classifier_, X)
        number = window.ints[_I["number"]]
        at = start + np.flatnonzero(node)  # the new nodes' columns of the window
        new_clusters, new_sizes, child, survivor = step(
            window.state,
            now,
            numbers[node],
            number[i],
            number[j],
            links,
            model.pair_window,
            model.link_threshold_,
            detections.x[at],
            detections.y[at],
            model.max_extent,
        )
        merges = []
        cluster = window.ints[_I["cluster"]]
        if len(child):
            first_new = int(numbers[0])
            merges = [(s, c) for c, s in zip(child.tolist(), survivor.tolist(), strict=True) if c < first_new]
            old = cluster[:start]
            for c, s in zip(child.tolist(), survivor.tolist(), strict=True):  # in order: chains of merges
                if c < first_new:
                    old[old == c] = s
        cluster[start:][node] = new_clusters
        clusters[rows[node]] = new_clusters
        sizes[rows[node]] = new_sizes
        return clusters, sizes, merges

    def _context(self, d, node, cluster, start, i, j, now):
        """The context features of the pairs (i, j) (window columns) from the clusters before this scan."""
        window = self.model.cluster_window
        found = context_features(d.x, d.y, d.t, d.v, d.los, cluster, node, 0, start, window, i, j, now)
        return found[:, self._context_columns]

    def recent(self, sequence):
        """The buffered nodes of a sequence: ``cluster`` now, ``x``, ``y`` (m), ``v_r`` (m/s), ``los`` (rad), ``us``."""
        window = self._windows[sequence]
        node = window.ints[_I["node"]].astype(bool)
        found = {
            name: window.floats[_F[key]][node] for name, key in (("x", "x"), ("y", "y"), ("v_r", "v"), ("los", "los"))
        }
        return {"cluster": window.ints[_I["cluster"]][node], "us": window.ints[_I["us"]][node], **found}

    def retained_rows(self):
        """Detections held by the windows of every sequence."""
        return sum(window.floats.shape[1] for window in self._windows.values())

    @staticmethod
    def _proba(compiled, model, X):
        if compiled is not None:
            return boosting_proba(compiled, X)
        return positive_proba(model, X)


def _fast(classifier):
    """The compiled walk of a classifier (None: use predict_proba); a constant probability as it is."""
    if isinstance(classifier, float):
        return classifier
    return compile_boosting(classifier)


class LearnedIds:
    """Object ids of the learned clusters of every sequence: unique across sequences, the older kept at a merge.

    A cluster gets the next id when it is first reported; within a sequence clusters are numbered in arrival order
    and reported in that order, so the smaller of two ids is the older cluster.  A cluster that can gain no more
    detections (its last one older than the pair window) is forgotten.
    """

    def __init__(self, window):
        self.window = window
        self.next_id = 0
        self.of_sequence = {}  # sequence -> {cluster number: [object id, time of its last detection, s]}
        self.first_us = {}  # object id -> time of its first detection, us
        self.size = {}  # object id -> its detections so far
        self.dropped = {}  # sequence -> object ids forgotten whose first time its object list may still need

    def update(self, sequence, now, us, clusters, sizes, merges):
        """Object ids of a scan's clusters (-1 stays -1), and the aliases of its merges."""
        known = self.of_sequence.setdefault(sequence, {})
        for number in [n for n, (_, last) in known.items() if not now - last <= self.window]:
            object_id = known.pop(number)[0]
            self.dropped.setdefault(sequence, []).append(object_id)
            self.size.pop(object_id, None)
        aliases = []
        for survivor, merged in merges:
            kept, lost = known[survivor], known.pop(merged)
            kept[1] = max(kept[1], lost[1])
            self.first_us[kept[0]] = min(self.first_us[kept[0]], self.first_us.pop(lost[0]))
            self.size[kept[0]] = self.size.get(kept[0], 0) + self.size.pop(lost[0], 0)
            aliases.append((us, kept[0], lost[0], "learned"))
        object_ids = np.full(len(clusters), -1, dtype=np.int64)
        found = clusters >= 0
        numbers = clusters[found].tolist()
        size_of = dict(zip(numbers, sizes[found].tolist(), strict=True))  # (the rows of one cluster: its one size)
        for number in sorted(size_of):  # (a scan's few clusters: plain Python is quicker than np.unique)
            if number not in known:
                known[number] = [self.next_id, now]
                self.first_us[self.next_id] = us
                self.next_id += 1
            known[number][1] = now
            self.size[known[number][0]] = size_of[number]
        object_ids[found] = [known[number][0] for number in numbers]
        return object_ids, aliases

    def of(self, sequence, clusters):
        """Object id of each cluster number of a sequence."""
        known = self.of_sequence[sequence]
        return np.array([known[n][0] for n in clusters.tolist()], dtype=np.int64)


def learned_update(online, state, sequence, us, c, work, keep, objects):
    """The ScanResult of one scan by the learned grouping (OnlinePipeline.update's work after the filter).

    ``online`` is the OnlinePipeline (its ``_learned``, ``_learned_ids``, ``_min_size``), ``state`` the sequence's
    windows, ``c`` the raw columns and ``work`` the working ones.
    """
    from ._pipeline import ScanResult
    from ._tracker import followed_ids, sequence_frame

    stream, ids = online._learned, online._learned_ids
    t = work["t"]
    columns = {
        "x": work["x"],
        "y": work["y"],
        "t": t,
        "v_r": work["v_r"],
        "los": c["azimuth_sc"] + c["sensor_yaw"] + work["heading"],
        "rcs": c.get("rcs"),
        "range_sc": c["range_sc"],
        "sensor_id": np.asarray(c["sensor_id"], dtype=np.float64),
        "ego_vx": c["ego_vx"],
        "us": us,
    }
    clusters, sizes, merges = stream.update(sequence, columns, keep)
    object_ids, aliases = ids.update(sequence, float(t[0]), us, clusters, sizes, merges)
    pairs = [(kept, lost) for _, kept, lost, _ in aliases]
    result = ScanResult(
        labels=object_ids,
        object_ids=object_ids.copy(),
        confirmed=(object_ids >= 0) & (sizes >= online._min_size),
        keep=keep,
        objects=_objects(online, state, sequence, us, object_ids, aliases) if objects else empty_object_list(),
        aliases=aliases,
        merges=pairs,
        joins=list(pairs),
    )
    if state.tracker is not None:
        x_seq, y_seq, los_seq = sequence_frame(c, work["x"], work["y"], online._frame.frame)
        followed = followed_ids(object_ids, result.confirmed, learned=True)
        result.track_id = state.tracker.update(x_seq, y_seq, work["v_r"], los_seq, t[0], followed)
    if ids.dropped.get(sequence):  # forget the first times that the object list no longer needs
        listed = state.objects.records
        for object_id in ids.dropped[sequence]:
            if object_id not in listed:
                ids.first_us.pop(object_id, None)
        ids.dropped[sequence] = [object_id for object_id in ids.dropped[sequence] if object_id in listed]
    return result


def _objects(online, state, sequence, now_us, object_ids, aliases):
    """The scan's object list: the objects it updated get new figures from their recent detections."""
    stream, ids = online._learned, online._learned_ids
    updated = set(object_ids[object_ids >= 0].tolist()) | {alias[1] for alias in aliases}
    gone = [alias[2] for alias in aliases]
    found, figures = np.zeros(0, dtype=np.int64), {}
    if updated:
        rows = stream.recent(sequence)
        known = ids.of_sequence[sequence]
        numbers = rows["cluster"]
        alive = np.array([n in known for n in numbers.tolist()], dtype=bool)
        mine = np.zeros(len(numbers), dtype=bool)
        mine[alive] = np.isin(ids.of(sequence, numbers[alive]), np.fromiter(updated, dtype=np.int64))
        if mine.any():
            found, figures = object_figures(
                ids.of(sequence, numbers[mine]),
                rows["x"][mine],
                rows["y"][mine],
                rows["v_r"][mine],
                rows["los"][mine],
                rows["us"][mine],
            )
    state.objects.update(found, figures, gone)
    oldest_us = now_us - round(stream.span * 1e6)
    size, min_size = ids.size, online._min_size
    listable = None if min_size <= 1 else (lambda object_id: size.get(object_id, 0) >= min_size)
    return state.objects.listed(sequence, now_us, oldest_us, ids.first_us, listable)
