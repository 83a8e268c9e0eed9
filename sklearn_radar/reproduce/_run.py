"""``sklearn-radar reproduce``: re-run the paper's experiments and write a report.

Every experiment is a Pipeline of this package's estimators
(:func:`sklearn_radar.experiments.experiment_pipeline`) tuned by Bayesian
optimisation on the training half of the sequences (grouped cross-validation)
and scored on the held-out half with the radar V-measure against the
pre-clustered target.  Results are written after every experiment, atomically,
so an interrupted run keeps what it finished.

The output folder holds one run at a time, and ``run.json`` says which and
whether it is complete: it is written first (``"complete": false``), then
the previous run's files are removed, and it is rewritten with
``"complete": true`` and the SHA-256 of every file of the run only after
``report.md`` and the figures.  ``results.json`` gets ``meta.wall_time_s``
only then, too.  Temporary files and the pipeline cache are named
``.sklearn-radar-tmp-<pid>-...``; a run removes those of processes that no
longer run.

The results are typed (:mod:`._results`), the in-memory state is a
:class:`~._context.RunContext`, and the report is built from the sections of
:mod:`._sections`.
"""

from __future__ import annotations

import contextlib
import datetime
import io
import json
import os
import sys
import tempfile
import threading
import time
import uuid
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from numbers import Integral
from pathlib import Path
from types import SimpleNamespace

import joblib
import numpy as np
from joblib import Parallel, delayed, effective_n_jobs
from sklearn.base import clone
from sklearn.utils._param_validation import HasMethods, Interval, StrOptions, validate_params
from threadpoolctl import threadpool_limits

from .. import __version__
from .._distributed import connect_cluster
from .._skopt import Integer, Real
from ..cluster import SequenceDBSCAN, SequenceHDBSCAN, WindowedDBSCAN, WindowedHDBSCAN
from ..datasets import format_statistics
from ..datasets._statistics import combine_statistics, statistics_parts
from ..evaluation import FilterEvaluationOptions
from ..evaluation._filter_parts import (
    combine_error_windows,
    combine_filter_grid,
    combine_filter_settings_table,
    filter_error_windows_parts,
    filter_grid_parts,
    filter_settings_table_parts,
)
from ..experiments import derived_params, experiment_pipeline, get_experiment, paper_params, search_space
from ..metrics._parts import (
    OBJECTIVES,  # what the searches can maximise: "v1", "pq"
    combine_instance_parts,
    combine_parts,
    instance_parts,
    score_parts,
)
from ..model_selection import ProgressPrinter
from ..model_selection._sequence_search import (
    SearchData,
    candidate_scores,
    search_and_score_start,
    sized_sequence_folds,
)
from ..model_selection._sequence_search import fixed_prefix as _fixed_stage0
from ..preprocessing import DopplerDensityFilter, FrameTransform
from ._constants import (
    ALL_EXPERIMENTS,
    BASELINES,
    BEST_STAGE1,
    BEST_STAGE1_UNFILTERED,
    FCS_BASELINE,
    FILTER,
    FILTER_EFFECT,
    FRAMES,
    NUMBERS,
    PAPER_FILTER_SETTING,
    SOURCE_PAPER,
    SOURCE_SEARCH,
)
from ._context import RunContext
from ._io import (
    RUN_TOOL,
    atomic_write_text,
    check_run_folder,
    check_writable,
    previous_run_files,
    remove_empty_folders,
    remove_stale_temporaries,
    run_marker,
    sha256,
    temporary_prefix,
)
from ._progress import REPORT_S, RunProgress, compile_cost, duration, rough, step_cost
from ._report import write_report
from ._results import (
    BaselineResult,
    BestRemoval,
    Budget,
    ClusteringCost,
    DataMeta,
    DataStatistics,
    ExperimentResult,
    FilterEffectFigures,
    FilterEffectResult,
    FilterGridResult,
    FilterResult,
    FilterSettingRow,
    FilterWindows,
    GridTable,
    InstanceScores,
    RepeatResult,
    RunMeta,
    RunResults,
    SearchRecord,
)
from ._search import search_on_a_worker
from ._sections._figures import CONVERGENCE, SCENE, V1_BARS
from ._sections._filter import FILTER_SCENE, HEATMAP
from ._sequences import RunSequences

#: The largest seed numpy's random generators take; a run uses the seeds seed ... seed + repeats - 1.
SEED_MAX = 2**32 - 1
#: The run marker: which run the folder holds and whether it is complete.
RUN_MARKER = "run.json"
#: Every file a run may write besides the marker (a previous run's are removed when a new one starts).
RUN_FILES = ("report.md", "results.json", "params.json", HEATMAP, FILTER_SCENE, V1_BARS, SCENE, CONVERGENCE)


@dataclass
class Run:
    """One reproduce run: where it writes, its budget and settings, and the results gathered so far.

    Attributes
    ----------
    out : Path
        Output folder.
    budget : Budget
    seed : int
    n_jobs : int or None
        Candidates evaluated in parallel.
    stream : file-like
        Progress output.
    results : RunResults
    started : float
        ``time.perf_counter()`` at the start.
    progress : RunProgress or None
        The overall progress, shown on the progress lines.
    """

    out: Path
    budget: Budget
    seed: int
    n_jobs: int | None
    stream: object
    results: RunResults
    started: float = field(default_factory=time.perf_counter)
    # --- dask (sklearn_radar._distributed): candidates proposed per search step, and the cluster or None.
    n_points: int = 1
    cluster: object = None
    run_id: str = field(default_factory=lambda: uuid.uuid4().hex)
    started_utc: str = field(default_factory=lambda: _utc_now())
    progress: RunProgress | None = None


#: Length of the frames of the object-level scores, s (Scheiner et al. 2021 evaluate 500 ms).
FRAME_S = 0.5
#: The object-level scores kept per experiment (:class:`InstanceScores`).
INSTANCE_FIELDS = tuple(name for name in InstanceScores.__dataclass_fields__ if name != "frame_s")


