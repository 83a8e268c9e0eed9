"""Learned grouping, a research prototype (issue 42): which supervised design groups road users best, how fast?

Not library code: one script that simulates labelled sequences, learns from the training half and scores the test
half, to choose the design that the library's learned grouping stage will implement.

Data: ``make_scenes`` (``--data easy realistic radarscenes``, ``--n-sequences`` x ``--duration`` s per seed), split
half/half by sequence with ``sequence_train_test_split(random_state=seed)`` (the object-level ablation's split, so
its baselines are scored on the same test sequences).  Every detection passes the framework's front, per sequence:
``FrameTransform(frame="frame")`` (world x, y in m, compensated Doppler v_r in m/s, t in s) then
``DopplerDensityFilter()`` (its ``keep``); a detection it drops is noise.  The target is the main job's,
``metrics.precluster_target``, and the test half is scored with ``metrics.panoptic_quality`` (0.5 s windows).

Designs (each learner a ``HistGradientBoosting*`` on vectorised numpy features of cKDTree neighbourhoods):

* ``objectness``: per detection, P(it belongs to a road user) from its Doppler, RCS, range and neighbourhood (counts,
  Doppler spread, a local rigid velocity fitted to the neighbours' Doppler and lines of sight as in Eq. 6 of the
  paper, and its residual).  Every design below is gated by it.
* ``A`` (learned links + average linkage): candidate pairs within ``--pair-radius`` m and ``--pair-window`` s among
  detections with P(object) > 0.05; pair features (offsets, Doppler difference, consistency of both Doppler values
  with one rigid velocity, RCS, range, both sides' neighbourhoods and objectness); the link classifier learns
  "same instance, both road users".  Grouping: average-linkage hierarchical clustering (scipy) of 1 - P(link)
  (1 for pairs that are not candidates) per sequence and chunk of ``chunk`` s (chunk borders are offset by 0.25 s
  from the 0.5 s PQ windows, so a split at a border costs as it would on line); the cut, the objectness threshold,
  the chunk length and a minimum cluster size are tuned for PQ.
* ``A-mean`` (the default; learned links + average linkage over the existing links only): greedily merge the two
  clusters with the largest mean P(link) over the candidate pairs between them while it exceeds the link threshold;
  pairs that are not candidates carry no evidence (not distance 1 as in ``A``), so neither chaining nor the time
  span of a track splits it.  Link threshold, objectness gate and minimum cluster size tuned for PQ; the merge
  order does not depend on the threshold, so one run per gate gives every threshold.
* ``A-gaec`` (learned links + greedy additive edge contraction, a correlation clustering): merge the two clusters
  with the largest sum of ``logit(P) + bias`` over the pairs between them while it is positive; bias, gate and
  minimum size tuned.
* ``A-mutual`` (learned links, no hierarchy): a link counts if P(link) > p_min and it is among the top-k links of
  both ends; connected components of those links; tuned like ``A``.
* ``B`` (centre voting, Liu et al. 2022): two regressors predict each detection's offset to its object's centre
  (the mean of the object's detections within 0.15 s) along and across its line of sight; the shifted detections
  are clustered by DBSCAN on (x, y, a_t t) per sequence; eps, min_samples, a_t and the objectness threshold tuned.
  ``--vote-control`` adds ``B0``, the same gate and DBSCAN search without the shift.

Tuning (never on the test half): every threshold is chosen on out-of-fold predictions of the training half
(``GroupKFold`` by sequence; later stages see out-of-fold outputs of earlier ones, as at test time); the models are
then refitted on the whole training half and applied once to the test half.

Baselines (``--baselines``): the object-level ablation's ``SequenceDBSCAN`` (per-sequence scikit-learn DBSCAN on
(x, y, a_v v_r, a_t t) after a Doppler gate, Bayesian search for PQ, ``--n-iter`` iterations) and the object
experiment (``objects``), run through ``benchmarks/ablation_object_level.py``'s ``run_one`` on the same data and
split.

Times: ``fit`` is features + final model fits on the training half; ``tune`` the out-of-fold fits and the threshold
search; ``predict`` the test half end to end (front excluded) per scan (one sensor's cycle), batch-amortised, one
core.

Run (one core, niced; the first line is a smoke run of a minute or two, the second about 5-8 minutes per preset
and seed on a busy 2-core machine; ``--designs`` picks designs, default ``A-mean A-mutual B``)::

    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/experiment_learned_grouping.py --quick
    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/experiment_learned_grouping.py --data realistic radarscenes \
        --seeds 0 1 2 --designs A-mean B --vote-control --baselines
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import heapq
import sys
import time
from pathlib import Path

import numpy as np
from scipy.cluster.hierarchy import fcluster, linkage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree
from sklearn.cluster import DBSCAN
from sklearn.ensemble import HistGradientBoostingClassifier, HistGradientBoostingRegressor
from sklearn.pipeline import Pipeline
from threadpoolctl import threadpool_limits

from sklearn_radar import DopplerDensityFilter, FrameTransform
from sklearn_radar.datasets import make_scenes
from sklearn_radar.metrics import panoptic_quality, precluster_target
from sklearn_radar.model_selection import sequence_train_test_split

P_CANDIDATE = 0.05  # objectness above which a detection takes part in pairs and votes
V_MOVING = 0.2  # m/s: neighbours above it enter the local rigid-velocity fit
LOCAL_RADIUS, LOCAL_WINDOW = 2.5, 0.15  # m, s: neighbourhood of the per-detection features
CENTRE_WINDOW = 0.15  # s: an object's centre at time t is the mean of its detections within t +- this
CHUNK_OFFSET = 0.25  # s: hierarchical-clustering chunks start 0.25 s after the PQ windows


# --------------------------------------------------------------------------------------------------- data


def load(preset, seed, n_sequences, duration):
    """Simulated sequences through the front; one dict of kept-detection arrays per sequence, and the split."""
    scenes = make_scenes(n_sequences=n_sequences, duration=duration, difficulty=preset, random_state=seed)
    X, groups = scenes.data, scenes.groups
    target = precluster_target(X, scenes.target)
    train_rows, _ = sequence_train_test_split(groups, test_size=0.5, random_state=seed)
    train_ids = set(np.unique(groups[train_rows]).tolist())
    front = Pipeline([("frame", FrameTransform(frame="frame")), ("filter", DopplerDensityFilter())])
    sequences = []
    for number in np.unique(groups):
        rows = np.flatnonzero(groups == number)
        Z = front.fit_transform(X.iloc[rows])
        t = Z["t"].to_numpy(np.float64)
        keep = Z["keep"].to_numpy(bool)
        los = (Z["heading"] + Z["sensor_yaw"] + Z["azimuth_sc"]).to_numpy(np.float64)
        seq = {
            "number": int(number),
            "train": int(number) in train_ids,
            "n_rows": len(rows),
            "t_all": t,
            "target_all": target[rows],
            "n_scans": int(Z.groupby(["sensor_id", "timestamp"]).ngroups),
            "keep": keep,
        }
        for name, values in (
            ("x", Z["x"]),
            ("y", Z["y"]),
            ("v", Z["v_r"]),
            ("rcs", Z["rcs"]),
            ("range", Z["range_sc"]),
            ("ego", Z["ego_vx"]),
        ):
            seq[name] = values.to_numpy(np.float64)[keep]
        seq["t"] = t[keep] - t.min()
        seq["los"] = los[keep]
        seq["sensor"] = Z["sensor_id"].to_numpy()[keep]
        seq["target"] = target[rows][keep]
        sequences.append(seq)
    return sequences


def pairs_within(x, y, t, radius, window, subset=None):
    """Pairs i < j (indices into the arrays) with planar distance <= radius (m) and |dt| <= window (s)."""
    idx = np.arange(len(x)) if subset is None else np.flatnonzero(subset)
    if len(idx) < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    pts = np.column_stack([x[idx], y[idx], t[idx] * (radius / window)])
    found = cKDTree(pts).query_pairs(radius * np.sqrt(2.0), output_type="ndarray")
    i, j = idx[found[:, 0]], idx[found[:, 1]]
    ok = ((x[i] - x[j]) ** 2 + (y[i] - y[j]) ** 2 <= radius**2) & (np.abs(t[i] - t[j]) <= window)
    return i[ok], j[ok]


def _both(i, j):
    return np.concatenate([i, j]), np.concatenate([j, i])


# --------------------------------------------------------------------------------------------------- features


def detection_features(s):
    """Per kept detection: features for objectness (and the local rigid velocity, stored in ``s``)."""
    x, y, t, v = s["x"], s["y"], s["t"], s["v"]
    n = len(x)
    src, dst = _both(*pairs_within(x, y, t, LOCAL_RADIUS, LOCAL_WINDOW))
    dv = np.abs(v[src] - v[dst])
    count = np.bincount(src, minlength=n).astype(np.float64)
    similar = np.bincount(src, weights=(dv < 0.5), minlength=n)
    moving_nb = np.abs(v[dst]) > V_MOVING
    n_moving = np.bincount(src, weights=moving_nb, minlength=n)
    mean_v = np.bincount(src, weights=v[dst], minlength=n) / np.maximum(count, 1)
    mean_sq = np.bincount(src, weights=v[dst] ** 2, minlength=n) / np.maximum(count, 1)
    spread = np.sqrt(np.maximum(mean_sq - mean_v**2, 0))
    mean_abs = np.bincount(src, weights=np.abs(v[dst]), minlength=n) / np.maximum(count, 1)
    src1, _ = _both(*pairs_within(x, y, t, 1.0, 0.1))
    count1 = np.bincount(src1, minlength=n).astype(np.float64)
    # Local rigid velocity V (Eq. 6's model v_r = u . V) fitted to the moving neighbours and the detection itself,
    # ridge-regularised towards the radial-only solution v u; with its Doppler residual.
    c, sn = np.cos(s["los"]), np.sin(s["los"])
    w = moving_nb.astype(np.float64)
    a11 = np.bincount(src, weights=w * c[dst] ** 2, minlength=n) + c**2
    a12 = np.bincount(src, weights=w * c[dst] * sn[dst], minlength=n) + c * sn
    a22 = np.bincount(src, weights=w * sn[dst] ** 2, minlength=n) + sn**2
    b1 = np.bincount(src, weights=w * v[dst] * c[dst], minlength=n) + v * c
    b2 = np.bincount(src, weights=w * v[dst] * sn[dst], minlength=n) + v * sn
    vv = np.bincount(src, weights=w * v[dst] ** 2, minlength=n) + v**2
    lam = 0.3
    r1, r2 = b1 + lam * v * c, b2 + lam * v * sn
    m11, m22 = a11 + lam, a22 + lam
    det = m11 * m22 - a12**2
    vx, vy = (m22 * r1 - a12 * r2) / det, (m11 * r2 - a12 * r1) / det
    sq = vv - 2 * (vx * b1 + vy * b2) + vx**2 * a11 + 2 * vx * vy * a12 + vy**2 * a22
    residual = np.sqrt(np.maximum(sq, 0) / (n_moving + 1))
    s["vx"], s["vy"] = vx, vy
    s["count"], s["spread"] = count, spread
    tangential = -vx * sn + vy * c
    features = np.column_stack(
        [
            np.abs(v),
            v,
            s["rcs"],
            s["range"],
            np.abs(s["ego"]),
            count,
            count1,
            similar,
            n_moving,
            mean_abs,
            spread,
            np.hypot(vx, vy),
            tangential,
            residual,
            s["sensor"],
        ]
    )
    return features


def pair_features(s, i, j):
    """Symmetric features of candidate pairs (i, j) of one sequence."""
    x, y, t, v, los = s["x"], s["y"], s["t"], s["v"], s["los"]
    dx, dy, dt = x[j] - x[i], y[j] - y[i], t[j] - t[i]
    c, sn = np.cos(los), np.sin(los)
    vx, vy = s["vx"], s["vy"]
    # Consistency of both Doppler values with one rigid velocity: each side's local velocity predicts the other's
    # Doppler; and the velocity the two Doppler values alone imply (2 x 2 solve, large when inconsistent).
    res_ij = np.abs(v[j] - (c[j] * vx[i] + sn[j] * vy[i]))
    res_ji = np.abs(v[i] - (c[i] * vx[j] + sn[i] * vy[j]))
    det = c[i] * sn[j] - sn[i] * c[j]
    safe = np.where(np.abs(det) < 1e-3, np.copysign(1e-3, det + 1e-12), det)
    px = (v[i] * sn[j] - v[j] * sn[i]) / safe
    py = (c[i] * v[j] - c[j] * v[i]) / safe
    implied = np.minimum(np.hypot(px, py), 60.0)
    mvx, mvy = (vx[i] + vx[j]) / 2, (vy[i] + vy[j]) / 2
    motion = np.hypot(dx - mvx * dt, dy - mvy * dt)
    p = s["p_obj"]

    def lo_hi(a):
        return np.minimum(a[i], a[j]), np.maximum(a[i], a[j])

    columns = [
        np.hypot(dx, dy),
        np.abs(dt),
        np.abs(v[i] - v[j]),
        np.minimum(res_ij, res_ji),
        np.maximum(res_ij, res_ji),
        implied,
        np.abs(det),
        np.hypot(vx[i] - vx[j], vy[i] - vy[j]),
        motion,
        (s["range"][i] + s["range"][j]) / 2,
        (s["sensor"][i] == s["sensor"][j]).astype(np.float64),
    ]
    for a in (s["rcs"], s["count"], s["spread"], p, np.abs(v)):
        columns.extend(lo_hi(a))
    return np.column_stack(columns)


def centre_offsets(s):
    """Target of centre voting: (along, across) the line of sight offset to the object's centre; NaN for others."""
    x, y, t, target = s["x"], s["y"], s["t"], s["target"]
    cx, cy = np.full(len(x), np.nan), np.full(len(x), np.nan)
    for label in np.unique(target[target >= 0]):
        rows = np.flatnonzero(target == label)
        rows = rows[np.argsort(t[rows], kind="stable")]
        tt = t[rows]
        lo = np.searchsorted(tt, tt - CENTRE_WINDOW, side="left")
        hi = np.searchsorted(tt, tt + CENTRE_WINDOW, side="right")
        sx, sy = np.concatenate([[0], np.cumsum(x[rows])]), np.concatenate([[0], np.cumsum(y[rows])])
        cx[rows] = (sx[hi] - sx[lo]) / (hi - lo)
        cy[rows] = (sy[hi] - sy[lo]) / (hi - lo)
    c, sn = np.cos(s["los"]), np.sin(s["los"])
    ox, oy = cx - x, cy - y
    return np.column_stack([ox * c + oy * sn, -ox * sn + oy * c])


