"""The ``sklearn-radar`` command line (also ``python -m sklearn_radar``)."""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

from . import __version__


def main(argv=None) -> int:
    try:
        _import_the_estimators()
    except KeyboardInterrupt:  # Ctrl-C during start-up: a one-line message, not a traceback from an import
        print("sklearn-radar: interrupted", file=sys.stderr)
        return 130
    parser = _parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    try:
        code = args.run(args)
        sys.stdout.flush()  # a closed pipe shows here, inside the try, rather than at exit
        return code
    except KeyboardInterrupt:
        print("sklearn-radar: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # The reader left (``sklearn-radar stats | head -2``): not an error. Nothing more can be written.
        _silence_stdout()
        return 0
    except (ValueError, OSError, ImportError) as error:  # ImportError: dask for --scheduler/--workers, missing
        print(f"sklearn-radar: error: {error}", file=sys.stderr)
        return 1


def _import_the_estimators():
    """The heavy imports every command needs (numpy, pandas, scikit-learn, numba, the estimators; about 1.5 s).

    ``sklearn_radar/__init__.py`` imports them lazily, so they happen here,
    inside :func:`main`, where an interrupt is caught.
    """
    from . import cluster, datasets, preprocessing  # noqa: F401


def _silence_stdout():
    """Point standard output at the null device, so that Python's flush at exit does not fail again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):
        pass


def _shown(path):
    """A path as text that can be printed and written as UTF-8: undecodable bytes appear as ``\\xff``."""
    return os.fsencode(path).decode("utf-8", "backslashreplace")


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
    simulate.add_argument(
        "--out", required=True, help="data folder to create (sensors.json, sequences.json, sequence_N/)"
    )
    simulate.add_argument("--n-sequences", type=int, default=4, help="number of recordings (default: 4)")
    simulate.add_argument("--duration", type=float, default=30.0, help="length of each recording in s (default: 30)")
    simulate.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    simulate.add_argument("--overwrite", action="store_true", help="replace an existing data folder")
    simulate.add_argument(
        "--difficulty",
        choices=("easy", "realistic"),
        default="realistic",
        help="phenomena of real radar data: realistic (ego-motion errors, multipath, clutter, dense traffic, "
        "sensing limits) or easy (none) (default: realistic)",
    )
    simulate.set_defaults(run=_simulate)

    stats = commands.add_parser(
        "stats",
        help="print statistics of a RadarScenes data folder",
        description="Print detections per second, static share and detections per object per scan.",
    )
    stats.add_argument("--data", required=True, help="RadarScenes data folder (or its parent)")
    stats.set_defaults(run=_stats)

    reproduce = commands.add_parser(
        "reproduce",
        help="re-run the paper's experiments and write a report",
        description="Re-run the experiments #1-#13 of Scheiner et al. (ITSC 2019), the filter evaluation and "
        "scikit-learn baselines; write report.md, results.json, params.json and figures.",
    )
    reproduce.add_argument("--data", help="RadarScenes data folder (default: simulate one)")
    reproduce.add_argument(
        "--out", default="sklearn-radar-report", help="output folder (default: sklearn-radar-report)"
    )
    reproduce.add_argument(
        "--n-iter", type=int, help="Bayesian-optimisation iterations per experiment (default 10; 100 with --full)"
    )
    reproduce.add_argument(
        "--n-jobs", type=int, help="candidates evaluated in parallel (default: one at a time; -1: all cores)"
    )
    reproduce.add_argument(
        "--experiments", help="comma-separated: filter, 1-13 (ranges like 2-9), filter-effect, baselines"
    )
    reproduce.add_argument(
        "--full", action="store_true", help="the paper's budget (100 iterations, 30 random) on ~1M detections"
    )
    reproduce.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    reproduce.add_argument(
        "--repeats",
        type=int,
        help="searches per tuned experiment and baseline, with the seeds seed, seed+1, ... on the same split; the "
        "report gives mean +- sd and checks the findings beyond the noise (default: 1; 3 with --full)",
    )
    reproduce.add_argument(
        "--difficulty",
        choices=("easy", "realistic"),
        default="realistic",
        help="difficulty of the simulated data when --data is not given (default: realistic)",
    )
    reproduce.add_argument(
        "--objective",
        choices=("v1", "pq"),
        default="v1",
        help="what the searches maximise: v1, the paper's radar V-measure, or pq, the panoptic quality of moving "
        "road users per 0.5 s frame (default: v1)",
    )
    _add_cluster_flags(reproduce)
    reproduce.add_argument(
        "--n-points",
        metavar="K",
        help="candidates each search step evaluates at a time (default 1, with or without a cluster); "
        "the results depend on it, not on where the fits run",
    )
    reproduce.set_defaults(run=_reproduce)

    cluster = commands.add_parser(
        "cluster",
        help="cluster a RadarScenes folder with saved parameters",
        description="Apply a setting saved by 'sklearn-radar reproduce' (params.json) and write the devkit's "
        "per-point predictions JSON (schema 2), keyed by detection uuid.",
    )
    cluster.add_argument("--data", required=True, help="RadarScenes data folder (or its parent)")
    cluster.add_argument("--params", required=True, help="params.json written by 'sklearn-radar reproduce'")
    cluster.add_argument("--out", required=True, help="predictions file to write (JSON)")
    cluster.add_argument("--experiment", type=int, help="which saved experiment (default: the best)")
    _add_cluster_flags(cluster)
    cluster.set_defaults(run=_cluster)
    return parser


def _add_cluster_flags(command):
    """``--scheduler`` and ``--workers`` (dask.distributed, the ``[distributed]`` extra)."""
    where = command.add_mutually_exclusive_group()
    where.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run on an existing dask scheduler, e.g. tcp://host:8786 (needs the [distributed] extra)",
    )
    # Parsed here rather than by argparse, so that a bad value is a one-line error like the others.
    where.add_argument("--workers", metavar="N", help="run on a local dask cluster of N worker processes")


def _cluster_args(args):
    """``(scheduler, workers)`` of the command line; ValueError for a bad ``--workers``."""
    return args.scheduler, _positive_int(args.workers, "--workers", "a whole number of worker processes")


def _positive_int(text, flag, what):
    if text is None:
        return None
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise ValueError(f"{flag} must be {what} >= 1, got {text!r}")
    return value


def _simulate(args) -> int:
    from .datasets import format_statistics, make_scenes, scene_statistics, write_radarscenes

    start = time.perf_counter()
    scenes = make_scenes(
        n_sequences=args.n_sequences, duration=args.duration, random_state=args.seed, difficulty=args.difficulty
    )
    simulated = time.perf_counter() - start
    try:
        path = write_radarscenes(scenes, args.out, overwrite=args.overwrite)
    except FileExistsError:
        from .reproduce._io import blocking_file

        blocking = blocking_file(args.out)
        if blocking is not None and blocking != Path(args.out):
            raise FileExistsError(
                f"cannot create {_shown(args.out)}: {_shown(blocking)} is a file, not a folder"
            ) from None
        what = "is a file, not a data folder" if blocking is not None else "exists and is not empty"
        raise FileExistsError(f"{_shown(args.out)} {what}; pass --overwrite to replace it") from None
    print(f"simulated {len(scenes.data)} detections in {simulated:.2f} s; wrote {_shown(path)}")
    print(format_statistics(*scene_statistics(scenes)))
    return 0


def _stats(args) -> int:
    from .datasets import format_statistics, load_radarscenes, scene_statistics

    print(format_statistics(*scene_statistics(load_radarscenes(args.data))))
    return 0


def _reproduce(args) -> int:
    from .reproduce import reproduce

    if args.n_iter is not None and args.n_iter < 1:
        raise ValueError(f"--n-iter must be at least 1, got {args.n_iter}")
    scheduler, workers = _cluster_args(args)
    n_points = _positive_int(args.n_points, "--n-points", "a whole number of candidates")
    if args.repeats is not None and args.repeats < 1:
        raise ValueError(f"--repeats must be at least 1, got {args.repeats}")
    start = time.perf_counter()
    reproduce(
        args.data,
        args.out,
        n_iter=args.n_iter,
        n_jobs=args.n_jobs,
        experiments=args.experiments,
        full=args.full,
        seed=args.seed,
        objective=args.objective,
        difficulty=args.difficulty,
        scheduler=scheduler,
        workers=workers,
        n_points=n_points,
        repeats=args.repeats,
    )
    print(
        f"wrote {_shown(args.out)}/report.md, results.json, params.json and figures "
        f"in {time.perf_counter() - start:.0f} s"
    )
    return 0


def _cluster(args) -> int:
    from .reproduce import cluster_radarscenes

    scheduler, workers = _cluster_args(args)
    summary = cluster_radarscenes(
        args.data, args.params, args.out, experiment=args.experiment, scheduler=scheduler, workers=workers
    )
    print(
        f"experiment #{summary['experiment']}: {summary['n_detections']} detections in "
        f"{summary['n_clusters']} clusters; wrote {_shown(summary['out'])}"
    )
    return 0
