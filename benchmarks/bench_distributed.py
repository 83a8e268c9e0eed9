"""dask.distributed: search speed-up, concurrent searches, peak memory of a streamed ``cluster``, projection.

Run: ``python benchmarks/bench_distributed.py`` (about 25 min on 2 idle cores; ``--parts speedup``,
``concurrent``, ``memory`` or ``projection`` run parts; ``--repeats``, ``--n-iter``, ``--search-scales``,
``--scale`` change the sizes).  Needs the ``[distributed]`` extra.

1. **Speed-up of one search.**  The search of #8 (or ``--search-experiment``; ``--n-iter`` 100 candidates, 30
   random, 3 grouped folds, ``n_points`` 1) as ``reproduce`` runs it
   (:mod:`sklearn_radar.model_selection._sequence_search`), on the default run's training half (2 simulated
   sequences x 20 s) times each of ``--search-scales``: in one process and on 2 local worker processes
   (``--workers 2``), interleaved ``--repeats`` times.  The clock runs from the first candidate to the last (stage
   0 done before; no cluster start-up, no data placement).  Both must find the same scores (checked).  The step
   times give E (a candidate's evaluation: the random steps) and g (the Gaussian process: guided steps minus E),
   hence Amdahl's bound.
1b. **Concurrent searches.**  ``reproduce --experiments 2-9`` on the default data, 1 process against
   ``--workers 2``, where the 8 independent searches run at once: whole-run wall time, same figures.
2. **Memory.**  ``cluster`` of a simulated data set ``--scale`` (10) times the default size of
   ``sklearn-radar simulate`` (4 sequences x 30 s), with the saved setting of #8: the whole table in one
   process (what ``cluster`` did before), the stream in one process, and the stream on 2 local workers.
   Peak RSS is each process's ``VmHWM``; the per-sequence task times give the per-detection cost.
2b. **Memory of reproduce.**  ``reproduce`` (``filter,1,3,filter-effect``, 2 iterations) on the same folder in one
   process and on 2 local workers: peak RSS of the command's process and of each worker, same results.
3. **Projection** of ``reproduce --full`` and ``cluster`` on the real RadarScenes data set (158 sequences,
   ~100 M detections) for 8, 32 and 128 workers, from the measured costs, with the arithmetic printed.
"""

from __future__ import annotations

import argparse
import io
import json
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


# ----------------------------------------------------------------------------- 1. speed-up


def _training_half(scale, seed=0):
    """The default run's training half (2 simulated sequences x 20 s) ``scale`` times: X, target, groups."""
    from sklearn_radar.datasets import make_scenes
    from sklearn_radar.metrics import precluster_target

    scenes = make_scenes(n_sequences=2 * scale, duration=20.0, random_state=seed)
    X = scenes.data[[c for c in scenes.data.columns if c not in ("uuid", "track_id", "label_id")]]
    return X, precluster_target(scenes.data, scenes.target), scenes.groups


class _StepClock:
    """Callback of a search: the wall time of every step."""

    def __init__(self):
        self.times, self._last = [], time.perf_counter()

    def __call__(self, result):
        now = time.perf_counter()
        self.times.append(now - self._last)
        self._last = now


def _timed_search(data, searched, space, folds, n_iter):
    from sklearn_radar.model_selection._sequence_search import bayes_search

    clock = _StepClock()
    start = time.perf_counter()
    found = bayes_search(
        searched,
        space,
        data,
        folds,
        objective="v1",
        n_iter=n_iter,
        n_initial_points=30,
        random_state=0,
        callback=clock,
    )
    return time.perf_counter() - start, clock.times, found.scores