def vote_features(s, candidate):
    """Neighbourhood geometry for centre voting, in the detection's line-of-sight frame."""
    x, y, t, v = s["x"], s["y"], s["t"], s["v"]
    n = len(x)
    c, sn = np.cos(s["los"]), np.sin(s["los"])
    src, dst = _both(*pairs_within(x, y, t, 4.0, 0.1, subset=candidate))
    w = s["p_obj"][dst] * np.exp(-(((v[dst] - v[src]) / 1.0) ** 2))
    dx, dy = x[dst] - x[src], y[dst] - y[src]
    along, across = dx * c[src] + dy * sn[src], -dx * sn[src] + dy * c[src]
    wsum = np.bincount(src, weights=w, minlength=n)
    denom = np.maximum(wsum, 1e-6)
    m_along = np.bincount(src, weights=w * along, minlength=n) / denom
    m_across = np.bincount(src, weights=w * across, minlength=n) / denom
    s_along = np.sqrt(np.maximum(np.bincount(src, weights=w * along**2, minlength=n) / denom - m_along**2, 0))
    s_across = np.sqrt(np.maximum(np.bincount(src, weights=w * across**2, minlength=n) / denom - m_across**2, 0))
    mx_along = np.full(n, 0.0)
    np.maximum.at(mx_along, src, np.where(w > 0.2, along, 0))
    mn_along = np.full(n, 0.0)
    np.minimum.at(mn_along, src, np.where(w > 0.2, along, 0))
    vx, vy = s["vx"], s["vy"]
    return np.column_stack(
        [
            s["det_features"],
            s["p_obj"],
            wsum,
            m_along,
            m_across,
            s_along,
            s_across,
            mx_along,
            mn_along,
            vx * c + vy * sn,
            -vx * sn + vy * c,
        ]
    )


