"""Persistent object ids over stage-1 clusters, and the per-scan object list handed to a tracker."""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
import pandas as pd

from ..cluster._velocity import _estimate_velocities

#: The stages whose merges make aliases: stage-1 clusters that met, a stage-2 merge, or a merge of the learned
#: grouping's clusters.
ALIAS_REASONS = ("stage1", "stage2", "learned")


class ObjectIds:
    """Object id of every retained stage-1 cluster; merges keep the older (smaller) id.

    An object's id is the stage-1 id of its oldest cluster.  Stage-1 ids are
    allocated in arrival order and never reused, so neither are object ids,
    and the smaller of two ids is the older object.  Only the clusters still
    retained by some window are remembered, so memory stays bounded.
    """

    def __init__(self):
        self.root = {}  # stage-1 id -> object id
        self.first_us = {}  # object id -> time of its first detection, us
        self.size = {}  # object id -> its detections so far (as merged so far)

    def add(self, labels, timestamp_us):
        """Register the stage-1 ids seen for the first time."""
        for label in labels:
            if label not in self.root:
                self.root[label] = label
                self.first_us[label] = timestamp_us

    def merge(self, a, b, timestamp_us, reason):
        """Join the objects of stage-1 ids a and b; returns the alias record or None if already one."""
        keep, lost = sorted((self.root[a], self.root[b]))
        if keep == lost:
            return None
        for label, root in self.root.items():
            if root == lost:
                self.root[label] = keep
        self.first_us[keep] = min(self.first_us[keep], self.first_us.pop(lost))
        self.size[keep] = self.size.get(keep, 0) + self.size.pop(lost, 0)
        return (timestamp_us, keep, lost, reason)

    def count(self, object_ids):
        """Add the detections of a scan (their object ids, -1 for noise) to their objects' sizes."""
        found, counts = np.unique(object_ids[object_ids >= 0], return_counts=True)
        for object_id, n in zip(found.tolist(), counts.tolist(), strict=True):
            self.size[object_id] = self.size.get(object_id, 0) + n

    def confirmed(self, object_ids, min_size):
        """Whether each object id (-1: noise) has at least ``min_size`` detections so far."""
        size = self.size
        return np.array([i >= 0 and size.get(i, 0) >= min_size for i in object_ids.tolist()], dtype=bool)

    def of(self, labels):
        """Object id of each stage-1 label (-1 for noise)."""
        root = self.root
        return np.array([root[label] if label >= 0 else -1 for label in labels.tolist()], dtype=np.int64)

    def forget(self, labels):
        """Drop stage-1 ids no window retains (an object's first time goes with its last cluster)."""
        if not labels:
            return
        for label in labels:
            self.root.pop(label, None)
        alive = set(self.root.values())
        for object_id in [o for o in self.first_us if o not in alive]:
            del self.first_us[object_id]
            self.size.pop(object_id, None)


@dataclass
class ObjectList:
    """The live objects of one sequence after a scan: plain arrays, one entry per object.

    An object is live when it was updated (given detections, or merged)
    within the last ``eps_t`` seconds, stage 1's window; its figures are
    computed at its last update from its detections of the ``eps_t``
    seconds before it, and carried unchanged until the next one (so a scan
    costs the estimates of the objects it sees, not of all).

    Read more in the :ref:`User Guide <user-guide-online>`.

    Parameters
    ----------
    object_id : ndarray of int64
        Persistent id (see :class:`OnlinePipeline`).
    sequence : ndarray of int64
        The sequence (recording) of the object.
    x, y : ndarray of float64
        Centroid, m, in the working frame (the sequence frame with ``frame="frame"``).
    vx, vy : ndarray of float64
        Eq. 6 velocity estimate (Doppler and lines of sight, :func:`~sklearn_radar.cluster.estimate_velocity`),
        m/s; NaN when unknown.
    velocity_known : ndarray of bool
        False when the geometry gives no estimate (too few detections, too little spread of the lines of sight).
    extent_x, extent_y : ndarray of float64
        Sides of the detections' bounding box, m.
    n_detections : ndarray of int64
        Detections in the window.
    age : ndarray of float64
        s since the object's first detection.
    last_update : ndarray of int64
        Time of its latest detection, us (as the data's ``timestamp``).
    """

    object_id: np.ndarray
    sequence: np.ndarray
    x: np.ndarray
    y: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    velocity_known: np.ndarray
    extent_x: np.ndarray
    extent_y: np.ndarray
    n_detections: np.ndarray
    age: np.ndarray
    last_update: np.ndarray

    def __len__(self):
        return len(self.object_id)

    def to_frame(self):
        """The list as a DataFrame.

        Returns
        -------
        table : DataFrame
            One row per object, a column per field, in the order above.
        """
        return pd.DataFrame({field.name: getattr(self, field.name) for field in fields(self)})