def speedup(scales, n_iter, repeats, number=8):
    """Part 1: a search of ``number`` (#8) in one process and on 2 local workers, at several data sizes."""
    from distributed import wait
    from threadpoolctl import threadpool_limits

    from sklearn_radar._executor import connect_executor
    from sklearn_radar.experiments import experiment_pipeline, search_space
    from sklearn_radar.model_selection._sequence_search import SearchData, fixed_prefix, sequence_folds

    print(
        f"## 1. Speed-up: a {n_iter}-iteration search of #{number} (30 random candidates, then guided), "
        "1 process against 2 local worker processes"
    )
    print("  the training half of the default run (2 sequences x 20 s) times the scale; 3 grouped folds\n")
    print("  | scale | training detections | candidate E | proposing g | 1 process | 2 workers | speed-up |")
    print("  |---|---|---|---|---|---|---|")
    rows = []
    with connect_executor(workers=2) as cluster, threadpool_limits(limits=1, user_api="blas"):
        for scale in scales:
            X, target, groups = _training_half(scale)
            stage0, searched, space, _ = fixed_prefix(experiment_pipeline(number), search_space(number))
            folds = sequence_folds(groups, 3)
            times = {"1 process": [], "2 workers": []}
            steps, scores = {}, {}
            for _ in range(repeats):
                for name, where in (("1 process", None), ("2 workers", cluster)):
                    # Placed anew for each run and dropped after it: at scale 128 one copy is about 3 GB.
                    data = SearchData.place(X, target, groups, where).prepare(stage0)
                    if where is not None:
                        wait(data.blocks)  # stage 0 done on the workers before the clock starts
                    seconds, step_times, found = _timed_search(data, searched, space, folds, n_iter)
                    del data
                    times[name].append(seconds)
                    steps[name], scores[name] = step_times, found
            one, two = statistics.median(times["1 process"]), statistics.median(times["2 workers"])
            random_steps = statistics.median(steps["1 process"][1:30])  # no Gaussian process: the evaluation
            guided_steps = statistics.median(steps["1 process"][30:])
            row = {
                "scale": scale,
                "n_train": len(X),
                "one": one,
                "two": two,
                "E": random_steps,
                "g": guided_steps - random_steps,
                "n_iter": n_iter,
                "same": scores["1 process"] == scores["2 workers"],
            }
            rows.append(row)
            print(f"  row: {json.dumps(row)}", file=sys.stderr)
            print(
                f"  | {scale} | {len(X):,} | {row['E']:.3f} s | {row['g']:.3f} s | {one:.1f} s | {two:.1f} s "
                f"| **{one / two:.2f}x** |",
                flush=True,
            )
            del X, target, groups
    print()
    for row in rows:
        print(
            f"  scale {row['scale']}: same {n_iter} scores in both: {'yes' if row['same'] else 'NO'}; "
            f"per pair: {repeats} interleaved repeat(s), medians shown"
        )
    print(
        "  E: median step of the 29 random candidates after the first (the evaluation alone); g: median guided "
        "step minus E (the Gaussian process, in the command's process).  Amdahl: at most (g + E) / (g + E / 2)."
    )
    return rows


# ----------------------------------------------------------------------------- 1b. concurrent searches


def concurrent(work, n_iter, experiments="2-9"):
    """Part 1b: ``reproduce`` of the independent stage-1 experiments, 1 process against 2 local workers."""
    from sklearn_radar.reproduce import reproduce

    print(f"\n## 1b. reproduce --experiments {experiments} --n-iter {n_iter} (default data): searches at once")
    walls, figures = {}, {}
    for name, workers in (("1 process", None), ("2 workers", 2)):
        out = work / f"concurrent-{workers}"
        start = time.perf_counter()
        reproduce(None, out, n_iter=n_iter, experiments=experiments, workers=workers, stream=_quiet())
        walls[name] = time.perf_counter() - start
        figures[name] = _figures(out)
        print(f"  {name:<9}: {walls[name]:6.1f} s wall (whole run: data, searches, test scores, report)", flush=True)
    print(
        f"  speed-up {walls['1 process'] / walls['2 workers']:.2f}x; same figures: "
        f"{'yes' if figures['1 process'] == figures['2 workers'] else 'NO'}"
    )
    return walls


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
from sklearn_radar._executor import peak_rss
print(json.dumps({"peak": peak_rss(), "seconds":
    time.perf_counter() - start, "n": n}))
"""


REPRODUCE_PEAK = """
import io, json, sys, time
from sklearn_radar._executor import connect_executor, peak_rss
from sklearn_radar.reproduce import reproduce
workers, data, out, steps = int(sys.argv[1]), sys.argv[2], sys.argv[3], sys.argv[4]
start = time.perf_counter()
peaks = {}
if workers:  # as --workers starts them, the scheduler in this process
    with connect_executor(workers=workers) as cluster:
        reproduce(data, out, n_iter=2, experiments=steps, stream=io.StringIO(), scheduler=cluster.address)
        peaks = cluster.client.run(peak_rss)
else:
    reproduce(data, out, n_iter=2, experiments=steps, stream=io.StringIO())
print(json.dumps({"peak": peak_rss(), "seconds": time.perf_counter() - start, "workers": peaks}))
"""


def reproduce_memory(work, data, detections, steps="filter,1,3,filter-effect"):
    """Part 2b: peak memory of the command's process of ``reproduce`` on the same folder, 1 process and 2 workers."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    mb = 1 / 2**20
    print(f"\n## 2b. Peak memory of reproduce's own process on the same {detections:,} detections ({steps}, n-iter 2)")
    for workers in (0, 2):
        done = subprocess.run(
            [sys.executable, "-c", REPRODUCE_PEAK, str(workers), str(data), str(work / f"r-{workers}"), steps],
            capture_output=True,
            text=True,
            env=env,
            check=True,
        )
        row = json.loads(done.stdout.strip().splitlines()[-1])
        where = "1 process" if not workers else f"--workers {workers} (the command's process: client and scheduler)"
        print(f"  {where}: peak RSS {row['peak'] * mb:7.0f} MB, {row['seconds']:.0f} s", flush=True)
        for address, peak in sorted(row["workers"].items()):
            print(f"    worker {address}: peak RSS {peak * mb:7.0f} MB")
    one, two = (_figures(work / f"r-{w}") for w in (0, 2))
    for figures in (one, two):  # the filter effect's measured clustering times differ from run to run
        for side in ("filtered", "unfiltered"):
            figures["filter_effect"][side].pop("clustering_s")
    print(f"  same results.json (but the filter effect's clustering clock): {one == two}")


