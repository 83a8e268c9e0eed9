"""Stage 2 on a live stream: ClusterMerger's causal decisions, each taken as soon as its data are complete.

Offline, the pair (A, B) is decided at ``tau = min(end of B, s_B + eps_t2)``
from the detections at or before tau (see :class:`ClusterMerger`).  On a
stream tau is known once B has a detection after ``s_B + eps_t2`` (then
``tau = s_B + eps_t2``) or once B can grow no more (its stage-1 id left the
stage-1 window, or the clusters met and B's rows went to the older id);
then every detection at or before tau has arrived, and the pair is decided
with the offline kernels on the retained data of A and B, which gives the
offline decision exactly.

What is retained, and in which order, is what the offline kernels read:

* ``mode="continuation"`` reads per cluster its per-scan centres (the mean
  of the cluster's detections of a scan, summed in the offline order
  (x, y, v_r) as :func:`cluster_runs` sums them) up to tau: each scan's
  centres are computed once, when it arrives, and the last five scans of A
  before tau (four smoothed centres and the neighbour of the first) must
  be kept: A's last scan is at most ``eps_t2`` before s_B and consecutive
  scans of a stage-1 cluster are at most ``eps_t`` apart, so the centres of
  the last ``eps_t2 + 4 eps_t`` before the oldest pending B are kept.
* ``mode="velocity"`` reads A's detections in ``[s_B - eps_t2, tau]`` and
  B's up to tau, in the offline order (time, then x, y, v_r, line of
  sight): each scan's rows are stored sorted so, and the last
  ``max(eps_t2, eps_t)`` are kept (``eps_t`` for the object list).

With ``min_samples > 1`` the second DBSCAN over clusters
(:func:`~sklearn_radar.cluster._merge_kernels.merge_components`) decides
which accepted pairs join: core clusters (at least ``min_samples - 1``
accepted partners) that are partners join at once, and a non-core cluster
joins its first core partner in the offline order of the pairs.  A cluster's
partner count is final once no pair with it can still be decided; a join
is made as soon as it is certain (:class:`MergeComponents`), which may be
later than the pair's decision.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..cluster._merge_kernels import ClusterRuns, continuation_edges

_MARGIN_S = 0.05  # s kept beyond the horizon: rounding of the time windows never reaches it

_ROWS = ("t", "x", "y", "v_r", "los", "label", "us")
_TRACKS = ("label", "t", "x", "y")


@dataclass
class _Cluster:
    key: tuple  # first detection (t s, x m, y m, v_r m/s[, line of sight rad]): A precedes B when smaller
    start: float  # s, first detection time s_A
    latest: float  # s, latest detection time so far
    decided: bool = False


class MergeWindow:
    """Stage 2 for one sequence: the retained data of the clusters and their pending decisions.

    Parameters
    ----------
    merger : ClusterMerger or None
        Its parameters define the criterion (``mode``, ``eps_d``, ``eps_phi``, ``eps_v``, ``eps_t2``,
        ``unknown_velocity``) and the second DBSCAN (``min_samples``).  None: no stage 2, the window only
        keeps the last ``eps_t`` for the object list.
    eps_t : float
        Stage 1's time threshold, s.
    """

    def __init__(self, merger, eps_t):
        self.merger = merger
        self.velocity = merger is not None and merger.mode == "velocity"
        self.continuation = merger is not None and not self.velocity
        self.eps_t2 = 0.0 if merger is None else float(merger.eps_t2)
        eps_t = float(eps_t)
        self.rows_back = (max(self.eps_t2, eps_t) if self.velocity else eps_t) + _MARGIN_S
        self.tracks_back = self.eps_t2 + 4.0 * eps_t + _MARGIN_S
        self.components = None if merger is None else MergeComponents(int(merger.min_samples), self.eps_t2)
        self.clusters = {}
        self.pending = set()  # labels of the clusters not yet decided as B
        self.absorbed = set()  # labels whose rows stage 1 gave to an older cluster (they grow no more)
        self.rows = TimeColumns(_ROWS)
        self.tracks = TimeColumns(_TRACKS)  # continuation: one entry per (cluster, scan), its centre
        self.gone = []  # the clusters forgotten by the last decide()
        self._swept = -np.inf  # s, the threshold of the last sweep of the clusters

    def add(self, labels, t, x, y, v_r, los, timestamp_us):
        """Append a scan's clustered rows (``labels >= 0``), register the clusters it starts; returns its labels."""
        clustered = np.flatnonzero(labels >= 0)
        if len(clustered) == 0:
            return []
        if self.merger is None:
            return self._keep_for_objects(labels[clustered], t[0], x, y, v_r, los, clustered, timestamp_us)
        label = labels[clustered]
        keys = [x[clustered], y[clustered], v_r[clustered], *((los[clustered],) if self.velocity else ())]
        order = np.lexsort((*keys[::-1], label))  # by label, then the offline keys (one time: the scan's)
        label = label[order]
        new = {"label": label, "t": t[clustered], "x": keys[0][order], "y": keys[1][order], "v_r": keys[2][order]}
        new["los"] = keys[3][order] if self.velocity else los[clustered][order]
        new["us"] = np.full(len(label), timestamp_us, dtype=np.int64)
        self.rows.append(new)
        starts = np.empty(len(label), dtype=bool)  # where a cluster's rows start in the sorted scan
        starts[0] = True
        np.not_equal(label[1:], label[:-1], out=starts[1:])
        first = np.flatnonzero(starts)
        if self.continuation:
            run = np.cumsum(starts) - 1
            count = np.bincount(run)
            centre = {"x": np.bincount(run, new["x"]) / count, "y": np.bincount(run, new["y"]) / count}
            scan = {"label": label[first], "t": new["t"][first], **centre}
            self.tracks.append(scan)
        now = float(new["t"][0])
        names = ("t", "x", "y", "v_r", *(("los",) if self.velocity else ()))
        scan_labels = label[first].tolist()
        for cluster_label, row in zip(scan_labels, first.tolist(), strict=True):
            cluster = self.clusters.get(cluster_label)
            if cluster is not None:
                cluster.latest = now
                continue
            key = tuple(float(new[name][row]) for name in names)
            self.clusters[cluster_label] = _Cluster(key=key, start=now, latest=now, decided=self.merger is None)
            if self.merger is not None:
                self.pending.add(cluster_label)
        return scan_labels

    def _keep_for_objects(self, label, now, x, y, v_r, los, clustered, timestamp_us):
        """Without stage 2: the rows only serve the object list, in any order; returns the scan's labels."""
        new = {"label": label, "t": np.full(len(label), now), "x": x[clustered], "y": y[clustered]}
        new["v_r"], new["los"] = v_r[clustered], los[clustered]
        new["us"] = np.full(len(label), timestamp_us, dtype=np.int64)
        self.rows.append(new)
        scan_labels = set(label.tolist())
        now = float(now)
        for cluster_label in scan_labels:
            cluster = self.clusters.get(cluster_label)
            if cluster is None:
                self.clusters[cluster_label] = _Cluster(key=(now,), start=now, latest=now, decided=True)
            else:
                cluster.latest = now
        return sorted(scan_labels)

    def growing(self, label, window_start):
        """Whether stage-1 cluster ``label`` can still receive detections.

        It can while it has a detection in stage 1's window (which starts at
        ``window_start``, s; None: the stream ended): its latest detection
        is there (the rows other clusters gave it when they met are older
        than the detection that met them, which it got) and it did not give
        its rows to an older cluster.
        """
        return window_start is not None and label not in self.absorbed and self.clusters[label].latest >= window_start

    def decide(self, now, window_start):
        """Decide the pending clusters whose data are complete.

        Parameters
        ----------
        now : float
            s, the time of the scan just added.
        window_start : float or None
            s, the time of the oldest detection in stage 1's window (inf: none); None: the stream ended.

        Returns
        -------
        accepted : list of (int, int)
            The pairs (A, B) the criterion accepts, as stage-1 labels (the offline ``merges_``).
        joins : list of (int, int)
            The pairs of clusters that became one object now (all accepted pairs when ``min_samples``
            is 1; see :class:`MergeComponents` otherwise).
        """
        if self.merger is None:
            self._prune(now)
            return [], []
        due = [
            label
            for label in self.pending
            if not self.growing(label, window_start)
            or self.clusters[label].latest > self.clusters[label].start + self.eps_t2
        ]
        pairs = []
        for b in sorted(due):
            cluster_b = self.clusters[b]
            cluster_b.decided = True
            self.pending.discard(b)
            threshold = cluster_b.start - self.eps_t2
            pairs += [
                (a, b)
                for a, cluster_a in self.clusters.items()
                if a != b and cluster_a.key < cluster_b.key and cluster_a.latest > threshold
            ]
        accepted = self._accepted(pairs) if pairs else []
        joins = self.components.update(accepted, self, now, window_start)
        self._prune(now)
        return accepted, joins

    def _accepted(self, pairs):
        """The pairs the offline criterion accepts, computed by its kernels on the retained data."""
        involved = np.unique(np.array(pairs, dtype=np.int64).ravel())
        m = self.merger
        if self.continuation:
            runs = _runs(self.tracks["label"], involved, self.tracks, scans=True)
        else:
            runs = _runs(self.rows["label"], involved, self.rows, scans=False)
        pair_a = np.searchsorted(runs.ids, np.array([a for a, _ in pairs], dtype=np.int64))
        pair_b = np.searchsorted(runs.ids, np.array([b for _, b in pairs], dtype=np.int64))
        if self.velocity:
            merge = m._velocity_merges(runs, pair_a, pair_b, self.rows["v_r"], self.rows["los"])
        else:
            merge = continuation_edges(
                runs, pair_a, pair_b, m.eps_d, m.eps_v, self.eps_t2, m.unknown_velocity == "accept"
            )
        return [pair for pair, accepted in zip(pairs, merge.tolist(), strict=True) if accepted]

    def _prune(self, now):
        """Forget the data and clusters no pending or future decision (or the object list) reads."""
        oldest = min([now, *(self.clusters[label].start for label in self.pending)])
        self.rows.drop_before(oldest - self.rows_back)
        if self.continuation:
            self.tracks.drop_before(oldest - self.tracks_back)
        threshold = oldest - max(self.rows_back, self.tracks_back if self.continuation else 0.0)
        self.gone = []
        if threshold < self._swept + _MARGIN_S:  # the clusters are swept every 0.05 s: a loop over all of them
            return
        self._swept = threshold
        held = set() if self.components is None else self.components.members
        gone = [label for label, c in self.clusters.items() if c.decided and c.latest < threshold and label not in held]
        for label in gone:
            del self.clusters[label]
            self.absorbed.discard(label)
        self.gone = gone

    def is_final(self, label, now, window_start):
        """Whether no pair with cluster ``label`` can still be decided (its partner count is final)."""
        cluster = self.clusters.get(label)
        if cluster is None:
            return True  # forgotten: long past every decision
        if not cluster.decided or self.growing(label, window_start):
            return False
        if window_start is not None and cluster.latest > now - self.eps_t2:
            return False  # a cluster starting after now could still pair with it
        return not any(
            self.clusters[b].key > cluster.key and cluster.latest > self.clusters[b].start - self.eps_t2
            for b in self.pending
        )

    def recent(self, since):
        """The retained rows at or after ``since`` (s)."""
        first = int(np.searchsorted(self.rows["t"], since, side="left"))
        return {name: self.rows[name][first:] for name in _ROWS}


