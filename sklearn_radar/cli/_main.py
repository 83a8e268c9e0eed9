"""The ``sklearn-radar`` command line (also ``python -m sklearn_radar``).

The commands import the package's estimators inside their functions, not at the top: ``--help``, ``--version``
and a usage error answer without importing scikit-learn.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time

from .. import __version__
from .._files import shown_path as _shown


def main(argv=None) -> int:
    try:
        parser = _parser()
        # --help and --version end here, before any heavy import; a usage error exits 2 with the usage of the
        # command it concerns (argparse's own parse_args would give the top-level usage for a command's unknown
        # option).
        args, unknown = parser.parse_known_args(argv)
        if unknown:
            (parser if args.command is None else args.parser).error(f"unrecognized arguments: {' '.join(unknown)}")
        if args.command is None:
            parser.print_help(sys.stderr)
            return USAGE_ERROR
        return _run(args)
    except KeyboardInterrupt:  # Ctrl-C during start-up or a run: a one-line message, not a traceback
        print("sklearn-radar: interrupted", file=sys.stderr)
        return 130


#: The exit code of a usage error (a bad option, or options that do not go together), as argparse's.
USAGE_ERROR = 2


class UsageError(ValueError):
    """A bad option value, or options that do not go together: one line, exit code :data:`USAGE_ERROR`."""


def _run(args) -> int:
    """Check every option, import the estimators, then run the command; errors as one line."""
    try:
        try:
            _check_options(args)  # before anything is imported or written
        except ValueError as error:
            raise UsageError(str(error)) from None
        _import_the_estimators()
        code = args.run(args)
        sys.stdout.flush()  # a closed pipe shows here, inside the try, rather than at exit
        return code
    except BrokenPipeError:
        # The reader left (``sklearn-radar stats | head -2``): not an error. Nothing more can be written.
        _silence_stdout()
        return 0
    except UsageError as error:
        print(f"sklearn-radar: error: {error}", file=sys.stderr)
        return USAGE_ERROR
    except (ValueError, OSError, ImportError) as error:  # ImportError: dask for --scheduler/--workers, missing
        print(f"sklearn-radar: error: {error}", file=sys.stderr)
        return 1


def _import_the_estimators():
    """The heavy imports every command needs (numpy, pandas, scikit-learn, numba, the estimators).

    ``sklearn_radar/__init__.py`` imports them lazily, and so does this
    module: ``--help`` and ``--version`` never import them.  A command
    imports them here, inside :func:`main`, where an interrupt is caught.
    """
    from .. import cluster, datasets, preprocessing  # noqa: F401


def _silence_stdout():
    """Point standard output at the null device, so that Python's flush at exit does not fail again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):
        pass