@validate_params({"text": [str, None]}, prefer_skip_nested_validation=True)
def parse_experiments(text):
    """``"filter,1-8,13,baselines"`` -> the experiment keys, in run order; ValueError names unknown ones.

    Parameters
    ----------
    text : str or None
        Comma-separated keys: ``filter``, experiment numbers ``1``-``13``,
        ranges such as ``2-9``, ``filter-effect`` and ``baselines``.  None
        selects every step.

    Returns
    -------
    keys : list of str
        The selected steps, each once, in the order a run executes them.
    """
    if text is None:
        return list(ALL_EXPERIMENTS)
    first, last = min(NUMBERS), max(NUMBERS)
    chosen = set()
    for part in (p.strip() for p in text.split(",") if p.strip()):
        if "-" in part and part not in ALL_EXPERIMENTS:
            low, _, high = part.partition("-")
            if not (low.isdigit() and high.isdigit()) or not first <= int(low) <= int(high) <= last:
                raise ValueError(
                    f"unknown experiment range {part!r}; experiments are {first}-{last}, "
                    f"{FILTER}, {FILTER_EFFECT}, {BASELINES}"
                )
            chosen.update(str(n) for n in range(int(low), int(high) + 1))
        elif part in ALL_EXPERIMENTS:
            chosen.add(part)
        else:
            raise ValueError(
                f"unknown experiment {part!r}; choose from {', '.join(ALL_EXPERIMENTS)} (ranges like 1-8 work)"
            )
    if not chosen:
        raise ValueError("--experiments is empty")
    return [key for key in ALL_EXPERIMENTS if key in chosen]


@validate_params(
    {
        "data": [str, os.PathLike, None],
        "out": [str, os.PathLike],
        "n_iter": [Interval(Integral, 1, None, closed="left"), None],
        "n_jobs": [Interval(Integral, None, -1, closed="right"), Interval(Integral, 1, None, closed="left"), None],
        "experiments": [str, None],
        "full": ["boolean"],
        "seed": [Interval(Integral, 0, SEED_MAX, closed="both")],
        "stream": [HasMethods(["write"]), None],
        "objective": [StrOptions(set(OBJECTIVES))],
        "difficulty": [StrOptions({"easy", "realistic"})],
        "scheduler": [str, None],
        "workers": [Interval(Integral, 1, None, closed="left"), None],
        "n_points": [Interval(Integral, 1, None, closed="left"), None],
        "repeats": [Interval(Integral, 1, None, closed="left"), None],
    },
    prefer_skip_nested_validation=True,
)
def reproduce(
    data=None,
    out="sklearn-radar-report",
    *,
    n_iter=None,
    n_jobs=None,
    experiments=None,
    full=False,
    seed=0,
    stream=None,
    objective="v1",
    difficulty="realistic",
    scheduler=None,
    workers=None,
    n_points=None,
    repeats=None,
):
    """Run the paper's experiments and write ``report.md``, ``results.json``, ``params.json`` and figures.

    Parameters
    ----------
    data : str or path-like, default=None
        A RadarScenes data folder; None simulates one (:func:`make_scenes`).
    out : str or path-like, default="sklearn-radar-report"
        Output folder (created).  It holds one run: a previous run's files
        there (a folder whose ``run.json`` a run wrote) are removed when
        this one starts, other files are left alone, and a folder that
        holds a file of a run's name (``report.md``, ``run.json``, ...)
        that no run wrote is refused (FileExistsError) before anything is
        written.  ``run.json`` says ``"complete": true`` only once every
        file of the run is written.
    n_iter : int, default=None
        Bayesian-optimisation iterations per tuned experiment; None: 10, or
        100 with ``full`` (30 % of them random, as the paper's 30 + 70).
    n_jobs : int, default=None
        Candidates evaluated in parallel (-1: all cores; 0 is refused).
    experiments : str, default=None
        Comma-separated keys (``filter``, ``1``-``13``, ranges such as
        ``2-9``, ``filter-effect``, ``baselines``); None runs all.
    full : bool, default=False
        The paper's budget on about a million simulated detections.
    seed : int, default=0
        Random seed of the simulated data, the split and the searches
        (``seed + repeats - 1`` at most ``2**32 - 1``).
    stream : file-like, default=None
        Progress output; None: standard output.  Plain lines (no carriage
        returns): first an estimate of the run's length (and of ``full``'s),
        then one line per step and per search iteration with the overall
        progress, the time elapsed and the time left.
    objective : {"v1", "pq"}, default="v1"
        What every search maximises on the training half, and what ranks
        ``params.json``'s ``best``: ``"v1"`` the paper's radar V-measure,
        ``"pq"`` the panoptic quality of moving road users per 0.5 s frame
        (:func:`~sklearn_radar.metrics.panoptic_quality`).  Both are
        reported for every experiment whatever the choice.
    difficulty : {"easy", "realistic"}, default="realistic"
        Difficulty of the simulated data (:func:`make_scenes`) when
        ``data`` is None; ignored for a RadarScenes folder.
    scheduler : str, default=None
        Address of a running dask scheduler (``tcp://host:8786``): the
        searches' training sequences are placed on its workers, each
        candidate is one task per sequence there, and the independent
        searches run at once.  Needs the
        ``[distributed]`` extra; an unreachable address fails within a few
        seconds (OSError naming it).
    workers : int, default=None
        Start a local dask cluster of this many worker processes instead.
        Without ``scheduler`` or ``workers`` dask is not imported.
    n_points : int, default=None
        Candidates each search step proposes and evaluates at a time
        (``BayesSearchCV(n_points=...)``); None: 1.  The results depend on
        it, not on where the fits run: for the same seed and ``n_points`` a
        cluster run equals a single-process one.
    repeats : int, default=None
        Searches per tuned experiment and per baseline, with the seeds
        ``seed``, ``seed + 1``, ... on the same split, each repeat's kept
        setting scored on the test half; None: 1, or 3 with ``full``.  The
        report gives test scores as mean and standard deviation over the
        repeats and checks the paper's findings by paired differences
        (``results.json`` keeps every repeat).  With ``n_jobs`` above 1 the
        repeats of a step run concurrently, ``n_jobs`` split between them.

    Returns
    -------
    results : dict
        What ``results.json`` holds, and ``figures``: the figures drawn.
    """
    # Every argument is checked before a cluster starts or anything is written.
    parse_experiments(experiments)
    last_seed = seed + (repeats or (3 if full else 1)) - 1
    if last_seed > SEED_MAX:
        raise ValueError(f"seed {seed} with its repeats uses seeds up to {last_seed}; the largest is {SEED_MAX}")
    check_run_folder(out, RUN_MARKER, RUN_FILES)
    with connect_cluster(scheduler, workers) as cluster:
        return _reproduce(
            data,
            out,
            n_iter,
            n_jobs,
            experiments,
            full,
            seed,
            stream,
            objective,
            difficulty,
            cluster,
            n_points,
            repeats,
        )


