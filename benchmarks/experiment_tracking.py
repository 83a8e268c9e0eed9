"""Tracking measurement (issue #44): the object setting streamed with and without the Tracker, and a baseline tracker.

Per preset (realistic, radarscenes, easy) and seed: ``make_scenes`` of ``--n-sequences`` x ``--duration`` s, split
by ``sequence_train_test_split(random_state=seed)`` as ``benchmarks/ablation_object_level.py`` does.

1. ``--tune``: on the training half, the causal object experiment (``objects causal``: stage 1, then stage 2 on it)
   and SlidingDBSCAN (the baseline's clusterer) tuned for per-frame PQ with the ablation's ``run_one``
   (``--n-iter`` iterations each); their settings are saved in ``--cache``.
2. (default) the tuned object setting is streamed through ``OnlinePipeline`` on both halves, SlidingDBSCAN labels
   both halves (it is causal: each scan from its past window only), and the per-scan clusters are kept; then the
   trackers' few parameters are tuned on the training half for MOTA (a fixed random sample of ``--n-settings``
   settings, the same for every tracker) and the best is scored on the test half with ``tracking_scores`` (MOTA,
   IDF1) and ``hota_scores`` (HOTA, DetA, AssA), per 0.5 s frame, against the moving road users.

Rows of the table, per preset (mean over seeds ± standard error; paired differences with their standard error):

* ``objects (reported)``: the object setting's ids as reported at each scan (OnlinePipeline without a tracker);
* ``objects (final, not causal)``: the same after every alias, which a car never sees (for reference);
* ``oracle: truth on clustered``: the true object ids on the detections the object setting clusters, -1 on its
  noise: a reference for a tracker that labels only the clustered detections (it splits clusters by the truth);
* ``oracle: cluster majority``: each scan's cluster of the object setting labelled with the true object most of
  its detections belong to (-1 when most are background), from the first scan on: a reference for a tracker
  that gives each scan's cluster one id (not a strict bound: withholding a cluster's id can raise MOTA);
* ``objects + Tracker``: :class:`sklearn_radar.online.Tracker` on the reported ids (``noise_radius=None``);
* ``objects + Tracker, noise``: the same with ``noise_radius`` tuned too (noise detections near a confirmed track
  whose Doppler agrees take its id);
* ``SlidingDBSCAN + nearest``: the baseline a user would write (:class:`NearestCentroidTracker` below):
  SlidingDBSCAN's clusters of each scan associated to the tracks' last centroids with the Hungarian method, a gate
  in metres, the same confirmation and deletion rule.  It is a class of this script, not of the library: it is the
  comparison point (no motion model, no Doppler), not a tracker to recommend.

Run (about an hour per preset and 3 seeds on 2 shared cores)::

    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/experiment_tracking.py --tune --data realistic --seeds 0 1 2
    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/experiment_tracking.py --data realistic --seeds 0 1 2
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

from ablation_object_level import run_one, variants
from scipy.optimize import linear_sum_assignment
from sklearn.base import clone

from sklearn_radar import FrameTransform
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import object_pipeline
from sklearn_radar.metrics import hota_scores, tracking_scores
from sklearn_radar.model_selection import sequence_train_test_split
from sklearn_radar.online import OnlinePipeline, Tracker
from sklearn_radar.online._replay import replay
from sklearn_radar.online._scans import scan_order

PRESETS = ("realistic", "radarscenes", "easy")
OBJECTS, SLIDING = "objects causal", "SlidingDBSCAN"


def _cache_file(cache, preset, seed):
    return Path(cache) / f"tuned_{preset}_{seed}.json"


def tune(preset, seed, options):
    """The object setting and SlidingDBSCAN tuned for PQ on the training half; saved in the cache."""
    out = _cache_file(options.cache, preset, seed)
    if out.exists():
        return json.loads(out.read_text())
    wanted = {f"{OBJECTS} (stage 1)", OBJECTS, SLIDING}
    chosen = [v for v in variants() if v.name in wanted]
    found = run_one(preset, seed, chosen, options)
    saved = {name: {k: v for k, v in record.items() if k != "bounds"} for name, record in found.items()}
    Path(options.cache).mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(saved, indent=1))
    return saved


def scenes_of(preset, seed, options):
    """The data set of (preset, seed) and its train / test rows."""
    scenes = make_scenes(
        n_sequences=options.n_sequences, duration=options.duration, difficulty=preset, random_state=seed
    )
    train, test = sequence_train_test_split(scenes.groups, test_size=0.5, random_state=seed)
    return scenes, train, test


class NearestCentroidTracker:
    """The baseline tracker a user would write: each scan's clusters to the tracks' last centroids, Hungarian method.

    No motion model and no Doppler: a track is where its last cluster was.  A cluster within ``gate`` metres of a
    track's last centroid may be assigned to it (one cluster per track, the assignment of least total distance);
    any other cluster starts a tentative track.  The confirmation and deletion rule are the Tracker's:
    confirmed after ``min_hits`` scans with a cluster, ended after ``max_age`` s without one.
    """

    def __init__(self, gate=2.0, min_hits=3, max_age=0.5):
        self.gate, self.min_hits, self.max_age = gate, min_hits, max_age
        self.xy = np.zeros((0, 2))
        self.ids = np.zeros(0, dtype=np.int64)
        self.hits = np.zeros(0, dtype=np.int64)
        self.last = np.zeros(0)
        self.next_id = 0

    def update(self, x, y, v_r, los, t, clusters):
        alive = t - self.last <= self.max_age
        self.xy, self.ids, self.hits, self.last = self.xy[alive], self.ids[alive], self.hits[alive], self.last[alive]
        out = np.full(len(x), -1, dtype=np.int64)
        rows = np.flatnonzero(clusters >= 0)
        if len(rows) == 0:
            return out
        codes, member = np.unique(clusters[rows], return_inverse=True)
        count = np.bincount(member)
        centroid = np.c_[np.bincount(member, x[rows]), np.bincount(member, y[rows])] / count[:, None]
        slot = np.full(len(codes), -1)
        if len(self.ids):
            distance = np.linalg.norm(centroid[:, None, :] - self.xy[None, :, :], axis=2)
            cost = np.where(distance <= self.gate, distance, 1e9)
            r, c = linear_sum_assignment(cost)
            ok = cost[r, c] < 1e9
            slot[r[ok]] = c[ok]
        new = np.flatnonzero(slot < 0)
        if len(new):
            slot[new] = len(self.ids) + np.arange(len(new))
            self.xy = np.r_[self.xy, centroid[new]]
            self.ids = np.r_[self.ids, self.next_id + np.arange(len(new))]
            self.next_id += len(new)
            self.hits = np.r_[self.hits, np.zeros(len(new), dtype=np.int64)]
            self.last = np.r_[self.last, np.zeros(len(new))]
        self.xy[slot] = centroid
        self.hits[slot] += 1
        self.last[slot] = t
        shown = np.where(self.hits[slot] >= self.min_hits, self.ids[slot], -1)
        out[rows] = shown[member]
        return out


def fixed_frame(data):
    """x, y (m, sequence frame), compensated v_r (m/s), line of sight (rad), t (s) of every detection."""
    work = FrameTransform(frame="frame").fit_transform(data)
    los = work["azimuth_sc"] + work["sensor_yaw"] + work["heading"]
    return {name: work[name].to_numpy() for name in ("x", "y", "v_r", "t")} | {"los": los.to_numpy()}


def streamed(preset, seed, tuned, options):
    """Per half: detections (fixed-frame columns, truth, sequence, scan), the object setting's reported ids, its
    confirmed flags and SlidingDBSCAN's labels."""
    scenes, train, test = scenes_of(preset, seed, options)
    objects = object_pipeline(
        2, stage1_params=tuned[f"{OBJECTS} (stage 1)"]["params"], params=tuned[OBJECTS]["params"], causal=True
    )
    sliding_variant = next(v for v in variants() if v.name == SLIDING)
    sliding = clone(sliding_variant.searched).set_params(**tuned[SLIDING]["params"])
    halves = {}
    for half, rows in (("train", train), ("test", test)):
        parts = []
        for sequence in np.unique(scenes.groups[rows]):
            data = scenes.data.iloc[rows[scenes.groups[rows] == sequence]].reset_index(drop=True)
            replayed = replay(OnlinePipeline(objects), data)
            work = clone(sliding_variant.stage0).fit_transform(data)
            part = fixed_frame(data)
            part.update(
                reported=replayed["reported"],
                confirmed=replayed["confirmed"],
                final=replayed["object_ids"],
                sliding=clone(sliding).fit(work)[-1].labels_,
                sequence=np.full(len(data), sequence),
            )
            part["truth"] = scenes.target[rows[scenes.groups[rows] == sequence]]
            parts.append(part)
        halves[half] = parts
    return halves