class MergeComponents:
    """The second DBSCAN of stage 2 (over clusters, ``min_samples``) on a stream: joins as soon as certain.

    Offline (:func:`~sklearn_radar.cluster._merge_kernels.merge_components`)
    a cluster is core when it has at least ``min_samples - 1`` accepted
    partners over the whole sequence; core partners share one root; a
    non-core cluster joins the root of its first core partner in the order
    of the pairs (by B's first detection, then A's).  Online a partner
    count only grows, so a cluster is core from the pair that makes it so,
    and core partners are joined then.  A non-core cluster waits until its
    count is final (:meth:`MergeWindow.is_final`) and, going through its
    pairs in the offline order, each partner is core or final; then it
    joins the first core one (or stays alone).  The partition equals the
    offline one; the join of a non-core cluster may come well after its
    pair was decided (as long as a partner before the core one may still
    become core).  With ``min_samples = 1`` every accepted pair joins at
    once.

    Parameters
    ----------
    min_samples : int
        N_min of the second DBSCAN, counted in clusters (itself included).
    eps_t2 : float
        Stage 2's time window, s.
    """

    def __init__(self, min_samples, eps_t2):
        self.min_samples = min_samples
        self.eps_t2 = eps_t2
        self.partners = {}  # label -> list of (offline order key of the pair, partner label)
        self.core = set()
        self.waiting = set()  # non-core clusters whose join is not decided yet

    @property
    def members(self):
        """The clusters whose pairs are still remembered (their records must be kept)."""
        return self.partners.keys()

    def update(self, accepted, window, now, window_start):
        """Register the pairs accepted now; returns the joins that are certain now."""
        if self.min_samples <= 1:
            return list(accepted)
        joins = []
        newly_core = []
        for a, b in accepted:
            key = (window.clusters[b].key, window.clusters[a].key)  # the offline order: by B, then by A
            for one, other in ((a, b), (b, a)):
                self.partners.setdefault(one, []).append((key, other))
                if one not in self.core and len(self.partners[one]) + 1 >= self.min_samples:
                    self.core.add(one)
                    self.waiting.discard(one)
                    newly_core.append(one)
                elif one not in self.core:
                    self.waiting.add(one)
        for a, b in accepted:
            if a in self.core and b in self.core:
                joins.append((a, b))
        for one in newly_core:
            joins += [(one, other) for _, other in self.partners[one] if other in self.core and other != one]
        joins += self._attach(window, now, window_start)
        self._forget(window, now, window_start)
        return list(dict.fromkeys(tuple(sorted(pair)) for pair in joins))

    def _attach(self, window, now, window_start):
        """Joins of the waiting non-core clusters whose first core partner is certain."""
        joins = []
        for label in sorted(self.waiting):
            if not window.is_final(label, now, window_start):
                continue
            decided = False
            for _, other in sorted(self.partners[label]):
                if other in self.core:
                    joins.append((other, label))
                    decided = True
                    break
                if not window.is_final(other, now, window_start):
                    break  # it may still become core: wait
            else:
                decided = True  # no core partner: it stays alone
            if decided:
                self.waiting.discard(label)
        return joins

    def _forget(self, window, now, window_start):
        """Drop the clusters whose pairs no waiting cluster reads any more."""
        settled = [
            label for label in self.partners if label not in self.waiting and window.is_final(label, now, window_start)
        ]
        for label in settled:
            if not any(other in self.waiting for _, other in self.partners[label]):
                del self.partners[label]
                self.core.discard(label)