def _named(experiment):
    """``#13`` for a paper experiment, ``'objects'`` for the object experiment (``'learned'`` the learned one)."""
    return f"#{experiment}" if isinstance(experiment, int) else repr(experiment)


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
    simulate.set_defaults(run=_simulate, parser=simulate)
    simulate.add_argument(
        "--out", required=True, help="data folder to create (sensors.json, sequences.json, sequence_N/)"
    )
    _add_checked(simulate, "--n-sequences", _at_least(1), default=4, help="number of recordings (default: 4)")
    _add_checked(simulate, "--duration", _duration, default=30.0, help="length of each recording in s (default: 30)")
    _add_checked(simulate, "--seed", _seed, default=0, help="random seed (default: 0)")
    simulate.add_argument(
        "--overwrite",
        action="store_true",
        help="replace a data folder that sklearn-radar wrote before (other folders and files are never replaced)",
    )
    simulate.add_argument(
        "--difficulty",
        choices=("easy", "realistic", "radarscenes"),
        default="realistic",
        help="phenomena of real radar data: realistic (ego-motion errors, multipath, clutter, dense traffic, "
        "sensing limits), radarscenes (realistic with RadarScenes' traffic statistics, road users that stop and "
        "start, and angle glint) or easy (none) (default: realistic)",
    )

    stats = commands.add_parser(
        "stats",
        help="print statistics of a RadarScenes data folder",
        description="Print detections per second, static share and detections per object per scan.",
    )
    stats.set_defaults(run=_stats, parser=stats)
    stats.add_argument("--data", required=True, help="RadarScenes data folder (or its parent)")

    reproduce = commands.add_parser(
        "reproduce",
        help="re-run the paper's experiments and write a report",
        description="Re-run the experiments #1-#13 of Scheiner et al. (ITSC 2019), the filter evaluation and "
        "scikit-learn baselines; write report.md, results.json, params.json and figures.",
        epilog=_REPRODUCE_EPILOG,
    )
    reproduce.set_defaults(run=_reproduce, parser=reproduce)
    reproduce.add_argument("--data", help="RadarScenes data folder (default: simulate one)")
    reproduce.add_argument(
        "--out",
        default="sklearn-radar-report",
        help="output folder (default: sklearn-radar-report), apart from --data (not it, inside it or around it); "
        "a previous run's files there are replaced, other files stay, and a folder holding a file of the same "
        "name that no run wrote is refused",
    )
    _add_checked(
        reproduce,
        "--n-iter",
        _at_least(1),
        help="Bayesian-optimisation iterations per experiment (default 10; 100 with --full)",
    )
    _add_checked(
        reproduce,
        "--n-jobs",
        _n_jobs,
        metavar="J",
        help="on one machine: how many candidates (and repeats of a step) are evaluated at once in this process, "
        "and the threads of the library calls within a step (default: 1; -1: all cores); the results do not "
        "depend on it",
    )
    reproduce.add_argument(
        "--experiments",
        metavar="LIST",
        help="comma-separated steps to run (default: all but learned): " + ", ".join(_STEP_HELP),
    )
    reproduce.add_argument(
        "--full", action="store_true", help="the paper's budget (100 iterations, 30 random) on ~1M detections"
    )
    _add_checked(reproduce, "--seed", _seed, default=0, help="random seed (default: 0)")
    _add_checked(
        reproduce,
        "--repeats",
        _at_least(1),
        help="searches per tuned experiment and baseline, with the repeat seeds seed, seed+1, ... on the same split; "
        "the report gives mean +- sd and checks the findings beyond the noise (default: 1; 3 with --full)",
    )
    reproduce.add_argument(
        "--difficulty",
        choices=("easy", "realistic", "radarscenes"),
        default="realistic",
        help="difficulty of the simulated data when --data is not given: easy, realistic or radarscenes "
        "(default: realistic)",
    )
    reproduce.add_argument(
        "--objective",
        choices=("v1", "pq"),
        default="v1",
        help="what the searches maximise: v1, the paper's radar V-measure, or pq, the panoptic quality of moving "
        "road users per 0.5 s time window (default: v1)",
    )
    _add_cluster_flags(
        reproduce,
        "for work larger than the default run's (--full, a RadarScenes folder); a run it would slow down stays in "
        "this process and says so",
    )
    _add_checked(
        reproduce,
        "--n-points",
        _at_least(1),
        metavar="K",
        help="candidates the Bayesian optimiser proposes per guided search step (default: 1): K above 1 lets K "
        "cores or workers evaluate a guided step at once, but changes the search and so the results (compare "
        "runs of equal K); the random first candidates are queued at once whatever K",
    )

    cluster = commands.add_parser(
        "cluster",
        help="cluster a RadarScenes folder with saved parameters",
        description="Apply a setting saved by 'sklearn-radar reproduce' (params.json) and write the devkit's "
        "per-point predictions JSON (schema 2), keyed by detection uuid. With --classifier, each detection's "
        "class is the devkit's ClassificationLabel index of its predicted road-user class (CAR 0, PEDESTRIAN 1, "
        "PEDESTRIAN_GROUP 2, TWO_WHEELER 3, LARGE_VEHICLE 4; STATIC 5 for noise and background).",
    )
    cluster.set_defaults(run=_cluster, parser=cluster, together=_check_setting_options)
    cluster.add_argument("--data", required=True, help="RadarScenes data folder (or its parent)")
    cluster.add_argument("--params", help=_PARAMS_HELP)
    cluster.add_argument("--classifier", metavar="FILE", help=_CLASSIFIER_HELP)
    cluster.add_argument(
        "--out",
        required=True,
        help="predictions file to write (JSON); an existing file is replaced only if it is such a predictions file",
    )
    _add_checked(cluster, "--experiment", _saved_experiment, help=_SAVED_EXPERIMENT_HELP)
    _add_cluster_flags(cluster, "each worker reads and clusters whole sequences, for folders of many sequences")

    stream = commands.add_parser(
        "stream",
        help="replay a RadarScenes folder scan by scan through the online pipeline",
        description="Label every radar scan of a RadarScenes folder as it would arrive on a car (timestamp order "
        "across sensors, each stage causal), with persistent object ids; write the devkit's per-point predictions "
        "JSON and print the per-scan latency and the real-time factor. With --classifier, the final objects are "
        "classified after the replay (per 0.5 s time window, each from that window and, with --history mean_proba, "
        "the object's earlier ones) and each detection's class is the devkit's ClassificationLabel index, as for "
        "'cluster'.",
    )
    stream.set_defaults(run=_stream, parser=stream, together=_check_stream_options)
    replaced_only = "an existing file is replaced only if it is such"
    for flag, required, text in (
        ("--data", True, "RadarScenes data folder (or its parent)"),
        ("--params", False, _PARAMS_HELP),
        ("--classifier", False, _CLASSIFIER_HELP),
        ("--out", True, f"predictions file to write (JSON, final object id per detection); {replaced_only} a file"),
        ("--objects", False, f"object list to write (CSV, one row per live object per scan); {replaced_only} a list"),
    ):
        stream.add_argument(flag, required=required, help=text, metavar="FILE" if flag == "--classifier" else None)
    _add_checked(stream, "--experiment", _saved_experiment, help=_SAVED_EXPERIMENT_HELP)
    stream.add_argument(
        "--track",
        action="store_true",
        help="run the Tracker that reproduce tuned and saved in --params (its key 'tracker') and write each "
        "detection's track id, as given at its scan, instead of its final object id (not with --classifier)",
    )
    stream.add_argument(
        "--history",
        choices=["none", "mean_proba"],
        help="with --classifier: classify each object's 0.5 s window from its windows so far (mean_proba: the mean "
        "of their class probabilities; causal over the windows of the final object id) or from that window alone "
        "(none); default: as the classifier was saved (a classifier trained with history features keeps them)",
    )
    return parser


