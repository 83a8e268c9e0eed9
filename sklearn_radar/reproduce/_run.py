"""``sklearn-radar reproduce``: re-run the paper's experiments and write a report.

The steps (:data:`._steps.STEPS`) run in one loop (:func:`run_steps`), their work where the executor
(:mod:`sklearn_radar._executor`) runs it; ``results.json`` (:mod:`._results`) is written after every step,
atomically, so an interrupted run keeps what it finished.  The output folder holds one run at a time, and
``run.json`` says which and whether it is complete (:ref:`contributing-runner`).
"""

from __future__ import annotations

import contextlib
import datetime
import json
import os
import sys
import time
import uuid
from dataclasses import dataclass, field
from numbers import Integral
from pathlib import Path

import numpy as np
from sklearn.utils._param_validation import HasMethods, Interval, StrOptions, validate_params

from .. import __version__
from .._executor import connect_executor
from .._files import (
    atomic_write_text,
    check_writable,
    remove_empty_folders,
    remove_stale_temporaries,
    sha256,
    shown_path,
    temporary_prefix,
)
from ..classification import save_classifier
from ..datasets._presets import DIFFICULTY_PRESETS
from ..experiments import SKLEARN_BASELINES, get_experiment
from ..experiments._learned import save_learned
from ..metrics._parts import OBJECTIVES  # what the searches can maximise: "v1", "pq"
from ._budget import Budget
from ._classification import CLASSIFIER_FILES
from ._constants import (
    ALL_EXPERIMENTS,
    BASELINES,
    CLASSIFICATION,
    DEFAULT_EXPERIMENTS,
    FILTER,
    FILTER_EFFECT,
    LEARNED,
    NUMBERS,
    OBJECTS,
    TRACKING,
)
from ._context import RunContext
from ._io import RUN_TOOL, check_apart, check_run_folder, previous_run_files, run_marker
from ._learned import LEARNED_CAUSAL_FILE, LEARNED_FILE
from ._progress import DATA, REPORT, RunProgress, duration, uncompiled_kernels
from ._report import write_report
from ._results import DataMeta, RunMeta, RunResults
from ._sections._base import counted
from ._sections._figures import CONVERGENCE, SCENE, V1_BARS
from ._sections._filter import FILTER_SCENE, HEATMAP
from ._sequences import RunSequences
from ._steps import STEPS, RunEnv, data_statistics, units
from ._tuning import TrainingData

#: The largest seed numpy's random generators take; a run uses the seeds seed ... seed + repeats - 1.
SEED_MAX = 2**32 - 1
#: The run marker: which run the folder holds and whether it is complete.
RUN_MARKER = "run.json"
#: Every file a run may write besides the marker (a previous run's are removed when a new one starts).
RUN_FILES = (
    "report.md",
    "results.json",
    "params.json",
    HEATMAP,
    FILTER_SCENE,
    V1_BARS,
    SCENE,
    CONVERGENCE,
    *CLASSIFIER_FILES.values(),
    LEARNED_FILE,
    LEARNED_CAUSAL_FILE,
)
#: Simulated data of at most this many sequence-seconds (the default run's 4 x 20 s) with one search at a time
#: runs in this process although ``--workers`` asks for a local cluster (why: :ref:`contributing-runner`).
IN_PROCESS_MAX_SEQUENCE_S = 80.0


@dataclass
class Run:
    """One reproduce run: its output folder, its results so far, its progress, its ``perf_counter`` start, its id."""

    out: Path
    results: RunResults
    progress: RunProgress
    started: float
    run_id: str = field(default_factory=lambda: uuid.uuid4().hex)
    started_utc: str = field(default_factory=lambda: _utc_now())

    def say(self, text):
        self.progress.say(text)


