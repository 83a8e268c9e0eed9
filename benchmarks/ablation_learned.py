"""Ablation of LinkClustering over seeds: grouping designs on the same classifiers, feature groups (issue 42, item 5).

Data, split, target and scoring are those of ``experiment_learned.py`` (``make_scenes`` ``--n-sequences`` x
``--duration`` s, ``sequence_train_test_split(random_state=seed)``, ``metrics.precluster_target``, the test half scored
by ``metrics.panoptic_quality`` in 0.5 s windows).  Variants (each a row of the summary):

**Designs** share one fit of the library default (:class:`~sklearn_radar.cluster.LinkClustering()`; its objectness
and link classifiers, their out-of-fold probabilities of the training half, its candidate pairs) and differ only in
the grouping step, each tuned for PQ on those out-of-fold probabilities over the same (gate, threshold, min size)
grids, as the library tunes its own:

* ``mean-link`` -- the library (greedy mean-link agglomeration over the candidate pairs); its labels are checked
  equal to ``LinkClustering.predict``;
* ``components`` -- connected components of the links above the threshold.  This is also single-linkage (max-link)
  agglomeration cut at that threshold: the two are the same partition, so one row stands for both;
* ``mean-link, old grids`` -- the library's grouping tuned over the grids before they were widened (objectness from
  0.05, min size to 20), on the same classifiers;
* ``average linkage`` -- average linkage (UPGMA) of the same links: the link of two clusters is the sum of P(link)
  over their candidate pairs divided by the product of their sizes (pairs that are no candidates count as 0), as
  scipy's average linkage of the distance 1 - P on the dense matrix (the issue's first prototype); its link grid
  reaches down to 0.0005;
* ``centre voting`` -- two ``HistGradientBoostingRegressor`` (150 iterations) on the detection features predict each
  road-user detection's offset (m) to its instance's centre (the mean position of the instance's detections within
  0.1 s); detections above the objectness gate are moved by the offset and grouped by DBSCAN with ``min_samples=1``
  on the moved points (within ``eps`` m in x-y and 0.1 s); the gate, ``eps`` and the min size tuned the same way on
  out-of-fold offsets and objectness.

**Feature groups** refit the library default with a group of features left out (``no rigid velocity``: every feature
of the local rigid velocity of Eq. 6 and the lines of sight; ``no neighbourhood``: neighbour counts and Doppler
statistics; ``no RCS/range``; ``pairs without objectness``: the pair features ``lo/hi_objectness``).

``old grids, refit`` is the ``learned`` row of the saved ``learned_<preset>_seed<seed>.json`` of
``experiment_learned.py`` (the library before the grids were widened, same data and seed); ``objects`` and
``baseline`` come from the same files.  Each (preset, seed, variant) is saved as
``benchmarks/results/ablation_learned_<preset>_seed<seed>_<variant>.json`` when done; a rerun skips it.
``--summary`` prints per preset the mean test PQ and recall of each variant and its paired difference to the library
default (``mean-link``), mean ± 2 SE over seeds.  ``--fit-time`` times one fit of the default on ``--threads``
threads.

Run (one core, niced)::

    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/ablation_learned.py --phase designs centre
    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/ablation_learned.py --phase features --data realistic
    python benchmarks/ablation_learned.py --summary
"""

from __future__ import annotations

import argparse
import heapq
import json
import math
import sys
import time
from contextlib import contextmanager
from pathlib import Path

import numba
import numpy as np
import pandas as pd
from numba import types
from numba.typed import Dict, List
from threadpoolctl import threadpool_limits

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import bench_link_clustering as bench  # noqa: E402
import experiment_learned as experiment  # noqa: E402
from experiment_learned import _mean_2se  # noqa: E402

