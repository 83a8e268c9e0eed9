"""The causal learned grouping with a cap on the links per detection, paired with the saved uncapped rows.

For each seed, on the data and split of ``experiment_learned.py --method learned_causal`` (``make_scenes``, 4 x 20 s,
``sequence_train_test_split(random_state=seed)``, a causal front), fits
``LinkClustering(causal=True, max_iter=40, max_links_per_detection=K)`` on the training half and scores the test half
with ``metrics.panoptic_quality`` (0.5 s windows), as that script scores the uncapped model; prints each seed's test
PQ beside the saved ``learned_causal_<preset>_seed<seed>.json`` (the same fit without a cap: the fit is
deterministic), and the paired difference (mean ± 2 SE over seeds).

Run (one core, niced; one to three minutes per seed on a busy 2-core machine)::

    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/experiment_learned_links_cap.py --max-links 16 --data realistic
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import experiment_learned as learned  # noqa: E402

from sklearn_radar.cluster import LinkClustering  # noqa: E402


def capped_pq(preset, seed, max_links, threads=1):
    """Test PQ of the capped causal model on one preset and seed, and its tuned thresholds."""
    (train, y_train), (test, y_test) = learned.bench.load(preset, seed, 4, 20.0, causal=True)
    model = LinkClustering(causal=True, max_iter=40, n_jobs=threads, max_links_per_detection=max_links)
    with threadpool_limits(threads):
        labels = model.fit(train, y_train).predict(test)
    record = learned._scores("capped", labels, y_test, test["t"].to_numpy(), test["sequence"].to_numpy())
    return record["pq"], (model.link_threshold_, model.objectness_threshold_, model.min_cluster_size_)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-links", type=int, required=True, help="max_links_per_detection")
    parser.add_argument("--data", default="realistic", choices=["easy", "realistic", "radarscenes"])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--results", type=Path, default=learned.RESULTS, help="folder of the saved uncapped rows")
    options = parser.parse_args(argv)
    differences = []
    for seed in options.seeds:
        pq, thresholds = capped_pq(options.data, seed, options.max_links)
        saved = json.loads((options.results / f"learned_causal_{options.data}_seed{seed}.json").read_text())
        base = (saved[0] if isinstance(saved, list) else saved)["pq"]
        differences.append(pq - base)
        print(f"{options.data} seed {seed}: capped {pq:.3f} (thresholds {thresholds}), uncapped {base:.3f}")
    d = np.array(differences)
    se = d.std(ddof=1) / np.sqrt(len(d)) if len(d) > 1 else float("nan")
    print(f"capped - uncapped: {d.mean():+.3f} ± {2 * se:.3f} (mean ± 2 SE over {len(d)} seeds)")


if __name__ == "__main__":
    main()
