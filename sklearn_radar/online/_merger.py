"""Stage 2 on a live stream: ClusterMerger's causal decisions, each taken as soon as its data are complete.

Offline, the pair (A, B) is decided at ``tau = min(end of B, s_B + eps_t2)``
from the detections at or before tau (see :class:`ClusterMerger`).  On a
stream tau is known once B has a detection after ``s_B + eps_t2`` (then
``tau = s_B + eps_t2``) or once B can grow no more (its stage-1 id left the
stage-1 window, or the clusters met and B's rows went to the older id);
then every detection at or before tau has arrived, and the pair is decided
with the offline kernels on the retained rows of A and B, which gives the
offline decision exactly.  Rows are kept while a pending or future decision
can read them: from ``max(eps_t2, 4 eps_t)`` before the oldest pending B
(four stage-1 gaps of at most ``eps_t`` hold the five last scans that the
continuation's smoothed cubic reads).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..cluster._merge_kernels import cluster_runs, continuation_edges

_MARGIN_S = 0.05  # s kept beyond the horizon: rounding of the time windows never reaches it


@dataclass
class _Cluster:
    key: tuple  # first detection (t s, x m, y m, v_r m/s[, line of sight rad]): A precedes B when smaller
    start: float  # s, first detection time s_A
    latest: float  # s, latest detection time so far
    decided: bool = False


class MergeWindow:
    """Stage 2 for one sequence: the retained clustered rows and the clusters' pending decisions.

    Parameters
    ----------
    merger : ClusterMerger or None
        Its parameters define the criterion (``mode``, ``eps_d``, ``eps_phi``, ``eps_v``, ``eps_t2``,
        ``unknown_velocity``); ``min_samples`` must be 1 (checked by the caller).  None: no stage 2, the
        window only keeps the last ``eps_t`` for the object list.
    eps_t : float
        Stage 1's time threshold, s.
    """

    def __init__(self, merger, eps_t):
        self.merger = merger
        self.velocity = merger is not None and merger.mode == "velocity"
        self.eps_t2 = 0.0 if merger is None else float(merger.eps_t2)
        self.keep_back = (max(self.eps_t2, 4.0 * float(eps_t)) if merger is not None else float(eps_t)) + _MARGIN_S
        self.clusters = {}
        self.rows = {name: np.zeros(0) for name in ("t", "x", "y", "v_r", "los")}
        self.rows["label"] = np.zeros(0, dtype=np.int64)
        self.rows["us"] = np.zeros(0, dtype=np.int64)
        self.gone = []  # the clusters forgotten by the last decide()

    def add(self, labels, t, x, y, v_r, los, timestamp_us):
        """Append a scan's clustered rows (``labels >= 0``) and register the clusters it starts."""
        clustered = np.flatnonzero(labels >= 0)
        if len(clustered) == 0:
            return
        new = {"label": labels[clustered], "t": t[clustered], "x": x[clustered], "y": y[clustered]}
        new["v_r"], new["los"] = v_r[clustered], los[clustered]
        new["us"] = np.full(len(clustered), timestamp_us, dtype=np.int64)
        for name, values in new.items():
            self.rows[name] = np.concatenate([self.rows[name], values])
        now = float(new["t"][0])
        keys = [new[name] for name in ("t", "x", "y", "v_r", *(("los",) if self.velocity else ()))]
        order = np.lexsort((*keys[::-1], new["label"]))  # by label, then the offline first-detection keys
        sorted_labels = new["label"][order]
        first = order[np.r_[True, sorted_labels[1:] != sorted_labels[:-1]]]
        for label, row in zip(new["label"][first].tolist(), first.tolist(), strict=True):
            cluster = self.clusters.get(label)
            if cluster is not None:
                cluster.latest = now
                continue
            key = tuple(float(values[row]) for values in keys)
            self.clusters[label] = _Cluster(key=key, start=key[0], latest=key[0], decided=self.merger is None)

    def decide(self, now, growing):
        """Decide the pending clusters whose data are complete; returns the accepted pairs (A, B) as labels.

        Parameters
        ----------
        now : float
            s, the time of the scan just added.
        growing : set of int or None
            Stage-1 ids that can still receive detections; None: none can (end of the stream).
        """
        due = [
            label
            for label, cluster in self.clusters.items()
            if not cluster.decided
            and (cluster.latest > cluster.start + self.eps_t2 or growing is None or label not in growing)
        ]
        pairs = []
        for b in due:
            cluster_b = self.clusters[b]
            cluster_b.decided = True
            threshold = cluster_b.start - self.eps_t2
            pairs += [
                (a, b)
                for a, cluster_a in self.clusters.items()
                if a != b and cluster_a.key < cluster_b.key and cluster_a.latest > threshold
            ]
        merged = self._accepted(pairs) if pairs else []
        self._prune(now)
        return merged

    def _accepted(self, pairs):
        """The pairs the offline criterion merges, computed by its kernels on the retained rows."""
        involved = np.unique(np.array(pairs, dtype=np.int64).ravel())
        rows = np.flatnonzero((self.rows["label"][:, None] == involved).any(axis=1))  # few clusters: no sort
        r = {name: values[rows] for name, values in self.rows.items()}
        extra = (r["v_r"], r["los"]) if self.velocity else (r["v_r"],)
        runs = cluster_runs(r["label"], r["x"], r["y"], r["t"], extra)
        pair_a = np.searchsorted(runs.ids, np.array([a for a, _ in pairs], dtype=np.int64))
        pair_b = np.searchsorted(runs.ids, np.array([b for _, b in pairs], dtype=np.int64))
        m = self.merger
        if self.velocity:
            merge = m._velocity_merges(runs, pair_a, pair_b, r["v_r"], r["los"])
        else:
            merge = continuation_edges(
                runs, pair_a, pair_b, m.eps_d, m.eps_v, self.eps_t2, m.unknown_velocity == "accept"
            )
        return [pair for pair, accepted in zip(pairs, merge.tolist(), strict=True) if accepted]

    def _prune(self, now):
        """Forget the rows and clusters no pending or future decision reads."""
        pending = [cluster.start for cluster in self.clusters.values() if not cluster.decided]
        threshold = min([now, *pending]) - self.keep_back
        first_kept = int(np.searchsorted(self.rows["t"], threshold, side="left"))
        if first_kept:
            self.rows = {name: values[first_kept:] for name, values in self.rows.items()}
        gone = [label for label, c in self.clusters.items() if c.decided and c.latest < threshold]
        for label in gone:
            del self.clusters[label]
        self.gone = gone

    def recent(self, since):
        """The retained rows at or after ``since`` (s)."""
        first = int(np.searchsorted(self.rows["t"], since, side="left"))
        return {name: values[first:] for name, values in self.rows.items()}
