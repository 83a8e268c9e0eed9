"""Per-call time of the compiled tree walk against ``predict_proba`` on small batches (LinkClustering's classifier).

A HistGradientBoostingClassifier as LinkClustering fits it (150 iterations, 31 leaves) on random rows with 15 and 21
features (the detection and pair feature counts); median per-call time of ``predict_proba(X)[:, 1]`` and of
``boosting_proba`` on batches of 30 and 300 rows, one thread.

Run::

    OMP_NUM_THREADS=1 python benchmarks/bench_tree_walk.py
"""

import time

import numpy as np
from sklearn.ensemble import HistGradientBoostingClassifier
from threadpoolctl import threadpool_limits

from sklearn_radar.cluster._tree_walk import boosting_proba, compile_boosting


def _median_seconds(call, batches, repeats=300):
    """Median seconds of ``call(batch)``, cycling through distinct batches (the same one would train the branch
    predictor on its rows)."""
    times = []
    for k in range(repeats):
        batch = batches[k % len(batches)]
        start = time.perf_counter()
        call(batch)
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def main():
    rng = np.random.RandomState(0)
    with threadpool_limits(1):
        for n_features in (15, 21):
            X = rng.normal(size=(20_000, n_features))
            X[rng.uniform(size=X.shape) < 0.05] = np.nan
            y = np.nan_to_num(X[:, 0]) + np.nan_to_num(X[:, 1]) ** 2 + rng.normal(size=len(X)) > 0.8
            classifier = HistGradientBoostingClassifier(
                max_iter=150, max_leaf_nodes=31, early_stopping=False, random_state=0
            ).fit(X, y)
            start = time.perf_counter()
            compiled = compile_boosting(classifier)
            compile_ms = 1e3 * (time.perf_counter() - start)
            boosting_proba(compiled, X[:2])  # the numba compilation (or cache load)
            for n in (30, 300):
                batches = [X[k * n : (k + 1) * n] for k in range(len(X) // n)]
                assert np.array_equal(boosting_proba(compiled, batches[0]), classifier.predict_proba(batches[0])[:, 1])
                sk = _median_seconds(lambda batch, c=classifier: c.predict_proba(batch)[:, 1], batches)
                walk = _median_seconds(lambda batch, c=compiled: boosting_proba(c, batch), batches)
                print(
                    f"{n_features} features, {n:>3} rows: predict_proba {1e6 * sk:8.1f} us, "
                    f"walk {1e6 * walk:7.1f} us ({sk / walk:.0f}x); compile_boosting {compile_ms:.1f} ms"
                )


if __name__ == "__main__":
    main()
