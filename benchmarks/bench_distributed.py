"""dask.distributed: search speed-up, peak memory per worker of a streamed ``cluster``, projection to RadarScenes.

Run: ``python benchmarks/bench_distributed.py`` (about 15 min on 2 idle cores; ``--parts speedup``,
``--parts memory`` or ``--parts projection`` run one part; ``--repeats``, ``--n-iter``, ``--scale`` change the size).
Needs the ``[distributed]`` extra.

1. **Speed-up.**  ``reproduce`` of the stage-1 experiment #8 (default data: 4 simulated sequences x 20 s,
   2 grouped folds on the training half) with a ``--n-iter`` (100) iteration search, once in one process
   and once with ``--workers 2``, the same ``n_points`` (1: each step's two folds run side by side), runs
   interleaved ``--repeats`` times.  The figure is the search's own wall time (``search_wall_time_s`` of
   ``results.json``: no data loading, no cluster start-up, no report); the ratio of the medians is the
   speed-up.  Both runs must write the same figures (checked and printed).
2. **Memory.**  ``cluster`` of a simulated data set ``--scale`` (10) times the default size of
   ``sklearn-radar simulate`` (4 sequences x 30 s), with the saved setting of #8: the whole table in one
   process (what ``cluster`` did before), the stream in one process, and the stream on 2 local workers.
   Peak RSS is each process's ``ru_maxrss``; the per-sequence task times give the per-detection cost.
3. **Projection** of ``reproduce --full`` and ``cluster`` on the real RadarScenes data set (158 sequences,
   ~100 M detections) for 8, 32 and 128 workers, from the measured costs, with the arithmetic printed.
"""

from __future__ import annotations

import argparse
import dataclasses
import io
import json
import logging
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

#: The real data set (RadarScenes: 158 sequences, over 4 h of driving, on the order of 100 M detections).
REAL_SEQUENCES = 158
REAL_DETECTIONS = 100e6
#: ``--full``'s searches: experiments #2-#9, #12, #13 and the 4 baselines, each ``PAPER_N_ITER`` candidates,
#: on the training half, 3 folds.
FULL_SEARCHES = 14
FULL_ITER = 100
FULL_FOLDS = 3


def _quiet():
    # In memory: with an open file as its progress stream a run on a cluster could not ship its tasks (it hung).
    return io.StringIO()


def _figures(out):
    def strip(value):
        if isinstance(value, dict):
            return {k: strip(v) for k, v in value.items() if "time" not in k}
        if isinstance(value, list):
            return [strip(v) for v in value]
        return value

    return strip(json.loads((Path(out) / "results.json").read_text()))


def _search_seconds(out, number="8"):
    return json.loads((Path(out) / "results.json").read_text())["experiments"][number]["search_wall_time_s"]


# ----------------------------------------------------------------------------- 1. speed-up


def speedup(work, n_iter, repeats, n_points, scale=1):
    from sklearn_radar.datasets import make_scenes, write_radarscenes
    from sklearn_radar.reproduce import reproduce
    from sklearn_radar.reproduce._results import Budget

    budget = Budget.default()
    data = work / f"speedup-data-{scale}"
    n_sequences = budget.n_sequences * scale
    scenes = make_scenes(n_sequences=n_sequences, duration=budget.duration, random_state=0)
    write_radarscenes(scenes, data)
    print(
        f"## 1. Speed-up: a {n_iter}-iteration stage-1 search (#8), {len(scenes.data):,} detections "
        f"({n_sequences} x {budget.duration:g} s, {scale}x the default data), {budget.cv_folds} folds, "
        f"n_points {n_points}"
    )
    times = {"1 process": [], "2 workers": []}
    figures = {}
    for repeat in range(repeats):
        for name, workers in (("1 process", None), ("2 workers", 2)):
            out = work / f"speedup-{scale}-{repeat}-{workers}"
            reproduce(data, out, n_iter=n_iter, experiments="8", n_points=n_points, workers=workers, stream=_quiet())
            seconds = _search_seconds(out)
            times[name].append(seconds)
            figures[name] = _figures(out)
            print(f"  run {repeat + 1}, {name:<9}: search {seconds:7.1f} s", flush=True)
    one, two = statistics.median(times["1 process"]), statistics.median(times["2 workers"])
    same = figures["1 process"] == figures["2 workers"]
    print(f"  median: 1 process {one:.1f} s, 2 workers {two:.1f} s; speed-up {one / two:.2f}x")
    print(f"  same figures (results.json without wall times): {'yes' if same else 'NO'}")
    per_run = [a / b for a, b in zip(times["1 process"], times["2 workers"], strict=True)]
    print(f"  speed-up per interleaved pair: {', '.join(f'{r:.2f}x' for r in per_run)}")
    return {
        "one": one,
        "two": two,
        "n_iter": n_iter,
        "n_train": figures["1 process"]["meta"]["data"]["n_train"],
        "scale": scale,
    }


