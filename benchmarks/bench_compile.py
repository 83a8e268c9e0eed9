"""Benchmark of the numba kernels' compile time: cold (empty cache) and warm (cached) per kernel module.

Run: ``python benchmarks/bench_compile.py [--repeat 3]``.

Each measurement runs in a child process of its own with ``NUMBA_CACHE_DIR``
pointing at a temporary directory: the first child of a module finds it
empty (cold: every kernel the module's entry points reach is compiled and
written to the cache), the second finds what the first wrote (warm: the
kernels are loaded from the cache).  A child imports the package first
(not timed), then calls the module's entry points once on a few hundred
points and reports that call's seconds, the compile events numba counted
and the type signatures each kernel was compiled for.  A module's cold time
includes the kernels of other modules that its kernels call (the grid of
``_neighbors`` and the union-find of ``_union_find``): it is what the first
call of that module costs in a fresh environment.  The last row runs every
module's entry points in one child, the cost of a fresh environment's first
``fit`` of each estimator kind.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

MODULES = {
    "_neighbors": "sklearn_radar._neighbors",
    "_labels": "sklearn_radar._labels",
    "_radar_dbscan_kernels": "sklearn_radar.cluster._radar_dbscan_kernels",
    "_merge_kernels": "sklearn_radar.cluster._merge_kernels",
}


# ----------------------------------------------------------------------------- the entry points of each module


def _points(n=400, seed=0):
    rng = np.random.default_rng(seed)
    t = np.repeat(np.arange(n // 20) * 0.06, 20)
    x, y = rng.uniform(0.0, 20.0, n), rng.uniform(0.0, 20.0, n)
    v = rng.choice([0.0, 3.0, -4.0], n) + rng.normal(0.0, 0.1, n)
    return x, y, v, t


def call_neighbors():
    from sklearn_radar._neighbors import build_grid, count_neighbors

    x, y, _v, t = _points()
    count_neighbors(build_grid(x, y, t, 1.0), 1.0, 0.25, 0.25, 5)


def call_labels():
    from sklearn_radar._labels import consecutive_labels

    consecutive_labels(np.array([3, -1, 3, 0, 7], dtype=np.int64))


def call_radar_dbscan_kernels():
    from sklearn_radar._neighbors import build_grid
    from sklearn_radar.cluster import _radar_dbscan_kernels as k

    x, y, v, t = _points()
    heading = np.linspace(0.0, 0.3, len(x))
    for metric in ("box", "xy", "xyv"):  # one compiled kernel serves every metric (a run-time code)
        crit = k.criterion_of(
            metric=metric, eps_xy=1.5, eps_vr=1.0, vr_scale=1.0, eps_xyv=1.5, eps_t=0.25, heading=heading
        )
        grid = build_grid(x, y, t, 1.5)
        o = grid.order
        points = k.points_of(x=x[o], y=y[o], v=v[o], t=t[o], heading=heading[o])
        min_points = np.full(len(x), 3.0)
        k.cluster_sorted(
            points=points, grid=grid, min_points=min_points, can_be_core=np.abs(v[o]) > 1.0, criterion=crit
        )
        points = k.points_of(x=x, y=y, v=v, t=t, heading=heading)
        k.cluster_causal(points=points, min_points=min_points, can_be_core=np.abs(v) > 1.0, criterion=crit)


def call_merge_kernels():
    from sklearn_radar.cluster import _merge_kernels as k

    x, y, _v, t = _points()
    labels = (np.arange(len(x)) % 7).astype(np.int64)
    runs = k.cluster_runs(labels, x, y, t)
    for mode in ("velocity", "continuation"):
        a, b = k.candidate_pairs(runs, 0.5, 2.0, mode)
    k.time_compatible_pairs(runs, 0.5)
    k.velocity_windows(runs, a, b, 2.0, 0.5)
    k.continuation_edges(runs, a, b, 2.0, 1.0, 0.5, True)
    k.merge_components(7, [(0, 1), (1, 2)], 2)


CALLS = {
    "_neighbors": [call_neighbors],
    "_labels": [call_labels],
    "_radar_dbscan_kernels": [call_radar_dbscan_kernels],
    "_merge_kernels": [call_merge_kernels],
}
CALLS["all"] = [call for calls in list(CALLS.values()) for call in calls]


# ----------------------------------------------------------------------------- one child process


def child(name):
    """Import the package, call ``name``'s entry points once; print a JSON line of seconds, compiles, signatures."""
    import importlib

    from numba.core import event
    from numba.core.registry import CPUDispatcher

    started = time.perf_counter()
    for module in MODULES.values():  # the imports (numpy, numba, the package), not timed below
        importlib.import_module(module)
    import_s = time.perf_counter() - started
    compiled = []

    class Compiles(event.Listener):
        def on_start(self, ev):
            pass

        def on_end(self, ev):
            compiled.append(ev.data["dispatcher"].py_func.__module__)

    listener = Compiles()
    event.register("numba:compile", listener)
    started, cpu_started = time.perf_counter(), time.process_time()
    for call in CALLS[name]:
        call()
    seconds, cpu_s = time.perf_counter() - started, time.process_time() - cpu_started
    event.unregister("numba:compile", listener)
    signatures = {}
    for module in (*MODULES.values(), "sklearn_radar._union_find"):
        for value in vars(importlib.import_module(module)).values():
            if isinstance(value, CPUDispatcher) and value.signatures:
                kernel = f"{value.py_func.__module__.rsplit('.', 1)[-1]}.{value.py_func.__name__}"
                signatures[kernel] = [str(s) for s in value.signatures]
    ours = sum(module.startswith("sklearn_radar") for module in compiled)
    print(json.dumps(dict(seconds=seconds, cpu_s=cpu_s, import_s=import_s, compiles=ours, signatures=signatures)))