class TimeColumns:
    """Time-sorted columns (``t`` among them) in buffers with room for more entries.

    ``columns[name]`` is a view of the live entries ``[lo, hi)``: appending
    writes at ``hi``, dropping old entries moves ``lo``, and the live span
    moves to the front (of a buffer twice its size when needed) only when
    the buffer is full, so a scan does not copy the whole window.
    """

    def __init__(self, names, capacity=1024):
        self.names = names
        self._buffers = {name: np.zeros(capacity, dtype=_dtype(name)) for name in names}
        self.lo = self.hi = 0

    def __getitem__(self, name):
        return self._buffers[name][self.lo : self.hi]

    def __len__(self):
        return self.hi - self.lo

    def append(self, new):
        """Add entries (a dict of equal-length arrays, times not before the last ones)."""
        n = len(new["t"])
        capacity = len(self._buffers["t"])
        if self.hi + n > capacity:
            live = self.hi - self.lo
            if live + n > capacity // 2:
                capacity = 2 * (live + n)
            for name, buffer in self._buffers.items():
                moved = np.zeros(capacity, dtype=buffer.dtype)
                moved[:live] = buffer[self.lo : self.hi]
                self._buffers[name] = moved
            self.lo, self.hi = 0, live
        for name in self.names:
            self._buffers[name][self.hi : self.hi + n] = new[name]
        self.hi += n

    def drop_before(self, threshold):
        """Forget the entries before ``threshold`` (s)."""
        self.lo += int(np.searchsorted(self["t"], threshold, side="left"))