def _reproduce(
    data, out, n_iter, n_jobs, experiments, full, seed, stream, objective, difficulty, cluster, n_points, repeats
):
    """:func:`reproduce` with its cluster (or None) connected."""
    started = time.perf_counter()
    keys = parse_experiments(experiments)
    out = Path(out)
    created = check_writable(out)
    budget = Budget.full(n_iter) if full else Budget.default(n_iter)
    repeats = (3 if full else 1) if repeats is None else int(repeats)
    stream = stream or sys.stdout
    try:
        sequences, source = _data(data, budget, seed, difficulty, cluster, n_jobs)
        train, test = sequences.split(random_state=seed)
    except BaseException:
        remove_empty_folders(created)  # a run that never started leaves no folder behind
        raise
    meta = RunMeta(
        version=__version__,
        seed=seed,
        budget=budget,
        objective=objective,
        repeats=repeats,
        data=DataMeta(
            source=source,
            n_detections=sequences.n_detections,
            n_sequences=len(sequences.ids),
            n_train=sequences.size(train),
            n_test=sequences.size(test),
            train_sequences=train,
            test_sequences=test,
        ),
    )
    results = RunResults(meta=meta, statistics=_statistics(sequences))
    run = Run(out=out, budget=budget, seed=seed, n_jobs=n_jobs, stream=stream, results=results, started=started)
    _use_cluster(run, cluster, n_points)
    _start_folder(run)
    _say(
        run,
        f"data: {source}, {meta.data.n_detections:,} detections in {meta.data.n_sequences} sequences; "
        f"train {meta.data.n_train:,} / test {meta.data.n_test:,}; budget: {budget.label}, {budget.n_iter} iterations"
        + (f"; {repeats} repeats of each search (seeds {seed}-{seed + repeats - 1})" if repeats > 1 else ""),
    )
    run.progress = _estimate(run, keys, full=full, simulated=data is None)
    context = RunContext(sequences=sequences, train=train, test=test)
    try:
        # The pipeline cache (tens of MB) lives beside the output, named so that the next run removes it if
        # this process is killed.
        with tempfile.TemporaryDirectory(prefix=temporary_prefix("cache-"), dir=out) as cache:
            context.cache = cache
            try:
                with _concurrent_searches(run, context, keys):
                    for position, key in enumerate(keys, start=1):
                        _say(run, f"[{position}/{len(keys)}] {_title(key)} | {run.progress.status()}")
                        start = time.perf_counter()
                        run.progress.start(key)
                        _RUNNERS[_runner_of(key)](run, context, key)
                        run.progress.finish(key)
                        meta.completed.append(key)
                        _say(
                            run,
                            f"[{position}/{len(keys)}] {_title(key)} done in {time.perf_counter() - start:.1f} s"
                            f" | {run.progress.status()}",
                        )
                        _save(run)
            except KeyboardInterrupt:
                meta.interrupted = True
                _say(run, "interrupted: writing the finished results")
                _finish(run, context, "interrupted")
                raise
        _finish(run, context, "complete")
    except BaseException as error:
        marker = run_marker(run.out / RUN_MARKER) or {}
        if marker.get("run_id") == run.run_id and marker.get("status") == "running":
            _write_marker(run, "failed", error=f"{type(error).__name__}: {error}")
        raise
    return run.results.to_json_dict(figures=True)


def _estimate(run, keys, *, full, simulated):
    """The run's cost model (:class:`RunProgress`), and a line saying how long this run and ``--full`` take."""
    data = run.results.meta.data

    def costs(budget, scale, repeats):
        sizes = {
            "n_train": data.n_train * scale,
            "n_test": data.n_test * scale,
            "n_detections": data.n_detections * scale,
        }
        steps = {key: step_cost(key, budget, tuned=_tuned(key), **sizes) * _repeated(key, repeats) for key in keys}
        return {**steps, REPORT: REPORT_S}

    # The time spent on the data so far (simulation, statistics, compilation) counts towards the run's length.
    spent = time.perf_counter() - run.started
    steps = costs(run.budget, 1.0, run.results.meta.repeats)
    compiling = compile_cost()  # on an empty numba cache (a new environment), charged to the first step
    steps[keys[0] if keys else REPORT] += compiling
    progress = RunProgress({**steps, DATA: spent}, run.started)
    progress.finish(DATA)
    text = f"estimated run time: {rough(progress.total)} on an idle 2-core machine"
    if compiling:
        text += f" (with {rough(compiling)} to compile the numba kernels: this first run fills their cache)"
    if not full:
        # --full simulates the paper's data size; on a data folder it keeps the data and raises the budget.
        default, paper = Budget.default(), Budget.full()
        scale = (paper.n_sequences * paper.duration) / (default.n_sequences * default.duration) if simulated else 1.0
        full_s = spent * scale + sum(costs(paper, scale, 3).values()) + compiling  # 3 repeats of each search
        text += f"; --full (the paper's budget, 3 repeats) takes {rough(full_s)}"
    _say(run, text + "; the progress lines below re-estimate the time left as the run goes")
    return progress


#: The first and the last step of every run, for the progress: making the data, and the figures and the report.
DATA = "data"
REPORT = "report"


def _tuned(key):
    return key.isdigit() and get_experiment(int(key)).tuned


def _use_cluster(run, cluster, n_points):
    """The cluster (or None) and the candidates per search step: 1 unless asked, with or without a cluster.

    On a cluster a candidate is already one task per training sequence, and
    independent searches run at once (:func:`_concurrent_searches`): more
    candidates per step are not needed to keep the workers busy, and with
    the same ``n_points`` the results equal a single-process run's.
    """
    run.cluster = cluster
    run.n_points = n_points or 1
    if cluster is not None:
        _say(run, f"{cluster.describe()}; {run.n_points} candidate(s) per search step, one task per block of sequences")


def _repeated(key, repeats):
    """How many times a step's work runs: ``repeats`` for the searches and for #8's derived settings, else once."""
    if key == BASELINES or _tuned(key):
        return repeats
    if key.isdigit() and get_experiment(int(key)).derived_from is not None:
        return repeats
    return 1


def _finish(run, context, status):
    """Figures and report.md first, then results.json with the wall time, then the marker: readers see the end last."""
    run.results.meta.wall_time_s = time.perf_counter() - run.started
    if run.progress is not None:
        run.progress.start(REPORT)
        _say(run, f"run {status}; drawing the figures and writing the report | {run.progress.status()}")
    write_report(run.out, run.results, context)
    if run.progress is not None:
        run.progress.finish(REPORT)
        _say(
            run,
            f"report written after {duration(time.perf_counter() - run.started)} in all "
            f"(estimated at the start: {rough(run.progress.total)})",
        )
    _save(run)
    _write_marker(run, status)


def _utc_now():
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")