def measure(name, cache_dir):
    env = {**os.environ, "NUMBA_CACHE_DIR": cache_dir}
    env["PYTHONPATH"] = os.pathsep.join([str(Path(__file__).resolve().parents[1]), env.get("PYTHONPATH", "")])
    done = subprocess.run(
        [sys.executable, __file__, "--child", name], env=env, capture_output=True, text=True, check=True
    )
    return json.loads(done.stdout.strip().splitlines()[-1])


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3, help="cold/warm pairs per module (medians are printed)")
    parser.add_argument("--modules", nargs="+", default=list(CALLS), choices=list(CALLS))
    parser.add_argument("--child", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.child)
        return
    print(f"load average at the start: {os.getloadavg()[0]:.2f} (1 min), on {os.cpu_count()} cores")
    print("first call of each module's entry points, s: median (min-max) of --repeat fresh caches;")
    print("CPU = the child's CPU time (compiling is single-threaded: nearly load-independent), wall = elapsed")
    columns = ("cold CPU", "cold wall", "warm CPU", "warm wall")
    print(f"{'module':<22}", *(f"{c:>17}" for c in columns), f"{'compiles':>8} {'sigs':>5}")
    import_times, signatures = [], {}
    for name in args.modules:
        runs = {"cold": [], "warm": []}
        for _ in range(args.repeat):
            with tempfile.TemporaryDirectory() as cache_dir:
                first = measure(name, cache_dir)
                second = measure(name, cache_dir)
            runs["cold"].append(first)
            runs["warm"].append(second)
            import_times += [first["import_s"], second["import_s"]]
            if second["compiles"]:
                print(f"   {name}: {second['compiles']} kernel(s) compiled again although cached (cache miss)")
        signatures.update(first["signatures"])
        n_signatures = sum(len(s) for s in first["signatures"].values())
        figures = [_spread([r[key] for r in runs[kind]]) for kind in ("cold", "warm") for key in ("cpu_s", "seconds")]
        print(f"{name:<22}", *(f"{f:>17}" for f in figures), f"{first['compiles']:>8d} {n_signatures:>5d}")
    print(f"importing the kernel modules (numpy, numba; not in the figures above): {_spread(import_times)} s")
    print(f"load average at the end: {os.getloadavg()[0]:.2f} (1 min)")
    several = {kernel: s for kernel, s in signatures.items() if len(s) > 1}
    print("kernels compiled for more than one signature:", "none" if not several else "")
    for kernel, s in several.items():
        print(f"   {kernel}:", *s, sep="\n      ")


def _spread(values):
    values = sorted(values)
    return f"{np.median(values):.2f} ({values[0]:.2f}-{values[-1]:.2f})"


if __name__ == "__main__":
    main()
