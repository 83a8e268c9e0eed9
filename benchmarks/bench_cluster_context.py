"""Time per scan of the learned stream with and without cluster context, interleaved so that both see the same load.

The main job's causal model (``LEARNED_CAUSAL_PARAMS``) is fitted twice on the same simulated training sequences
(realistic preset, 20 s each, seed 1000 as ``bench_online.py``), once with ``cluster_window`` None and once with
``--cluster-window``; then the same test recording (realistic preset, other seeds) is streamed through a fresh
``OnlinePipeline`` of each, alternately, ``--repeat`` times (optionally with a ``Tracker``).  Printed: the thread CPU
time per scan (``time.thread_time``), p50 and p99 of each run, and per model the median over runs of each.

Run::

    OMP_NUM_THREADS=1 python benchmarks/bench_cluster_context.py --repeat 5 --tracker
"""

from __future__ import annotations

import argparse
import sys

import numpy as np
from threadpoolctl import threadpool_limits

from sklearn_radar import instance_target
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments._learned import learned_pipeline
from sklearn_radar.metrics import precluster_target
from sklearn_radar.online import OnlinePipeline, Tracker
from sklearn_radar.online._replay import replay
from sklearn_radar.reproduce._learned import LEARNED_CAUSAL_PARAMS


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cluster-window", type=float, default=0.5, help="s")
    parser.add_argument("--train", type=int, default=2, help="training sequences of 20 s")
    parser.add_argument("--test", type=int, default=3, help="test sequences of 20 s")
    parser.add_argument("--repeat", type=int, default=5, help="streams of each model, alternating")
    parser.add_argument("--tracker", action="store_true", help="stream with a Tracker")
    options = parser.parse_args(argv)
    train = make_scenes(n_sequences=options.train, duration=20.0, difficulty="realistic", random_state=1000)
    y = precluster_target(train.data, instance_target(train.data["track_id"], train.data["sequence"]))
    test = make_scenes(n_sequences=options.test, duration=20.0, difficulty="realistic", random_state=2000).data
    params = {**LEARNED_CAUSAL_PARAMS, "link__causal": True, "filter__causal": True, "link__window": 0.5}
    models = {}
    with threadpool_limits(1):
        for name, window in (("without", None), ("with", options.cluster_window)):
            models[name] = learned_pipeline({**params, "link__cluster_window": window}).fit(train.data, y)
        figures = {name: [] for name in models}
        for run in range(options.repeat + 1):  # the first round warms up (compilation, caches) and is not counted
            for name, model in models.items():
                online = OnlinePipeline(model, tracker=Tracker() if options.tracker else None)
                cpu = np.asarray(replay(online, test)["cpu"]) * 1e6
                if run:
                    figures[name].append(np.percentile(cpu, [50, 99]))
                    print(
                        f"run {run} {name:8s} cluster context: p50 {figures[name][-1][0]:.0f} us, "
                        f"p99 {figures[name][-1][1]:.0f} us ({len(cpu)} scans)",
                        flush=True,
                    )
    for name, runs in figures.items():
        p50, p99 = np.median(np.asarray(runs), axis=0)
        print(
            f"{name:8s} cluster context{' + Tracker' if options.tracker else ''}: median over {len(runs)} runs "
            f"p50 {p50:.0f} us, p99 {p99:.0f} us"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