def _add_cluster_flags(command, when):
    """``--scheduler`` and ``--workers`` (dask.distributed, the ``[distributed]`` extra); ``when``: when to use it."""
    where = command.add_mutually_exclusive_group()
    where.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run on an existing dask scheduler, e.g. tcp://host:8786, to use several machines (needs the "
        "[distributed] extra)",
    )
    _add_checked(
        where,
        "--workers",
        _at_least(1),
        metavar="N",
        help=f"run on a local dask cluster of N worker processes (needs the [distributed] extra): {when}",
    )


def _add_checked(command, flag, check, **kwargs):
    """Add ``flag``, read as text and turned into its value by ``check(text, flag)`` in :func:`_check_options`.

    Not argparse's ``type=``: a bad value is then a one-line error naming the option (exit code 2, as
    argparse's usage errors), never a usage dump.
    """
    action = command.add_argument(flag, **kwargs)
    action.check = check
    return action


def _check_options(args):
    """Replace each checked option's text by its value, then check the options together; ValueError names them."""
    for action in args.parser._actions:
        check = getattr(action, "check", None)
        if check is not None:
            setattr(args, action.dest, check(getattr(args, action.dest), action.option_strings[0]))
    together = getattr(args, "together", None)
    if together is not None:
        together(args)


def _check_setting_options(args):
    """``cluster`` and ``stream``: a setting to apply, ``--experiment`` only with ``--params``, two outputs."""
    if args.params is None and args.classifier is None:
        raise ValueError("give --params (a params.json of 'sklearn-radar reproduce'), --classifier, or both")
    if args.params is None and args.experiment is not None:
        raise ValueError("--experiment chooses a setting of --params: give --params with it")
    objects = getattr(args, "objects", None)
    if objects is not None and os.path.realpath(objects) == os.path.realpath(args.out):
        raise ValueError(f"--objects and --out name the same file: {_shown(args.out)}")


