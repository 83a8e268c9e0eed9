"""Cost of the physical-plausibility checks against the pipeline they guard (issue #26).

Run: ``python benchmarks/bench_plausibility.py [--n-detections 1000000] [--profile]``.
Simulated recordings (``make_scenes``, 4 sequences of 30 s) are tiled, each
copy a new sequence, up to about ``--n-detections`` rows.  Printed:

* the pipeline FrameTransform + DopplerDensityFilter + RadarDBSCAN with the
  checks off (``config_context(check_plausibility=False)``), stage by stage;
* the checks alone: what they add to each stage's reading of its input
  (``read_columns`` with the checks on minus off, best of 7 or ``--repeat``),
  summed over the stages (each reads its input once in ``fit_transform``
  or ``fit``);
* the ratio of the two, and the pipeline once more with the checks on as a
  cross-check (its difference is the same cost, within timing noise).

``--profile`` adds the top functions of a cProfile of FrameTransform's reading, the costliest.
"""

import argparse
import cProfile
import pstats
import time

import numpy as np
import pandas as pd

from sklearn_radar import DopplerDensityFilter, FrameTransform, RadarDBSCAN, config_context
from sklearn_radar._schema import FILTER_READS, FRAME_TRANSFORM_READS, STAGE1_READS
from sklearn_radar._validation import read_columns
from sklearn_radar.datasets import make_scenes


def timed(func, repeat):
    best, result = np.inf, None
    for _ in range(repeat):
        start = time.perf_counter()
        result = func()
        best = min(best, time.perf_counter() - start)
    return best, result


def tiled_scenes(n_detections, random_state=0):
    """Simulated detections repeated, each copy a sequence of its own with uuids of its own, to at least
    ``n_detections`` rows."""
    base = make_scenes(n_sequences=4, duration=30.0, random_state=random_state).data
    copies = -(-n_detections // len(base))
    step = int(base["sequence"].max()) + 1
    tiles = [base.assign(sequence=base["sequence"] + k * step, uuid=base["uuid"] + f"-{k}") for k in range(copies)]
    return pd.concat(tiles, ignore_index=True).iloc[:n_detections].reset_index(drop=True)


def read_seconds(estimator, X, reads, check, repeat):
    """Seconds of the stage's own input reading (``read_columns``), with the checks on or off."""
    with config_context(check_plausibility=check):
        return timed(lambda: read_columns(estimator, X, reads, reset=True), repeat)[0]


def pipeline_times(data, repeat):
    """Seconds of each stage, best of ``repeat``."""
    transform_s, Xt = timed(lambda: FrameTransform().fit_transform(data), repeat)
    filter_s, Xf = timed(lambda: DopplerDensityFilter().fit_transform(Xt), repeat)
    cluster_s, _ = timed(lambda: RadarDBSCAN().fit(Xf), repeat)
    return {"FrameTransform": transform_s, "DopplerDensityFilter": filter_s, "RadarDBSCAN": cluster_s}, Xt, Xf


def check_times(data, Xt, Xf, repeat):
    """Seconds the checks add to each stage's reading of its input (on minus off), best of ``repeat`` each."""
    stages = {
        "FrameTransform (fit_transform)": (FrameTransform(), data, FRAME_TRANSFORM_READS, 1),
        "DopplerDensityFilter (fit_transform)": (DopplerDensityFilter(), Xt, FILTER_READS, 1),
        "RadarDBSCAN": (RadarDBSCAN(), Xf, STAGE1_READS, 1),
    }
    times = {}
    for name, (estimator, X, reads, calls) in stages.items():
        on = read_seconds(estimator, X, reads, True, max(repeat, 7))  # a small difference: more runs
        off = read_seconds(estimator, X, reads, False, max(repeat, 7))
        times[name] = calls * max(on - off, 0.0)
    return times


def profile_checks(X):
    profiler = cProfile.Profile()
    profiler.enable()
    read_columns(FrameTransform(), X, FRAME_TRANSFORM_READS, reset=True)
    profiler.disable()
    pstats.Stats(profiler).sort_stats("tottime").print_stats(8)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--n-detections", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=3, help="best of this many runs of each timing")
    parser.add_argument("--profile", action="store_true")
    args = parser.parse_args()

    data = tiled_scenes(args.n_detections)
    print(f"{len(data)} detections in {data['sequence'].nunique()} sequences (tiled make_scenes, 4 x 30 s)")
    with config_context(check_plausibility=False):
        warm = FrameTransform().fit_transform(data.iloc[:5000])
        RadarDBSCAN().fit(DopplerDensityFilter().fit_transform(warm))  # JIT compilation, not timed
        stages, Xt, Xf = pipeline_times(data, repeat=args.repeat)
    checks = check_times(data, Xt, Xf, args.repeat)
    pipeline_s, checks_s = sum(stages.values()), sum(checks.values())
    for name, seconds in stages.items():
        print(f"  pipeline {name:<48s} {seconds:8.3f} s")
    print(f"pipeline, checks off                                     {pipeline_s:8.3f} s")
    for name, seconds in checks.items():
        print(f"  checks of {name:<46s} {seconds:8.3f} s")
    print(f"plausibility checks                                      {checks_s:8.3f} s")
    print(f"ratio checks / pipeline                                  {checks_s / pipeline_s:8.2%}")
    with config_context(check_plausibility=True):
        stages_on, _, _ = pipeline_times(data, repeat=args.repeat)
    print(f"cross-check: pipeline with checks on {sum(stages_on.values()):.3f} s (best of {args.repeat}; noisy)")
    if args.profile:
        profile_checks(data)


if __name__ == "__main__":
    main()
