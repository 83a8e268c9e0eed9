"""LinkClustering (the learned grouping) on simulated sequences: test PQ, fit time and predict time per scan.

The data and split of ``benchmarks/experiment_learned_grouping.py`` (its design ``A-mean`` is what
``LinkClustering`` implements): ``make_scenes`` (``--data``, ``--n-sequences`` x ``--duration`` s, seed), split
half/half by sequence with ``sequence_train_test_split(random_state=seed)``; each sequence passes
``FrameTransform(frame="frame")`` and ``DopplerDensityFilter()``; the target is ``metrics.precluster_target``;
the test half is scored with ``metrics.panoptic_quality`` (0.5 s frames).  ``fit`` is timed on the training half
(features, classifiers, out-of-fold tuning, and the labels of the training data), ``predict`` on the test half per
scan (one sensor's cycle), batch-amortised; the front is excluded from both.  Wall and CPU seconds are printed
(CPU sums the classifiers' threads), with the load average: on a shared machine the wall time depends on others.

Run (``--threads`` bounds the classifiers' OpenMP threads, the issue's budget is 2 cores; ``--prototype`` runs the
prototype's A-mean on the same data beside it, a few minutes per preset and seed)::

    python benchmarks/bench_link_clustering.py --data realistic --seeds 0 --threads 2
    python benchmarks/bench_link_clustering.py --data easy radarscenes --seeds 0 --threads 1 --prototype
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
from sklearn.pipeline import Pipeline
from threadpoolctl import threadpool_limits

from sklearn_radar import DopplerDensityFilter, FrameTransform
from sklearn_radar.cluster import LinkClustering
from sklearn_radar.datasets import make_scenes
from sklearn_radar.metrics import panoptic_quality, precluster_target
from sklearn_radar.model_selection import sequence_train_test_split

#: Test PQ of the prototype's design A-mean (``experiment_learned_grouping.py --designs A-mean``, same data and
#: split), where it was run; ``--prototype`` runs it again for any preset and seed.
PROTOTYPE_PQ = {("realistic", 0): 0.699}


def prototype_pq(preset, seed, options):
    """Test PQ of the prototype's A-mean on the same data and split (one thread, as the prototype runs)."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import experiment_learned_grouping as prototype

    settings = argparse.Namespace(
        designs=["A-mean"],
        n_sequences=options.n_sequences,
        duration=options.duration,
        max_iter=150,
        max_rows=400_000,
        pair_radius=3.0,
        pair_window=0.25,
        thresholds=[0.05, 0.15, 0.3, 0.5],
        min_sizes=[1, 3, 6, 10, 15, 20],
    )
    with threadpool_limits(1):
        (record,) = prototype.run(preset, seed, settings)
    return record["pq"]


def load(preset, seed, n_sequences, duration, causal=False):
    """Working detections of the training and the test half (through the front, per sequence), and targets.

    ``causal``: the front's filter counts the past only, as a stream's does.
    """
    scenes = make_scenes(n_sequences=n_sequences, duration=duration, difficulty=preset, random_state=seed)
    target = precluster_target(scenes.data, scenes.target)
    train_rows, _ = sequence_train_test_split(scenes.groups, test_size=0.5, random_state=seed)
    train_ids = set(np.unique(scenes.groups[train_rows]).tolist())
    front = Pipeline([("frame", FrameTransform(frame="frame")), ("filter", DopplerDensityFilter(causal=causal))])
    halves = {True: ([], []), False: ([], [])}
    for number in np.unique(scenes.groups):
        rows = np.flatnonzero(scenes.groups == number)
        frames, targets = halves[int(number) in train_ids]
        frames.append(front.fit_transform(scenes.data.iloc[rows]))
        targets.append(target[rows])
    return [(pd.concat(frames, ignore_index=True), np.concatenate(targets)) for frames, targets in halves.values()]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", nargs="+", default=["realistic"], choices=["easy", "realistic", "radarscenes"])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--n-sequences", type=int, default=4)
    parser.add_argument("--duration", type=float, default=20.0, help="s per sequence")
    parser.add_argument("--threads", type=int, default=2, help="OpenMP threads of the classifiers (n_jobs)")
    parser.add_argument("--random-state", type=int, default=0, help="LinkClustering's seed (classifiers, subsampling)")
    parser.add_argument("--prototype", action="store_true", help="also run the prototype's A-mean (minutes each)")
    options = parser.parse_args(argv)
    print(f"{'preset':<12} seed  test PQ  recall  precision  cv PQ  prototype  fit s  predict ms/scan  setting")
    for preset in options.data:
        for seed in options.seeds:
            (train, y_train), (test, y_test) = load(preset, seed, options.n_sequences, options.duration)
            model = LinkClustering(n_jobs=options.threads, random_state=options.random_state)
            start, cpu = time.perf_counter(), time.process_time()
            model.fit(train, y_train)
            fit_s, fit_cpu = time.perf_counter() - start, time.process_time() - cpu
            start, cpu = time.perf_counter(), time.process_time()
            labels = model.predict(test)
            predict_s, predict_cpu = time.perf_counter() - start, time.process_time() - cpu
            n_scans = test.groupby(["sequence", "sensor_id", "timestamp"]).ngroups
            scores = panoptic_quality(y_test, labels, times=test["t"].to_numpy(), groups=test["sequence"].to_numpy())
            setting = (model.link_threshold_, model.objectness_threshold_, model.min_cluster_size_)
            prototype = prototype_pq(preset, seed, options) if options.prototype else PROTOTYPE_PQ.get((preset, seed))
            print(
                f"{preset:<12} {seed:>4}  {scores.pq:.3f}    {scores.recall:.3f}   {scores.precision:.3f}      "
                f"{model.cv_score_:.3f}  {'   -  ' if prototype is None else f'{prototype:.3f}'}     "
                f"{fit_s:5.1f}  {1e3 * predict_s / n_scans:.2f}  {setting}",
                flush=True,
            )
            print(
                f"    CPU: fit {fit_cpu:.1f} s, predict {1e3 * predict_cpu / n_scans:.2f} ms/scan; "
                f"load average {os.getloadavg()[0]:.1f}; {len(train)} training and {len(test)} test detections",
                flush=True,
            )
            print(
                f"    boosting iterations: objectness {getattr(model.objectness_classifier_, 'n_iter_', 0)}, "
                f"links {getattr(model.link_classifier_, 'n_iter_', 0)}; {model.n_training_pairs_} training pairs",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