# --------------------------------------------------------------------------------------------------- learners


def _classifier(max_iter):
    return HistGradientBoostingClassifier(max_iter=max_iter, learning_rate=0.1, max_leaf_nodes=31, random_state=0)


def _regressor(max_iter):
    return HistGradientBoostingRegressor(max_iter=max_iter, learning_rate=0.1, max_leaf_nodes=31, random_state=0)


def _subsample(n, limit, rng):
    return np.arange(n) if n <= limit else np.sort(rng.choice(n, limit, replace=False))


def cross_fit(train, build, fit_one, predict_one, name):
    """Out-of-fold outputs on the training sequences (one fold per sequence), then a refit on all of them.

    ``build(seq)`` gives ``(X, y)`` of one sequence for fitting; ``predict_one(model, seq)``'s out-of-fold outputs
    go to ``seq[name]``.  Returns the refitted model, the seconds of the out-of-fold fits and of the refit.
    """
    start = time.perf_counter()
    for k, held in enumerate(train):  # GroupKFold by sequence with as many folds as training sequences
        others = [s for m, s in enumerate(train) if m != k]
        model = fit_one([build(s) for s in others])
        held[name] = predict_one(model, held)
    middle = time.perf_counter()
    model = fit_one([build(s) for s in train])
    return model, middle - start, time.perf_counter() - middle