from sklearn_radar._labels import consecutive_labels, drop_small_clusters, roots_to_rows  # noqa: E402
from sklearn_radar._validation import read_columns  # noqa: E402
from sklearn_radar.cluster import LinkClustering  # noqa: E402
from sklearn_radar.cluster import _link_clustering as lc  # noqa: E402
from sklearn_radar.cluster._agglomeration import mean_link_merges, roots_at  # noqa: E402
from sklearn_radar.cluster._link_features import DETECTION_FEATURES, PAIR_FEATURES, pairs_within  # noqa: E402
from sklearn_radar.cluster._link_training import fold_of_groups, positive_proba, tune  # noqa: E402
from sklearn_radar.metrics import panoptic_quality  # noqa: E402

RESULTS = HERE / "results"
OLD_OBJECTNESS_GRID = (0.05, 0.15, 0.3, 0.5)
OLD_MIN_SIZE_GRID = (1, 3, 6, 10, 15, 20)
AVERAGE_LINK_GRID = (0.0005, 0.001, 0.002, 0.003, 0.005, 0.01, 0.02, 0.03, 0.05, 0.07, *lc.LINK_GRID)
EPS_GRID = (0.3, 0.5, 0.75, 1.0, 1.5, 2.0)
CENTRE_WINDOW = 0.1  # s: the instance's detections whose mean is the centre, and the time of the voting's DBSCAN
DEFAULT = "mean-link"
DESIGNS = ("mean-link", "components", "mean-link, old grids")
FEATURE_GROUPS = {
    "no rigid velocity": [
        name for table in (DETECTION_FEATURES, PAIR_FEATURES) for name, (_, _, needs) in table.items() if "los" in needs
    ],
    "no neighbourhood": [
        "n_local", "n_near", "n_similar", "n_moving", "mean_abs_v_r", "spread_v_r",
        "lo_n_local", "hi_n_local", "lo_spread_v_r", "hi_spread_v_r",
    ],
    "no RCS/range": ["rcs", "range", "mean_range", "lo_rcs", "hi_rcs"],
    "pairs without objectness": ["lo_objectness", "hi_objectness"],
}  # fmt: skip


# ------------------------------------------------------------------------------------------ grouping designs


def kruskal_merges(n, i, j, p, floor):
    """Single-linkage merges in the form of ``mean_link_merges``: edges by decreasing ``p`` (> floor), union-find."""
    keep = p > floor
    i, j, p = i[keep], j[keep], p[keep]
    order = np.lexsort((j, i, -p))
    return _kruskal(np.int64(n), i[order].astype(np.int64), j[order].astype(np.int64), p[order].astype(np.float64))


@numba.njit(cache=True)
def _kruskal(n, i, j, p):
    parent = np.arange(n)
    child = np.empty(max(n - 1, 0), np.int64)
    survivor = np.empty(max(n - 1, 0), np.int64)
    link = np.empty(max(n - 1, 0), np.float64)
    m = 0
    for e in range(len(i)):
        a = i[e]
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        b = j[e]
        while parent[b] != b:
            parent[b] = parent[parent[b]]
            b = parent[b]
        if a != b:
            a, b = min(a, b), max(a, b)
            parent[b] = a
            child[m], survivor[m], link[m] = b, a, p[e]
            m += 1
    return child[:m].copy(), survivor[:m].copy(), link[:m].copy()


def average_link_merges(n, i, j, p, floor):
    """Average-linkage (UPGMA) merges, in the form of ``mean_link_merges``: the link of two clusters is the sum of
    ``p`` over their candidate pairs divided by the product of their sizes (non-candidate pairs count as p = 0), the
    merges of scipy's average linkage on the dense distance ``1 - p`` (checked on random graphs).  Average linkage
    is reducible, so the links of the merges never increase and ``roots_at`` replays them."""
    i, j, p = np.asarray(i, np.int64), np.asarray(j, np.int64), np.asarray(p, np.float64)
    return _average(np.int64(n), i, j, p, np.float64(floor))


