"""ClusterMerger's spatial prefilter of cluster pairs (issue 15, item 1): linear memory, identical merges."""

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from sklearn_radar.cluster._merge_kernels import (
    candidate_pairs,
    cluster_runs,
    continuation_edges,
    time_compatible_pairs,
    velocity_windows,
)


def _random_clusters(rng, n_clusters, spread, tiny_dt=False, offset=0.0):
    """Labels, x, y, t of ``n_clusters`` short random tracks (some fast, some with near-equal scan times)."""
    rows = []
    for label in range(n_clusters):
        n_scans = int(rng.integers(1, 7))
        t0 = rng.uniform(0, 3.0)
        dt = rng.choice([0.06, 1e-9, 1e-200]) if tiny_dt else 0.06
        times = t0 + dt * np.arange(n_scans)
        speed = rng.normal(0, rng.choice([1.0, 30.0]), 2)
        origin = offset + rng.uniform(-spread, spread, 2)
        for time in times:
            for _ in range(int(rng.integers(1, 4))):
                xy = origin + speed * (time - t0) + rng.normal(0, 0.3, 2)
                rows.append((label, xy[0], xy[1], time))
    labels, x, y, t = (np.array(column) for column in zip(*rows, strict=True))
    permutation = rng.permutation(len(labels))
    return labels[permutation].astype(np.int64), x[permutation], y[permutation], t[permutation]


@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize("eps_d, eps_t2", [(0.94, 0.35), (3.0, 1.0), (0.2, 0.1)])
def test_pruned_pairs_give_the_same_merges_as_all_time_compatible_pairs(seed, eps_d, eps_t2):
    rng = np.random.default_rng(seed)
    offset = [0.0, 0.0, 1e7][seed % 3]
    labels, x, y, t = _random_clusters(rng, 120, spread=15.0, tiny_dt=seed % 2 == 1, offset=offset)
    runs = cluster_runs(labels, x, y, t)
    all_a, all_b = time_compatible_pairs(runs, eps_t2)
    for accept in (False, True):
        merge = continuation_edges(runs, all_a, all_b, eps_d, 2.72, eps_t2, accept)
        a, b = candidate_pairs(runs, eps_t2, eps_d, "continuation")
        kept = continuation_edges(runs, a, b, eps_d, 2.72, eps_t2, accept)
        np.testing.assert_array_equal(np.c_[a[kept], b[kept]], np.c_[all_a[merge], all_b[merge]])
    frames_all = velocity_windows(runs, all_a, all_b, eps_d, eps_t2)
    a, b = candidate_pairs(runs, eps_t2, eps_d, "velocity")
    frames = velocity_windows(runs, a, b, eps_d, eps_t2)
    np.testing.assert_array_equal(
        np.c_[a[frames[:, 0]], b[frames[:, 0]]], np.c_[all_a[frames_all[:, 0]], all_b[frames_all[:, 0]]]
    )
    np.testing.assert_array_equal(frames[:, 1:], frames_all[:, 1:])
    # The pruned pairs are a subset of the time-compatible ones, in the same order.
    position = {pair: k for k, pair in enumerate(zip(all_a.tolist(), all_b.tolist(), strict=True))}
    kept_positions = [position[pair] for pair in zip(a.tolist(), b.tolist(), strict=True)]
    assert kept_positions == sorted(kept_positions)


def test_clusters_beyond_the_cell_keys_range_are_compared_with_all():
    # 1e12 m: beyond 2**31 grid cells of a few metres, where a cell key would overflow.
    labels, x, y, t = _random_clusters(np.random.default_rng(0), 60, spread=15.0, offset=1e12)
    runs = cluster_runs(labels, x, y, t)
    all_a, all_b = time_compatible_pairs(runs, 0.35)
    frames_all = velocity_windows(runs, all_a, all_b, 0.94, 0.35)
    a, b = candidate_pairs(runs, 0.35, 0.94, "velocity")
    frames = velocity_windows(runs, a, b, 0.94, 0.35)
    assert len(frames_all) > 0
    np.testing.assert_array_equal(
        np.c_[a[frames[:, 0]], b[frames[:, 0]]], np.c_[all_a[frames_all[:, 0]], all_b[frames_all[:, 0]]]
    )


def test_spread_out_clusters_give_a_linear_number_of_candidate_pairs():
    n = 20000
    labels = np.arange(2 * n) // 2
    x = 3.0 * labels + 0.1 * (np.arange(2 * n) % 2)
    t = np.random.default_rng(0).uniform(0, 0.25, 2 * n)
    runs = cluster_runs(labels, x, np.zeros(2 * n), t)
    for mode in ("continuation", "velocity"):
        a, _ = candidate_pairs(runs, 0.35, 0.94, mode)
        assert len(a) < 10 * n  # all time-compatible pairs: n (n - 1) / 2 = 2e8


def test_the_issue_case_runs_in_little_memory():
    # Issue 15, item 1: 20k two-point clusters alive at once took 52 s and 5.2 GB.  Memory only: the project's
    # tests never time (the machine is shared); the pair count above is what keeps the time linear.  The kernels
    # are compiled on a small case first, so the figure is the growth of the peak that the large case causes, not
    # the import's or a cold numba compile's (a CI run once saw a 900 MB peak with the kernels uncached).
    script = textwrap.dedent(
        """
        import resource
        import numpy as np, pandas as pd
        from sklearn_radar import ClusterMerger, RadarDBSCAN

        def case(n):
            k = np.arange(n) // 2
            X = pd.DataFrame({"x": 3.0 * k + 0.1 * (np.arange(n) % 2), "y": 0.0, "v_r": 5.0,
                              "t": np.random.default_rng(0).uniform(0, .25, n), "sequence": 1})
            for mode in ("continuation", "velocity"):
                X["azimuth_sc"] = 0.3; X["sensor_yaw"] = 0.0
                stage1 = RadarDBSCAN(metric="xy", eps_xy=0.5, min_samples=2, vr_min=-np.inf)
                model = ClusterMerger(mode=mode, stage1=stage1).fit(X)
                assert len(model.labels_) == n

        case(400)
        before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        case(40000)
        print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024 - before)
        """
    )
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    growth_mb = float(result.stdout.split()[-1])
    assert growth_mb < 400