def evaluation_cost(work, n_candidates=20, scale=1):
    """Seconds per candidate (all folds) of #8's search without the Gaussian process (random candidates only)."""
    from sklearn_radar.reproduce import reproduce
    from sklearn_radar.reproduce._results import Budget

    data = work / f"speedup-data-{scale}"
    out = work / f"random-only-{scale}"
    # Every candidate random (n_initial_points = n_iter): the time is the evaluations', no Gaussian process.
    original = Budget.__dict__["default"]
    Budget.default = staticmethod(
        lambda n_iter=None: dataclasses.replace(original.__func__(Budget, n_iter), n_initial_points=n_candidates)
    )
    try:
        reproduce(data, out, n_iter=n_candidates, experiments="8", stream=_quiet())
    finally:
        Budget.default = original
    seconds = _search_seconds(out)
    return seconds / n_candidates


# ----------------------------------------------------------------------------- 2. memory


PEAK = """
import json, sys, time
from sklearn_radar.reproduce import cluster_radarscenes, load_params
from sklearn_radar.datasets import load_radarscenes
from sklearn_radar.experiments import experiment_pipeline
mode, data, params, out = sys.argv[1:5]
start = time.perf_counter()
if mode == "whole":
    setting = load_params(params)
    scenes = load_radarscenes(data)
    labels = experiment_pipeline(setting["experiment"], params=setting["params"]).fit_predict(scenes.data)
    n = len(labels)
else:
    n = cluster_radarscenes(data, params, out)["n_detections"]
from sklearn_radar._distributed import peak_rss
print(json.dumps({"peak": peak_rss(), "seconds":
    time.perf_counter() - start, "n": n}))
"""


def memory(work, scale):
    import dask.distributed as distributed

    from sklearn_radar._distributed import peak_rss
    from sklearn_radar.datasets import make_scenes, write_radarscenes
    from sklearn_radar.reproduce import cluster_radarscenes, reproduce

    n_sequences, duration = 4 * scale, 30.0
    data = work / "memory-data"
    start = time.perf_counter()
    detections = 0
    # Written in parts so that this script does not hold the whole set either.
    part_size = 4
    for first in range(0, n_sequences, part_size):
        scenes = make_scenes(n_sequences=part_size, duration=duration, random_state=first)
        scenes = _renumbered(scenes, first)
        detections += len(scenes.data)
        write_radarscenes(scenes, work / f"part-{first}")
    _merge_parts(work, data, n_sequences, part_size)
    print(
        f"\n## 2. Peak memory: cluster on {n_sequences} sequences x {duration:g} s = {scale}x the default "
        f"simulate size, {detections:,} detections (simulated in {time.perf_counter() - start:.0f} s)"
    )
    params = work / "memory-params" / "params.json"
    reproduce(work / "part-0", params.parent, n_iter=1, experiments="8", stream=_quiet())
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    rows = {}
    for mode in ("whole", "stream"):
        done = subprocess.run(
            [sys.executable, "-c", PEAK, mode, str(data), str(params), str(work / f"p-{mode}.json")],
            capture_output=True,
            text=True,
            env=env,
            check=True,
        )
        rows[mode] = json.loads(done.stdout.strip().splitlines()[-1])
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=logging.ERROR
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        idle = client.run(peak_rss)
        with distributed.get_task_stream(client=client) as stream:
            start = time.perf_counter()
            cluster_radarscenes(data, params, work / "p-workers.json", scheduler=cluster.scheduler_address)
            seconds = time.perf_counter() - start
        peaks = client.run(peak_rss)
    same = (work / "p-workers.json").read_bytes() == (work / "p-stream.json").read_bytes()
    mb = 1 / 2**20
    print(
        f"  whole table, 1 process (before): peak RSS {rows['whole']['peak'] * mb:7.0f} MB, "
        f"{rows['whole']['seconds']:.0f} s"
    )
    print(
        f"  stream, 1 process:                peak RSS {rows['stream']['peak'] * mb:7.0f} MB, "
        f"{rows['stream']['seconds']:.0f} s"
    )
    for address, peak in sorted(peaks.items()):
        print(f"  stream, worker {address}: peak RSS {peak * mb:7.0f} MB (idle worker: {idle[address] * mb:.0f} MB)")
    print(f"  stream on 2 workers: {seconds:.0f} s wall; predictions identical to the 1-process stream: {same}")
    tasks = [t for t in stream.data if "cluster_sequence" in t["key"]]
    busy = sum(
        stop - begin
        for t in tasks
        for kind, begin, stop in ((s["action"], s["start"], s["stop"]) for s in t["startstops"])
        if kind == "compute"
    )
    per_detection = busy / detections
    print(
        f"  per-sequence tasks: {len(tasks)}, compute {busy:.1f} s in total = {per_detection * 1e6:.2f} µs per "
        f"detection (load + stages 0-2)"
    )
    return {"per_detection_cluster": per_detection, "detections": detections}