def _dtype(name):
    """int64 for labels and times in us, float64 otherwise."""
    return np.int64 if name in ("label", "us") else np.float64


def _runs(labels, involved, columns, scans):
    """The :class:`ClusterRuns` the pair kernels read, of the clusters ``involved`` (sorted labels).

    The entries are time-sorted, each time's sorted by (label, offline
    keys), so a stable sort by label gives the offline order (label, time,
    keys).  ``scans``: the entries are per-scan centres (continuation), and
    a scan is one entry; else rows (Eq. 6).
    """
    selected = np.flatnonzero((labels[:, None] == involved).any(axis=1))  # a few clusters: no hash table
    order = selected[np.argsort(labels[selected], kind="stable")]
    sorted_labels = labels[order]
    starts = np.empty(len(order), dtype=bool)
    starts[0] = True
    np.not_equal(sorted_labels[1:], sorted_labels[:-1], out=starts[1:])
    run_start = np.flatnonzero(starts)
    ids = sorted_labels[run_start]
    run_end = np.append(run_start[1:], len(order))
    t, x, y = (np.ascontiguousarray(columns[name][order]) for name in ("t", "x", "y"))
    tracks = dict(scan_t=t, scan_x=x, scan_y=y, scan_start=run_start, scan_end=run_end) if scans else {}
    tracks = {name: tracks.get(name) for name in ("scan_t", "scan_x", "scan_y", "scan_start", "scan_end")}
    return ClusterRuns(
        ids=ids, order=order, run_start=run_start, run_end=run_end, t=t, x=x, y=y, **tracks, by_start=None
    )
