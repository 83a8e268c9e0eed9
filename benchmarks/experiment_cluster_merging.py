"""Stage 2 on simulated data: V-measure before and after cluster merging, and its share of the run time.

Run: ``python benchmarks/experiment_cluster_merging.py [--n-sequences 8] [--n-candidates 40]``.

Stage 1 is the paper's best setting (#8, FCS, filtered).  Both merging modes
are scored on the held-out half of the sequences (radar V-measure against
the pre-clustered target) with the paper's parameters (#12, #13) and with
parameters tuned by random search on the training half.  Stage 1 runs once
thanks to ``ClusterMerger(memory=...)``.
"""

import argparse
import tempfile
import time

import numpy as np
from scipy.stats import uniform
from sklearn.model_selection import ParameterSampler

from sklearn_radar import ClusterMerger, DopplerDensityFilter, FrameTransform, RadarDBSCAN
from sklearn_radar.datasets import make_scenes
from sklearn_radar.metrics import precluster_target, radar_v_measure

STAGE1 = dict(metric="xyv", eps_xyv=1.04, vr_scale=1.03, min_samples=3.87, alpha_r=0.99, vr_min=1.0)
PAPER = {
    "velocity": dict(eps_d=1.00, eps_phi=np.deg2rad(23.11), eps_v=1.04, eps_t2=0.35),  # #12
    "continuation": dict(eps_d=0.94, eps_v=2.72, eps_t2=0.35),  # #13
}
SPACE = {
    "velocity": {
        "eps_d": uniform(0.2, 2.8),
        "eps_phi": uniform(0.05, 1.0),
        "eps_v": uniform(0.2, 4.0),
        "eps_t2": uniform(0.1, 0.9),
    },
    "continuation": {"eps_d": uniform(0.2, 2.8), "eps_v": uniform(0.2, 5.8), "eps_t2": uniform(0.1, 0.9)},
}


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--n-sequences", type=int, default=8)
    parser.add_argument("--n-candidates", type=int, default=40)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    scenes = make_scenes(n_sequences=args.n_sequences, duration=30.0, random_state=args.seed)
    start = time.perf_counter()
    X = FrameTransform().fit_transform(scenes.data)
    frame_s = time.perf_counter() - start
    start = time.perf_counter()
    X = DopplerDensityFilter().fit_transform(X)
    filter_s = time.perf_counter() - start
    target = precluster_target(X, scenes.target)
    train = np.isin(scenes.groups, np.unique(scenes.groups)[::2])
    stage1 = RadarDBSCAN(**STAGE1)
    start = time.perf_counter()
    stage1_labels = stage1.fit(X).labels_
    stage1_s = time.perf_counter() - start

    def score(labels, rows):
        return radar_v_measure(target[rows], labels[rows], groups=scenes.groups[rows])

    print(f"{len(X)} detections ({args.n_sequences} sequences x 30 s), train/test by sequence; stage 1 = paper #8")
    print(f"stage 1 alone: test V1 {score(stage1_labels, ~train):.4f}, {stage1_labels.max() + 1} clusters\n")
    print(f"{'mode':<13} {'parameters':<7} {'test V1':>8} {'change':>8} {'merges':>7}  values")
    with tempfile.TemporaryDirectory() as cache:
        for mode in ("velocity", "continuation"):

            def merged(params, rows=slice(None), mode=mode):
                model = ClusterMerger(mode=mode, stage1=stage1, memory=cache, **params).fit(X)
                return model.labels_, len(model.merges_)

            sampled = list(ParameterSampler(SPACE[mode], n_iter=args.n_candidates, random_state=args.seed))
            tuned = max(sampled, key=lambda p: score(merged(p)[0], train))
            for name, params in (("paper", PAPER[mode]), ("tuned", tuned)):
                labels, n_merges = merged(params)
                v = score(labels, ~train)
                values = ", ".join(f"{k}={val:.2f}" for k, val in params.items())
                print(f"{mode:<13} {name:<7} {v:8.4f} {v - score(stage1_labels, ~train):+8.4f} {n_merges:7d}  {values}")
            start = time.perf_counter()
            ClusterMerger(mode=mode, stage1=stage1, **PAPER[mode]).fit(X)
            stage2_s = time.perf_counter() - start - stage1_s
            total = frame_s + filter_s + stage1_s + stage2_s
            print(
                f"{'':<13} time: stage 2 {stage2_s:.2f} s = {len(X) / stage2_s:,.0f} detections/s, "
                f"{100 * stage2_s / total:.0f} % of frame + filter + stage 1 + stage 2 ({total:.2f} s)"
            )


if __name__ == "__main__":
    main()