def empty_object_list():
    """An ObjectList without objects."""
    floats, ints = np.zeros(0), np.zeros(0, dtype=np.int64)
    return ObjectList(
        ints, ints, floats, floats, floats, floats, np.zeros(0, dtype=bool), floats, floats, ints, floats, ints
    )


#: The figures of an object kept between scans, in the order of :func:`object_figures`' columns.
FIGURES = ("x", "y", "vx", "vy", "velocity_known", "extent_x", "extent_y", "n_detections", "last_update")


def object_figures(object_ids, x, y, v_r, los, timestamp_us):
    """Per object of the given rows: its id and the figures of :data:`FIGURES`, as arrays."""
    ids, group, count = np.unique(object_ids, return_inverse=True, return_counts=True)
    group = group.ravel()

    def per_object(reduce, values, start):
        out = np.full(len(ids), start)
        reduce.at(out, group, values)
        return out

    vx, vy, _, _ = _estimate_velocities(v_r, los, group)
    figures = {
        "x": np.bincount(group, x) / count,
        "y": np.bincount(group, y) / count,
        "vx": vx,
        "vy": vy,
        "velocity_known": np.isfinite(vx) & np.isfinite(vy),
        "extent_x": per_object(np.maximum, x, -np.inf) - per_object(np.minimum, x, np.inf),
        "extent_y": per_object(np.maximum, y, -np.inf) - per_object(np.minimum, y, np.inf),
        "n_detections": count.astype(np.int64),
        "last_update": per_object(np.maximum, timestamp_us, np.iinfo(np.int64).min),
    }
    return ids, figures


class ObjectTable:
    """The object list of one sequence, kept up to date: an object's figures change only when it is updated.

    An object is updated at a scan that gives it detections (or merges it);
    its figures are then computed from its detections of the ``eps_t``
    seconds before.  It is listed while its last update is at most ``eps_t``
    old, as stage 1 forgets it after that.
    """

    def __init__(self):
        self.records = {}  # object id -> tuple of FIGURES values

    def update(self, ids, figures, gone):
        """Store the figures of the updated objects; drop the merged-away ids in ``gone``."""
        for object_id in gone:
            self.records.pop(object_id, None)
        if len(ids) == 0:
            return
        columns = [figures[name].tolist() for name in FIGURES]
        for k, object_id in enumerate(ids.tolist()):
            self.records[object_id] = tuple(column[k] for column in columns)

    def listed(self, sequence, now_us, oldest_us, first_us, listable=None):
        """The ObjectList of the objects updated at or after ``oldest_us`` (us); forgets the older ones.

        ``listable``: a function of an object id that says whether to list it (None: every object).
        """
        for object_id in [o for o, record in self.records.items() if record[-1] < oldest_us]:
            del self.records[object_id]
        shown = [o for o in self.records if listable is None or listable(o)]
        if not shown:
            return empty_object_list()
        ids = np.array(shown, dtype=np.int64)
        values = list(zip(*(self.records[o] for o in shown), strict=True))
        figures = {name: np.array(column) for name, column in zip(FIGURES, values, strict=True)}
        first = np.array([first_us[i] for i in ids.tolist()], dtype=np.int64)
        return ObjectList(
            object_id=ids,
            sequence=np.full(len(ids), sequence, dtype=np.int64),
            **{name: figures[name] for name in FIGURES if name not in ("n_detections", "last_update")},
            n_detections=figures["n_detections"].astype(np.int64),
            age=(now_us - first) * 1e-6,
            last_update=figures["last_update"].astype(np.int64),
        )
