"""Where the causal learned grouping loses PQ against the offline one: its links, its agglomeration, its confirmation.

For each preset and seed: ``make_scenes`` (4 x 20 s), split in halves by ``sequence_train_test_split`` (as
``experiment_tracking.py`` does), and on the training half the main job's two learned models fitted with
``precluster_target``: the causal one (``experiment_tracking.LEARNED_CAUSAL``: causal features, causal filter,
the causal agglomeration's thresholds) and the offline one (``learned_pipeline()``).  The test half is labelled
five ways and scored by per-frame PQ (0.5 s windows) against ``precluster_target``:

1. ``causal``: the causal model's ``predict`` (what the stream gives): causal links, the causal agglomeration, and
   a detection labelled only when its cluster has ``min_cluster_size`` detections at its time;
2. ``causal, labels from the end``: the same merges, each detection labelled by the cluster it ends in when that
   has ``min_cluster_size`` detections (the confirmation's delay undone; not causal);
3. ``causal links, offline agglomeration``: the causal model's links merged over the whole sequence at once
   (``sequence_roots``, the offline agglomeration) with its thresholds;
4. ``offline``: the offline model's ``predict`` (offline features and agglomeration);
5. ``offline links, causal agglomeration``: the offline model's links through the causal agglomeration at the
   offline thresholds (for reference: how the causal agglomeration does with the offline links).

The steps 1 -> 2 (confirmation), 2 -> 3 (agglomeration) and 3 -> 4 (links: features and the model trained on them)
add up to the gap 1 -> 4.  The report gives the mean over seeds and each step's paired difference (mean +- 2 SE).
The records in ``benchmarks/results/causal_gap/`` were taken before the main job's causal model had the cluster
context (``link__cluster_window``); a rerun now measures the model with it.

Run (the learned guide's table, section "Where the causal score goes")::

    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/experiment_causal_gap.py --data easy realistic radarscenes \\
        --seeds 0 1 2 3 4 --out benchmarks/results/causal_gap
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from sklearn_radar._labels import consecutive_labels, drop_small_clusters, roots_to_rows
from sklearn_radar._validation import read_columns
from sklearn_radar.cluster._causal_agglomeration import confirmed_roots, sequence_merges
from sklearn_radar.cluster._link_clustering import LINK_READS, _sequences, sequence_roots
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments._learned import learned_pipeline
from sklearn_radar.metrics import panoptic_quality, precluster_target
from sklearn_radar.model_selection import sequence_train_test_split

sys.path.insert(0, str(Path(__file__).parent))
from experiment_learned import _mean_2se
from experiment_tracking import LABEL_COLUMNS, LEARNED_CAUSAL

CAUSAL, RETRO, OFFLINE_AGGLOMERATION = "causal", "causal, labels from the end", "causal links, offline agglomeration"
OFFLINE, OFFLINE_LINKS_CAUSAL = "offline", "offline links, causal agglomeration"
ROWS = (CAUSAL, RETRO, OFFLINE_AGGLOMERATION, OFFLINE, OFFLINE_LINKS_CAUSAL)
#: The steps of the gap: (name, from, to).
STEPS = (
    ("confirmation", CAUSAL, RETRO),
    ("agglomeration", RETRO, OFFLINE_AGGLOMERATION),
    ("links", OFFLINE_AGGLOMERATION, OFFLINE),
    ("whole gap", CAUSAL, OFFLINE),
)


def labellings(link, Xt, causal):
    """``{row: labels}`` of the fitted ``link`` on the transformed test half ``Xt``: the rows besides its
    ``predict`` (``RETRO`` and ``OFFLINE_AGGLOMERATION`` for the causal model, ``OFFLINE_LINKS_CAUSAL`` for the
    offline one)."""
    _, c = read_columns(link, Xt, LINK_READS, reset=False)
    n = len(c["x"])
    names = (RETRO, OFFLINE_AGGLOMERATION) if causal else (OFFLINE_LINKS_CAUSAL,)
    roots = {name: np.full(n, -1, dtype=np.int64) for name in names}
    size = link.min_cluster_size_
    for s in _sequences(c, causal):
        objectness, i, j, links = link._probabilities(s, link.objectness_threshold_)
        node = objectness > link.objectness_threshold_
        d = s.detections
        if causal:
            roots_to_rows(
                s.rows,
                sequence_roots(len(s.rows), i, j, links, node, link.link_threshold_, size),
                roots[OFFLINE_AGGLOMERATION],
            )
        else:  # the causal agglomeration takes each pair at its later end: (earlier, later), in order of the later
            i, j = np.minimum(i, j), np.maximum(i, j)
            order = np.lexsort((i, j))
            i, j, links = i[order], j[order], links[order]
        final, sizes = sequence_merges(d.t, node, i, j, links, link.pair_window, link.link_threshold_)
        if causal:  # (the causal labels themselves are its predict's: confirmed_roots of these merges)
            roots_to_rows(s.rows, drop_small_clusters(final, size), roots[RETRO])
        else:
            roots_to_rows(s.rows, confirmed_roots(final, sizes, size), roots[OFFLINE_LINKS_CAUSAL])
    return {name: consecutive_labels(r) for name, r in roots.items()}


def run_one(preset, seed):
    """The per-frame PQ of each row on the test half of one data set."""
    scenes = make_scenes(n_sequences=4, duration=20.0, difficulty=preset, random_state=seed)
    train, test = sequence_train_test_split(scenes.groups, test_size=0.5, random_state=seed)
    instances = precluster_target(scenes.data, scenes.target)
    inputs = scenes.data[[c for c in scenes.data.columns if c not in LABEL_COLUMNS]]
    X_train, X_test = inputs.iloc[train].reset_index(drop=True), inputs.iloc[test].reset_index(drop=True)
    found = {}
    for causal, params in ((True, LEARNED_CAUSAL), (False, {})):
        model = learned_pipeline({**params, "link__random_state": seed, "link__n_jobs": 1})
        model.fit(X_train, instances[train])
        Xt = model[:-1].transform(X_test)
        times, groups = Xt["t"].to_numpy(), Xt["sequence"].to_numpy()
        labels = labellings(model[-1], Xt, causal)
        labels[CAUSAL if causal else OFFLINE] = model[-1].predict(Xt)  # (causal: the stream's labels)
        for name, predicted in labels.items():
            pq = panoptic_quality(instances[test], predicted, times=times, groups=groups, window=0.5).pq
            found[name] = float(pq)
    return found


def report(preset, runs):
    """Mean PQ of each row and the paired difference of each step, over the seeds."""
    lines = [f"\n{preset}, seeds {sorted(runs)}: test-half PQ per 0.5 s frame, mean over seeds"]
    for name in ROWS:
        values = [run[name] for run in runs.values()]
        lines.append(f"  {name:40s} {np.mean(values):.3f}  ({', '.join(f'{v:.3f}' for v in values)})")
    lines.append("  steps, paired over seeds (mean ± 2 SE):")
    for step, start, end in STEPS:
        lines.append(f"  {step:40s} {_mean_2se([run[end] - run[start] for run in runs.values()])}")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument(
        "--data", nargs="+", default=["easy", "realistic", "radarscenes"], choices=["easy", "realistic", "radarscenes"]
    )
    parser.add_argument("--out", help="folder to write each preset's PQ per seed in (causal_gap_<preset>.json)")
    options = parser.parse_args(argv)
    with threadpool_limits(1):
        for preset in options.data:
            runs = {}
            for seed in options.seeds:
                runs[seed] = run_one(preset, seed)
                print(
                    f"  {preset} seed {seed}: " + ", ".join(f"{k} {v:.3f}" for k, v in runs[seed].items()), flush=True
                )
            if options.out:
                Path(options.out).mkdir(parents=True, exist_ok=True)
                (Path(options.out) / f"causal_gap_{preset}.json").write_text(json.dumps(runs, indent=1))
            print(report(preset, runs), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