# --------------------------------------------------------------------------------------------------- grouping


def group_linkage(s, i, j, p, threshold, chunk, cuts):
    """Average linkage of 1 - P(link) per chunk among detections with P(object) > threshold: {cut: labels}."""
    n = len(s["x"])
    node = s["p_obj"] > threshold
    chunk_id = np.floor((s["t"] + CHUNK_OFFSET) / chunk).astype(np.int64)
    keep = node[i] & node[j] & (chunk_id[i] == chunk_id[j])
    i, j, d = i[keep], j[keep], 1.0 - p[keep]
    out = {cut: np.full(n, -1, np.int64) for cut in cuts}
    next_label = 0
    pair_chunk = chunk_id[i]
    order = np.argsort(pair_chunk, kind="stable")
    i, j, d, pair_chunk = i[order], j[order], d[order], pair_chunk[order]
    bounds = np.searchsorted(pair_chunk, np.unique(chunk_id[node]))
    bounds_hi = np.searchsorted(pair_chunk, np.unique(chunk_id[node]), side="right")
    for c_id, lo, hi in zip(np.unique(chunk_id[node]), bounds, bounds_hi, strict=True):
        members = np.flatnonzero(node & (chunk_id == c_id))
        m = len(members)
        if m == 1:
            for cut in cuts:
                out[cut][members] = next_label
            next_label += 1
            continue
        local = np.full(n, -1, np.int64)
        local[members] = np.arange(m)
        li, lj = local[i[lo:hi]], local[j[lo:hi]]
        a, b = np.minimum(li, lj), np.maximum(li, lj)
        condensed = np.ones(m * (m - 1) // 2)
        condensed[m * a - a * (a + 1) // 2 + (b - a - 1)] = d[lo:hi]
        tree = linkage(condensed, method="average")
        for cut in cuts:
            labels = fcluster(tree, cut, criterion="distance")
            out[cut][members] = next_label + labels
        next_label += m + 1
    return out


def group_mutual(s, i, j, p, threshold, p_min, k):
    """Connected components of links with P > p_min that are among the top-k of both ends."""
    n = len(s["x"])
    node = s["p_obj"] > threshold
    keep = node[i] & node[j] & (p > p_min)
    i, j, p = i[keep], j[keep], p[keep]
    src = np.concatenate([i, j])
    both_p = np.concatenate([p, p])
    order = np.lexsort((-both_p, src))  # by node, then by decreasing probability
    src = src[order]
    starts = np.searchsorted(src, src, side="left")
    rank = np.arange(len(src)) - starts
    top = rank < k
    half = len(i)
    undo = np.empty(len(src), np.int64)
    undo[order] = np.arange(len(src))
    mutual = top[undo[:half]] & top[undo[half:]]
    graph = coo_matrix((np.ones(int(mutual.sum())), (i[mutual], j[mutual])), shape=(n, n))
    _, labels = connected_components(graph, directed=False)
    labels = np.where(node, labels, -1)
    return labels


def group_agglomerative(s, i, j, p, threshold, bias, mode):
    """Greedy agglomeration on the sparse link graph, without chaining; missing pairs carry no evidence.

    ``mode="sum"``: greedy additive edge contraction (correlation clustering, Keuper et al. 2015) on the weights
    ``logit(P) + bias``: contract the pair of clusters with the largest summed weight while it is positive.
    ``mode="mean"``: average linkage over the existing links only: merge the pair of clusters with the largest mean
    P(link) over the candidate pairs between them while it exceeds ``bias``.
    """
    merges = agglomerate(s, i, j, p, threshold, bias, mode)
    return labels_at(s, threshold, merges, bias if mode == "mean" else -np.inf)


def agglomerate(s, i, j, p, threshold, bias, mode):
    """The greedy merges ``(child, parent, priority)`` in order (see :func:`group_agglomerative`).

    In ``mode="mean"`` the order does not depend on ``bias`` (it only stops the merging), so one run at the lowest
    bias gives the merges of every higher one: :func:`labels_at` replays them up to the first below it.
    """
    node = s["p_obj"] > threshold
    keep = node[i] & node[j]
    i, j, p = i[keep], j[keep], np.clip(p[keep], 1e-4, 1 - 1e-4)
    weight = np.log(p / (1 - p)) + bias if mode == "sum" else p
    adjacency = {}
    for a, b, w in zip(i.tolist(), j.tolist(), weight.tolist(), strict=True):
        adjacency.setdefault(a, {})[b] = [w, 1]
        adjacency.setdefault(b, {})[a] = [w, 1]
    merged = set()
    merges = []
    heap = []

    def priority(entry):
        return entry[0] if mode == "sum" else entry[0] / entry[1]

    limit = 0.0 if mode == "sum" else bias
    for a, neighbours in adjacency.items():
        for b, entry in neighbours.items():
            if a < b and priority(entry) > limit:
                heap.append((-priority(entry), a, b))
    heapq.heapify(heap)
    while heap:
        value, a, b = heapq.heappop(heap)
        if a in merged or b in merged:
            continue
        entry = adjacency[a].get(b)
        if entry is None or -value != priority(entry):
            continue  # stale
        # Merge the smaller adjacency into the larger; the survivor keeps its id.
        if len(adjacency[a]) < len(adjacency[b]):
            a, b = b, a
        merged.add(b)
        merges.append((b, a, -value))
        big, small = adjacency[a], adjacency.pop(b)
        del big[b]
        for c, (w, k) in small.items():
            if c == a:
                continue
            other = adjacency[c]
            del other[b]
            if c in big:
                big[c][0] += w
                big[c][1] += k
            else:
                big[c] = [w, k]
            other[a] = big[c]
            if priority(big[c]) > limit:
                heapq.heappush(heap, (-priority(big[c]), min(a, c), max(a, c)))
    return merges


def labels_at(s, threshold, merges, bias):
    """Labels after the merges up to the first whose priority is not above ``bias``; -1 below the gate."""
    n = len(s["x"])
    parent = np.arange(n)
    for child, survivor, value in merges:
        if value <= bias:
            break
        parent[child] = survivor
    for _ in range(64):  # pointer jumping to the roots
        grand = parent[parent]
        if np.array_equal(grand, parent):
            break
        parent = grand
    return np.where(s["p_obj"] > threshold, parent, -1)


def apply_min_size(labels, min_size):
    if min_size <= 1:
        return labels
    valid = labels >= 0
    _, inverse, counts = np.unique(labels[valid], return_inverse=True, return_counts=True)
    out = labels.copy()
    out[np.flatnonzero(valid)[counts[inverse] < min_size]] = -1
    return out


def group_votes(s, threshold, eps, min_samples, t_scale):
    n = len(s["x"])
    node = np.flatnonzero(s["p_obj"] > threshold)
    labels = np.full(n, -1, np.int64)
    if len(node) == 0:
        return labels
    off = s["offset"][node]
    c, sn = np.cos(s["los"][node]), np.sin(s["los"][node])
    px = s["x"][node] + off[:, 0] * c - off[:, 1] * sn
    py = s["y"][node] + off[:, 0] * sn + off[:, 1] * c
    pts = np.column_stack([px, py, s["t"][node] * t_scale])
    labels[node] = DBSCAN(eps=eps, min_samples=min_samples).fit_predict(pts)
    return labels


# --------------------------------------------------------------------------------------------------- scoring


def score(sequences, labels_of):
    """PQ (precluster target, 0.5 s windows) of per-sequence kept-detection labels, over the given sequences."""
    truth, pred, times, groups = [], [], [], []
    for s in sequences:
        full = np.full(s["n_rows"], -1, np.int64)
        labels = labels_of(s)
        full[s["keep"]] = np.where(labels >= 0, labels, -1)
        truth.append(s["target_all"])
        pred.append(full)
        times.append(s["t_all"])
        groups.append(np.full(s["n_rows"], s["number"]))
    return panoptic_quality(
        np.concatenate(truth), np.concatenate(pred), times=np.concatenate(times), groups=np.concatenate(groups)
    )


def anatomy(sequences, labels_of):
    """Missed ground-truth segments (0.5 s windows, as PQ) by cause, and the median size of missed and matched ones.

    A segment is missed when no cluster's segment reaches IoU > 0.5 with it: ``noise`` when more than half of its
    detections are noise; else ``merged`` when the cluster holding most of it covers more than half of it (so the
    cluster is too large: other objects or background joined); else ``split`` (pieces, none large enough).
    """
    counts = {"matched": 0, "noise": 0, "merged": 0, "split": 0}
    sizes = {"matched": [], "missed": []}
    for s in sequences:
        pred = np.full(s["n_rows"], -1, np.int64)
        pred[s["keep"]] = labels_of(s)
        window = np.floor((s["t_all"] - s["t_all"].min()) / 0.5).astype(np.int64)
        truth = s["target_all"]
        _, pred_code = np.unique(np.column_stack([window, pred]), axis=0, return_inverse=True)
        pred_code = np.where(pred >= 0, pred_code.ravel(), -1)
        pred_size = np.bincount(pred_code[pred_code >= 0])
        obj = np.flatnonzero(truth >= 0)
        _, gt_code = np.unique(np.column_stack([window[obj], truth[obj]]), axis=0, return_inverse=True)
        gt_code = gt_code.ravel()
        gt_size = np.bincount(gt_code)
        noise = np.bincount(gt_code, weights=pred[obj] < 0, minlength=len(gt_size))
        hit = pred_code[obj] >= 0
        cells, inter = np.unique(np.column_stack([gt_code[hit], pred_code[obj][hit]]), axis=0, return_counts=True)
        iou = inter / (gt_size[cells[:, 0]] + pred_size[cells[:, 1]] - inter)
        best_iou = np.zeros(len(gt_size))
        np.maximum.at(best_iou, cells[:, 0], iou)
        best_inter = np.zeros(len(gt_size))
        np.maximum.at(best_inter, cells[:, 0], inter)
        matched = best_iou > 0.5
        counts["matched"] += int(matched.sum())
        missed_noise = ~matched & (noise > gt_size / 2)
        missed_merged = ~matched & ~missed_noise & (best_inter > gt_size / 2)
        counts["noise"] += int(missed_noise.sum())
        counts["merged"] += int(missed_merged.sum())
        counts["split"] += int((~matched & ~missed_noise & ~missed_merged).sum())
        sizes["matched"].append(gt_size[matched])
        sizes["missed"].append(gt_size[~matched])
    for key, values in sizes.items():
        values = np.concatenate(values)
        counts[f"median size {key}"] = float(np.median(values)) if len(values) else float("nan")
    return counts


def tune(train, grid, labels_for):
    """Best setting of ``grid`` for PQ on the training sequences' out-of-fold outputs."""
    best, best_pq = None, -1.0
    for setting in grid:
        pq = score(train, lambda s, setting=setting: labels_for(s, setting)).pq
        if pq > best_pq:
            best, best_pq = setting, pq
    return best, best_pq


# --------------------------------------------------------------------------------------------------- run


def run(preset, seed, options):
    rng = np.random.default_rng(seed)
    sequences = load(preset, seed, options.n_sequences, options.duration)
    train = [s for s in sequences if s["train"]]
    test = [s for s in sequences if not s["train"]]
    n_scans = sum(s["n_scans"] for s in test)
    results = []
    clock = {}

    def timed(key, fn, *args):
        start = time.perf_counter()
        value = fn(*args)
        clock[key] = clock.get(key, 0.0) + time.perf_counter() - start
        return value

    # Objectness (all designs).
    for s in sequences:
        key = "fit" if s["train"] else "predict"
        s["det_features"] = timed(key, detection_features, s)

    def fit_obj(parts):
        X = np.concatenate([p[0] for p in parts])
        y = np.concatenate([p[1] for p in parts])
        rows = _subsample(len(X), options.max_rows, rng)
        return _classifier(options.max_iter).fit(X[rows], y[rows])

    obj_model, clock["tune"], seconds = cross_fit(
        train,
        lambda s: (s["det_features"], s["target"] >= 0),
        fit_obj,
        lambda m, s: m.predict_proba(s["det_features"])[:, 1],
        "p_obj",
    )
    clock["fit"] += seconds
    for s in test:
        s["p_obj"] = timed("predict", lambda s=s: obj_model.predict_proba(s["det_features"])[:, 1])
    base_clock = dict(clock)
    print(f"  objectness: fit {clock['fit']:.1f} s, test features+predict {clock['predict']:.1f} s", flush=True)

    if {"A", "A-gaec", "A-mean", "A-mutual"} & set(options.designs):
        results.extend(run_links(train, test, options, rng, dict(base_clock), n_scans))
    if "B" in options.designs:
        results.extend(run_votes(train, test, options, rng, dict(base_clock), n_scans))
    return results


def _record(design, test, labels_of, clock, n_scans, setting, cv_pq):
    start = time.perf_counter()
    labels = {s["number"]: labels_of(s) for s in test}
    clock["predict"] += time.perf_counter() - start
    scores = score(test, lambda s: labels[s["number"]])
    return {
        "anatomy": anatomy(test, lambda s: labels[s["number"]]),
        "design": design,
        "pq": scores.pq,
        "recall": scores.recall,
        "precision": scores.precision,
        "cv_pq": cv_pq,
        "fit_s": clock["fit"],
        "tune_s": clock["tune"],
        "predict_ms_per_scan": 1e3 * clock["predict"] / max(n_scans, 1),
        "setting": setting,
    }


def run_links(train, test, options, rng, clock, n_scans):
    """Designs A and A-mutual: learned links, then average linkage or mutual top-k components."""
    start = time.perf_counter()
    for s in train + test:
        t0 = time.perf_counter()
        s["pairs"] = pairs_within(
            s["x"], s["y"], s["t"], options.pair_radius, options.pair_window, subset=s["p_obj"] > P_CANDIDATE
        )
        if not s["train"]:
            clock["predict"] += time.perf_counter() - t0
    t0 = time.perf_counter()
    for s in train:
        i, j = s["pairs"]
        s["pair_X"] = pair_features(s, i, j)
        s["pair_y"] = (s["target"][i] == s["target"][j]) & (s["target"][i] >= 0)
    clock["fit"] += time.perf_counter() - t0
    n_pairs = sum(len(s["pairs"][0]) for s in train)
    positives = sum(int(s["pair_y"].sum()) for s in train)

    def fit_link(parts):
        X = np.concatenate([p[0] for p in parts])
        y = np.concatenate([p[1] for p in parts])
        rows = _subsample(len(X), options.max_rows, rng)
        return _classifier(options.max_iter).fit(X[rows], y[rows])

    link_model, oof_seconds, seconds = cross_fit(
        train, lambda s: (s["pair_X"], s["pair_y"]), fit_link, lambda m, s: m.predict_proba(s["pair_X"])[:, 1], "p"
    )
    clock["tune"] += oof_seconds
    clock["fit"] += seconds
    t0 = time.perf_counter()
    for s in test:
        s["p"] = link_model.predict_proba(pair_features(s, *s["pairs"]))[:, 1]
    clock["predict"] += time.perf_counter() - t0
    print(
        f"  links: {n_pairs} training pairs ({positives} positive), pairs+fit {time.perf_counter() - start:.1f} s",
        flush=True,
    )
    results = []
    if "A" in options.designs:
        cuts = options.cuts
        cache = {}

        def linkage_labels(s, setting):
            threshold, chunk, cut, min_size = setting
            key = (s["number"], threshold, chunk)
            if key not in cache:
                cache[key] = group_linkage(s, *s["pairs"], s["p"], threshold, chunk, cuts)
            return apply_min_size(cache[key][cut], min_size)

        grid = [
            (th, ch, cut, ms)
            for th in options.thresholds
            for ch in options.chunks
            for cut in cuts
            for ms in options.min_sizes
        ]
        t0 = time.perf_counter()
        setting, cv_pq = tune(train, grid, linkage_labels)
        tune_clock = dict(clock, tune=clock["tune"] + time.perf_counter() - t0)
        threshold, chunk, cut, min_size = setting

        def final(s):
            labels = group_linkage(s, *s["pairs"], s["p"], threshold, chunk, [cut])[cut]
            return apply_min_size(labels, min_size)

        rec = _record("A links+avg-linkage", test, final, tune_clock, n_scans, setting, cv_pq)
        results.append(rec)
        _print(rec)
    for design, mode, biases in (
        ("A-gaec", "sum", (-2.0, -1.0, 0.0, 1.0, 2.0, 3.0)),
        ("A-mean", "mean", tuple(np.round(np.arange(0.1, 0.951, 0.05), 2).tolist())),
    ):
        if design not in options.designs:
            continue
        grid = [(th, bias, ms) for th in options.thresholds for bias in biases for ms in options.min_sizes]
        cache = {}
        floor = min(biases)

        def agglo_labels(s, setting, mode=mode, cache=cache, floor=floor):
            th, bias, ms = setting
            if mode == "mean":  # one run per gate: the merges of every higher bias are a prefix
                if (s["number"], th) not in cache:
                    cache[s["number"], th] = agglomerate(s, *s["pairs"], s["p"], th, floor, mode)
                return apply_min_size(labels_at(s, th, cache[s["number"], th], bias), ms)
            if (s["number"], th, bias) not in cache:
                cache[s["number"], th, bias] = group_agglomerative(s, *s["pairs"], s["p"], th, bias, mode)
            return apply_min_size(cache[s["number"], th, bias], ms)

        t0 = time.perf_counter()
        setting, cv_pq = tune(train, grid, agglo_labels)
        tune_clock = dict(clock, tune=clock["tune"] + time.perf_counter() - t0)
        th, bias, ms = setting

        def final(s, th=th, bias=bias, ms=ms, mode=mode):
            return apply_min_size(group_agglomerative(s, *s["pairs"], s["p"], th, bias, mode), ms)

        rec = _record(f"{design} links+{mode} agglo", test, final, tune_clock, n_scans, setting, cv_pq)
        results.append(rec)
        _print(rec)
    if "A-mutual" in options.designs:
        grid = [
            (th, pm, k, ms)
            for th in options.thresholds
            for pm in (0.1, 0.3, 0.5, 0.7)
            for k in (3, 6, 12, 24)
            for ms in options.min_sizes
        ]

        def mutual_labels(s, setting):
            th, pm, k, ms = setting
            return apply_min_size(group_mutual(s, *s["pairs"], s["p"], th, pm, k), ms)

        t0 = time.perf_counter()
        setting, cv_pq = tune(train, grid, mutual_labels)
        tune_clock = dict(clock, tune=clock["tune"] + time.perf_counter() - t0)
        rec = _record(
            "A-mutual links+top-k CC", test, lambda s: mutual_labels(s, setting), tune_clock, n_scans, setting, cv_pq
        )
        results.append(rec)
        _print(rec)
    return results


def run_votes(train, test, options, rng, clock, n_scans):
    """Design B: centre voting, then DBSCAN of the shifted detections."""
    t0 = time.perf_counter()
    for s in train:
        s["vote_X"] = vote_features(s, s["p_obj"] > P_CANDIDATE)
        s["vote_y"] = centre_offsets(s)
    clock["fit"] += time.perf_counter() - t0

    def fit_vote(parts):
        X = np.concatenate([p[0] for p in parts])
        y = np.concatenate([p[1] for p in parts])
        rows = np.flatnonzero(np.isfinite(y[:, 0]))
        rows = rows[_subsample(len(rows), options.max_rows, rng)]
        return [_regressor(options.max_iter).fit(X[rows], y[rows, k]) for k in range(2)]

    def predict_vote(models, s):
        return np.column_stack([m.predict(s["vote_X"]) for m in models])

    models, oof_seconds, seconds = cross_fit(
        train, lambda s: (s["vote_X"], s["vote_y"]), fit_vote, predict_vote, "offset"
    )
    clock["tune"] += oof_seconds
    clock["fit"] += seconds
    t0 = time.perf_counter()
    for s in test:
        s["vote_X"] = vote_features(s, s["p_obj"] > P_CANDIDATE)
        s["offset"] = predict_vote(models, s)
    clock["predict"] += time.perf_counter() - t0
    errors = np.concatenate([np.hypot(*(s["offset"] - s["vote_y"]).T) for s in train])
    baseline = np.concatenate([np.hypot(*s["vote_y"].T) for s in train])
    ok = np.isfinite(errors)
    print(
        f"  votes: out-of-fold centre error median {np.median(errors[ok]):.2f} m "
        f"(no shift {np.median(baseline[ok]):.2f} m)",
        flush=True,
    )
    grid = [
        (th, eps, ms, ts)
        for th in options.thresholds
        for eps in (0.6, 0.9, 1.3, 1.8, 2.5)
        for ms in (2, 3, 5, 8)
        for ts in (2.0, 5.0, 10.0)
    ]
    t0 = time.perf_counter()
    setting, cv_pq = tune(train, grid, lambda s, g: group_votes(s, *g))
    clock["tune"] += time.perf_counter() - t0
    rec = _record("B centre votes+DBSCAN", test, lambda s: group_votes(s, *setting), clock, n_scans, setting, cv_pq)
    _print(rec)
    results = [rec]
    if options.vote_control:  # the same gate and DBSCAN search without the shift: does voting help?
        for s in train + test:
            s["offset"] = np.zeros_like(s["offset"])
        setting, cv_pq = tune(train, grid, lambda s, g: group_votes(s, *g))
        rec = _record("B0 objectness+DBSCAN", test, lambda s: group_votes(s, *setting), clock, n_scans, setting, cv_pq)
        _print(rec)
        results.append(rec)
    return results


def _print(rec):
    print(
        f"  {rec['design']:<26} test PQ {rec['pq']:.3f} recall {rec['recall']:.3f} precision {rec['precision']:.3f}"
        f" (cv PQ {rec['cv_pq']:.3f}) fit {rec['fit_s']:.1f} s tune {rec['tune_s']:.1f} s"
        f" predict {rec['predict_ms_per_scan']:.2f} ms/scan setting {rec['setting']}",
        flush=True,
    )
    print(f"    test ground-truth segments: {rec['anatomy']}", flush=True)


def run_baselines(preset, seed, options):
    """The object-level ablation's SequenceDBSCAN and object experiment on the same data and split.

    Returns ``{name: (test PQ, anatomy or None)}``; the object experiment's tuned pipeline is applied again to each
    test sequence for its error anatomy (its PQ from these labels is printed as a check).
    """
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import ablation_object_level as ablation

    from sklearn_radar.experiments import object_pipeline

    chosen = [v for v in ablation.variants() if v.name in ("SequenceDBSCAN", "objects (stage 1)", "objects")]
    args = argparse.Namespace(
        n_sequences=options.n_sequences, duration=options.duration, n_iter=options.n_iter, cv_folds=3
    )
    found = ablation.run_one(preset, seed, chosen, args)
    scenes = make_scenes(
        n_sequences=options.n_sequences, duration=options.duration, difficulty=preset, random_state=seed
    )
    target = precluster_target(scenes.data, scenes.target)
    _, test_rows = sequence_train_test_split(scenes.groups, test_size=0.5, random_state=seed)
    pipeline = object_pipeline(2, stage1_params=found["objects (stage 1)"]["params"], params=found["objects"]["params"])
    sequences = []
    for number in np.unique(scenes.groups[test_rows]):
        rows = np.flatnonzero(scenes.groups == number)
        labels = pipeline.fit_predict(scenes.data.iloc[rows])
        t = scenes.data["timestamp"].to_numpy()[rows] * 1e-6
        sequences.append(
            {
                "number": int(number),
                "n_rows": len(rows),
                "keep": np.ones(len(rows), bool),
                "t_all": t,
                "target_all": target[rows],
                "labels": np.asarray(labels),
            }
        )
    check = score(sequences, lambda s: s["labels"]).pq
    print(f"  objects: PQ from the re-applied pipeline {check:.3f} (ablation {found['objects']['pq']:.3f})")
    objects_anatomy = anatomy(sequences, lambda s: s["labels"])
    print(f"    test ground-truth segments: {objects_anatomy}", flush=True)
    return {
        "SequenceDBSCAN": (found["SequenceDBSCAN"]["pq"], None),
        "objects": (found["objects"]["pq"], objects_anatomy),
    }


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", nargs="+", default=["realistic"], choices=["easy", "realistic", "radarscenes"])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--n-sequences", type=int, default=4)
    parser.add_argument("--duration", type=float, default=20.0, help="s per sequence")
    designs = ["A", "A-gaec", "A-mean", "A-mutual", "B"]
    parser.add_argument("--designs", nargs="+", default=["A-mean", "A-mutual", "B"], choices=designs)
    parser.add_argument("--max-iter", type=int, default=150, help="boosting iterations of every learner")
    parser.add_argument("--max-rows", type=int, default=400_000, help="training rows per fit (random subsample)")
    parser.add_argument("--pair-radius", type=float, default=3.0, help="m")
    parser.add_argument("--pair-window", type=float, default=0.25, help="s")
    parser.add_argument("--thresholds", type=float, nargs="+", default=[0.05, 0.15, 0.3, 0.5], help="objectness gates")
    parser.add_argument("--chunks", type=float, nargs="+", default=[0.5, 1.0, 2.0], help="s, linkage chunks")
    parser.add_argument(
        "--cuts", type=float, nargs="+", default=[0.5, 0.6, 0.7, 0.8, 0.85, 0.9, 0.95, 0.98], help="linkage cuts"
    )
    parser.add_argument("--min-sizes", type=int, nargs="+", default=[1, 3, 6, 10, 15, 20])
    parser.add_argument("--vote-control", action="store_true", help="also B's DBSCAN without the shift (B0)")
    parser.add_argument("--baselines", action="store_true", help="also run the ablation's SequenceDBSCAN + objects")
    parser.add_argument("--n-iter", type=int, default=20, help="search iterations of the baselines")
    parser.add_argument("--quick", action="store_true", help="4 x 8 s, 60 boosting iterations, one seed and preset")
    options = parser.parse_args(argv)
    if options.quick:
        options.seeds, options.data = options.seeds[:1], options.data[:1]
        options.duration, options.max_iter, options.max_rows = 8.0, 60, 100_000
    rows = []
    with threadpool_limits(1):
        for preset in options.data:
            for seed in options.seeds:
                print(f"{preset} seed {seed}: {options.n_sequences} x {options.duration:g} s", flush=True)
                for rec in run(preset, seed, options):
                    rows.append((preset, seed, rec))
                if options.baselines:
                    for name, (pq, errors) in run_baselines(preset, seed, options).items():
                        rows.append((preset, seed, {"design": name, "pq": pq, "anatomy": errors}))
    print(f"\n{'design':<26} {'preset':<12} seed  test PQ  recall  precision  fit s  tune s  predict ms/scan")
    for preset, seed, rec in rows:
        if "recall" in rec:
            print(
                f"{rec['design']:<26} {preset:<12} {seed:>4}  {rec['pq']:.3f}    {rec['recall']:.3f}   "
                f"{rec['precision']:.3f}     {rec['fit_s']:5.1f}  {rec['tune_s']:6.1f}  "
                f"{rec['predict_ms_per_scan']:.2f}"
            )
        else:
            print(f"{rec['design']:<26} {preset:<12} {seed:>4}  {rec['pq']:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