def _renumbered(scenes, first):
    """Sequences ``first + 1 ...`` instead of ``1 ...`` (one simulated part of a larger set)."""
    from sklearn.utils import Bunch

    offset = first
    data = scenes.data.copy()
    data["sequence"] += offset
    odometry = scenes.odometry.copy()
    odometry["sequence"] += offset
    sequences = scenes.sequences.copy()
    sequences["sequence"] += offset
    sequences["name"] = [f"sequence_{n}" for n in sequences["sequence"]]
    return Bunch(
        **{**scenes, "data": data, "odometry": odometry, "sequences": sequences, "groups": scenes.groups + offset}
    )


def _merge_parts(work, data, n_sequences, part_size):
    """One data folder from the parts: the sequence folders moved, the catalogues joined."""
    data.mkdir()
    catalogue = {}
    for first in range(0, n_sequences, part_size):
        part = work / f"part-{first}"
        catalogue.update(json.loads((part / "sequences.json").read_text())["sequences"])
        for folder in part.glob("sequence_*"):
            os.symlink(folder, data / folder.name)
        if first == 0:
            (data / "sensors.json").write_text((part / "sensors.json").read_text())
    document = json.loads((work / "part-0" / "sequences.json").read_text())
    document["sequences"] = catalogue
    (data / "sequences.json").write_text(json.dumps(document))


# ----------------------------------------------------------------------------- 3. projection


def projection(search, per_candidate, cluster_cost):
    print("\n## 3. Projection to RadarScenes (158 sequences, ~100 M detections)")
    n_train = search["n_train"]
    g = max(search["one"] / search["n_iter"] - per_candidate, 0.0)
    e_det = per_candidate / n_train
    train = REAL_DETECTIONS / 2
    E = e_det * train
    print(
        f"  measured: one candidate of #8 (all folds) {per_candidate:.3f} s on {n_train:,} training detections "
        f"= {e_det * 1e6:.2f} µs per detection; proposing a candidate (Gaussian process, this process) "
        f"g = {search['one']:.1f} s / {search['n_iter']} - {per_candidate:.3f} s = {g:.3f} s"
    )
    print(
        f"  RadarScenes training half: {train / 1e6:.0f} M detections -> one candidate E = {e_det * 1e6:.2f} µs "
        f"x {train / 1e6:.0f} M = {E:.0f} s of work"
    )
    print(
        f"  a search: {FULL_ITER} candidates, n_points = W / {FULL_FOLDS} per step (every worker busy), so "
        f"{FULL_ITER} x {FULL_FOLDS} / W steps of (n_points x g + E / {FULL_FOLDS}):"
    )
    print(
        f"    T_search(W) = {FULL_ITER} x g + {FULL_ITER} x E / W;  "
        f"--full = {FULL_SEARCHES} searches, one after the other"
    )
    c = cluster_cost["per_detection_cluster"]
    print(
        f"  cluster: {c * 1e6:.2f} µs per detection (load + stages 0-2) x 100 M = {c * REAL_DETECTIONS / 3600:.1f} h "
        f"of work, {REAL_SEQUENCES} sequence tasks"
    )
    print()
    print("  | workers | one search | --full searches (x14) | cluster (100 M) |")
    print("  |---|---|---|---|")
    for W in (8, 32, 128):
        t_search = FULL_ITER * g + FULL_ITER * E / W
        # Sequences are the tasks: no faster than the mean sequence (100 M / 158) once W >= 158.
        t_cluster = c * REAL_DETECTIONS / min(W, REAL_SEQUENCES)
        print(
            f"  | {W:>3} | {FULL_ITER} x {g:.2f} + {FULL_ITER} x {E:.0f} / {W} = {t_search / 3600:.2f} h "
            f"| {FULL_SEARCHES * t_search / 3600:.1f} h | {c * 1e6:.2f} µs x 100 M / {W} = {t_cluster:.0f} s |"
        )
    print(
        "  Assumptions: every search costs as much per detection as #8's (stage 2 and HDBSCAN cost more); the folds"
        " are balanced; g does not grow with the data (it grows with n_points: skopt fits the GP once per proposed"
        " point); the per-sequence cluster tasks are balanced (158 tasks: above 158 workers nothing is gained)."
    )


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--parts", default="speedup,memory,projection")
    parser.add_argument("--n-iter", type=int, default=100)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--n-points", type=int, default=1)
    parser.add_argument("--scale", type=int, default=10, help="data size of the memory part, x the default")
    parser.add_argument(
        "--search-scales", default="1,4", help="data sizes of the speed-up part, x the default (comma-separated)"
    )
    args = parser.parse_args()
    parts = set(args.parts.split(","))
    with tempfile.TemporaryDirectory(prefix="bench-distributed-") as work:
        work = Path(work)
        search = per_candidate = cluster_cost = None
        if parts & {"speedup", "projection"}:
            for scale in (int(text) for text in args.search_scales.split(",")):
                search = speedup(work, args.n_iter, args.repeats, args.n_points, scale)
                per_candidate = evaluation_cost(work, scale=scale)
                print(f"  one candidate without the Gaussian process: {per_candidate:.3f} s (20 random candidates)")
        if parts & {"memory", "projection"}:
            cluster_cost = memory(work, args.scale)
        if "projection" in parts:
            projection(search, per_candidate, cluster_cost)


if __name__ == "__main__":
    main()