@numba.njit(cache=True)
def _average(n, i, j, p, floor):
    neighbours = List()
    for _ in range(n):
        neighbours.append(Dict.empty(key_type=types.int64, value_type=types.float64))
    for e in range(len(i)):
        neighbours[i[e]][j[e]] = p[e]
        neighbours[j[e]][i[e]] = p[e]
    size = np.ones(n, np.float64)
    version = np.zeros(n, np.int64)
    alive = np.ones(n, np.bool_)
    heap = [(0.0, np.int64(0), np.int64(0), np.int64(0), np.int64(0))]
    heap.pop()
    for e in range(len(i)):
        if p[e] > floor:
            heap.append((-p[e], min(i[e], j[e]), max(i[e], j[e]), np.int64(0), np.int64(0)))
    heapq.heapify(heap)
    child = np.empty(max(n - 1, 0), np.int64)
    survivor = np.empty(max(n - 1, 0), np.int64)
    link = np.empty(max(n - 1, 0), np.float64)
    m = 0
    while len(heap):
        negative, a, b, va, vb = heapq.heappop(heap)
        if not (alive[a] and alive[b]) or version[a] != va or version[b] != vb:
            continue
        if len(neighbours[a]) < len(neighbours[b]):
            a, b = b, a
        alive[b] = False
        child[m], survivor[m], link[m] = b, a, -negative
        m += 1
        nb = neighbours[b]
        na = neighbours[a]
        del na[b]
        for c, s in nb.items():
            if c == a:
                continue
            nc = neighbours[c]
            del nc[b]
            if c in na:
                na[c] += s
            else:
                na[c] = s
            nc[a] = na[c]
        nb.clear()
        size[a] += size[b]
        version[a] += 1
        for c, s in na.items():
            value = s / (size[a] * size[c])
            if value > floor:
                lo, hi = min(a, c), max(a, c)
                heapq.heappush(heap, (-value, lo, hi, version[lo], version[hi]))
    return child[:m].copy(), survivor[:m].copy(), link[:m].copy()


MERGES = {
    "mean-link": mean_link_merges,
    "components": kruskal_merges,
    "mean-link, old grids": mean_link_merges,
    "average linkage": average_link_merges,
}


def label_merges(model, test_parts, n_rows, setting, merges_fn):
    """Test labels of one design from the fitted classifiers' probabilities (``_labels`` with the merges swapped)."""
    threshold, gate, size = setting
    roots = np.full(n_rows, -1, dtype=np.int64)
    for s, objectness, i, j, links in test_parts:
        node = objectness > gate
        both = node[i] & node[j]
        merged = merges_fn(len(s.rows), i[both], j[both], links[both], threshold)
        local = drop_small_clusters(np.where(node, roots_at(len(s.rows), *merged, threshold), -1), size)
        roots_to_rows(s.rows, local, roots)
    return consecutive_labels(roots)


def test_parts(model, test):
    """Per test sequence: the sequence, objectness of every kept detection, all pairs above the lowest gate, links."""
    _, c = read_columns(model, test, lc.LINK_READS, reset=False)
    det_cols = np.flatnonzero(np.isin(list(DETECTION_FEATURES), model.detection_feature_names_))
    pair_cols = np.flatnonzero(np.isin(list(PAIR_FEATURES), model.pair_feature_names_))
    floor = min(min(lc.OBJECTNESS_GRID), OLD_OBJECTNESS_GRID[0])
    parts = []
    for s in lc._sequences(c):
        objectness = positive_proba(model.objectness_classifier_, s.features[:, det_cols])
        i, j = model._pairs(s, objectness > floor)
        features = lc.pair_features(s.detections, s.local, objectness, i, j)[:, pair_cols]
        parts.append((s, objectness, i, j, positive_proba(model.link_classifier_, features)))
    return parts


def fit_capturing(train, y_train, threads, **params):
    """The library default fitted, and what its tuning saw (out-of-fold probabilities, pairs), and its fit seconds."""
    seen = {}
    original = lc.tune

    def spy(*args):
        seen["args"] = args
        return original(*args)

    lc.tune = spy
    try:
        model = LinkClustering(n_jobs=threads, **params)
        start = time.perf_counter()
        model.fit(train, y_train)
        seconds = time.perf_counter() - start
    finally:
        lc.tune = original
    return model, seen["args"], seconds