def _check_stream_options(args):
    """``stream``: as :func:`_check_setting_options`, and --track and --history with what they need."""
    _check_setting_options(args)
    if args.track and args.classifier is not None:
        raise ValueError("--track does not go with --classifier: the classifiers label the final object ids")
    if args.track and args.params is None:
        raise ValueError("--track runs the Tracker saved in --params: give --params")
    if args.history is not None and args.classifier is None:
        raise ValueError("--history chooses how --classifier classifies the objects: give --classifier with it")


def _at_least(low):
    """The check of a whole number ``>= low`` (None stays None: the option's default applies)."""

    def check(text, flag):
        return _whole(text, flag, low, None)

    return check


#: The steps ``reproduce --experiments`` takes, as its help lists them (the CLI imports no experiment module).
_STEP_HELP = (
    "filter (Tables I and II)",
    "1-13 (the paper's experiments; ranges like 2-9)",
    "objects (the object experiment)",
    "filter-effect",
    "baselines (scikit-learn clusterers)",
    "tracking (object ids online)",
    "classification (the classifier of clusters)",
    "learned (the grouping learned from the training half; not in the default run)",
)

#: When to use which of ``reproduce``'s options for parallel work.
_REPRODUCE_EPILOG = (
    "Parallel work: --n-jobs J uses J cores of this machine (no extra needed); --workers N a local dask "
    "cluster, worth its start for runs larger than the default one; --scheduler ADDRESS a dask cluster of "
    "several machines. None of them changes the results. --n-points K above 1 gives a guided search step K "
    "candidates to evaluate at once, for many cores or workers; it changes the search."
)

#: ``--params`` of ``cluster`` and ``stream``.
_PARAMS_HELP = (
    "params.json written by 'sklearn-radar reproduce' (required unless --classifier holds a whole pipeline; "
    "with both, their clustering must agree)"
)
#: ``--classifier`` of ``cluster`` and ``stream``.
_CLASSIFIER_HELP = (
    "classifier file written by save_classifier: a pipeline from raw detections ending in a ClusterClassifier "
    "(it fixes the clustering, --params is then optional) or a bare ClusterClassifier (--params gives the steps "
    "before it); loading runs pickle: only use files you trust"
)

#: What ``--experiment`` of ``cluster`` and ``stream`` takes.
_SAVED_EXPERIMENT_HELP = (
    "which saved experiment: a number 1-13, 'objects' or 'learned' (the learned grouping's saved model: 'cluster' "
    "applies the offline one, 'stream' the causal one) (default: the run's best by cross-validated score on the "
    "training half)"
)
#: The learned experiment's key (the CLI imports no experiment module).
_LEARNED = "learned"


def _saved_experiment(text, flag):
    """An experiment number >= 1, or the object or learned experiment's key (the CLI imports no experiment module)."""
    if text in ("objects", _LEARNED):
        return text
    try:
        return _whole(text, flag, 1, None)
    except ValueError:
        raise ValueError(f"{flag} must be a whole number >= 1, 'objects' or '{_LEARNED}', got {text!r}") from None


