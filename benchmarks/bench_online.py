"""Benchmark of the whole framework online: per-scan latency of OnlinePipeline, real-time factor, flat memory.

Run: ``python benchmarks/bench_online.py [--minutes 10] [--experiments 1 8 12 13] [--repeat 3] [--learned]``.

``--learned`` adds the learned grouping (a causal LinkClustering after the
frame transform and the filter, row ``learned``), fitted once before the
streams on a simulated training recording of its own (``--learned-train``
sequences of 20 s of the realistic preset, other seeds than the stream's;
``--learned-max-iter`` boosting iterations, ``--learned-max-links`` its
``max_links_per_detection`` (``none`` for every pair),
``--learned-max-depth`` its ``max_depth``, ``--learned-cluster-window``
its ``cluster_window`` (``none``: no cluster context), by default those of
the main job's causal model (``LEARNED_CAUSAL_PARAMS``);
``--learned-max-leaf-nodes`` its ``max_leaf_nodes``), trained
on the pre-clustered instances as the main job trains it, thresholds
tuned as ``LinkClustering`` tunes them; the fit time and the thresholds
are printed.

The recording is simulated a minute at a time (realistic preset, the
RadarScenes rates: four unsynchronised sensors with a 60 ms cycle, a scan
every 15 ms on average) and replayed through one OnlinePipeline as a single
long sequence (each minute's timestamps shifted past the previous one), so
that the stream runs for ``--minutes`` of recorded time while only one
minute of detections is in memory at once.

Printed per setting:

* latency per scan (all four stages: frame transform, filter, stage 1,
  stage 2), p50 / p99 / max, as wall time and as the CPU time of the
  thread (``time.thread_time``: what the load of a shared machine does not
  inflate), without and with the object list, and with a Tracker;
* the real-time factor: recorded time / processing time (above 1 is faster
  than real time);
* peak RSS (``ru_maxrss``) and the rows the windows retain after the first
  and after the last minute: flat memory means equal figures.

Each setting runs in a child process of its own, so its peak RSS is its own;
``--repeat`` runs each child several times and prints the spread (min-max)
of its p50 and p99, since a shared machine's load moves the figures.
"""

import argparse
import json
import resource
import subprocess
import sys
import time

import numpy as np

#: What each child process times.
KINDS = {0: "all stages", 1: "with objects", 2: "stage 1 only", 3: "with tracker"}


def minute_of_data(k, difficulty="realistic"):
    """The k-th minute of the recording: a simulated 60 s sequence, its timestamps shifted by k minutes."""
    from sklearn_radar.datasets import make_scenes

    data = make_scenes(n_sequences=1, duration=60.0, random_state=k, difficulty=difficulty).data
    data = data.drop(columns=["uuid", "track_id"])
    data["timestamp"] = data["timestamp"] - data["timestamp"].min() + k * 60_000_000
    data["sequence"] = 0
    return data


#: The experiment number that stands for the learned grouping (the fitted model's file in LEARNED_MODEL_ENV).
LEARNED = 0
LEARNED_MODEL_ENV = "SKLEARN_RADAR_BENCH_LEARNED_MODEL"


def fit_learned(n_sequences, path, max_iter, max_links=None, max_leaf_nodes=31, max_depth=None, cluster_window=None):
    """Fit the causal learned pipeline on simulated training sequences; save it to ``path``; print what it took."""
    import joblib
    from sklearn.pipeline import Pipeline

    from sklearn_radar import DopplerDensityFilter, FrameTransform, instance_target
    from sklearn_radar.cluster import LinkClustering
    from sklearn_radar.datasets import make_scenes
    from sklearn_radar.metrics import precluster_target

    scenes = make_scenes(n_sequences=n_sequences, duration=20.0, difficulty="realistic", random_state=1000)
    y = precluster_target(scenes.data, instance_target(scenes.data["track_id"], scenes.data["sequence"]))
    model = Pipeline(
        [
            ("frame", FrameTransform(frame="car")),
            ("filter", DopplerDensityFilter()),
            (
                "link",
                LinkClustering(
                    causal=True,
                    window=0.5,
                    max_iter=max_iter,
                    random_state=0,
                    max_links_per_detection=max_links,
                    max_leaf_nodes=max_leaf_nodes,
                    max_depth=max_depth,
                    cluster_window=cluster_window,
                ),
            ),
        ]
    )
    start = time.perf_counter()
    model.fit(scenes.data, y)
    link = model[-1]
    print(
        f"learned: causal LinkClustering fitted on {n_sequences} x 20 s ({len(scenes.data)} detections) in "
        f"{time.perf_counter() - start:.0f} s; link {link.link_threshold_}, objectness {link.objectness_threshold_}, "
        f"min size {link.min_cluster_size_}, out-of-fold PQ {link.cv_score_:.3f}",
        flush=True,
    )
    joblib.dump(model, path)