@validate_params({"text": [str, None]}, prefer_skip_nested_validation=True)
def parse_experiments(text):
    """``"filter,1-8,13,baselines"`` -> the experiment keys, in run order; ValueError names unknown ones.

    Parameters
    ----------
    text : str or None
        Comma-separated keys: ``filter``, experiment numbers ``1``-``13``,
        ranges such as ``2-9``, ``objects``, ``filter-effect``, ``baselines``,
        ``tracking``, ``classification`` and ``learned``.  None selects every step but ``learned``
        (:data:`~._constants.DEFAULT_EXPERIMENTS`).

    Returns
    -------
    keys : list of str
        The selected steps, each once, in the order a run executes them.
    """
    if text is None:
        return list(DEFAULT_EXPERIMENTS)
    first, last = min(NUMBERS), max(NUMBERS)
    chosen = set()
    for part in (p.strip() for p in text.split(",") if p.strip()):
        if "-" in part and part not in ALL_EXPERIMENTS:
            low, _, high = part.partition("-")
            if not (low.isdigit() and high.isdigit()) or not first <= int(low) <= int(high) <= last:
                raise ValueError(
                    f"unknown experiment range {part!r}; experiments are {first}-{last}, "
                    f"{FILTER}, {FILTER_EFFECT}, {BASELINES}, {TRACKING}, {CLASSIFICATION}, {LEARNED}"
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
        "difficulty": [StrOptions(set(DIFFICULTY_PRESETS))],
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
        Output folder (created), apart from ``data``: neither that folder,
        nor inside it, nor holding it (ValueError).  It holds one run: a
        previous run's files there (a folder whose ``run.json`` a run wrote) are removed when
        this one starts, other files are left alone, and a folder that
        holds a file of a run's name (``report.md``, ``run.json``, ...)
        that no run wrote is refused (FileExistsError) before anything is
        written.  ``run.json`` says ``"complete": true`` only once every
        file of the run is written.
    n_iter : int, default=None
        Bayesian-optimisation iterations per tuned experiment; None: 10, or
        100 with ``full`` (30 % of them random, as the paper's 30 + 70).
    n_jobs : int, default=None
        Candidates evaluated in parallel, and the threads of the library
        calls in all (-1: all cores; 0 is refused; None: one, one thread).
    experiments : str, default=None
        Comma-separated keys (``filter``, ``1``-``13``, ranges such as
        ``2-9``, ``objects``, ``filter-effect``, ``baselines``, ``tracking``,
        ``classification``, ``learned``); None runs all but ``learned`` (the
        grouping learned from the training half's instances, saved as
        ``learned.joblib``: its fit would add a quarter to the default run).
    full : bool, default=False
        The paper's budget on about a million simulated detections.
    seed : int, default=0
        Random seed of the simulated data and the split; each search draws
        from its own stream, derived from it and the experiment (or
        baseline) by :func:`~._tuning.search_seed`, so that searches of
        equal spaces are independent (``seed + repeats - 1`` at most
        ``2**32 - 1``).
    stream : file-like, default=None
        Progress output; None: standard output.  Plain lines (no carriage
        returns): first an estimate of the run's length (and of ``full``'s),
        then one line per step and per search iteration with the overall
        progress, the time elapsed and the time left.
    objective : {"v1", "pq"}, default="v1"
        What every search maximises on the training half, and whose
        cross-validated training score ranks ``params.json``'s ``best`` (a
        test score never does): ``"v1"`` the paper's radar V-measure,
        ``"pq"`` the panoptic quality of moving road users per 0.5 s time window
        (:func:`~sklearn_radar.metrics.panoptic_quality`).  Both are
        reported for every experiment whatever the choice.
    difficulty : {"easy", "realistic", "radarscenes"}, default="realistic"
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
        Start a local dask cluster of this many worker processes instead;
        a run that it would slow down (one search at a time on simulated
        data no larger than the default run's,
        :data:`IN_PROCESS_MAX_SEQUENCE_S`) stays in this process, and its
        first line says so.  Without ``scheduler`` or ``workers`` dask is
        not imported.
    n_points : int, default=None
        Candidates each search step proposes and evaluates at a time
        (``BayesSearchCV(n_points=...)``); None: 1.  The results depend on
        it, not on where the fits run: for the same seed and ``n_points`` a
        cluster run equals a single-process one.
    repeats : int, default=None
        Searches per tuned experiment and per baseline, with the repeat
        seeds ``seed``, ``seed + 1``, ... (each search's seed derived from
        its repeat's) on the same split, each repeat's kept
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
    keys = parse_experiments(experiments)
    repeats = (3 if full else 1) if repeats is None else int(repeats)
    last_seed = seed + repeats - 1
    if last_seed > SEED_MAX:
        raise ValueError(f"seed {seed} with its repeats uses seeds up to {last_seed}; the largest is {SEED_MAX}")
    if data is not None:
        check_apart(data, out)
    check_run_folder(out, RUN_MARKER, RUN_FILES)
    budget = Budget.full(n_iter) if full else Budget.default(n_iter)
    small = _in_process_reason(data, budget, keys, repeats)
    with connect_executor(scheduler, workers, n_jobs, in_process_reason=small) as executor:
        return _reproduce(
            data,
            Path(out),
            keys,
            budget,
            seed,
            repeats,
            stream or sys.stdout,
            objective,
            difficulty,
            executor,
            n_points or 1,
        )


def _in_process_reason(data, budget, keys, repeats):
    """Why a local cluster would be slower than this process for this run (None: it would not be)."""
    size = budget.n_sequences * budget.duration
    if data is not None or size > IN_PROCESS_MAX_SEQUENCE_S:
        return None
    at_once = max(_searches_at_once(keys, repeats), 1)
    if at_once > 1:
        return None
    return (
        f"one search at a time on {budget.n_sequences} simulated sequences x {budget.duration:g} s, where a local "
        f"cluster was 2x slower than one process (measured; at most {IN_PROCESS_MAX_SEQUENCE_S:g} sequence-seconds)"
    )


def _searches_at_once(keys, repeats):
    """The most searches the run has at once: those of the steps that need no other (together), or one step's."""
    ahead = sum(_searches(key, repeats) for key in keys if _runs_ahead(key, keys))
    return max([ahead, *(_searches(key, repeats) for key in keys)])


def _searches(key, repeats):
    """How many searches step ``key`` runs."""
    experiment = get_experiment(int(key)) if key.isdigit() else None
    if key == OBJECTS:
        return 2 * repeats
    return repeats * (len(SKLEARN_BASELINES) if key == BASELINES else int(experiment is not None and experiment.tuned))


def _runs_ahead(key, keys):
    """Whether step ``key`` may start with the run: none of the steps it needs is among ``keys``."""
    return not set(STEPS[key].needs) & set(keys)


def _reproduce(data, out, keys, budget, seed, repeats, stream, objective, difficulty, executor, n_points):
    """:func:`reproduce` with its executor connected."""
    started = time.perf_counter()
    created = check_writable(out)
    if executor.describe():
        print(f"{executor.describe()}; {n_points} candidate(s) per search step", file=stream, flush=True)
    try:
        sequences, source = _data(data, budget, seed, difficulty, executor)
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
    results = RunResults(meta=meta, statistics=data_statistics(sequences))
    work = {
        DATA: (DATA, 1),
        **{key: (STEPS[key].kind, units(key, budget, repeats)) for key in keys},
        REPORT: (REPORT, 1),
    }
    progress = RunProgress(work, started, stream, searches=sum(_searches(key, repeats) for key in keys))
    run = Run(out=out, results=results, progress=progress, started=started)
    run.progress.finish(DATA, time.perf_counter() - started)
    _start_folder(run)
    run.say(
        f"data: {source}, {meta.data.n_detections:,} detections in {counted(meta.data.n_sequences, 'sequence')}; "
        f"train {meta.data.n_train:,} / test {meta.data.n_test:,}; budget: {budget.label}, "
        f"{counted(budget.n_iter, 'iteration')}"
        + (f"; {repeats} repeats of each search (seeds {seed}-{seed + repeats - 1})" if repeats > 1 else ""),
    )
    _say_the_work(run, keys, budget, repeats)
    context = RunContext(sequences=sequences, drawn_sequence=test[0])
    try:
        # The pipeline cache (tens of MB) lives beside the output, named so that the next run removes it if
        # this process is killed.
        with executor.pipeline_cache(out, temporary_prefix("cache-")) as cache:
            env = RunEnv(
                executor,
                sequences,
                train,
                test,
                budget,
                seed,
                objective,
                repeats,
                n_points,
                cache,
                run.progress,
                TrainingData(sequences, train),
            )
            try:
                run_steps(run, env, keys, context)
            except KeyboardInterrupt:
                meta.interrupted = True
                run.say("interrupted: writing the finished results")
                _finish(run, context, "interrupted")
                raise
        _finish(run, context, "complete")
    except BaseException as error:
        marker = run_marker(run.out / RUN_MARKER) or {}
        if marker.get("run_id") == run.run_id and marker.get("status") == "running":
            _write_marker(run, "failed", error=f"{type(error).__name__}: {error}")
        raise
    return run.results.to_json_dict(figures=True)


def run_steps(run, env, keys, context):
    """Run the steps ``keys`` in order, each with the results it needs, saving after each (the free ones at once)."""
    found = {}
    first = [key for key in keys if _runs_ahead(key, keys)]
    ahead = env.executor.ahead(_started(run, env, found), first)
    at_once = sum(_searches(key, env.repeats) for key in first)
    if not env.executor.alone and at_once > 1:
        run.say(
            f"{at_once} independent searches run on the cluster at once, each a task on a worker "
            "(their iterations are not printed; a line as each ends)"
        )
    with contextlib.closing(ahead):
        for position, key in enumerate(keys, start=1):
            _run_step(run, env, keys, context, found, position, key, ahead)


def _run_step(run, env, keys, context, found, position, key, ahead):
    """Step ``key`` (the next of ``ahead`` when it started with the run): its result stored, said and saved."""
    title = f"[{position}/{len(keys)}] {_title(key)}"
    run.say(f"{title} | {run.progress.status()}")
    start = time.perf_counter()
    if _runs_ahead(key, keys):
        outcome, seconds = next(ahead)
    else:
        outcome, seconds = _started(run, env, found)(env.executor, key)
    run.progress.finish(key, seconds)
    found[key] = outcome.result
    _store(run.results, key, outcome.result)
    if outcome.labels is not None:
        context.labels[int(key)] = outcome.labels
    if outcome.tracks is not None:
        context.tracks.update(outcome.tracks)
    for name, model in (outcome.models or {}).items():
        (save_learned if name in (LEARNED_FILE, LEARNED_CAUSAL_FILE) else save_classifier)(model, run.out / name)
    if outcome.summary:
        run.say(outcome.summary)
    run.results.meta.completed.append(key)
    run.say(f"{title} done in {time.perf_counter() - start:.1f} s | {run.progress.status()}")
    _save(run)


def _started(run, env, found):
    """``step(executor, key) -> (outcome, seconds)``: the step ``key`` timed, its needs read from ``found``."""

    def step(executor, key):
        run.progress.start(key)
        start = time.perf_counter()
        needed = {need: found[need] for need in STEPS[key].needs if need in found}
        return STEPS[key].run(env.on(executor), key, needed), time.perf_counter() - start

    return step


def _store(results, key, result):
    """A step's result, where ``results.json`` holds it: an experiment by number, another step at its key."""
    if key.isdigit():
        results.experiments[int(key)] = result
    else:
        setattr(results, key.replace("-", "_"), result)


def _say_the_work(run, keys, budget, repeats):
    """The first progress line: the run's work, and that its time is estimated from the work as it goes."""
    n_search = sum(units(key, budget, repeats) for key in keys if STEPS[key].kind in ("stage 1", "stage 2", BASELINES))
    text = (
        f"the run's work: {counted(len(keys), 'step')}, {counted(n_search, 'search iteration')} in all; the progress "
        "lines estimate the time left from the rate measured so far for each kind of step (unknown until a step of "
        "each kind still to come has been timed)"
    )
    uncompiled = uncompiled_kernels()
    if uncompiled:
        text += f" ({len(uncompiled)} of its numba kernels compile in this first run: its first steps run slower)"
    run.say(text)


def _finish(run, context, status):
    """Figures and report.md first, then results.json with the wall time, then the marker: readers see the end last."""
    run.results.meta.wall_time_s = time.perf_counter() - run.started
    run.progress.start(REPORT)
    run.say(f"run {status}; drawing the figures and writing the report | {run.progress.status()}")
    write_report(run.out, run.results, context)
    run.progress.finish(REPORT)
    run.say(f"report written after {duration(time.perf_counter() - run.started)} in all")
    _save(run)
    _write_marker(run, status)


def _utc_now():
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")


def _start_folder(run):
    """Claim the output folder: the marker first ("running"), then the previous run's files (a run wrote them) go."""
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
        drawn = sorted(set(run.results.figures.drawn.values()))
        names = ["report.md", "results.json", "params.json", *drawn, *run.results.saved_classifiers()]
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


def _data(data, budget, seed, difficulty, executor):
    """The run's sequences (:class:`._sequences.RunSequences`, where the executor keeps them) and their source."""
    if data is None:
        sequences = RunSequences.simulated(budget.n_sequences, budget.duration, seed, difficulty, executor)
        return sequences, (
            f"simulated ({budget.n_sequences} sequences x {budget.duration:g} s, seed {seed}, difficulty {difficulty})"
        )
    # The source goes into report.md (UTF-8): an undecodable byte of the path is shown as \xff.
    return RunSequences.from_folder(data, executor), f"RadarScenes folder {shown_path(data)}"


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
        BASELINES: "scikit-learn baselines (DBSCAN, HDBSCAN per 0.25 s window and per sequence; DBSCAN over a "
        "sliding past window)",
        OBJECTS: "the object experiment (the framework's stages tuned for PQ)",
        TRACKING: "object tracking online (MOTA, IDF1, HOTA of the streamed and tracked ids, a baseline tracker)",
        CLASSIFICATION: "the classifier of clusters (class PQ, mAP@0.5, macro-F1, mCov)",
        LEARNED: "the learned grouping (fitted on the training half's instances, scored offline and causally)",
    }[key]
