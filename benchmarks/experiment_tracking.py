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
* ``learned causal (reported)``: the learned grouping's causal model (``learned_pipeline`` with ``link__causal`` and
  ``filter__causal``, ``LEARNED_CAUSAL_PARAMS``: what the main job's learned step fits), fitted on the training half
  with the pre-clustered instance target (``precluster_target``, as ``experiment_learned.py``), streamed through
  ``OnlinePipeline``, its ids as reported at each scan;
* ``learned causal + Tracker``: the Tracker on those ids, its parameters tuned on the training half's learned ids
  the same way as ``objects + Tracker`` (those ids are in-sample: the model was fitted on that half);
* ``learned causal + Tracker, out-of-fold``: the same Tracker on the same test ids, its parameters tuned instead on
  out-of-fold ids of the training half: each training sequence streamed by a model fitted on the other training
  sequences (like the test half, ids of a model that never saw the sequence; one sequence fewer to learn from);
* ``objects, confirmed + Tracker`` and ``learned causal, confirmed + Tracker``: the Tracker fed only the detections
  whose cluster is confirmed at their scan (``min_cluster_size`` reached; what ``OnlinePipeline`` feeds its Tracker
  with the learned grouping), tuned the same way (``..., noise``: with ``noise_radius`` tuned too; ``..., out-of-fold``:
  tuned on the out-of-fold models' confirmed ids of the training half);
* ``learned causal + objects' Tracker``: the Tracker at ``objects + Tracker``'s setting (what the main job does);
* ``SlidingDBSCAN + nearest``: the baseline a user would write (the main job's baseline tracker,
  ``reproduce/_baseline_tracker.py``): SlidingDBSCAN's clusters of each scan associated to the tracks' last centroids
  with the Hungarian method, a gate in metres, the same confirmation and deletion rule.  It lives with the runner,
  not in the library: it is the comparison point (no motion model, no Doppler), not a tracker to recommend.

Besides, per seed, the causal per-frame PQ (``panoptic_quality`` on the streamed final ids, 0.5 s windows, against
the pre-clustered target, as ``experiment_learned.py`` scores) of the learned stream, the object setting's stream and
SlidingDBSCAN on the test half, and its paired differences.

Run (about an hour per preset and 3 seeds on 2 shared cores)::

    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/experiment_tracking.py --tune --data realistic --seeds 0 1 2
    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/experiment_tracking.py --data realistic --seeds 0 1 2

``--pq-only`` measures the causal PQ alone (no trackers, no out-of-fold models, the training half not streamed);
``--without-sliding`` neither tunes nor streams SlidingDBSCAN (its tuning is most of a seed's time).  Tuned
settings are cached per preset and seed only: give data of another size its own ``--cache``.

``--learned-param link__pair_window=0.5`` (repeatable) fits a variant of the main job's causal model;
``--drop-feature-group 'no rigid velocity'`` fits it without a feature group of ``ablation_learned.py`` (the stream
then computes only the features the model was fitted with).

``--form 'learned causal, confirmed + Tracker'`` (repeatable) tunes and scores only the tracked forms named (the
untracked rows and the causal PQ are always measured).

``--save FOLDER`` writes each seed's rows as ``tracking_<preset>_<seed>.json`` (seeds may then run as separate
processes); ``--summary --save FOLDER`` prints the tables of the saved rows.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from contextlib import nullcontext
from pathlib import Path
from types import SimpleNamespace

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

from ablation_learned import without_features
from ablation_object_level import run_one, variants
from sklearn.base import clone

from sklearn_radar import FrameTransform
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import object_pipeline
from sklearn_radar.experiments._learned import learned_pipeline
from sklearn_radar.metrics import hota_scores, panoptic_quality, precluster_target, tracking_scores
from sklearn_radar.model_selection import sequence_train_test_split
from sklearn_radar.online import OnlinePipeline, Tracker
from sklearn_radar.online._replay import replay
from sklearn_radar.online._scans import scan_order
from sklearn_radar.reproduce._baseline_tracker import NearestCentroidTracker as BaselineTracker
from sklearn_radar.reproduce._learned import LEARNED_CAUSAL_PARAMS

PRESETS = ("realistic", "radarscenes", "easy")
#: The learned step's causal model (``reproduce/_learned.py``: LEARNED_CAUSAL_PARAMS, the window, causal front).
LEARNED_CAUSAL = {**LEARNED_CAUSAL_PARAMS, "link__window": 0.5, "link__causal": True, "filter__causal": True}
#: The label columns, which the learned model is not given.
LABEL_COLUMNS = ("uuid", "track_id", "label_id")
OBJECTS, SLIDING = "objects causal", "SlidingDBSCAN"


def _cache_file(cache, preset, seed):
    return Path(cache) / f"tuned_{preset}_{seed}.json"


def tune(preset, seed, options):
    """The object setting and SlidingDBSCAN tuned for PQ on the training half; saved in the cache."""
    out = _cache_file(options.cache, preset, seed)
    if out.exists():
        return json.loads(out.read_text())
    wanted = {f"{OBJECTS} (stage 1)", OBJECTS} | (set() if options.without_sliding else {SLIDING})
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


class NearestCentroidTracker(BaselineTracker):
    """The main job's baseline tracker (nearest centroid, Hungarian method), called as the Tracker is called."""

    def update(self, x, y, v_r, los, t, clusters):
        return super().update(x, y, t, clusters)


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
    sliding = None  # not measured: --without-sliding
    if not options.without_sliding:
        if SLIDING not in tuned:
            raise ValueError(f"{_cache_file(options.cache, preset, seed)} has no SlidingDBSCAN: give --without-sliding")
        sliding = clone(sliding_variant.searched).set_params(**tuned[SLIDING]["params"])
    instances = precluster_target(scenes.data, scenes.target)
    inputs = scenes.data[[c for c in scenes.data.columns if c not in LABEL_COLUMNS]]
    changed = dict(options.learned_params or ())  # --learned-param: a variant of the main job's model
    learned = learned_pipeline({**LEARNED_CAUSAL, "link__random_state": seed, "link__n_jobs": 1, **changed})
    start = time.perf_counter()
    with nullcontext() if options.drop_feature_group is None else without_features(options.drop_feature_group):
        learned.fit(inputs.iloc[train].reset_index(drop=True), instances[train])
    print(f"  {preset} seed {seed}: learned causal model fitted in {time.perf_counter() - start:.0f} s", flush=True)
    out_of_fold = {}  # training sequence -> the model fitted on the other training sequences
    for sequence in [] if options.pq_only else np.unique(scenes.groups[train]):
        others = train[scenes.groups[train] != sequence]
        if len(others):
            out_of_fold[sequence] = clone(learned).fit(inputs.iloc[others].reset_index(drop=True), instances[others])
    halves = {}
    for half, rows in (("train", train), ("test", test)):
        if options.pq_only and half == "train":  # the trackers' tuning is all it serves
            continue
        parts = []
        for sequence in np.unique(scenes.groups[rows]):
            data = scenes.data.iloc[rows[scenes.groups[rows] == sequence]].reset_index(drop=True)
            replayed = replay(OnlinePipeline(objects), data)
            learned_ids = replay(OnlinePipeline(learned), data)
            part = fixed_frame(data)
            part.update(
                reported=replayed["reported"],
                confirmed=replayed["confirmed"],
                final=replayed["object_ids"],
                sequence=np.full(len(data), sequence),
                learned=learned_ids["reported"],
                learned_confirmed=learned_ids["followed"],  # what the pipeline's own Tracker follows
                learned_final=learned_ids["object_ids"],
            )
            if sliding is not None:
                part["sliding"] = clone(sliding).fit(clone(sliding_variant.stage0).fit_transform(data))[-1].labels_
            if half == "train":  # the ids of a model that did not see this sequence (what the test half gets;
                model = out_of_fold.get(sequence, learned)  # a lone training sequence has none: the final model's)
                replayed_oof = replay(OnlinePipeline(model), data)
                part["learned_oof"], part["learned_oof_followed"] = replayed_oof["reported"], replayed_oof["followed"]
            part["truth"] = scenes.target[rows[scenes.groups[rows] == sequence]]
            part["instances"] = instances[rows[scenes.groups[rows] == sequence]]
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
    truth = np.concatenate([p["truth"] for p in parts])
    times = np.concatenate([p["t"] for p in parts])
    groups = np.concatenate([p["sequence"] for p in parts])
    for setting in [{}, *sample(space, n, seed)]:
        ids = track(parts, lambda s=setting: make(**s), clusters)
        mota = tracking_scores(truth, ids, times=times, groups=groups, window=0.5)["mota"]  # no HOTA: not needed
        if mota > best[0]:
            best = (mota, setting)
    return best


#: The tracked forms measured: name -> (tracker class, search space, cluster ids fed[, the training half's ids the
#: tracker is tuned on, when not those]).
FORMS = {
    "objects + Tracker": (Tracker, TRACKER_SPACE, lambda p: p["reported"]),
    "objects + Tracker, noise": (Tracker, NOISE_SPACE, lambda p: p["reported"]),
    "objects, confirmed + Tracker": (Tracker, TRACKER_SPACE, lambda p: np.where(p["confirmed"], p["reported"], -1)),
    "learned causal + Tracker": (Tracker, TRACKER_SPACE, lambda p: p["learned"]),
    "learned causal + Tracker, out-of-fold": (
        Tracker,
        TRACKER_SPACE,
        lambda p: p["learned"],
        lambda p: p["learned_oof"],
    ),
    "learned causal, confirmed + Tracker": (Tracker, TRACKER_SPACE, lambda p: p["learned_confirmed"]),
    "learned causal, confirmed + Tracker, noise": (Tracker, NOISE_SPACE, lambda p: p["learned_confirmed"]),
    "learned causal, confirmed + Tracker, out-of-fold": (
        Tracker,
        TRACKER_SPACE,
        lambda p: p["learned_confirmed"],
        lambda p: p["learned_oof_followed"],
    ),
    "SlidingDBSCAN + nearest": (NearestCentroidTracker, BASELINE_SPACE, lambda p: p["sliding"]),
}
#: The streams whose causal per-frame PQ is measured: name -> their final ids (or labels) on a part.
PQ_STREAMS = {
    "learned causal": lambda p: p["learned_final"],
    "objects causal": lambda p: p["final"],
    "SlidingDBSCAN": lambda p: p["sliding"],
}


def causal_pq(parts, without=()):
    """Per-frame PQ (0.5 s windows) of each of :data:`PQ_STREAMS` but ``without`` on ``parts``, against the
    pre-clustered target."""
    target = np.concatenate([p["instances"] for p in parts])
    times = np.concatenate([p["t"] for p in parts])
    groups = np.concatenate([p["sequence"] for p in parts])
    return {
        name: float(
            panoptic_quality(target, np.concatenate([ids(p) for p in parts]), times=times, groups=groups, window=0.5).pq
        )
        for name, ids in PQ_STREAMS.items()
        if name not in without
    }


def measure(preset, seed, tuned, options):
    """Every row's test scores (and the trackers' settings) for one data set."""
    halves = streamed(preset, seed, tuned, options)
    test = halves["test"]
    if options.pq_only:
        pq = causal_pq(test, without=(SLIDING,) if options.without_sliding else ())
        print(f"  {preset} seed {seed} causal PQ, test half: " + ", ".join(f"{k} {v:.3f}" for k, v in pq.items()))
        return {"_pq": pq}
    train = halves["train"]
    reported = np.concatenate([p["reported"] for p in test])
    truth = np.concatenate([p["truth"] for p in test])
    rows = {
        "objects (reported)": {"scores": scores(test, reported)},
        "objects (final, not causal)": {"scores": scores(test, np.concatenate([p["final"] for p in test]))},
        "oracle: truth on clustered": {"scores": scores(test, np.where(reported >= 0, truth, -1))},
        "oracle: cluster majority": {"scores": scores(test, np.concatenate([majority(p) for p in test]))},
        "learned causal (reported)": {"scores": scores(test, np.concatenate([p["learned"] for p in test]))},
    }
    for name, (kind, space, clusters, *tuned_on) in FORMS.items():
        if options.forms and name not in options.forms:
            continue
        start = time.perf_counter()
        train_clusters = tuned_on[0] if tuned_on else clusters
        train_mota, setting = tuned_tracker(train, kind, train_clusters, space, options.n_settings, seed)
        test_ids = track(test, lambda kind=kind, setting=setting: kind(**setting), clusters)
        rows[name] = {"scores": scores(test, test_ids), "setting": setting, "train_mota": train_mota}
        rows[name]["seconds"] = time.perf_counter() - start
    if "objects + Tracker" in rows:
        setting = rows["objects + Tracker"]["setting"]
        ids = track(test, lambda: Tracker(**setting), lambda p: p["learned"])
        rows["learned causal + objects' Tracker"] = {"scores": scores(test, ids)}
    pq = causal_pq(test)
    print(f"  {preset} seed {seed} causal PQ, test half: " + ", ".join(f"{k} {v:.3f}" for k, v in pq.items()))
    rows["_pq"] = pq
    for name, row in rows.items():
        if name == "_pq":
            continue
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
    """Mean ± standard error over seeds; paired differences (mean ± standard error) to the reported ids, the baseline
    tracker and, for the learned grouping, the tracked object setting; the causal PQ of the streams."""
    names = [name for name in runs[0] if name != "_pq"]
    metrics = ("mota", "idf1", "hota", "deta", "assa")
    lines = [f"\n{preset}: {len(runs)} seed(s), test half; mean ± standard error over seeds"]
    if names:  # not --pq-only
        lines.append(f"{'':<36} " + " ".join(f"{m:>15}" for m in ("MOTA", "IDF1", "HOTA", "DetA", "AssA")))
    for name in names:
        cells = [_mean_se([r[name]["scores"][m] for r in runs]) for m in metrics]
        lines.append(f"{name:<36} " + " ".join(f"{m:.3f} ± {se:.3f}".rjust(15) for m, se in cells))
    references = (
        "objects (reported)",
        "SlidingDBSCAN + nearest",
        "objects + Tracker",
        "learned causal + Tracker",
        "learned causal, confirmed + Tracker",
    )
    for reference in references:
        for name in names:
            if name == reference or "Tracker" not in name or reference not in runs[0]:
                continue
            if reference == "objects + Tracker" and not name.startswith("learned"):
                continue
            if reference.startswith("learned") and name != f"{reference}, out-of-fold":  # tuned on which ids
                continue
            cells = [_mean_se([r[name]["scores"][m] - r[reference]["scores"][m] for r in runs]) for m in metrics]
            short = "in-sample" if reference.startswith("learned") else reference.split(" ")[0]
            label = f"{name} - {short}{' + Tracker' if reference.endswith('Tracker') else ''}"
            lines.append(f"{label:<36} " + " ".join(f"{m:+.3f} ± {se:.3f}".rjust(15) for m, se in cells))
    for name in names:
        lines.append(
            f"  per seed {name}: "
            + "; ".join(" ".join(f"{r[name]['scores'][m]:.3f}" for m in ("mota", "idf1", "hota")) for r in runs)
        )
    if all("_pq" in r for r in runs):
        lines.append("causal per-frame PQ, test half (mean ± standard error; per seed)")
        measured = [name for name in PQ_STREAMS if all(name in r["_pq"] for r in runs)]
        for name in measured:
            mean, se = _mean_se([r["_pq"][name] for r in runs])
            per_seed = ", ".join(f"{r['_pq'][name]:.3f}" for r in runs)
            lines.append(f"  {name:<34} {mean:.3f} ± {se:.3f}  ({per_seed})")
        for other in [name for name in measured if name != "learned causal"]:
            mean, se = _mean_se([r["_pq"]["learned causal"] - r["_pq"][other] for r in runs])
            lines.append(f"  learned causal - {other:<17} {mean:+.3f} ± {se:.3f}")
    return "\n".join(lines)


def _learned_param(text):
    """``NAME=VALUE`` -> (NAME, VALUE read as JSON: a number, true/false, null)."""
    name, sep, value = text.partition("=")
    if not sep or "__" not in name:
        raise argparse.ArgumentTypeError(f"--learned-param {text!r}: give step__name=value")
    try:
        return name, json.loads(value)
    except json.JSONDecodeError as error:
        raise argparse.ArgumentTypeError(
            f"--learned-param {text!r}: {value!r} is not a number, true, false or null"
        ) from error


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
    parser.add_argument("--save", default=None, help="folder of each seed's rows (JSON), none by default")
    parser.add_argument("--summary", action="store_true", help="only the tables of the rows saved in --save")
    parser.add_argument(
        "--pq-only", action="store_true", help="only the causal PQ of the streams (no trackers, no training half)"
    )
    parser.add_argument("--without-sliding", action="store_true", help="neither tune nor stream SlidingDBSCAN")
    parser.add_argument(
        "--learned-param",
        dest="learned_params",
        action="append",
        type=_learned_param,
        metavar="NAME=VALUE",
        help="a parameter of the learned pipeline changed from the main job's (e.g. link__pair_window=0.5)",
    )
    parser.add_argument(
        "--form",
        dest="forms",
        action="append",
        choices=list(FORMS),
        help="measure only this tracked form (repeatable; default: every one)",
    )
    parser.add_argument(
        "--drop-feature-group",
        default=None,
        help="fit the learned model without a feature group of ablation_learned.py (e.g. 'no rigid velocity')",
    )
    options = parser.parse_args(argv)
    if options.without_sliding and not (options.pq_only or options.tune or options.summary):
        parser.error("--without-sliding needs --pq-only (or --tune): the trackers' rows include the baseline tracker")
    if options.summary:
        for preset in options.presets:
            runs = [json.loads(p.read_text()) for p in sorted(Path(options.save).glob(f"tracking_{preset}_*.json"))]
            if runs:
                print(table(preset, runs))
        return 0
    tables = []
    for preset in options.presets:
        runs = []
        for seed in options.seeds:
            start = time.perf_counter()
            found = tune(preset, seed, SimpleNamespace(**vars(options)))
            print(f"{preset} seed {seed}: tuned in {time.perf_counter() - start:.0f} s", flush=True)
            if not options.tune:
                runs.append(measure(preset, seed, found, options))
                if options.save:
                    Path(options.save).mkdir(parents=True, exist_ok=True)
                    saved = {k: v if k == "_pq" else {"scores": v["scores"]} for k, v in runs[-1].items()}
                    (Path(options.save) / f"tracking_{preset}_{seed}.json").write_text(json.dumps(saved, default=float))
        if runs:
            tables.append(table(preset, runs))
            print(tables[-1], flush=True)
    if len(tables) > 1:  # every preset's again, together
        print("\n".join(tables))
    return 0


if __name__ == "__main__":
    sys.exit(main())