# ------------------------------------------------------------------------------------------ centre voting


def centre_offsets(s, y_rows):
    """Offset (m) of each road-user detection to its instance's centre (mean x-y within CENTRE_WINDOW s); NaN else."""
    d = s.detections
    offset = np.full((len(y_rows), 2), np.nan)
    for instance in np.unique(y_rows[y_rows >= 0]):
        rows = np.flatnonzero(y_rows == instance)
        rows = rows[np.argsort(d.t[rows], kind="stable")]
        t = d.t[rows]
        cx = np.concatenate([[0.0], np.cumsum(d.x[rows])])
        cy = np.concatenate([[0.0], np.cumsum(d.y[rows])])
        lo = np.searchsorted(t, t - CENTRE_WINDOW, side="left")
        hi = np.searchsorted(t, t + CENTRE_WINDOW, side="right")
        count = hi - lo
        offset[rows, 0] = (cx[hi] - cx[lo]) / count - d.x[rows]
        offset[rows, 1] = (cy[hi] - cy[lo]) / count - d.y[rows]
    return offset


def fit_regressors(X, target, max_iter, seed):
    from sklearn.ensemble import HistGradientBoostingRegressor

    return [
        HistGradientBoostingRegressor(max_iter=max_iter, early_stopping=len(X) > 10_000, random_state=seed).fit(
            X, target[:, k]
        )
        for k in range(2)
    ]


def vote_roots(s, objectness, offset, gate, eps):
    """Roots of the detections above ``gate``, moved by ``offset``: components within ``eps`` m and 0.1 s."""
    d = s.detections
    node = objectness > gate
    i, j = pairs_within(d.x + offset[:, 0], d.y + offset[:, 1], d.t, eps, CENTRE_WINDOW, node)
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n = len(s.rows)
    _, component = connected_components(coo_matrix((np.ones(len(i)), (i, j)), shape=(n, n)), directed=False)
    first = np.full(n, n, dtype=np.int64)
    np.minimum.at(first, component, np.arange(n))  # name each component by its smallest detection
    return np.where(node, first[component], -1)


def run_centre(model, seen, test, y_test, times, groups, seed):
    sequences, objectness, _, _, grids, c, y, window = seen
    det_cols = np.flatnonzero(np.isin(list(DETECTION_FEATURES), model.detection_feature_names_))
    features = [s.features[:, det_cols] for s in sequences]
    offsets = [centre_offsets(s, y[s.rows]) for s in sequences]
    folds = fold_of_groups([np.full(len(s.rows), k, np.int64) for k, s in enumerate(sequences)], model.cv)
    X, T, F = np.concatenate(features), np.concatenate(offsets), np.concatenate(folds)
    labelled = ~np.isnan(T[:, 0])
    start = time.perf_counter()
    oof = np.zeros_like(T)
    for k in np.unique(F):
        fitted = fit_regressors(X[labelled & (F != k)], T[labelled & (F != k)], model.max_iter, seed)
        oof[F == k] = np.column_stack([r.predict(X[F == k]) for r in fitted])
    final = fit_regressors(X[labelled], T[labelled], model.max_iter, seed)
    fit_s = time.perf_counter() - start
    oof_parts = np.split(oof, np.cumsum([len(s.rows) for s in sequences])[:-1])
    n_rows = len(y)
    group_of = np.zeros(n_rows) if c["sequence"] is None else c["sequence"]
    best, best_score = None, -1.0
    for gate in grids[1]:
        for eps in EPS_GRID:
            roots = np.full(n_rows, -1, dtype=np.int64)
            for s, p, o in zip(sequences, objectness, oof_parts, strict=True):
                roots_to_rows(s.rows, vote_roots(s, p, o, gate, eps), roots)
            for size in grids[2]:
                score = panoptic_quality(
                    y, drop_small_clusters(roots, size), times=c["t"], groups=group_of, window=window
                ).pq
                if score > best_score:
                    best, best_score = (eps, gate, size), score
    eps, gate, size = best
    roots = np.full(len(y_test), -1, dtype=np.int64)
    for s, objectness_test, *_ in test_parts(model, test):
        X_test = s.features[:, det_cols]
        offset = np.column_stack([r.predict(X_test) for r in final])
        roots_to_rows(s.rows, drop_small_clusters(vote_roots(s, objectness_test, offset, gate, eps), size), roots)
    record = experiment._scores("centre voting", consecutive_labels(roots), y_test, times, groups)
    record.update(
        cv_pq=best_score, fit_s=fit_s, params={"eps": eps, "objectness_threshold": gate, "min_cluster_size": size}
    )
    return [record]