def memory(work, scale):
    import dask.distributed as distributed

    from sklearn_radar._executor import connect_executor, peak_rss
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
    # As --workers starts them (without dask's MALLOC_TRIM_THRESHOLD_, which slowed the kernels 2x).
    with connect_executor(workers=2) as local:
        client = local.client
        idle = client.run(peak_rss)
        with distributed.get_task_stream(client=client) as stream:
            start = time.perf_counter()
            cluster_radarscenes(data, params, work / "p-workers.json", scheduler=local.address)
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
    reproduce_memory(work, data, detections)
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


def projection(row, cluster_cost, repeats=3):
    """Part 3: ``reproduce --full`` and ``cluster`` on RadarScenes for 8, 32 and 128 workers, from measured costs."""
    print("\n## 3. Projection to RadarScenes (158 sequences, ~100 M detections)")
    e_det = row["E"] / row["n_train"]
    g = row["g"]
    train = REAL_DETECTIONS / 2
    train_sequences = REAL_SEQUENCES // 2
    E = e_det * train
    searches = FULL_SEARCHES * repeats
    print(
        f"  measured (scale {row['scale']}): one candidate of #8 E = {row['E']:.3f} s on {row['n_train']:,} training "
        f"detections = {e_det * 1e6:.3f} µs per detection; proposing a candidate g = {g:.3f} s"
    )
    print(
        f"  RadarScenes training half: {train / 1e6:.0f} M detections in {train_sequences} sequences -> one "
        f"candidate is {E:.1f} s of work in at most {train_sequences} tasks"
    )
    print(f"  one search:  T1(W) = {FULL_ITER} x (g + E / min(W, {train_sequences}))")
    print(
        f"  --full: {FULL_SEARCHES} searches x {repeats} repeats = {searches}; all but #12, #13 (x {repeats}) run "
        f"at once, each search loop on a worker, then #12 and #13 one search after the other, so  "
        f"T(W) ~ {searches} x {FULL_ITER} x (E + g) / W + 2 x {repeats} x T1(W)"
    )
    c = cluster_cost["per_detection_cluster"]
    print(
        f"  cluster: {c * 1e6:.2f} µs per detection (load + stages 0-2) x 100 M = {c * REAL_DETECTIONS / 3600:.1f} h "
        f"of work, {REAL_SEQUENCES} sequence tasks"
    )
    print()
    print("  | workers | one search | --full searches | cluster (100 M) |")
    print("  |---|---|---|---|")
    for W in (8, 32, 128):
        t1 = FULL_ITER * (g + E / min(W, train_sequences))
        t_full = searches * FULL_ITER * (E + g) / W + 2 * repeats * t1
        t_cluster = c * REAL_DETECTIONS / min(W, REAL_SEQUENCES)
        print(f"  | {W:>3} | {t1 / 60:.1f} min | {t_full / 3600:.2f} h | {t_cluster:.0f} s |")
    print(
        "  Assumptions: every search costs as much per detection as #8's (stage 2 and HDBSCAN cost more); the "
        "sequence blocks are balanced; g does not grow with the data; the per-sequence cluster tasks are balanced "
        "(158 tasks: above 158 workers nothing is gained); the workers' cores are all the search's; and the "
        "command's process holds the whole data set, which reproduce still needs (see the docs)."
    )


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--parts", default="speedup,concurrent,memory,projection")
    parser.add_argument("--n-iter", type=int, default=100)
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--scale", type=int, default=10, help="data size of the memory part, x the default")
    parser.add_argument(
        "--search-scales", default="1,4,16,64", help="data sizes of the speed-up part, x the default training half"
    )
    parser.add_argument(
        "--search-experiment", type=int, default=8, help="the stage-1 experiment the speed-up part searches"
    )
    parser.add_argument(
        "--search-row",
        help="JSON of a speed-up row printed by an earlier run ('row: {...}'): the projection uses it instead of "
        "measuring again (e.g. with --parts memory,projection)",
    )
    args = parser.parse_args()
    parts = set(args.parts.split(","))
    with tempfile.TemporaryDirectory(prefix="bench-distributed-") as work:
        work = Path(work)
        rows = cluster_cost = None
        if args.search_row:
            rows = [json.loads(args.search_row)]
        if "speedup" in parts or ("projection" in parts and not args.search_row):
            scales = [int(text) for text in args.search_scales.split(",")]
            rows = speedup(scales, args.n_iter, args.repeats, args.search_experiment)
        if "concurrent" in parts:
            concurrent(work, args.n_iter)
        if parts & {"memory", "projection"}:
            cluster_cost = memory(work, args.scale)
        if "projection" in parts:
            projection(rows[-1], cluster_cost)


if __name__ == "__main__":
    main()
