"""Where the tracked learned grouping's MOTA goes (issue #44): its misses and false positives, by kind.

Per preset and seed: ``make_scenes`` of ``--n-sequences`` x ``--duration`` s split as ``experiment_tracking.py``
splits it; the main job's causal model (``experiment_tracking.LEARNED_CAUSAL``) fitted on the training half with the
pre-clustered instance target and streamed through ``OnlinePipeline`` on both halves; the Tracker tuned on the
training half's confirmed clusters for MOTA (``experiment_tracking.tuned_tracker``: the defaults and
``--n-settings`` random settings, what the row ``learned causal, confirmed + Tracker`` measures) and run on the test
half's.  Three id sets of the test half are taken apart, per 0.5 s window and moving road user (an *object-frame*,
matched when a predicted id covers it with IoU > 0.5, which is the match of ``metrics.tracking_scores``):

* ``reported``: the stream's ids as reported at each scan (every cluster);
* ``confirmed``: the same, only where the cluster had ``min_cluster_size`` detections at the scan (what
  ``OnlinePipeline`` feeds its Tracker);
* ``tracked``: the Tracker's ids on the confirmed clusters.

Each missed object-frame is counted by where it lies in its road user's life (``never``: the road user is matched in
none of its windows; ``before``: before its first matched window; ``gap``: between two matched windows; ``after``:
after its last) and by whether the road user has at most ``--sparse`` detections in the window (``sparse``).  Each
false positive of the tracked ids (a window's id matched to no road user) is counted as ``background`` (most of its
detections are no road user's), ``duplicate`` (most are a matched road user's: a second id on it), ``merge`` (it
holds two or more road users, none covered with IoU > 0.5) or ``partial`` (one road user's, under half of it).

Besides the per-class counts (object-frames, misses of each id set, and the tracked false positives whose main road
user is of the class), each record keeps the tracked ids' MOTA, IDF1 and HOTA.  ``--extra-training N`` adds N
simulated sequences of the preset (seed + 1000) to the training half: the model is fitted, and the Tracker tuned, on
them too; the test half is the same (records ``benchmarks/results/tracking_errors/train8/`` with N = 6, ``train16/``
with N = 14).  ``--paste N`` adds instead N copies of the training sequences, each with its own road users pasted in
once more, turned and delayed (copy-paste augmentation, :func:`pasted`): the model is fitted on them too (each copy in
its sequence's cross-validation group), the Tracker tuned on the training half alone (records ``paste6/``, and
``paste14/`` of the realistic preset).

Run (about a minute per preset and seed on one core, 3-4 with ``--extra-training 6``; records
``benchmarks/results/tracking_errors/``)::

    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/experiment_tracking_errors.py --data realistic radarscenes easy \\
        --seeds 0 1 2 3 4 --save benchmarks/results/tracking_errors
    python benchmarks/experiment_tracking_errors.py --summary --save benchmarks/results/tracking_errors
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter
from contextlib import nullcontext
from pathlib import Path
from unittest.mock import patch

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).parent))

from experiment_tracking import (
    LABEL_COLUMNS,
    LEARNED_CAUSAL,
    PRESETS,
    TRACKER_SPACE,
    _mean_se,
    fixed_frame,
    scenes_of,
    scores,
    track,
    tuned_tracker,
)

from sklearn_radar import config_context
from sklearn_radar._schema import LABELS
from sklearn_radar.cluster import _link_clustering
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments._learned import learned_pipeline
from sklearn_radar.metrics import precluster_target
from sklearn_radar.online import OnlinePipeline, Tracker
from sklearn_radar.online._replay import replay

ID_SETS = ("reported", "confirmed", "tracked")
PLACES = ("never", "before", "gap", "after")
FALSE_KINDS = ("background", "duplicate", "merge", "partial")


def labelled_model(preset, seed, options, params=LEARNED_CAUSAL):
    """The data set's halves as (data, truth, half) and the main job's causal model (or the learned pipeline of
    ``params``) fitted on the training ones.

    With ``--extra-training N`` the training half has N more simulated sequences of the preset (seed + 1000, as
    ``experiment_classification.py`` adds them), renumbered after the data set's.  With ``--paste N`` the model is
    fitted on N copies of the training sequences with their road users pasted in again (:func:`pasted`) too, each in
    its sequence's cross-validation group; the copies are not among the halves returned.
    """
    scenes, train, test = scenes_of(preset, seed, options)
    labelled = [
        (scenes.data.iloc[train], scenes.target[train], "train"),
        (scenes.data.iloc[test], scenes.target[test], "test"),
    ]
    if options.extra_training:
        extra = make_scenes(
            n_sequences=options.extra_training, duration=options.duration, difficulty=preset, random_state=seed + 1000
        )
        shifted = extra.data.assign(sequence=extra.data["sequence"] + int(scenes.groups.max()) + 1)
        labelled.append((shifted, np.asarray(extra.target), "train"))
    training = [(data, np.asarray(truth)) for data, truth, half in labelled if half == "train"]
    origin = None
    if options.paste:
        data = pd.concat([d for d, _ in training], ignore_index=True)
        first = int(max(scenes.groups.max(), data["sequence"].max())) + 1
        *copies, origin = pasted(data, np.concatenate([t for _, t in training]), options.paste, first, seed)
        training.append(tuple(copies))
    # The pasted copies hold two ego paths, which the plausibility checks of the ego motion reject.
    with config_context(check_plausibility=False if origin else None):
        fitted_on = [(data, precluster_target(data, truth)) for data, truth in training]
        inputs = pd.concat([data for data, _ in fitted_on], ignore_index=True)
        inputs = inputs[[c for c in inputs.columns if c not in LABEL_COLUMNS]]
        model = learned_pipeline({"link__n_jobs": 1, **params, "link__random_state": seed})
        grouped = patch.object(_link_clustering, "_groups", by_origin(origin)) if origin else nullcontext()
        with grouped:
            model.fit(inputs, np.concatenate([instances for _, instances in fitted_on]))
    return labelled, model


def by_origin(origin):
    """``LinkClustering``'s cross-validation groups with each pasted sequence in its host's group (no leak)."""

    def groups(sequences, c, cv):
        return [np.full(len(q.rows), origin[int(c["sequence"][q.rows[0]])], dtype=np.int64) for q in sequences]

    return groups


def pasted(data, truth, n, first, seed):
    """``n`` sequences, each a training sequence with its own road users pasted in once more (copy-paste).

    The copies (rows with ``truth >= 0``) keep their car-frame measurements (range, azimuth, RCS, Doppler, sensor);
    their ego pose is turned by a random angle about the sequence's first ego position, so that positions, lines of
    sight and compensated Doppler stay consistent, and delayed by up to 2 s (rows past the sequence's end dropped).
    They get new instance ids.  Sequence ``first + k`` is the ``k % n_sequences``-th training sequence's.

    Returns
    -------
    data, truth : DataFrame, ndarray
        The pasted sequences.
    origin : dict
        Sequence id -> the training sequence it was made from (each training sequence its own).
    """
    rng = np.random.default_rng(seed + 2000)
    hosts = np.unique(data["sequence"])
    parts, truths, origin = [], [], {int(q): int(q) for q in hosts}
    top = int(truth.max()) + 1
    for k in range(n):
        rows = data["sequence"].to_numpy() == hosts[k % len(hosts)]
        base, base_truth = data[rows], truth[rows]
        start = base.loc[base["timestamp"].idxmin()]
        theta = rng.uniform(-np.pi, np.pi)
        delay = 7_001 + int(rng.uniform(0, 2e6))  # µs: off the sequence's scan times
        road, road_truth = base[base_truth >= 0].copy(), base_truth[base_truth >= 0]
        road["timestamp"] += delay
        kept = (road["timestamp"] <= base["timestamp"].max()).to_numpy()
        road, road_truth = road[kept], road_truth[kept]
        for px, py in (("ego_x_seq", "ego_y_seq"), ("x_seq", "y_seq")):
            dx, dy = road[px] - start["ego_x_seq"], road[py] - start["ego_y_seq"]
            road[px] = start["ego_x_seq"] + np.cos(theta) * dx - np.sin(theta) * dy
            road[py] = start["ego_y_seq"] + np.sin(theta) * dx + np.cos(theta) * dy
        road["ego_yaw_seq"] += theta
        road["uuid"] += f"p{k}"
        road["track_id"] += f"p{k}"
        road_truth = road_truth - road_truth.min() + top
        top = int(road_truth.max()) + 1
        parts.append(pd.concat([base, road], ignore_index=True).assign(sequence=first + k))
        truths.append(np.concatenate([base_truth, road_truth]))
        origin[first + k] = int(hosts[k % len(hosts)])
    return pd.concat(parts, ignore_index=True), np.concatenate(truths), origin


def streamed(preset, seed, options):
    """Per half, per sequence: fixed-frame columns, truth, and the stream's reported and confirmed ids.

    With ``--extra-training N`` the model is fitted, and the Tracker tuned, on the N extra sequences too
    (:func:`labelled_model`).
    """
    labelled, model = labelled_model(preset, seed, options)
    halves = {"train": [], "test": []}
    for frame, truth, half in labelled:
        groups = frame["sequence"].to_numpy()
        for sequence in np.unique(groups):
            data = frame[groups == sequence].reset_index(drop=True)
            replayed = replay(OnlinePipeline(model), data)
            part = fixed_frame(data)
            part.update(
                reported=replayed["reported"],
                confirmed=replayed["followed"],
                sequence=np.full(len(data), sequence),
                truth=truth[groups == sequence],
                label=data["label_id"].to_numpy(),
            )
            halves[half].append(part)
    return halves


def _best(inside, ids, window_rows):
    """Largest IoU of the detections ``inside`` (a road user's in a window) with one id of ``ids`` there."""
    best = 0.0
    for k in np.unique(ids[inside & (ids >= 0)]):
        predicted = window_rows & (ids == k)
        best = max(best, (inside & predicted).sum() / (inside | predicted).sum())
    return best


def _windows(part):
    """Each detection's 0.5 s window of its sequence (the windows of ``metrics.tracking_scores``)."""
    return np.floor((part["t"] - part["t"].min()) / 0.5).astype(np.int64)


def object_frames(part, sparse):
    """The object-frames of one sequence: ``"sparse"`` (at most ``sparse`` detections) and one count per class."""
    counts = Counter()
    window, truth = _windows(part), part["truth"]
    for road_user in np.unique(truth[truth >= 0]):
        own = truth == road_user
        sizes = np.bincount(window[own])
        sizes = sizes[sizes > 0]
        counts["sparse"] += int((sizes <= sparse).sum())
        counts[LABELS[int(part["label"][own][0])]] += len(sizes)
    return counts


def misses(part, ids, sparse):
    """Missed object-frames of one sequence, counted by place in the road user's life, sparseness and class."""
    counts = Counter()
    window, truth = _windows(part), part["truth"]
    for road_user in np.unique(truth[truth >= 0]):
        own = truth == road_user
        frames = []
        for w in np.unique(window[own]):
            inside = own & (window == w)
            frames.append((_best(inside, ids, window == w) > 0.5, int(inside.sum())))
        matched = np.array([m for m, _ in frames])
        first = int(np.argmax(matched)) if matched.any() else len(frames)
        name = LABELS[int(part["label"][own][0])]
        for i, (hit, n) in enumerate(frames):
            if hit:
                continue
            place = "never" if not matched.any() else "before" if i < first else "gap" if matched[i:].any() else "after"
            counts[place] += 1
            counts["sparse"] += n <= sparse
            counts[f"class {name}"] += 1
    return counts


def false_positives(part, ids):
    """False positives (a window's id matched to no road user) of one sequence, counted by kind."""
    counts = Counter()
    window, truth = _windows(part), part["truth"]
    for w in np.unique(window):
        here = window == w
        matched, unmatched = set(), []
        for k in np.unique(ids[here & (ids >= 0)]):
            predicted = here & (ids == k)
            users, held = np.unique(truth[predicted & (truth >= 0)], return_counts=True)
            ious = [(predicted & (truth == u)).sum() / (predicted | (here & (truth == u))).sum() for u in users]
            if ious and max(ious) > 0.5:
                matched.add(users[int(np.argmax(ious))])
            else:
                unmatched.append((predicted.sum(), users, held))
        for size, users, held in unmatched:
            main = users[int(np.argmax(held))] if len(users) else -1
            if held.sum() * 2 <= size:
                kind = "background"
            elif main in matched:
                kind = "duplicate"
            else:
                kind = "merge" if len(users) >= 2 else "partial"
            counts[kind] += 1
            if kind in ("merge", "partial"):
                counts[f"{kind} {LABELS[int(part['label'][truth == main][0])]}"] += 1
    return counts


def measure(preset, seed, options):
    """The counts of every id set, the Tracker's scores and setting, for one data set."""
    start = time.perf_counter()
    halves = streamed(preset, seed, options)
    mota, setting = tuned_tracker(
        halves["train"], Tracker, lambda p: p["confirmed"], TRACKER_SPACE, options.n_settings, seed
    )
    test = halves["test"]
    tracked = track(test, lambda: Tracker(**setting), lambda p: p["confirmed"])
    offsets = np.cumsum([0, *(len(p["t"]) for p in test)])
    for part, a, b in zip(test, offsets[:-1], offsets[1:], strict=True):
        part["tracked"] = tracked[a:b]
    frames = sum((object_frames(p, options.sparse) for p in test), Counter())
    sparse_frames = frames.pop("sparse", 0)
    record = {"setting": setting, "train_mota": mota, "sparse_frames": sparse_frames, "class_frames": dict(frames)}
    for name in ID_SETS:
        ids = np.concatenate([p[name] for p in test])
        counted = sum((misses(p, p[name], options.sparse) for p in test), Counter())
        record[name] = {"scores": scores(test, ids), "misses": dict(counted)}
    record["tracked"]["false"] = dict(sum((false_positives(p, p["tracked"]) for p in test), Counter()))
    record["seconds"] = time.perf_counter() - start
    s = record["tracked"]["scores"]
    print(
        f"{preset} seed {seed}: tracked MOTA {s['mota']:.3f}, misses {s['misses']} of {s['objects']}, "
        f"false positives {s['fp']} ({record['seconds']:.0f} s)",
        flush=True,
    )
    return record


def table(preset, runs):
    """Per id set: MOTA, and misses and false positives by kind as shares of the object-frames (mean ± SE)."""
    lines = [f"\n{preset}: {len(runs)} seed(s), test half; share of the object-frames, mean ± standard error"]
    header = ("MOTA", "misses", *PLACES, "sparse", "false pos.", *FALSE_KINDS)
    if all("sparse_frames" in run for run in runs):
        mean, se = _mean_se([run["sparse_frames"] / run["tracked"]["scores"]["objects"] for run in runs])
        lines.append(f"sparse object-frames (at most --sparse detections): {mean:.3f} ± {se:.3f}")
    lines.append(f"{'':<10} " + " ".join(f"{h:>14}" for h in header))
    for name in ID_SETS:
        cells = []
        for key in header:
            values = []
            for run in runs:
                row, objects = run[name], run[name]["scores"]["objects"]
                if key == "MOTA":
                    values.append(row["scores"]["mota"])
                elif key == "misses":
                    values.append(row["scores"]["misses"] / objects)
                elif key == "false pos.":
                    values.append(row["scores"]["fp"] / objects)
                elif key in FALSE_KINDS:
                    values.append(row["false"].get(key, 0) / objects if "false" in row else np.nan)
                else:
                    values.append(row["misses"].get(key, 0) / objects)
            mean, se = _mean_se(values)
            cells.append("-" if np.isnan(mean) else f"{mean:.3f} ± {se:.3f}")
        lines.append(f"{name:<10} " + " ".join(f"{c:>14}" for c in cells))
    if all("class_frames" in run for run in runs):
        lines.append(
            "per class (sums over seeds): object-frames; missed (reported / confirmed / tracked); tracked "
            "false positives whose main road user is of the class, merge / partial"
        )
        for name in sorted({k for run in runs for k in run["class_frames"]}):
            total = sum(run["class_frames"].get(name, 0) for run in runs)
            missed = [sum(run[ids]["misses"].get(f"class {name}", 0) for run in runs) for ids in ID_SETS]
            false = [sum(run["tracked"]["false"].get(f"{kind} {name}", 0) for run in runs) for kind in FALSE_KINDS[2:]]
            lines.append(
                f"  {name:<22} {total:>5}; missed "
                + " / ".join(f"{m / total:.2f}" for m in missed)
                + "; false "
                + " / ".join(f"{f / total:.2f}" for f in false)
            )
    return "\n".join(lines)


def compared(preset, runs, others):
    """Paired differences (mean ± 2 SE over the common seeds) of the tracked ids' scores: ``runs`` minus ``others``."""
    common = sorted(set(runs) & set(others))
    lines = [f"{preset}: tracked ids, {len(common)} seed(s) in both; mean here, there, difference ± 2 SE"]
    for key in ("mota", "idf1", "hota", "misses", "fp"):
        here = np.array([runs[s]["tracked"]["scores"][key] for s in common], dtype=float)
        there = np.array([others[s]["tracked"]["scores"][key] for s in common], dtype=float)
        if key in ("misses", "fp"):  # as shares of the object-frames
            objects = np.array([runs[s]["tracked"]["scores"]["objects"] for s in common], dtype=float)
            here, there = here / objects, there / objects
        mean, se = _mean_se(here - there)
        lines.append(f"  {key:<7} {here.mean():.3f} {there.mean():.3f} {mean:+.3f} ± {2 * se:.3f}")
    return "\n".join(lines)


def _record_path(folder, preset, seed):
    return Path(folder) / f"tracking_errors_{preset}_{seed}.json"


def data_arguments(parser):
    """The arguments of the data, the Tracker's search and the records, shared with ``experiment_sliding_grouping``."""
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("--data", nargs="+", default=list(PRESETS), choices=PRESETS, dest="presets")
    parser.add_argument("--n-sequences", type=int, default=4)
    parser.add_argument("--duration", type=float, default=20.0, help="s per sequence")
    parser.add_argument("--n-settings", type=int, default=30, help="random Tracker settings tried")
    parser.add_argument(
        "--extra-training", type=int, default=0, help="simulated sequences added to the training half (seed + 1000)"
    )
    parser.add_argument(
        "--paste", type=int, default=0, help="copies of the training sequences, their road users pasted in again"
    )
    parser.add_argument("--save", default=None, help="folder of each seed's record (JSON)")
    parser.add_argument("--summary", action="store_true", help="only the tables of the records in --save")


def parsed(parser, argv):
    """The options of ``argv``; an error when ``--summary`` comes without ``--save``, the folder it reads."""
    options = parser.parse_args(argv)
    if options.summary and not options.save:
        parser.error("--summary reads the records of --save: give the folder")
    return options


def records(options, preset, measure, path_of):
    """Seed -> record of one preset: measured (and saved in ``--save``), or with ``--summary`` read from there.

    ``measure(preset, seed, options)`` gives a record; ``path_of(folder, preset, seed)`` its file.
    """
    runs = {}
    for seed in options.seeds:
        path = None if options.save is None else path_of(options.save, preset, seed)
        if options.summary:
            if path.exists():
                runs[seed] = json.loads(path.read_text())
            continue
        runs[seed] = measure(preset, seed, options)
        if path is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(json.dumps(runs[seed], default=float))
    return runs


def saved_records(folder, preset, seeds, path_of):
    """Seed -> record of one preset saved in ``folder`` (``path_of(folder, preset, seed)``), for the seeds it has."""
    paths = {seed: path_of(folder, preset, seed) for seed in seeds}
    return {seed: json.loads(path.read_text()) for seed, path in paths.items() if path.exists()}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    data_arguments(parser)
    parser.add_argument("--sparse", type=int, default=5, help="a road user with at most this many detections")
    parser.add_argument("--against", help="with --summary: the tracked scores' paired differences to these records")
    options = parsed(parser, argv)
    if options.against and not options.summary:
        parser.error("--against compares saved records: give --summary too")
    for preset in options.presets:
        runs = records(options, preset, measure, _record_path)
        if runs:
            print(table(preset, list(runs.values())), flush=True)
        if options.against and runs:
            others = saved_records(options.against, preset, runs, _record_path)
            print(compared(preset, runs, others), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