# ------------------------------------------------------------------------------------------ variants


def run_designs(model, seen, fit_s, test, y_test, times, groups, designs=DESIGNS):
    sequences, objectness, pairs, links, grids, c, y, window = seen
    parts = test_parts(model, test)
    records = []
    for design in designs:
        design_grids = grids
        if design == "mean-link, old grids":
            design_grids = (grids[0], OLD_OBJECTNESS_GRID, OLD_MIN_SIZE_GRID)
        elif design == "average linkage":  # its links are diluted by the pairs that are no candidates: lower ones
            design_grids = (AVERAGE_LINK_GRID, grids[1], grids[2])
        start = time.perf_counter()
        setting, score = tune(sequences, objectness, pairs, links, design_grids, c, y, window, MERGES[design])
        tune_s = time.perf_counter() - start
        labels = label_merges(model, parts, len(y_test), setting, MERGES[design])
        if design == DEFAULT:
            library = (model.link_threshold_, model.objectness_threshold_, model.min_cluster_size_)
            if setting != library or not math.isclose(score, model.cv_score_):
                raise RuntimeError(f"mean-link tuned {setting} ({score}), the library {library} ({model.cv_score_})")
            if not np.array_equal(labels, model.predict(test)):
                raise RuntimeError("mean-link labels differ from LinkClustering.predict")
        record = experiment._scores(design, labels, y_test, times, groups)
        record.update(
            cv_pq=score,
            fit_s=fit_s if design == DEFAULT else tune_s,
            params={"link_threshold": setting[0], "objectness_threshold": setting[1], "min_cluster_size": setting[2]},
        )
        records.append(record)
    return records


@contextmanager
def without_features(name):
    """While it lasts, LinkClustering fits (and predicts) without the features of ``FEATURE_GROUPS[name]``."""
    original, dropped = lc.usable, list(FEATURE_GROUPS[name])
    lc.usable = lambda table, present: original(table, present) & ~np.isin(list(table), dropped)
    try:
        yield
    finally:
        lc.usable = original


def run_features(name, train, y_train, test, y_test, times, groups, threads):
    with without_features(name):
        model, _, fit_s = fit_capturing(train, y_train, threads)
        labels = model.predict(test)
    record = experiment._scores(name, labels, y_test, times, groups)
    record.update(
        cv_pq=model.cv_score_,
        fit_s=fit_s,
        params={
            "link_threshold": model.link_threshold_,
            "objectness_threshold": model.objectness_threshold_,
            "min_cluster_size": model.min_cluster_size_,
        },
    )
    return [record]


def _path(directory, preset, seed, variant):
    return directory / f"ablation_learned_{preset}_seed{seed}_{variant.replace(' ', '_').replace('/', '_')}.json"


