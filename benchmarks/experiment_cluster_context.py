"""The causal learned grouping with and without cluster context (``LinkClustering(cluster_window=...)``): PQ, tracking.

For each preset and seed: ``make_scenes`` (4 x 20 s), split in halves by ``sequence_train_test_split`` (as
``experiment_tracking.py`` does), and the main job's causal model (``experiment_tracking.LEARNED_CAUSAL``) fitted on
the training half with ``precluster_target``, once as it is and once with ``link__cluster_window`` set (the links
also see the cluster the earlier detection already belongs to; ``--cluster-window``, default 0.5 s).  Each model is
scored on the test half:

* ``PQ``: its ``predict`` (the stream's clusters), per-frame PQ (0.5 s windows) against ``precluster_target``;
* ``ids``: MOTA and IDF1 (``tracking_scores``, 0.5 s windows) of the stream's final ids themselves;
* ``+ Tracker``: MOTA, IDF1 and HOTA of ``sklearn_radar.online.Tracker`` fed the confirmed ids (what
  ``OnlinePipeline`` feeds its Tracker), its parameters tuned for MOTA on the training half's ids of out-of-fold
  models (each training sequence streamed by a model fitted on the other), as
  ``experiment_tracking.py``'s ``learned causal, confirmed + Tracker, out-of-fold`` (30 random settings).

The report gives each row's mean and the paired difference with context minus without (mean +- 2 SE over seeds).

``--rounds 2`` (a prototype, not in the library; ``--rounds 1 2`` fits both context models on the same split)
trains the context model's link classifier on more states: after the first round (the library's: the state that
the links without context make), the state that the first round's out-of-fold classifiers make at their tuned
threshold, its pairs added to the training rows, the classifier refitted and the thresholds retuned (data
aggregation).
Records: seeds 0-4 in ``benchmarks/results/cluster_context/`` (``rounds2/``: the second round's prototype, run
alone), fresh seeds 5-9 in ``fresh/`` (``--rounds 1 2``; the easy preset ``--rounds 1``).
Run (the learned guide's table, section "Cluster context"; about 4 minutes per seed on 2 shared cores)::

    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/experiment_cluster_context.py --data realistic \\
        --seeds 0 1 2 3 4 --out benchmarks/results/cluster_context
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from sklearn.base import clone
from threadpoolctl import threadpool_limits

from sklearn_radar.cluster import LinkClustering
from sklearn_radar.cluster._cluster_context import context_merges, links_by_fold
from sklearn_radar.cluster._link_training import cross_fit, fold_classifiers, tune_context
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments._learned import learned_pipeline
from sklearn_radar.metrics import panoptic_quality, precluster_target, tracking_scores
from sklearn_radar.model_selection import sequence_train_test_split
from sklearn_radar.online import OnlinePipeline, Tracker
from sklearn_radar.online._replay import replay

sys.path.insert(0, str(Path(__file__).parent))
from experiment_learned import _mean_2se
from experiment_tracking import LABEL_COLUMNS, LEARNED_CAUSAL, TRACKER_SPACE, fixed_frame, scores, track, tuned_tracker

WITHOUT, WITH = "pair features", "cluster context"
ROUNDS = {"rounds": 1}  # of the context model being fitted (``--rounds``)


def variant(rounds):
    """The record name of the context model trained on ``rounds`` rounds of states."""
    return WITH if rounds == 1 else f"{WITH}, {rounds} rounds"


METRICS = ("pq", "ids_mota", "ids_idf1", "mota", "idf1", "hota")


def _fit_context_rounds(self, training, c, y, grids, tuning, seed, tree, rng, rounds=2):
    """``LinkClustering._fit_context`` with ``rounds`` rounds of training states (tuning only)."""
    gate, window, columns = self.objectness_threshold_, self.cluster_window, self._context_columns()
    parts, features, targets, folds = [], [], [], []

    def merges(part, links_of, threshold):
        s, node, i, j = part[:4]
        return context_merges(s.detections, node, i, j, links_of, self.pair_window, threshold, window, self.max_extent)

    for s, p, (i, j), x, target, link, fold in zip(*training, strict=True):
        node = p > gate
        both = node[i] & node[j]
        part = (s, node, i[both], j[both], x[both], target[both], fold[both])
        context = merges(part, lambda rows, _c, link=link[both]: link[rows], self.link_threshold_)[2]
        parts.append(part)
        features.append(np.hstack([part[4], context[:, columns]]))
        targets.append(part[5])
        folds.append(part[6])
    link_grid, _, size_grid = grids
    models = setting = None  # (of the round before)
    for round_ in range(rounds):
        if round_:  # the state that the last round's out-of-fold classifiers make
            for part in parts:
                context = merges(part, links_by_fold(models, part[4], part[6], columns), setting[0])[2]
                features.append(np.hstack([part[4], context[:, columns]]))
                targets.append(part[5])
                folds.append(part[6])
        models = fold_classifiers(features, targets, folds, self.max_iter, seed, self.max_pairs, rng, tree)

        def merged_at(threshold, models=models):
            return [
                (part[0].rows, *merges(part, links_by_fold(models, part[4], part[6], columns), threshold)[:2])
                for part in parts
            ]

        setting, score = tune_context(merged_at, link_grid, size_grid, c, y, self.window)
    self.link_classifier_, _ = cross_fit(
        features, targets, folds, self.max_iter, seed, self.max_pairs, rng, out_of_fold=False, tree=tree
    )
    self.link_threshold_, self.min_cluster_size_ = float(setting[0]), int(setting[1])
    self.cv_score_ = float(score)


def streamed(model, data, groups, rows, truth, models=None):
    """Per sequence of ``rows``: fixed-frame columns, truth, final and confirmed ids of ``model`` (or of
    ``models[sequence]``) streamed."""
    parts = []
    for sequence in np.unique(groups[rows]):
        mine = rows[groups[rows] == sequence]
        frame = data.iloc[mine].reset_index(drop=True)
        replayed = replay(OnlinePipeline((models or {}).get(sequence, model)), frame)
        part = fixed_frame(frame)
        part.update(
            final=replayed["object_ids"],
            followed=replayed["followed"],
            truth=truth[mine],
            sequence=np.full(len(mine), sequence),
        )
        parts.append(part)
    return parts


def run_one(preset, seed, cluster_window, n_settings, rounds=(1,)):
    """Every metric of the model without context and of each context model (one per ``rounds``) on the test half
    of one data set."""
    scenes = make_scenes(n_sequences=4, duration=20.0, difficulty=preset, random_state=seed)
    train, test = sequence_train_test_split(scenes.groups, test_size=0.5, random_state=seed)
    instances = precluster_target(scenes.data, scenes.target)
    inputs = scenes.data[[c for c in scenes.data.columns if c not in LABEL_COLUMNS]]
    X_train, X_test = inputs.iloc[train].reset_index(drop=True), inputs.iloc[test].reset_index(drop=True)
    found = {}
    for name, window, n in ((WITHOUT, None, 1), *((variant(n), cluster_window, n) for n in rounds)):
        start = time.perf_counter()
        ROUNDS["rounds"] = n
        params = {**LEARNED_CAUSAL, "link__random_state": seed, "link__n_jobs": 1, "link__cluster_window": window}
        model = learned_pipeline(params).fit(X_train, instances[train])
        Xt = model[:-1].transform(X_test)
        times, groups = Xt["t"].to_numpy(), Xt["sequence"].to_numpy()
        labels = model[-1].predict(Xt)
        row = {"pq": float(panoptic_quality(instances[test], labels, times=times, groups=groups, window=0.5).pq)}
        out_of_fold = {}
        for sequence in np.unique(scenes.groups[train]):
            others = train[scenes.groups[train] != sequence]
            out_of_fold[sequence] = clone(model).fit(inputs.iloc[others].reset_index(drop=True), instances[others])
        train_parts = streamed(model, scenes.data, scenes.groups, train, scenes.target, out_of_fold)
        test_parts = streamed(model, scenes.data, scenes.groups, test, scenes.target)
        final = np.concatenate([p["final"] for p in test_parts])
        t = np.concatenate([p["t"] for p in test_parts])
        g = np.concatenate([p["sequence"] for p in test_parts])
        truth = np.concatenate([p["truth"] for p in test_parts])
        ids = tracking_scores(truth, final, times=t, groups=g, window=0.5)
        row["ids_mota"], row["ids_idf1"] = float(ids["mota"]), float(ids["idf1"])
        _, setting = tuned_tracker(train_parts, Tracker, lambda p: p["followed"], TRACKER_SPACE, n_settings, seed)
        tracked = scores(test_parts, track(test_parts, lambda s=setting: Tracker(**s), lambda p: p["followed"]))
        row.update(mota=float(tracked["mota"]), idf1=float(tracked["idf1"]), hota=float(tracked["hota"]))
        link = model[-1]
        row["setting"] = [link.link_threshold_, link.objectness_threshold_, link.min_cluster_size_, setting]
        row["seconds"] = time.perf_counter() - start
        found[name] = row
    return found


def report(preset, runs):
    """Mean of each metric per model and the paired differences over the seeds: each context model minus the model
    without, and each further context model minus the first."""
    lines = [f"\n{preset}, seeds {sorted(runs)}: test half, mean over seeds; difference paired (mean ± 2 SE)"]
    names = [name for name in next(iter(runs.values())) if name != WITHOUT]
    for metric in METRICS:
        without = np.array([run[WITHOUT][metric] for run in runs.values()])
        for name in names:
            within = np.array([run[name][metric] for run in runs.values()])
            lines.append(
                f"  {metric:9s} {WITHOUT} {without.mean():.3f}, {name} {within.mean():.3f}, "
                f"difference {_mean_2se(within - without)}"
            )
        for name in names[1:]:
            first, other = (np.array([run[n][metric] for run in runs.values()]) for n in (names[0], name))
            lines.append(f"  {metric:9s} {name} minus {names[0]}: {_mean_2se(other - first)}")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument(
        "--data", nargs="+", default=["easy", "realistic", "radarscenes"], choices=["easy", "realistic", "radarscenes"]
    )
    parser.add_argument("--cluster-window", type=float, default=0.5, help="LinkClustering's cluster_window, s")
    parser.add_argument("--n-settings", type=int, default=30, help="random settings tried for the Tracker")
    parser.add_argument(
        "--rounds",
        type=int,
        nargs="+",
        default=[1],
        help="rounds of training states, one context model per value (1: the library's; 2: the prototype)",
    )
    parser.add_argument("--out", help="folder to write each preset's runs in (cluster_context_<preset>.json)")
    options = parser.parse_args(argv)
    library = LinkClustering._fit_context

    def fit_context(self, *args):
        if ROUNDS["rounds"] == 1:
            return library(self, *args)
        return _fit_context_rounds(self, *args, rounds=ROUNDS["rounds"])

    LinkClustering._fit_context = fit_context
    with threadpool_limits(1):
        for preset in options.data:
            runs = {}
            for seed in options.seeds:
                runs[seed] = run_one(preset, seed, options.cluster_window, options.n_settings, options.rounds)
                print(f"  {preset} seed {seed}: {json.dumps(runs[seed])}", flush=True)
                if options.out:  # after each seed, so that a stopped run keeps what it measured
                    Path(options.out).mkdir(parents=True, exist_ok=True)
                    (Path(options.out) / f"cluster_context_{preset}.json").write_text(json.dumps(runs, indent=1))
            print(report(preset, runs), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
