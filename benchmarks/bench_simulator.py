"""Benchmark of the scene simulator and the RadarScenes writer/reader.

Run: ``python benchmarks/bench_simulator.py [--n-sequences 10] [--duration 30]``.
Prints wall times and detections/s of one run (best of ``--repeat``).
"""

import argparse
import tempfile
import time

from sklearn_radar.datasets import load_radarscenes, make_scenes, write_radarscenes


def best_of(repeat, func):
    times, result = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        result = func()
        times.append(time.perf_counter() - start)
    return min(times), result


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--n-sequences", type=int, default=10)
    parser.add_argument("--duration", type=float, default=30.0)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    seconds, scenes = best_of(args.repeat, lambda: make_scenes(args.n_sequences, args.duration, random_state=0))
    n = len(scenes.data)
    print(f"data: {args.n_sequences} sequences x {args.duration:g} s, {n} detections")
    print(f"{'step':<12} {'seconds':>8} {'detections/s':>14}")
    print(f"{'make_scenes':<12} {seconds:8.2f} {n / seconds:14.0f}")
    with tempfile.TemporaryDirectory() as tmp:
        path = f"{tmp}/data"
        seconds, _ = best_of(1, lambda: write_radarscenes(scenes, path))
        print(f"{'write':<12} {seconds:8.2f} {n / seconds:14.0f}")
        seconds, _ = best_of(args.repeat, lambda: load_radarscenes(path))
        print(f"{'load':<12} {seconds:8.2f} {n / seconds:14.0f}")


if __name__ == "__main__":
    main()