def run_seed(preset, seed, phases, options):
    """Every missing variant of ``phases`` on one preset and seed, each saved when done."""
    wanted = []
    if "designs" in phases:
        wanted.append("designs")
    if "features" in phases and preset in options.feature_presets:
        wanted += list(FEATURE_GROUPS)
    if "centre" in phases:
        wanted.append("centre voting")
    if "average" in phases:
        wanted.append("average linkage")
    wanted = [v for v in wanted if not _path(options.results, preset, seed, v).exists()]
    if not wanted:
        return
    (train, y_train), (test, y_test) = bench.load(preset, seed, options.n_sequences, options.duration)
    times, groups = test["t"].to_numpy(), test["sequence"].to_numpy()
    model = seen = None
    for variant in wanted:
        print(f"{preset} seed {seed}: {variant}", flush=True)
        with threadpool_limits(options.threads):
            if variant in ("designs", "centre voting", "average linkage") and model is None:
                model, seen, fit_s = fit_capturing(train, y_train, options.threads)
            if variant == "designs":
                records = run_designs(model, seen, fit_s, test, y_test, times, groups)
            elif variant == "average linkage":
                records = run_designs(model, seen, fit_s, test, y_test, times, groups, designs=("average linkage",))
            elif variant == "centre voting":
                records = run_centre(model, seen, test, y_test, times, groups, seed)
            else:
                records = run_features(variant, train, y_train, test, y_test, times, groups, options.threads)
        for r in records:
            r.update(preset=preset, seed=seed, variant=r["method"])
            print(f"  {r['method']:<26} test PQ {r['pq']:.3f} recall {r['recall']:.3f} (cv {r['cv_pq']:.3f}) "
                  f"{r['params']} {r['fit_s']:.0f} s", flush=True)  # fmt: skip
        _path(options.results, preset, seed, variant).write_text(json.dumps(records, indent=1, default=float))


# ------------------------------------------------------------------------------------------ summary


def summary(directory):
    rows = []
    for path in sorted(directory.glob("ablation_learned_*.json")):
        rows.extend(json.loads(path.read_text()))
    for path in sorted(directory.glob("learned_*_seed*.json")):
        if path.name.startswith("learned_causal_"):
            continue  # (the causal rows are experiment_learned's, not the offline ones this table pairs with)
        for r in json.loads(path.read_text()):
            name = {"learned": "old grids, refit", "objects": "objects", "baseline": "baseline"}[r["method"]]
            rows.append({**r, "method": name})
    if not rows:
        print(f"no results in {directory}")
        return None
    table = pd.DataFrame([{k: r[k] for k in ("preset", "seed", "method", "pq", "recall", "fit_s")} for r in rows])
    order = [*DESIGNS, "average linkage", "centre voting", *FEATURE_GROUPS, "old grids, refit", "objects", "baseline"]
    for preset in ("easy", "realistic", "radarscenes"):
        part = table[table.preset == preset]
        if not (part.method == DEFAULT).any():
            continue
        pq = part.pivot(index="seed", columns="method", values="pq")
        recall = part.pivot(index="seed", columns="method", values="recall")
        default = pq[DEFAULT].dropna()
        print(f"\n{preset}: test PQ over seeds {', '.join(str(s) for s in default.index)} (library default: {DEFAULT})")
        print(f"{'variant':<26} {'seeds':>5} {'PQ':>6} {'recall':>6} {'fit s':>6}  paired difference to {DEFAULT}")
        for method in order:
            if method not in pq:
                continue
            both = pq[list(dict.fromkeys([DEFAULT, method]))].dropna()
            fit = part[part.method == method].fit_s.mean()
            difference = _mean_2se(both[method] - both[DEFAULT]) if method != DEFAULT else ""
            print(
                f"{method:<26} {len(both):>5} {both[method].mean():6.3f} {recall.loc[both.index, method].mean():6.3f} "
                f"{fit:6.0f}  {difference}"
            )
        if {"objects", "baseline"} <= set(pq):
            both = pq[[DEFAULT, "objects", "baseline"]].dropna()
            best = np.maximum(both.objects, both.baseline)
            print(
                f"{DEFAULT} - objects: {_mean_2se(both[DEFAULT] - both.objects)}; {DEFAULT} - max(objects, baseline): "
                f"{_mean_2se(both[DEFAULT] - best)} ({len(both)} seeds)"
            )
        missed = {m: _missed(rows, preset, m, default.index) for m in (DEFAULT, "old grids, refit", "objects")}
        missed = {m: v for m, v in missed.items() if v is not None}
        if DEFAULT in missed and "objects" in missed:
            print(
                "missed segments (sums over those seeds): "
                + ", ".join(f"{m} {v}" for m, v in missed.items())
                + f"; {DEFAULT} against objects {missed[DEFAULT] / missed['objects'] - 1:+.1%}"
            )
    return table