def _start_folder(run):
    """Claim the output folder for this run: the marker first ("running"), then the previous run's files go.

    Only files a run wrote go: the run's file names in a folder that a run
    marked (:func:`check_run_folder`, checked again as the folder may have
    changed while the data were made), and the names the old marker lists
    whose contents are unchanged.
    """
    out = run.out
    check_run_folder(out, RUN_MARKER, RUN_FILES)
    remove_stale_temporaries(out, legacy=(*RUN_FILES, RUN_MARKER))
    previous = previous_run_files(out, run_marker(out / RUN_MARKER))
    _write_marker(run, "running")
    for name in {*RUN_FILES, *previous}:
        file = out / name
        if name != RUN_MARKER and (file.is_file() or file.is_symlink()):
            file.unlink()


def _write_marker(run, status, error=None):
    """Write ``run.json``: the run's id, its status and, once it ended, the SHA-256 of each of its files."""
    files = {}
    if status in ("complete", "interrupted"):
        names = ["report.md", "results.json", "params.json", *sorted(set(run.results.figures.drawn.values()))]
        files = {name: sha256(run.out / name) for name in names if (run.out / name).is_file()}
    marker = {
        "tool": RUN_TOOL,  # what run_marker recognises
        "version": __version__,
        "run_id": run.run_id,
        "started": run.started_utc,
        "status": status,
        "complete": status == "complete",
        "files": files,
    }
    if status != "running":
        marker["ended"] = _utc_now()
    if error is not None:
        marker["error"] = error
    atomic_write_text(run.out / RUN_MARKER, json.dumps(marker, indent=1))


def _data(data, budget, seed, difficulty="realistic", cluster=None, n_jobs=None):
    """The run's sequences (:class:`._sequences.RunSequences`; on a cluster: on its workers) and their source."""
    if data is None:
        sequences = RunSequences.simulated(budget.n_sequences, budget.duration, seed, difficulty, cluster, n_jobs)
        return sequences, (
            f"simulated ({budget.n_sequences} sequences x {budget.duration:g} s, seed {seed}, difficulty {difficulty})"
        )
    # The source goes into report.md (UTF-8): an undecodable byte of the path is shown as \xff.
    return (
        RunSequences.from_folder(data, cluster, n_jobs),
        f"RadarScenes folder {os.fsencode(data).decode('utf-8', 'backslashreplace')}",
    )


def _say(run, text):
    print(text, file=run.stream, flush=True)


def _save(run):
    """Write ``results.json`` and, once an experiment ran, ``params.json`` (read by ``sklearn-radar cluster``)."""
    atomic_write_text(run.out / "results.json", _dumps(run.results.to_json_dict()))
    saved = run.results.to_params_dict()
    if saved is not None:
        atomic_write_text(run.out / "params.json", _dumps(saved))


def _dumps(document):
    return json.dumps(document, indent=1, default=_json_default)