def _seed(text, flag):
    return _whole(text, flag, 0, SEED_MAX)


#: The largest seed numpy's random generators take (2**32 - 1).
SEED_MAX = 2**32 - 1


def _n_jobs(text, flag):
    """joblib's ``n_jobs``: a whole number other than 0 (-1: all cores)."""
    value = _whole(text, flag, None, None)
    if value == 0:
        raise ValueError(f"{flag} must be a whole number other than 0 (-1: all cores), got {text!r}")
    return value


def _whole(text, flag, low, high):
    if text is None:
        return None
    try:
        value = int(str(text).strip())
    except ValueError:
        value = None
    if value is None or (low is not None and value < low) or (high is not None and value > high):
        bounds = {(True, True): f"from {low} to {high}", (True, False): f">= {low}", (False, True): f"<= {high}"}
        what = bounds.get((low is not None, high is not None), "")
        raise ValueError(f"{flag} must be a whole number {what}".rstrip() + f", got {text!r}")
    return value


#: The shortest recording make_scenes simulates, s.
MIN_DURATION_S = 0.5


def _duration(text, flag):
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value >= MIN_DURATION_S):
        raise ValueError(f"{flag} must be a finite number of seconds >= {MIN_DURATION_S}, got {text!r}")
    return value


def _simulate(args) -> int:
    from ..datasets import format_statistics, make_scenes, scene_statistics, write_radarscenes
    from ..datasets._output_folder import check_output_folder

    check_output_folder(args.out, args.overwrite, flag="--overwrite")  # before the simulation, which takes a while
    start = time.perf_counter()
    scenes = make_scenes(
        n_sequences=args.n_sequences, duration=args.duration, random_state=args.seed, difficulty=args.difficulty
    )
    simulated = time.perf_counter() - start
    path = write_radarscenes(scenes, args.out, overwrite=args.overwrite)
    print(f"simulated {len(scenes.data)} detections in {simulated:.2f} s; wrote {_shown(path)}")
    print(format_statistics(*scene_statistics(scenes)))
    return 0


def _stats(args) -> int:
    from ..datasets import format_statistics, load_radarscenes, scene_statistics

    print(format_statistics(*scene_statistics(load_radarscenes(args.data))))
    return 0


def _reproduce(args) -> int:
    from ..reproduce import reproduce
    from ..reproduce._io import check_apart
    from ..reproduce._run import parse_experiments

    try:
        parse_experiments(args.experiments)
    except ValueError as error:
        raise UsageError(f"--experiments: {error}") from None
    repeats = args.repeats or (3 if args.full else 1)
    if args.seed + repeats - 1 > SEED_MAX:
        raise UsageError(
            f"--seed {args.seed} with {repeats} repeats uses seeds up to {args.seed + repeats - 1}; "
            f"the largest is {SEED_MAX}"
        )
    if args.data is not None:
        try:
            check_apart(args.data, args.out, "--data", "--out")
        except ValueError as error:
            raise UsageError(str(error)) from None
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
        scheduler=args.scheduler,
        workers=args.workers,
        n_points=args.n_points,
        repeats=args.repeats,
    )
    print(f"wrote {_written(args.out)} in {time.perf_counter() - start:.0f} s")
    return 0


def _written(out):
    """``"DIR: report.md, results.json, params.json, 5 figures and 2 classifier files"``: what the run wrote.

    The files its marker (``run.json``) lists, which are those that exist:
    a run without an experiment writes no ``params.json``.
    """
    from ..reproduce._io import run_marker
    from ..reproduce._run import RUN_MARKER

    marker = run_marker(os.path.join(out, RUN_MARKER)) or {}
    names = list(marker.get("files") or {})
    figures = [name for name in names if name.endswith(".png")]
    classifiers = [name for name in names if name.endswith(".joblib") and name.startswith("classifier")]
    parts = [name for name in names if name not in figures and name not in classifiers]
    parts += [_counted(len(figures), "figure")] if figures else []
    parts += [_counted(len(classifiers), "classifier file")] if classifiers else []
    listed = ", ".join(parts[:-1]) + " and " + parts[-1] if len(parts) > 1 else "".join(parts) or "no file"
    return f"{_shown(out)}: {listed}"