def rst_table(table):
    """The summary as a reStructuredText list-table: mean test PQ per variant and preset, and the paired difference
    to the default (mean ± 2 SE, seeds in brackets when fewer than the default's)."""
    presets = [
        p for p in ("easy", "realistic", "radarscenes") if ((table.preset == p) & (table.method == DEFAULT)).any()
    ]
    order = [*DESIGNS, "average linkage", "centre voting", *FEATURE_GROUPS, "old grids, refit", "objects", "baseline"]
    lines = [".. list-table::", "   :header-rows: 1", "", "   * - variant"] + [f"     - {p}" for p in presets]
    for method in order:
        cells = []
        for preset in presets:
            pq = table[table.preset == preset].pivot(index="seed", columns="method", values="pq")
            if method not in pq:
                cells.append("not run")
                continue
            both = pq[list(dict.fromkeys([DEFAULT, method]))].dropna()
            cell = f"{both[method].mean():.3f}"
            if method != DEFAULT:
                cell += f" ({_mean_2se(both[method] - both[DEFAULT])})"
            if len(both) < len(pq[DEFAULT].dropna()):
                cell += f" [{len(both)} seeds]"
            cells.append(cell)
        if any(cell != "not run" for cell in cells):
            lines += [f"   * - {method}"] + [f"     - {cell}" for cell in cells]
    return "\n".join(lines)


def _missed(rows, preset, method, seeds):
    """Missed test segments of ``method`` summed over ``seeds``; None when a seed lacks it."""
    found = {r["seed"]: r["errors"]["missed"] for r in rows if r["preset"] == preset and r["method"] == method}
    if not set(seeds) <= set(found):
        return None
    return int(sum(found[s] for s in seeds))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    presets = ["easy", "realistic", "radarscenes"]
    parser.add_argument("--data", nargs="+", default=["realistic", "easy", "radarscenes"], choices=presets)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("--phase", nargs="+", default=["designs"], choices=["designs", "features", "centre", "average"])
    parser.add_argument("--feature-presets", nargs="+", default=["realistic"], choices=presets)
    parser.add_argument("--n-sequences", type=int, default=4)
    parser.add_argument("--duration", type=float, default=20.0, help="s per sequence")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--results", type=Path, default=RESULTS)
    parser.add_argument("--summary", action="store_true", help="only print the tables of the saved results")
    parser.add_argument("--rst", action="store_true", help="with --summary: also print the table for the user guide")
    parser.add_argument("--fit-time", action="store_true", help="time one fit of the default (realistic, seed 0)")
    options = parser.parse_args(argv)
    if options.fit_time:
        (train, y_train), _ = bench.load("realistic", 0, options.n_sequences, options.duration)
        with threadpool_limits(options.threads):
            start, cpu = time.perf_counter(), time.process_time()
            LinkClustering(n_jobs=options.threads).fit(train, y_train)
        print(f"fit of the default on {len(train)} detections, {options.threads} threads: "
              f"{time.perf_counter() - start:.1f} s wall, {time.process_time() - cpu:.1f} s CPU")  # fmt: skip
        return 0
    if not options.summary:
        options.results.mkdir(parents=True, exist_ok=True)
        for preset in options.data:  # the phases of one preset and seed together: one fit of the default for all
            for seed in options.seeds:
                run_seed(preset, seed, set(options.phase), options)
    table = summary(options.results)
    if options.rst and table is not None:
        print(rst_table(table))
    return 0


if __name__ == "__main__":
    sys.exit(main())