def majority(part):
    """Each scan's cluster labelled with the true object most of its detections belong to (-1: background)."""
    out = np.full(len(part["t"]), -1, dtype=np.int64)
    clustered = np.flatnonzero(part["reported"] >= 0)
    scan = np.unique(part["t"][clustered], return_inverse=True)[1].ravel()
    key = np.unique(np.c_[scan, part["reported"][clustered]], axis=0, return_inverse=True)[1].ravel()
    truth = part["truth"][clustered]
    pairs, counts = np.unique(np.c_[key, truth], axis=0, return_counts=True)
    order = np.lexsort((-counts, pairs[:, 0]))  # per cluster, its most frequent truth first
    first = order[np.r_[True, np.diff(pairs[order, 0]) != 0]]
    best = np.full(key.max() + 1 if len(key) else 0, -1)
    best[pairs[first, 0]] = pairs[first, 1]
    out[clustered] = best[key]
    return out


def track(parts, make, clusters):
    """Track ids of every detection of ``parts`` (one fresh tracker per sequence), concatenated."""
    out = []
    for part in parts:
        tracker = make()
        ids = np.full(len(part["t"]), -1, dtype=np.int64)
        labels = clusters(part)
        for rows in scan_order({"timestamp": part["t"]}):
            ids[rows] = tracker.update(
                part["x"][rows], part["y"][rows], part["v_r"][rows], part["los"][rows], part["t"][rows[0]], labels[rows]
            )
        out.append(ids)
    return np.concatenate(out)