def bench_pipeline(number):
    """The offline pipeline of experiment ``number``, or the saved learned one (:data:`LEARNED`)."""
    if number == LEARNED:
        import os

        import joblib

        return joblib.load(os.environ[LEARNED_MODEL_ENV])
    from sklearn_radar.experiments import experiment_pipeline

    return experiment_pipeline(number)


def retained_rows(online):
    """Rows held by the windows of the stream (filter, stage 1, stage 2) and the ids remembered."""
    if online.learned:
        rows = online._learned.retained_rows()
        rows += sum(0 if state.filter is None else len(state.filter.window) for state in online._sequences.values())
        return rows, sum(len(known) for known in online._learned_ids.of_sequence.values())
    rows = sum(window.points.t.shape[0] for window in online._stage1._windows.values())
    for state in online._sequences.values():
        rows += state.merge.rows["t"].shape[0] + state.merge.tracks["t"].shape[0]
        rows += 0 if state.filter is None else len(state.filter.window)
    return rows, len(online._ids.root)


def stage1_alone(online, data, wall, cpu):
    """The reference: ScanStream alone on the working columns of the same scans (computed offline)."""
    from sklearn_radar.cluster import ScanStream
    from sklearn_radar.online._replay import scan_order

    work = online.causal_pipeline()[:-1].fit_transform(data)
    stage1 = online._stage1.clusterer
    stream = ScanStream(stage1)
    names = ("x", "y", "v_r", "t", "keep", "range_sc", "heading")
    columns = {name: work[name].to_numpy() for name in names if name in work.columns}
    for rows in scan_order(data):
        scan = {name: values[rows] for name, values in columns.items()}
        start_cpu, start = time.thread_time(), time.perf_counter()
        stream.update(
            scan["x"],
            scan["y"],
            scan["v_r"],
            scan["t"][0],
            keep=scan.get("keep"),
            range_sc=scan["range_sc"],
            heading=scan["heading"],
        )
        wall.append(time.perf_counter() - start)
        cpu.append(time.thread_time() - start_cpu)


def current_rss_mb():
    """Resident set size now, MB (Linux: /proc/self/statm)."""
    import os

    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def run(number, minutes, objects, one_minute=False):
    """Child process: stream ``minutes`` minutes with experiment ``number``; print the figures as JSON.

    ``objects`` 2 times stage 1 alone (ScanStream) on the same scans instead; 3 all stages and a Tracker
    (``noise_radius=1`` m, the rest at its defaults) without the object list.
    """
    from sklearn_radar.online import OnlinePipeline, Tracker
    from sklearn_radar.online._replay import scan_order

    online = OnlinePipeline(bench_pipeline(number), tracker=Tracker(noise_radius=1.0) if objects == 3 else None)
    wall, cpu, after = [], [], {}
    recorded = 0.0
    simulated = minute_of_data(0) if one_minute else None
    for k in range(minutes):
        if one_minute:  # the same detections each minute, shifted: the simulator's memory stays out of the figures
            data = simulated.copy()
            data["timestamp"] += k * 60_000_000
        else:
            data = minute_of_data(k)
        if objects == 2:
            stage1_alone(online, data, wall, cpu)
            recorded += (data["timestamp"].max() - data["timestamp"].min()) * 1e-6
            continue
        columns = {name: data[name].to_numpy() for name in data.columns}
        for rows in scan_order(data):
            scan = {name: values[rows] for name, values in columns.items()}
            start_cpu, start = time.thread_time(), time.perf_counter()
            online.update(scan, objects=objects == 1)
            wall.append(time.perf_counter() - start)
            cpu.append(time.thread_time() - start_cpu)
        recorded += (data["timestamp"].max() - data["timestamp"].min()) * 1e-6
        if k in (0, minutes - 1):
            rows, ids = retained_rows(online)
            after[k + 1] = {
                "rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                "rss_now_mb": current_rss_mb(),
                "rows": rows,
                "ids": ids,
            }
        del data, columns
    wall, cpu = np.array(wall[50:]) * 1e6, np.array(cpu[50:]) * 1e6  # the first scans load the compiled kernels
    figures = {
        "n_scans": len(wall),
        "wall_us": [float(np.percentile(wall, q)) for q in (50, 99)] + [float(wall.max())],
        "cpu_us": [float(np.percentile(cpu, q)) for q in (50, 99)] + [float(cpu.max())],
        "real_time_factor_wall": recorded / (wall.sum() * 1e-6),
        "real_time_factor_cpu": recorded / (cpu.sum() * 1e-6),
        "after_minutes": after,
    }
    print(json.dumps(figures))