def _counted(n, noun):
    return f"{n} {noun}" + ("" if n == 1 else "s")


def _cluster(args) -> int:
    from ._cluster import cluster_radarscenes

    summary = cluster_radarscenes(
        args.data,
        args.params,
        args.out,
        experiment=args.experiment,
        classifier=args.classifier,
        scheduler=args.scheduler,
        workers=args.workers,
    )
    _print_applied("applied", summary, args)
    if summary["stage1_params"] is not None:
        print(f"  with stage 1: {_setting(summary['stage1_params'])}")
    wrote = f"wrote {_shown(summary['out'])}"
    if "classes" in summary:
        print(f"{summary['n_detections']} detections, {summary['n_clusters']} road users; {_classes(summary)}")
        print(wrote)
    else:
        print(f"{summary['n_detections']} detections in {summary['n_clusters']} clusters; {wrote}")
    return 0


def _print_applied(verb, summary, args):
    """``applied experiment #13 of params.json: ...`` (and why, for the file's best) and/or ``classified with FILE``."""
    if summary["experiment"] is not None:
        applied = f"{_named(summary['experiment'])} of {_shown(args.params)}: {_setting(summary['params'])}"
        print(f"{verb} experiment {applied}")
        if summary.get("chosen"):
            print(f"  chosen as {summary['chosen']}")
    if args.classifier is not None:
        print(f"classified with {_shown(args.classifier)}")


def _classes(summary):
    """``detections per class: CAR 120, ...``."""
    return "detections per class: " + ", ".join(f"{name} {count}" for name, count in summary["classes"].items())


def _stream(args) -> int:
    import numpy as np

    from ._stream import stream_radarscenes

    summary = stream_radarscenes(
        args.data,
        args.params,
        args.out,
        objects=args.objects,
        experiment=args.experiment,
        classifier=args.classifier,
        track=args.track,
        history=args.history,
    )
    _print_applied("streamed", summary, args)
    if "tracker" in summary:
        print(f"tracked with the saved Tracker ({_setting(summary['tracker'])}): {summary['n_tracks']} tracks")
    print(
        f"{summary['n_detections']} detections in {summary['n_scans']} scans, {summary['n_objects']} objects "
        f"({summary['n_aliases']} merges made aliases)"
    )
    if "classes" in summary:
        print(f"{summary['n_road_users']} of them road users; {_classes(summary)}")
    for name, seconds in (("wall", summary["latency"]), ("cpu", summary["cpu"])):
        micro = seconds * 1e6 if len(seconds) else np.zeros(1)
        p50, p99 = np.percentile(micro, [50, 99])
        print(f"latency per scan ({name}): p50 {p50:.0f} us, p99 {p99:.0f} us, max {micro.max():.0f} us")
    busy, cpu = float(summary["latency"].sum()), float(summary["cpu"].sum())
    factor = summary["recording"] / busy if busy > 0 else float("inf")
    print(
        f"real-time factor {factor:.1f} ({summary['recording']:.1f} s of recording labelled in {busy:.2f} s, "
        f"{cpu:.2f} s of CPU; above 1 is faster than real time)"
    )
    written = ", ".join(_shown(path) for path in (summary["out"], summary["objects"]) if path is not None)
    print(f"wrote {written}")
    return 0


def _setting(params):
    """``{"cluster__eps_xy": 0.6, ...}`` -> ``"cluster__eps_xy=0.6, ..."``, every key and exact value."""
    return ", ".join(f"{key}={value!r}" for key, value in params.items()) or "the paper's setting"
