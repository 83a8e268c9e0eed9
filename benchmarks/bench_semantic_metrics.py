"""Benchmark of the semantic metrics: semantic_scores against the class-agnostic panoptic_quality.

Run: ``python benchmarks/bench_semantic_metrics.py [--n-detections 1000000] [--repeat 5] [--seed 0]``.

Data: random labellings of the shape of radar scenes, ``--n-detections`` detections in 8 sequences of 60 s
(times uniform), 40 % of them on 400 ground-truth objects per sequence, each with a road-user class 0-4 (1 % of
the detections ignored, -2); the prediction keeps 80 % of each object's detections in one instance, scatters the
rest, classifies each row right with probability 0.85 and adds clusters of background.  Printed, each the best of
``--repeat`` runs: the wall time of ``semantic_scores`` (class-aware PQ, mAP@0.5, macro-F1, mCov) and of
``panoptic_quality`` on the same instances (0.5 s windows both), and their ratio.
"""

import argparse
import time

import numpy as np

from sklearn_radar.metrics import panoptic_quality, semantic_scores


def random_scene(n, seed):
    """Columns of a random classified segmentation of n detections (see the module docstring)."""
    rng = np.random.default_rng(seed)
    groups = rng.integers(0, 8, n)
    times = rng.uniform(0.0, 60.0, n)
    on_object = rng.random(n) < 0.4
    instances_true = np.where(on_object, rng.integers(0, 400, n), -1)
    object_class = rng.integers(0, 5, 400)
    classes_true = np.where(on_object, object_class[np.maximum(instances_true, 0)], -1)
    classes_true[rng.random(n) < 0.01] = -2
    kept_whole = rng.random(n) < 0.8
    instances_pred = np.where(on_object & kept_whole, instances_true, rng.integers(-1, 2000, n))
    classes_pred = np.where(rng.random(n) < 0.85, np.maximum(classes_true, -1), rng.integers(-1, 5, n))
    confidence = rng.uniform(0.3, 1.0, n)
    return classes_true, instances_true, classes_pred, instances_pred, confidence, times, groups


def best_of(function, repeat):
    """Wall time in s of the fastest of ``repeat`` calls, and the last result."""
    best, result = np.inf, None
    for _ in range(repeat):
        start = time.perf_counter()
        result = function()
        best = min(best, time.perf_counter() - start)
    return best, result


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n-detections", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    classes_true, instances_true, classes_pred, instances_pred, confidence, times, groups = random_scene(
        args.n_detections, args.seed
    )
    semantic_time, scores = best_of(
        lambda: semantic_scores(
            classes_true, instances_true, classes_pred, instances_pred, confidence, times=times, groups=groups
        ),
        args.repeat,
    )
    panoptic_time, panoptic = best_of(
        lambda: panoptic_quality(instances_true, instances_pred, times=times, groups=groups), args.repeat
    )
    print(f"{args.n_detections} detections, best of {args.repeat}")
    print(
        f"semantic_scores  {semantic_time * 1e3:8.1f} ms  (pq {scores['pq']:.3f}, map {scores['map']:.3f}, "
        f"macro_f1 {scores['macro_f1']:.3f}, mcov {scores['mcov']:.3f})"
    )
    print(f"panoptic_quality {panoptic_time * 1e3:8.1f} ms  (pq {panoptic['pq']:.3f})")
    print(f"ratio semantic_scores / panoptic_quality: {semantic_time / panoptic_time:.2f}")


if __name__ == "__main__":
    main()
