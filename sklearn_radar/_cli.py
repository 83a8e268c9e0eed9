"""The ``sklearn-radar`` command line (also ``python -m sklearn_radar``)."""

from __future__ import annotations

import argparse
import sys
import time

from . import __version__


def main(argv=None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    try:
        return args.run(args)
    except KeyboardInterrupt:
        print("sklearn-radar: interrupted", file=sys.stderr)
        return 130
    except (ValueError, OSError) as error:
        print(f"sklearn-radar: error: {error}", file=sys.stderr)
        return 1


def _parser():
    parser = argparse.ArgumentParser(
        prog="sklearn-radar",
        description="Multi-stage clustering of automotive radar detections (Scheiner et al., ITSC 2019).",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")

    simulate = commands.add_parser(
        "simulate",
        help="write a simulated data set in the RadarScenes layout",
        description="Simulate urban radar recordings and write them as a RadarScenes data folder.",
    )
    simulate.add_argument("--out", required=True, help="data folder to create (sensors.json, sequences.json, sequence_N/)")
    simulate.add_argument("--n-sequences", type=int, default=4, help="number of recordings (default: 4)")
    simulate.add_argument("--duration", type=float, default=30.0, help="length of each recording in s (default: 30)")
    simulate.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    simulate.add_argument("--overwrite", action="store_true", help="replace an existing data folder")
    simulate.set_defaults(run=_simulate)

    stats = commands.add_parser(
        "stats",
        help="print statistics of a RadarScenes data folder",
        description="Print detections per second, static share and detections per object per scan.",
    )
    stats.add_argument("--data", required=True, help="RadarScenes data folder (or its parent)")
    stats.set_defaults(run=_stats)
    return parser


def _simulate(args) -> int:
    from .datasets import format_statistics, make_scenes, scene_statistics, write_radarscenes

    start = time.perf_counter()
    scenes = make_scenes(n_sequences=args.n_sequences, duration=args.duration, random_state=args.seed)
    simulated = time.perf_counter() - start
    path = write_radarscenes(scenes, args.out, overwrite=args.overwrite)
    print(f"simulated {len(scenes.data)} detections in {simulated:.2f} s; wrote {path}")
    print(format_statistics(*scene_statistics(scenes)))
    return 0


def _stats(args) -> int:
    from .datasets import format_statistics, load_radarscenes, scene_statistics

    print(format_statistics(*scene_statistics(load_radarscenes(args.data))))
    return 0
