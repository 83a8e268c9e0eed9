"""Benchmark of stage 0: FrameTransform and DopplerDensityFilter (Eq. 1).

Run: ``python benchmarks/bench_filter.py [--n-sequences 17] [--duration 30]``.
One run prints one table: detections/s of the frame transform, of the
filter, and of scikit-learn's KDTree counting neighbours on the same points
(an ellipsoid in scaled x-y-t, the nearest thing scikit-learn offers to the
cylinder of Eq. 1; same work, not the same result), plus a dense-clutter case.
"""

import argparse
import time

import numpy as np
import pandas as pd
from sklearn.neighbors import KDTree

from sklearn_radar import DopplerDensityFilter, FrameTransform
from sklearn_radar.datasets import make_scenes


def timed(func, repeat=3):
    best, result = np.inf, None
    for _ in range(repeat):
        start = time.perf_counter()
        result = func()
        best = min(best, time.perf_counter() - start)
    return best, result


def sklearn_counts(X, d_xy=1.4, dt=0.25):
    counts = np.empty(len(X), dtype=np.int64)
    for _, rows in X.groupby("sequence").indices.items():
        points = np.c_[X["x"].to_numpy()[rows], X["y"].to_numpy()[rows], X["t"].to_numpy()[rows] * (d_xy / dt)]
        counts[rows] = KDTree(points).query_radius(points, r=d_xy, count_only=True) - 1
    return counts


def dense_clutter(n_total, n_dense, rng):
    """Sparse detections plus ``n_dense`` static ones in 2 m x 2 m within 0.25 s."""
    sparse = n_total - n_dense
    x = np.r_[rng.uniform(0, 5000, sparse), rng.uniform(0, 2, n_dense)]
    y = np.r_[rng.uniform(0, 500, sparse), rng.uniform(0, 2, n_dense)]
    t = np.r_[rng.uniform(0, 600, sparse), rng.uniform(0, 0.25, n_dense)]
    return pd.DataFrame({"x": x, "y": y, "v_r": rng.normal(0, 0.05, n_total), "t": t, "sequence": 1})


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--n-sequences", type=int, default=17, help="17 x 30 s is about 1 million detections")
    parser.add_argument("--duration", type=float, default=30.0)
    args = parser.parse_args()

    scenes = make_scenes(args.n_sequences, args.duration, random_state=0)
    n = len(scenes.data)
    print(f"simulated data: {args.n_sequences} sequences x {args.duration:g} s = {n} detections")
    frame_s, X = timed(lambda: FrameTransform().fit_transform(scenes.data))
    DopplerDensityFilter().fit_transform(X.iloc[:1000])  # JIT warm-up, not timed
    filter_s, _ = timed(lambda: DopplerDensityFilter().fit_transform(X))
    filter2_s, _ = timed(lambda: DopplerDensityFilter(n_jobs=2).fit_transform(X))
    sklearn_s, _ = timed(lambda: sklearn_counts(X), repeat=1)

    rows = [
        ("FrameTransform (FCS)", frame_s),
        ("DopplerDensityFilter", filter_s),
        ("DopplerDensityFilter n_jobs=2", filter2_s),
        ("sklearn KDTree count (reference)", sklearn_s),
    ]
    print(f"\n{'step':<34} {'seconds':>8} {'detections/s':>14} {'vs sklearn':>11}")
    for name, seconds in rows:
        print(f"{name:<34} {seconds:8.2f} {n / seconds:14,.0f} {sklearn_s / seconds:10.1f}x")

    rng = np.random.default_rng(0)
    print(f"\n{'dense clutter (2 m x 2 m, 0.25 s)':<34} {'seconds':>8} {'detections/s':>14} {'vs sklearn':>11}")
    for n_dense in (0, 5_000, 20_000):
        D = dense_clutter(200_000, n_dense, rng)
        seconds, _ = timed(lambda D=D: DopplerDensityFilter().fit_transform(D))
        reference, _ = timed(lambda D=D: sklearn_counts(D), repeat=1)
        label = f"200k detections, {n_dense} dense"
        print(f"{label:<34} {seconds:8.2f} {len(D) / seconds:14,.0f} {reference / seconds:10.1f}x")


if __name__ == "__main__":
    main()