def _json_default(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def _title(key):
    if key.isdigit():
        return f"experiment #{key}: {get_experiment(int(key)).method}"
    return {
        FILTER: "filter evaluation (Tables I and II)",
        FILTER_EFFECT: "the filter's effect on clustering",
        BASELINES: "scikit-learn baselines (DBSCAN, HDBSCAN per 0.25 s window and per sequence)",
    }[key]


def _runner_of(key):
    return "experiment" if key.isdigit() else key


def _native(params):
    """Parameters with numpy scalars as Python numbers."""
    return {key: (value.item() if isinstance(value, np.generic) else value) for key, value in params.items()}


# ----------------------------------------------------------------------------- the experiments


def _run_filter(run, context, key):
    """Tables I and II and the error windows, combined from per-sequence summaries (computed where each lives)."""
    start = time.perf_counter()
    n_jobs = run.n_jobs if context.sequences.cluster is None else 1
    parts = context.sequences.map(_filter_parts, None, n_jobs)
    grids = {frame: combine_filter_grid([p["grids"][frame] for p in parts]) for frame in FRAMES}
    table_ii = combine_filter_settings_table([p["table_ii"] for p in parts])
    context.filter_grids = grids
    run.results.filter = FilterResult(
        table_i={
            frame: FilterGridResult(
                errors=GridTable.from_frame(g.errors), background_removed=GridTable.from_frame(g.background_removed)
            )
            for frame, g in grids.items()
        },
        table_ii=[FilterSettingRow(**row) for row in table_ii.to_dict(orient="records")],
        best_removal_with_zero_errors={frame: _best_removal(g, 0) for frame, g in grids.items()},
        windows=_error_windows(combine_error_windows([p["windows"] for p in parts])),
        wall_time_s=time.perf_counter() - start,
    )


def _filter_parts(sequence, n_jobs=None):
    """One sequence's share of the filter evaluation: Table I per frame, Table II, the error windows."""
    data, target = sequence.scenes.data, sequence.scenes.target
    return {
        "grids": {
            frame: filter_grid_parts(data, target, FilterEvaluationOptions(frame=frame, n_jobs=n_jobs))
            for frame in FRAMES
        },
        "table_ii": filter_settings_table_parts(data, target, options=FilterEvaluationOptions(n_jobs=n_jobs)),
        "windows": _sequence_error_windows(sequence),
    }


def _statistics(sequences):
    """The data's statistics (:func:`scene_statistics`) as JSON numbers and as text, from per-sequence parts."""
    summary, table = combine_statistics(sequences.map(_statistics_part))
    # The plain numbers and words of the summary; anything richer stays in the text.
    numbers = {key: value for key, value in _native(summary).items() if isinstance(value, (bool, int, float, str))}
    return DataStatistics(summary=numbers, text=format_statistics(summary, table))


def _statistics_part(sequence):
    return statistics_parts(sequence.scenes)


#: The error windows' setting: the paper's chosen filter (FCS, eta_1 = 0.10 m/s, d_xy = 1.4 m).
WINDOWS_FRAME, WINDOW_S, WINDOW_MIN_KEPT = "frame", 0.15, 0.75


def _sequence_error_windows(sequence):
    """The (object, window) table of one sequence at the paper's chosen filter setting."""
    vr_threshold, d_xy = PAPER_FILTER_SETTING
    prepared = FrameTransform(frame=WINDOWS_FRAME).fit_transform(sequence.scenes.data)
    prepared = DopplerDensityFilter(vr_threshold=vr_threshold, d_xy=d_xy).fit_transform(prepared)
    keep = prepared["keep"].to_numpy(dtype=bool)
    t = prepared["t"].to_numpy()
    return filter_error_windows_parts(keep, sequence.scenes.target, t, WINDOW_S, WINDOW_MIN_KEPT)


def _error_windows(windows):
    """The (object, window) cases at the paper's chosen filter setting, summarised."""
    setting = DopplerDensityFilter(vr_threshold=PAPER_FILTER_SETTING[0], d_xy=PAPER_FILTER_SETTING[1])
    errors = windows[windows["error"]]
    return FilterWindows(
        frame=WINDOWS_FRAME,
        vr_threshold=float(setting.vr_threshold),
        d_xy=float(setting.d_xy),
        window_s=WINDOW_S,
        min_kept=WINDOW_MIN_KEPT,
        n_windows=len(windows),
        n_errors=len(errors),
        mean_detections=float(windows["n"].mean()) if len(windows) else float("nan"),
        mean_detections_error=float(errors["n"].mean()) if len(errors) else None,
        n_errors_sparse=int((errors["n"] <= 3).sum()),
    )


def _best_removal(grid, max_errors):
    allowed = grid.background_removed.where(grid.errors <= max_errors)
    if not allowed.notna().any().any():
        return None
    vr, d_xy = allowed.stack().idxmax()
    return BestRemoval(vr_threshold=float(vr), d_xy=float(d_xy), background_removed=float(allowed.loc[vr, d_xy]))


def _score(context, pipeline):
    """Fit-predict on each test sequence; radar V-measure and object-level scores against the pre-clustered target.

    Returns ``(v1, found, instance)``: ``found`` holds the number of clusters
    and, for stage 2, of merges and stage-1 clusters, summed over the test
    sequences, and the labels of the sequence the figures draw (``labels``).
    """
    sequences = context.sequences
    if sequences.cluster is not None:
        pipeline = _without_cache(pipeline)
    drawn = context.drawn_sequence
    parts = sequences.map(_score_sequence, context.test, pipeline, drawn)
    v1 = combine_parts("v1", [p["v1"] for p in parts])
    scores = combine_instance_parts([p["instance"] for p in parts])
    instance = InstanceScores(frame_s=FRAME_S, **{name: float(scores[name]) for name in INSTANCE_FIELDS})
    found = {name: _sum_or_none([p[name] for p in parts]) for name in ("n_clusters", "n_merges", "n_stage1")}
    found["labels"] = next(p["labels"] for p in parts if p["labels"] is not None)
    return v1, found, instance


def _sum_or_none(values):
    return None if any(v is None for v in values) else int(sum(values))


def _score_sequence(sequence, pipeline, drawn):
    """One test sequence's share of :func:`_score` (its labels only when it is the one drawn)."""
    X = sequence.X
    fitted = clone(pipeline)
    labels = np.asarray(fitted.fit_predict(X))
    times = X["timestamp"].to_numpy(dtype=np.float64) * 1e-6
    found = {
        "v1": score_parts("v1", sequence.target, labels),
        "instance": instance_parts(sequence.target, labels, times=times, frame=FRAME_S),
        "n_clusters": len(np.unique(labels[labels >= 0])),
        "n_merges": None,
        "n_stage1": None,
        "labels": labels if sequence.id == drawn else None,
    }
    merger = fitted[-1] if hasattr(fitted, "steps") else None
    if hasattr(merger, "merges_"):
        found["n_merges"] = len(merger.merges_)
        found["n_stage1"] = len(np.unique(merger.stage1_labels_[merger.stage1_labels_ >= 0]))
    return found


def _tune(run, context, estimator, space, label, start_from=None, part=0, parts=1, seed=None):
    """Bayesian optimisation on the training half with grouped CV; returns (best params, SearchRecord).

    ``part`` of ``parts`` says which of the step's searches this is, for the overall progress; ``seed``
    is the search's random seed (None: the run's).  A candidate is one task per block of training
    sequences (:mod:`._search`), here or on the run's dask cluster.

    ``start_from`` (e.g. the paper's optimum) is scored on the same folds as
    one more candidate and wins when the search found nothing better: a
    short search should not report a worse setting than a known one.
    """
    budget = run.budget
    train = context.train
    folds = sized_sequence_folds(train, [context.sequences.size([s]) for s in train], budget.cv_folds)
    objective = run.results.meta.objective
    start = time.perf_counter()
    raw = _training_sequences(run, context)
    estimator = _without_cache(estimator)
    searched, searched_space, data, prefix = estimator, space, raw, ""
    fixed = _fixed_stage0(estimator, space)
    if fixed is not None:
        # Stage 0 once for every candidate and fold, per sequence (it never crosses sequences; tested).
        stage0, searched, prefix = fixed
        data = _prepared(context, raw, stage0)
        searched_space = {key[len(prefix) :]: dimension for key, dimension in space.items()}
    # The paper's setting is scored as one more candidate on the same folds (on the data as searched, when it
    # sets only the searched step).
    start_here = bool(start_from) and all(key.startswith(prefix) for key in start_from)
    start_candidate = {key[len(prefix) :]: value for key, value in start_from.items()} if start_here else None
    options = {
        "objective": objective,
        "n_iter": budget.n_iter,
        "n_initial_points": budget.n_initial_points,
        "n_points": getattr(run, "n_points", 1),  # a bare run object lacks it
        "random_state": run.seed if seed is None else seed,
    }
    cluster = getattr(run, "cluster", None)
    if cluster is not None and getattr(run, "remote_searches", False):
        found, known = search_on_a_worker(cluster, searched, searched_space, data, folds, start_candidate, **options)
    else:
        status = None if run.progress is None else run.progress.search_status(part, parts)
        printer = ProgressPrinter(budget.n_iter, label=label, stream=run.stream, status=status)
        # The Gaussian process works on tiny matrices, where multi-threaded BLAS was 20x slower (measured).
        with threadpool_limits(limits=1, user_api="blas"):
            found, known = search_and_score_start(
                searched, searched_space, data, folds, start_candidate, callback=printer, **options
            )
    best = {prefix + key: value for key, value in _native(found.best_params).items()}
    cv_best, source = found.best_score, SOURCE_SEARCH
    if start_from:
        if not start_here:
            known = candidate_scores(raw, estimator, [start_from], folds, objective)[0]
        if known >= cv_best:
            best = {key: start_from[key] for key in space if key in start_from}
            cv_best, source = known, SOURCE_PAPER
    record = SearchRecord(
        cv_best=cv_best,
        convergence=found.scores,
        best_source=source,
        cv_start_from=known,
        search_wall_time_s=time.perf_counter() - start,
    )
    return best, record


def _training_sequences(run, context):
    """The training half per sequence (:class:`._search.SearchData`): placed once per run, where tasks run."""
    cluster = getattr(run, "cluster", None)
    placed = getattr(context, "search_data", None)
    if placed is None or placed.cluster is not cluster:
        placed = context.sequences.search_data(context.train)
        context.search_data = placed
    return SearchData(placed.blocks, placed.ids, cluster, None if cluster is not None else run.n_jobs)


#: Stage-0 outputs kept per run (:func:`_prepared`): the inputs of the experiments, not of every setting.
PREPARED_KEPT = 4
_PREPARED_LOCK = threading.Lock()


def _prepared(context, raw, stage0):
    """``raw`` with ``stage0`` applied per sequence, shared by the searches with the same stage 0.

    The last :data:`PREPARED_KEPT` are kept (on a cluster: on the workers).
    """
    key = joblib.hash(stage0)
    with _PREPARED_LOCK:  # concurrent searches (threads) share the cache
        cache = getattr(context, "prepared", None)
        if cache is None:
            cache = context.prepared = {}
        found = cache.get(key)
        if found is None or found.cluster is not raw.cluster:
            found = cache[key] = raw.prepare(stage0)
            while len(cache) > PREPARED_KEPT:
                cache.pop(next(iter(cache)))
    return SearchData(found.blocks, found.ids, raw.cluster, raw.n_jobs)


def _without_cache(estimator):
    """A pipeline without its cache folder (which a worker on another machine cannot reach)."""
    if hasattr(estimator, "steps"):
        return clone(estimator).set_params(memory=None)
    return estimator


def _with_cluster_gate(space, stage, objective):
    """The paper's search space, plus the cluster-level Doppler gate when tuning for PQ.

    The paper's V-measure does not see clusters of static background, so the
    gate (``cluster_vr_min``, m/s: clusters whose median |v_r| is at most it
    become noise) only enters the searches for the panoptic quality, which
    counts them as false positives; tuned for V1 the experiments stay as
    printed.
    """
    if objective != "pq":
        return space
    name = f"{'merge' if stage == 2 else 'cluster'}__cluster_vr_min"
    return {**space, name: Real(0.0, 1.5, name=name)}


def _repeat_runs(run, repeats):
    """How the repeats of a step run: (concurrent repeats, the run each of them sees).

    With ``n_jobs`` above 1 and several repeats, up to ``n_jobs`` repeats run
    at once as independent joblib jobs, the cores split between them, each
    search quiet (its progress lines would interleave); otherwise, and on a
    dask cluster (whose workers each search keeps busy with its candidates),
    one after the other in this process, each search with the run's
    ``n_jobs`` and progress lines.  The seeds, and so the results, are the
    same either way.
    """
    if getattr(run, "cluster", None) is not None:
        return 1, run
    workers = effective_n_jobs(run.n_jobs) if run.n_jobs is not None else 1
    concurrent = min(repeats, workers)
    if concurrent < 2:
        return 1, run
    worker = _quiet_run(run, n_jobs=max(1, workers // concurrent), cluster=None)
    return concurrent, worker


def _quiet_run(run, *, n_jobs, cluster):
    """A run for a search that runs beside others: no progress lines, nothing written."""
    return SimpleNamespace(
        budget=run.budget,
        seed=run.seed,
        n_jobs=n_jobs,
        n_points=getattr(run, "n_points", 1),
        cluster=cluster,
        progress=None,
        stream=io.StringIO(),
        results=SimpleNamespace(meta=SimpleNamespace(objective=run.results.meta.objective)),
    )


def _map_repeats(run, job, repeats, pending=None):
    """``[job(worker_run, k) for k in range(repeats)]``, concurrently where ``n_jobs`` allows (:func:`_repeat_runs`).

    ``pending`` holds the repeats already started on the cluster (:func:`_concurrent_searches`): their results.
    """
    if pending:
        return [pending[k].result() if k in pending else job(run, k) for k in range(repeats)]
    concurrent, worker = _repeat_runs(run, repeats)
    if concurrent == 1:
        return [job(run, k) for k in range(repeats)]
    _say(run, f"    {repeats} repeats, {concurrent} at a time (their searches print no iterations)")
    return Parallel(n_jobs=concurrent)(delayed(job)(worker, k) for k in range(repeats))


def _repeat_label(label, k, repeats):
    return label if repeats == 1 else f"{label} repeat {k + 1}/{repeats}"


def _experiment_repeat(run, context, number, k, repeats, stage1):
    """Repeat ``k`` of experiment ``number``: search (seed ``run.seed + k``) or derive its setting, then score it.

    ``stage1`` is #8's setting of the same repeat (None: the paper's); returns a dictionary of what it found.
    """
    experiment = get_experiment(number)
    start = time.perf_counter()
    pipeline = experiment_pipeline(
        number, memory=context.cache, stage1_params=stage1 if experiment.stage == 2 else None
    )
    search = None
    if experiment.tuned:
        space = _with_cluster_gate(search_space(number), experiment.stage, run.results.meta.objective)
        params, search = _tune(
            run,
            context,
            pipeline,
            space,
            _repeat_label(f"#{number}", k, repeats),
            paper_params(number),
            part=k,
            parts=repeats,
            seed=run.seed + k,
        )
    elif experiment.derived_from is None:  # the expert setting (#1): the paper's, as it is
        params = {}
    else:  # #10, #11: #8's setting, transferred
        params = derived_params(number, stage1)
    pipeline.set_params(**params)
    v1, found, instance = _score(context, pipeline)
    found.update(params=params, search=search, v1=v1, instance=instance)
    found["wall_time_s"] = time.perf_counter() - start
    return found


def _experiment_job(context, number, repeats, stage1s):
    """``job(run, k)``: repeat ``k`` of experiment ``number`` (``stage1s[k]``: #8's setting it builds on)."""

    def job(worker, k):
        return _experiment_repeat(worker, context, number, k, repeats, stage1s[k])

    return job


def _baseline_job(context, name, clusterer, space, part, repeats):
    """``job(run, k)``: repeat ``k`` of the baseline ``name``, the ``part``-th of the baselines."""

    def job(worker, k):
        return _baseline_repeat(worker, context, name, clusterer, space, k, repeats, part, len(_BASELINES))

    return job


def _independent_searches(run, context, keys):
    """The searches among ``keys`` that need no other step's result: ``{pending key: job}``.

    The stage-1 experiments and the baselines; #10, #11 and stage 2 build on #8.
    """
    repeats = run.results.meta.repeats
    jobs = {}
    for key in keys:
        if key == BASELINES:
            for part, (name, (clusterer, space)) in enumerate(_BASELINES.items()):
                jobs[(key, name)] = _baseline_job(context, name, clusterer, space, part, repeats)
        elif _tuned(key) and get_experiment(int(key)).stage == 1:
            jobs[key] = _experiment_job(context, int(key), repeats, [None] * repeats)
    return jobs


@contextlib.contextmanager
def _concurrent_searches(run, context, keys):
    """On a dask cluster, every independent search starts at once: a task on a worker, awaited by a thread here.

    A search alone keeps the workers busy only while its candidates run,
    not while its Gaussian process chooses the next one; several at once
    fill those gaps.  Each search loop is a task on a worker
    (:func:`._search.search_on_a_worker`), so that their Gaussian processes
    do not queue for this process's GIL; the thread here then scores the
    kept setting on the test half.  Each search has its own seed, so the
    results are those of one search after the other.  The steps collect
    them in their order (``context.pending``); their iterations are not
    printed.
    """
    context.pending = {}
    cluster = getattr(run, "cluster", None)
    jobs = _independent_searches(run, context, keys) if cluster is not None else {}
    repeats = run.results.meta.repeats
    if len(jobs) * repeats < 2:
        yield
        return
    _training_sequences(run, context)  # placed once, before the threads share it
    quiet = _quiet_run(run, n_jobs=None, cluster=cluster)
    quiet.remote_searches = True  # each search's Gaussian process on a worker, not in this process's GIL
    threads = len(jobs) * repeats
    executor = ThreadPoolExecutor(max_workers=threads, thread_name_prefix="sklearn-radar-search")
    # BLAS limits are process-wide: set once here, so that the threads' own enter-and-leave cannot change them
    # under one another (a multi-threaded BLAS computes the Gaussian process to other rounding).
    limits = threadpool_limits(limits=1, user_api="blas")
    finished = _FinishedCount(run, threads)
    try:
        for tag, job in jobs.items():
            context.pending[tag] = {}
            for k in range(repeats):
                future = context.pending[tag][k] = executor.submit(job, quiet, k)
                key, share = (tag, 1 / repeats) if isinstance(tag, str) else (tag[0], 1 / (len(_BASELINES) * repeats))
                future.add_done_callback(finished.said(_pending_label(tag, k, repeats), key, share))
        _say(
            run,
            f"{threads} independent searches run on the cluster at once, each a task on a worker "
            "(their iterations are not printed; a line as each ends)",
        )
        yield
    finally:
        executor.shutdown(wait=False, cancel_futures=True)
        limits.restore_original_limits()


def _pending_label(tag, k, repeats):
    name = f"#{tag}" if isinstance(tag, str) else tag[1]
    return _repeat_label(name, k, repeats)


class _FinishedCount:
    """Says, as each concurrent search ends (in its thread), which one and how many of them have ended."""

    def __init__(self, run, total):
        self.run, self.total, self.done = run, total, 0
        self._lock = threading.Lock()

    def said(self, label, key, share):
        """The callback for the search ``label``, ``share`` of the step ``key`` (credited to the run's progress)."""

        def callback(future):
            if future.cancelled():
                return
            with self._lock:
                self.done += 1
                outcome = "failed" if future.exception() is not None else "ended"
                status = ""
                if self.run.progress is not None:
                    self.run.progress.credit(key, share)
                    status = f" | {self.run.progress.status()}"
                _say(
                    self.run,
                    f"    search {label} {outcome} ({self.done}/{self.total} of the concurrent searches){status}",
                )

        return callback


def _run_experiment(run, context, key):
    number = int(key)
    experiment = get_experiment(number)
    best = context.best_stage1
    start = time.perf_counter()
    # The fixed expert setting (#1) does not depend on a seed: it runs once whatever the repeats.
    repeats = run.results.meta.repeats if experiment.tuned or experiment.derived_from is not None else 1
    stage1s = context.best_stage1_repeats or [best] * repeats
    if len(stage1s) != repeats:
        stage1s = [best] * repeats

    found = _map_repeats(
        run, _experiment_job(context, number, repeats, stage1s), repeats, context.pending.pop(key, None)
    )
    first = found[0]
    recorded_stage1 = derived = None
    if experiment.stage == 2:
        recorded_stage1 = best or paper_params(BEST_STAGE1)
    if not experiment.tuned and experiment.derived_from is not None:
        derived = f"tuned #{BEST_STAGE1}" if best else f"paper's #{BEST_STAGE1} (experiment {BEST_STAGE1} not run)"
    result = ExperimentResult(
        number=number,
        method=experiment.method,
        frame=experiment.frame,
        filtered=experiment.filtered,
        stage=experiment.stage,
        paper_v1_percent=experiment.v1_percent,
        paper_params=paper_params(number),
        params={**paper_params(number), **first["params"]},
        v1_test=first["v1"],
        n_clusters_test=first["n_clusters"],
        wall_time_s=time.perf_counter() - start,
        stage1_params=recorded_stage1,
        derived_from_8=derived,
        instance_test=first["instance"],
        search=first["search"],
        n_merges_test=first["n_merges"],
        n_stage1_clusters_test=first["n_stage1"],
        repeats=_repeat_records(run, found, paper_params(number)) if repeats > 1 else None,
    )
    context.labels[number] = first["labels"]
    if number == BEST_STAGE1:
        context.best_stage1 = _stage1_setting(result.params)
        context.best_stage1_repeats = [_stage1_setting(r.params) for r in result.repeats or [result]]
    run.results.experiments[number] = result
    _say(
        run, f"    #{number}: test V1 {_spread(found, 'v1')} (paper {experiment.v1_percent:.2f} %), PQ {_spread(found)}"
    )


def _stage1_setting(params):
    return {k: v for k, v in params.items() if k.startswith("cluster__")}


def _repeat_records(run, found, defaults=None):
    """One :class:`RepeatResult` per repeat, in order."""
    return [
        RepeatResult(
            seed=run.seed + k,
            params={**(defaults or {}), **f["params"]},
            v1_test=f["v1"],
            n_clusters_test=f["n_clusters"],
            search=f["search"],
            instance_test=f["instance"],
        )
        for k, f in enumerate(found)
    ]


def _spread(found, score="pq"):
    """``"71.55 %"`` / ``"0.412"`` for one repeat, mean and sd over several (``"71.20 +- 0.35 %"``)."""
    values = np.array([f["v1"] if score == "v1" else f["instance"].pq for f in found])
    scale, unit, digits = (100, " %", 2) if score == "v1" else (1, "", 3)
    text = f"{scale * values.mean():.{digits}f}"
    if len(values) > 1:
        text += f" +- {scale * values.std(ddof=1):.{digits}f}"
    return text + unit


def _run_filter_effect(run, context, key):
    """Clustering time and number of clusters with and without the filter, at #8's setting."""
    params = context.best_stage1 or paper_params(BEST_STAGE1)
    found = context.sequences.map(_filter_effect_sequence, context.test, params)
    per_sequence, cost = {}, {}
    for filtered in (True, False):
        per_sequence[filtered] = {f["id"]: f[filtered][1] for f in found}
        # Each sequence's fastest of 3 clusterings (after a warm-up), summed over the test sequences.
        cost[filtered] = ClusteringCost(
            clustering_s=sum(f[filtered][0] for f in found), n_clusters=sum(f[filtered][1] for f in found)
        )
    with_filter, without = per_sequence[True], per_sequence[False]
    fewer = [1 - with_filter[g] / without[g] for g in with_filter if without[g] > 0]
    filtered, unfiltered = cost[True], cost[False]
    run.results.filter_effect = FilterEffectResult(
        setting=params,
        setting_source=f"tuned #{BEST_STAGE1}" if context.best_stage1 else f"paper's #{BEST_STAGE1}",
        filtered=filtered,
        unfiltered=unfiltered,
        measured=FilterEffectFigures(
            time_saving_percent=100 * (1 - filtered.clustering_s / unfiltered.clustering_s),
            fewer_clusters_per_sequence_percent=100 * float(np.mean(fewer)) if fewer else float("nan"),
            fewer_clusters_overall_percent=100 * (1 - filtered.n_clusters / max(unfiltered.n_clusters, 1)),
        ),
    )


def _filter_effect_sequence(sequence, params):
    """One test sequence clustered with and without the filter: ``{filtered: (fastest of 3 s, clusters)}``."""
    found = {"id": sequence.id}
    for filtered in (True, False):
        pipeline = experiment_pipeline(BEST_STAGE1 if filtered else BEST_STAGE1_UNFILTERED, params=params)
        prepared = pipeline[:-1].fit_transform(sequence.X)
        clusterer = pipeline[-1]
        clusterer.fit(prepared)  # warm-up: JIT compilation is not clustering time
        times = []
        for _ in range(3):
            start = time.perf_counter()
            labels = clusterer.fit(prepared).labels_
            times.append(time.perf_counter() - start)
        found[filtered] = (min(times), len(np.unique(labels[labels >= 0])))
    return found


_BASELINES = {
    "sklearn DBSCAN per 0.25 s window": (
        WindowedDBSCAN,
        {
            "cluster__eps": Real(0.2, 3.0, name="cluster__eps"),
            "cluster__min_samples": Integer(2, 8, name="cluster__min_samples"),
            "cluster__vr_scale": Real(0.3, 20.0, prior="log-uniform", name="cluster__vr_scale"),
        },
    ),
    "sklearn HDBSCAN per 0.25 s window": (
        WindowedHDBSCAN,
        {
            "cluster__min_cluster_size": Integer(2, 10, name="cluster__min_cluster_size"),
            "cluster__min_samples": Integer(1, 8, name="cluster__min_samples"),
            # cluster_selection_epsilon stays 0: scikit-learn 1.9.1's epsilon search crashed on this data.
            "cluster__vr_scale": Real(0.3, 20.0, prior="log-uniform", name="cluster__vr_scale"),
        },
    ),
    "sklearn DBSCAN per sequence (x, y, v_r, t) with Doppler gate": (
        SequenceDBSCAN,
        {
            "cluster__eps": Real(0.2, 3.0, name="cluster__eps"),
            "cluster__min_samples": Integer(2, 8, name="cluster__min_samples"),
            "cluster__vr_scale": Real(0.3, 20.0, prior="log-uniform", name="cluster__vr_scale"),
            # t_scale, m/s: how many metres one second counts (4 m/s puts 0.25 s, the paper's eps_t, at 1 m).
            "cluster__t_scale": Real(0.5, 50.0, prior="log-uniform", name="cluster__t_scale"),
            "cluster__vr_min": Real(0.0, 1.5, name="cluster__vr_min"),
        },
    ),
    "sklearn HDBSCAN per sequence (x, y, v_r, t) with Doppler gate": (
        SequenceHDBSCAN,
        {
            "cluster__min_cluster_size": Integer(2, 20, name="cluster__min_cluster_size"),
            "cluster__min_samples": Integer(1, 8, name="cluster__min_samples"),
            "cluster__vr_scale": Real(0.3, 20.0, prior="log-uniform", name="cluster__vr_scale"),
            "cluster__t_scale": Real(0.5, 50.0, prior="log-uniform", name="cluster__t_scale"),
            "cluster__vr_min": Real(
                0.1, 1.5, name="cluster__vr_min"
            ),  # below 0.1 m/s static clutter makes one fit take 6 s
        },
    ),
}


def _baseline_repeat(run, context, name, clusterer, space, k, repeats, part, parts):
    """Repeat ``k`` of a baseline: its search (seed ``run.seed + k``) and the kept setting's test scores."""
    start = time.perf_counter()
    pipeline = experiment_pipeline(FCS_BASELINE, memory=context.cache)
    pipeline.steps[-1] = ("cluster", clusterer())
    params, search = _tune(
        run,
        context,
        pipeline,
        space,
        _repeat_label(name, k, repeats),
        part=part * repeats + k,
        parts=parts * repeats,
        seed=run.seed + k,
    )
    pipeline.set_params(**params)
    v1, found, instance = _score(context, pipeline)
    return {
        **found,
        "params": params,
        "search": search,
        "v1": v1,
        "instance": instance,
        "wall_time_s": time.perf_counter() - start,
    }


def _run_baselines(run, context, key):
    """The clusterers a user would otherwise pick, on the same FCS + filter input, same budget and split."""
    baselines = run.results.baselines = {}
    repeats = run.results.meta.repeats
    for part, (name, (clusterer, space)) in enumerate(_BASELINES.items()):
        start = time.perf_counter()

        job = _baseline_job(context, name, clusterer, space, part, repeats)
        found = _map_repeats(run, job, repeats, context.pending.pop((key, name), None))
        first = found[0]
        baselines[name] = BaselineResult(
            search=first["search"],
            params=first["params"],
            v1_test=first["v1"],
            n_clusters_test=first["n_clusters"],
            wall_time_s=time.perf_counter() - start,
            instance_test=first["instance"],
            repeats=_repeat_records(run, found) if repeats > 1 else None,
        )
        _say(run, f"    {name}: test V1 {_spread(found, 'v1')}, PQ {_spread(found)}")


_RUNNERS = {
    FILTER: _run_filter,
    "experiment": _run_experiment,
    FILTER_EFFECT: _run_filter_effect,
    BASELINES: _run_baselines,
}

__all__ = ["ALL_EXPERIMENTS", "parse_experiments", "reproduce"]