def scores(parts, ids):
    """MOTA, IDF1, ID switches (tracking_scores) and HOTA, DetA, AssA (hota_scores) of ``ids`` on ``parts``."""
    truth = np.concatenate([p["truth"] for p in parts])
    times = np.concatenate([p["t"] for p in parts])
    groups = np.concatenate([p["sequence"] for p in parts])
    clear = tracking_scores(truth, ids, times=times, groups=groups, window=0.5)
    hota = hota_scores(truth, ids, times=times, groups=groups, window=0.5)
    return {
        "mota": clear["mota"],
        "idf1": clear["idf1"],
        "switches": clear["id_switches"],
        "misses": clear["misses"],
        "fp": clear["false_positives"],
        "objects": clear["n_objects"],
        "hota": hota["hota"],
        "deta": hota["deta"],
        "assa": hota["assa"],
    }


#: The trackers' search spaces: name -> (low, high, kind) with kind "log", "lin" or "int" (log-uniform integer).
TRACKER_SPACE = {
    "gate": (1.0, 8.0, "log"),
    "min_hits": (1, 30, "int"),
    "max_age": (0.1, 2.0, "log"),
    "position_noise": (0.3, 3.0, "log"),
    "doppler_noise": (0.1, 1.0, "log"),
    "acceleration": (0.3, 10.0, "log"),
    "doppler_gate": (0.2, 3.0, "log"),
}
NOISE_SPACE = {**TRACKER_SPACE, "noise_radius": (0.3, 4.0, "log")}
BASELINE_SPACE = {"gate": (0.3, 8.0, "log"), "min_hits": (1, 30, "int"), "max_age": (0.1, 2.0, "log")}


def sample(space, n, seed):
    """``n`` settings drawn from ``space`` (the same ones for a given seed)."""
    rng = np.random.default_rng(seed)
    settings = []
    for _ in range(n):
        setting = {}
        for name, (low, high, kind) in space.items():
            value = math.exp(rng.uniform(math.log(low), math.log(high + (kind == "int"))))
            setting[name] = int(value) if kind == "int" else float(value)
        settings.append(setting)
    return settings


def tuned_tracker(parts, make, clusters, space, n, seed):
    """The setting of ``space`` with the best training MOTA among ``n`` random ones (defaults first)."""
    best = (-np.inf, None)
    for setting in [{}, *sample(space, n, seed)]:
        mota = scores(parts, track(parts, lambda s=setting: make(**s), clusters))["mota"]
        if mota > best[0]:
            best = (mota, setting)
    return best


#: The tracked forms measured: name -> (tracker class, search space, cluster ids fed).
FORMS = {
    "objects + Tracker": (Tracker, TRACKER_SPACE, lambda p: p["reported"]),
    "objects + Tracker, noise": (Tracker, NOISE_SPACE, lambda p: p["reported"]),
    "SlidingDBSCAN + nearest": (NearestCentroidTracker, BASELINE_SPACE, lambda p: p["sliding"]),
}