def main():
    from sklearn_radar.reproduce._learned import LEARNED_CAUSAL_PARAMS as MAIN_JOB

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=int, default=10)
    parser.add_argument("--experiments", type=int, nargs="*", default=[1, 8, 12, 13])
    parser.add_argument(
        "--kinds", type=int, nargs="+", default=[2, 0, 1, 3], help="2: stage 1 alone, 0: all, 1: +objects, 3: +tracker"
    )
    parser.add_argument("--repeat", type=int, default=1, help="runs of each setting and kind")
    parser.add_argument(
        "--one-minute", action="store_true", help="simulate one minute, replay it shifted (RSS of the stream alone)"
    )
    parser.add_argument("--learned", action="store_true", help="add the learned grouping (causal LinkClustering)")
    parser.add_argument("--learned-train", type=int, default=4, help="training sequences (20 s) of the learned one")
    parser.add_argument(
        "--learned-max-iter",
        type=int,
        default=MAIN_JOB["link__max_iter"],
        help="boosting iterations of the learned one (default: the main job's causal model's)",
    )
    parser.add_argument(
        "--learned-max-links",
        type=lambda value: None if value == "none" else int(value),
        default=MAIN_JOB["link__max_links_per_detection"],
        help="max_links_per_detection of the learned one (default: the main job's; 'none': every pair)",
    )
    parser.add_argument(
        "--learned-max-leaf-nodes", type=int, default=31, help="max_leaf_nodes of the learned one's classifiers"
    )
    parser.add_argument(
        "--learned-max-depth",
        type=lambda text: None if text == "none" else int(text),
        default=MAIN_JOB["link__max_depth"],
        help="max_depth of the learned one's classifiers (default: the main job's; 'none': as the leaves allow)",
    )
    parser.add_argument(
        "--learned-cluster-window",
        type=lambda text: None if text == "none" else float(text),
        default=MAIN_JOB.get("link__cluster_window"),
        help="cluster_window of the learned one, s (default: the main job's; 'none': no cluster context)",
    )
    parser.add_argument("--child", nargs=3, type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        number, minutes, objects = args.child
        run(number, minutes, objects, args.one_minute)
        return
    print(f"OnlinePipeline, realistic preset, 4 sensors, {args.minutes} min of recording per setting")
    numbers = list(args.experiments)
    if args.learned:
        import os
        import tempfile

        path = os.path.join(tempfile.mkdtemp(), "learned_causal.joblib")
        fit_learned(
            args.learned_train,
            path,
            args.learned_max_iter,
            args.learned_max_links,
            args.learned_max_leaf_nodes,
            args.learned_max_depth,
            args.learned_cluster_window,
        )
        os.environ[LEARNED_MODEL_ENV] = path
        numbers.append(LEARNED)
        args.kinds = [kind for kind in args.kinds if kind != 2]  # no stage 1 of its own
    for number in numbers:
        for objects in args.kinds:  # stage 1 alone, the four stages, with the object list, with a tracker
            runs = [child_figures(number, args.minutes, objects, args.one_minute) for _ in range(args.repeat)]
            for f in runs:
                print_figures(number, objects, args.minutes, f)
            if args.repeat > 1:
                p50, p99 = ([f["cpu_us"][k] for f in runs] for k in (0, 1))
                print(
                    f"{'learned' if number == LEARNED else f'#{number:<2}'} {KINDS[objects]:12}  "
                    f"spread of {args.repeat} runs: "
                    f"cpu p50 {min(p50):.0f}-{max(p50):.0f} us, p99 {min(p99):.0f}-{max(p99):.0f} us"
                )


def child_figures(number, minutes, objects, one_minute=False):
    """The figures of one child process (see :func:`run`)."""
    child = [sys.executable, __file__, "--child", str(number), str(minutes), str(objects)]
    child += ["--one-minute"] if one_minute else []
    out = subprocess.run(child, capture_output=True, text=True, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def print_figures(number, objects, minutes, f):
    """One line of figures: latency, real-time factor, memory after the first and the last minute."""
    name = "learned" if number == LEARNED else f"#{number:<2}"
    unknown = {"rss_mb": float("nan"), "rss_now_mb": float("nan"), "rows": 0, "ids": 0}  # stage 1 alone: not measured
    first = f["after_minutes"].get("1", unknown)
    last = f["after_minutes"].get(str(minutes), unknown)
    print(
        f"{name} {KINDS[objects]:12}  "
        f"scans {f['n_scans']}  "
        f"wall p50/p99/max {f['wall_us'][0]:.0f}/{f['wall_us'][1]:.0f}/{f['wall_us'][2]:.0f} us  "
        f"cpu p50/p99/max {f['cpu_us'][0]:.0f}/{f['cpu_us'][1]:.0f}/{f['cpu_us'][2]:.0f} us  "
        f"real-time factor {f['real_time_factor_wall']:.0f} (cpu {f['real_time_factor_cpu']:.0f})  "
        f"peak RSS {first['rss_mb']:.0f} -> {last['rss_mb']:.0f} MB, "
        f"RSS now {first['rss_now_mb']:.0f} -> {last['rss_now_mb']:.0f} MB, "
        f"rows kept {first['rows']} -> {last['rows']}, ids {first['ids']} -> {last['ids']}",
        flush=True,
    )


if __name__ == "__main__":
    main()