def measure(preset, seed, tuned, options):
    """Every row's test scores (and the trackers' settings) for one data set."""
    halves = streamed(preset, seed, tuned, options)
    train, test = halves["train"], halves["test"]
    reported = np.concatenate([p["reported"] for p in test])
    truth = np.concatenate([p["truth"] for p in test])
    rows = {
        "objects (reported)": {"scores": scores(test, reported)},
        "objects (final, not causal)": {"scores": scores(test, np.concatenate([p["final"] for p in test]))},
        "oracle: truth on clustered": {"scores": scores(test, np.where(reported >= 0, truth, -1))},
        "oracle: cluster majority": {"scores": scores(test, np.concatenate([majority(p) for p in test]))},
    }
    for name, (kind, space, clusters) in FORMS.items():
        start = time.perf_counter()
        train_mota, setting = tuned_tracker(train, kind, clusters, space, options.n_settings, seed)
        test_ids = track(test, lambda kind=kind, setting=setting: kind(**setting), clusters)
        rows[name] = {"scores": scores(test, test_ids), "setting": setting, "train_mota": train_mota}
        rows[name]["seconds"] = time.perf_counter() - start
    for name, row in rows.items():
        s = row["scores"]
        print(
            f"  {preset} seed {seed} {name:<30} MOTA {s['mota']:.3f} IDF1 {s['idf1']:.3f} HOTA {s['hota']:.3f} "
            f"DetA {s['deta']:.3f} AssA {s['assa']:.3f} sw {s['switches']} miss {s['misses']} fp {s['fp']} "
            f"of {s['objects']}"
            + (
                f" (train MOTA {row['train_mota']:.3f}, {row['seconds']:.0f} s) {json.dumps(row['setting'])}"
                if "setting" in row
                else ""
            ),
            flush=True,
        )
    return rows


def _mean_se(values):
    values = np.asarray(values, dtype=np.float64)
    se = values.std(ddof=1) / math.sqrt(len(values)) if len(values) > 1 else float("nan")
    return float(values.mean()), float(se)


def table(preset, runs):
    """Mean ± standard error over seeds; paired differences to the reported ids and to the baseline tracker."""
    names = list(runs[0])
    lines = [f"\n{preset}: {len(runs)} seed(s), test half; mean ± standard error over seeds"]
    lines.append(f"{'':<30} " + " ".join(f"{m:>15}" for m in ("MOTA", "IDF1", "HOTA", "DetA", "AssA")))
    for name in names:
        cells = [_mean_se([r[name]["scores"][m] for r in runs]) for m in ("mota", "idf1", "hota", "deta", "assa")]
        lines.append(f"{name:<30} " + " ".join(f"{m:.3f} ± {se:.3f}".rjust(15) for m, se in cells))
    for reference in ("objects (reported)", "SlidingDBSCAN + nearest"):
        for name in names:
            if name == reference or "Tracker" not in name:
                continue
            cells = [
                _mean_se([r[name]["scores"][m] - r[reference]["scores"][m] for r in runs])
                for m in ("mota", "idf1", "hota", "deta", "assa")
            ]
            lines.append(
                f"{name + ' - ' + reference.split(' ')[0]:<30} "
                + " ".join(f"{m:+.3f} ± {se:.3f}".rjust(15) for m, se in cells)
            )
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--data", nargs="+", default=list(PRESETS), choices=PRESETS, dest="presets")
    parser.add_argument("--n-sequences", type=int, default=4)
    parser.add_argument("--duration", type=float, default=20.0, help="s per sequence")
    parser.add_argument("--n-iter", type=int, default=15, help="iterations of each PQ search")
    parser.add_argument("--cv-folds", type=int, default=2)
    parser.add_argument("--cache", default="/tmp/tracking_cache", help="folder of the tuned settings")
    parser.add_argument("--tune", action="store_true", help="only tune the clusterings (saved in --cache)")
    parser.add_argument("--n-settings", type=int, default=30, help="random settings tried per tracker")
    options = parser.parse_args(argv)
    tables = []
    for preset in options.presets:
        runs = []
        for seed in options.seeds:
            start = time.perf_counter()
            found = tune(preset, seed, SimpleNamespace(**vars(options)))
            print(f"{preset} seed {seed}: tuned in {time.perf_counter() - start:.0f} s", flush=True)
            if not options.tune:
                runs.append(measure(preset, seed, found, options))
        if runs:
            tables.append(table(preset, runs))
            print(tables[-1], flush=True)
    print("\n".join(tables))
    return 0


if __name__ == "__main__":
    sys.exit(main())
