"""The steps of a reproduce run: each a function from its inputs to its typed result, their dependencies in one table.

A step is ``run(env, key, needed) -> Outcome``: ``env`` says what every step reads, ``needed`` holds the results
of the steps it depends on (:data:`STEPS`) that the run ran.  A step writes nothing; the run (:mod:`._run`) stores
its result.  How the steps are laid out over the data: :ref:`contributing-runner`.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from sklearn.base import clone

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
from ..experiments import (
    SKLEARN_BASELINES,
    baseline_pipeline,
    derived_params,
    experiment_pipeline,
    get_experiment,
    object_pipeline,
    object_search_space,
    paper_params,
    search_space,
)
from ..metrics._parts import combine_instance_parts, combine_parts, instance_parts, score_parts
from ..preprocessing import DopplerDensityFilter, FrameTransform
from ._classification import run_classification
from ._constants import (
    ALL_EXPERIMENTS,
    BASELINES,
    BEST_STAGE1,
    BEST_STAGE1_UNFILTERED,
    CLASSIFICATION,
    CLASSIFIED,
    FILTER,
    FILTER_EFFECT,
    FRAMES,
    LEARNED,
    OBJECTS,
    PAPER_FILTER_SETTING,
    SCORE_WINDOW_S,
    STAGE2,
    TRACKED,
    TRACKING,
)
from ._context import Outcome
from ._experiment_records import (
    BaselineResult,
    ExperimentResult,
    InstanceScores,
    ObjectExperimentResult,
    ObjectRepeat,
    RepeatResult,
    SearchRecord,
)
from ._filter_records import (
    BestRemoval,
    ClusteringCost,
    FilterEffectFigures,
    FilterEffectResult,
    FilterGridResult,
    FilterResult,
    FilterSettingRow,
    FilterWindows,
    GridTable,
    time_savings_percent,
)
from ._learned import run_learned
from ._progress import SCORING
from ._results import DataStatistics
from ._sections._base import values_cell
from ._tracking import run_tracking
from ._tuning import native_params, search_seed, tune, with_cluster_gate

#: The object-level scores kept per experiment (:class:`InstanceScores`).
INSTANCE_FIELDS = tuple(name for name in InstanceScores.__dataclass_fields__ if name != "window_s")
#: The error windows' setting: the paper's chosen filter (FCS, eta_1 = 0.10 m/s, d_xy = 1.4 m).
WINDOWS_FRAME, WINDOW_S, WINDOW_MIN_KEPT = "frame", 0.15, 0.75
#: Rounds of the filter effect's timing, each clustering every test sequence filtered and unfiltered once.
TIMING_ROUNDS = 10


@dataclass(frozen=True)
class RunEnv:
    """What every step reads.

    Attributes
    ----------
    executor : LocalExecutor or DaskExecutor
        Where the work runs (:mod:`sklearn_radar._executor`).
    sequences : RunSequences
        The data, one table per sequence, where the executor keeps it.
    train, test : list of int
        The training and the test sequences.
    budget : Budget
    seed : int
        The run's seed: repeat ``k`` of a search has the seed
        :func:`search_seed` ``(seed + k, key)``.
    objective : {"v1", "pq"}
    repeats : int
    n_points : int
        Candidates per search step.
    cache : str or None
        Pipeline cache folder.
    progress : RunProgress
    training : TrainingData
        The training half, placed once per run, with its stage-0 outputs.
    """

    executor: Any
    sequences: Any
    train: list
    test: list
    budget: Any
    seed: int
    objective: str
    repeats: int
    n_points: int
    cache: str | None
    progress: Any
    training: Any

    def on(self, executor):
        """The same inputs, the work on ``executor`` (a repeat's, from :meth:`~LocalExecutor.map`)."""
        return dataclasses.replace(self, executor=executor)

    @property
    def drawn(self):
        """The test sequence the figures draw (the first), whose labels the steps keep."""
        return self.test[0]


@dataclass(frozen=True)
class TestScores:
    """A setting's scores on the test half (:func:`score_on_test`), summed or combined over its sequences."""

    v1: float
    instance: InstanceScores
    n_clusters: int | None
    n_merges: int | None
    n_stage1: int | None
    labels: np.ndarray


@dataclass(frozen=True)
class Repeat:
    """One repeat of a step: its kept setting, its search (None: not tuned), that setting's test scores, its time."""

    params: dict
    search: SearchRecord | None
    test: TestScores
    wall_time_s: float


@dataclass(frozen=True)
class Step:
    """A step of :data:`STEPS`: ``run(env, key, needed) -> Outcome``, the keys it reads the results of, its kind."""

    run: Callable
    needs: tuple = ()
    kind: str = SCORING


# ----------------------------------------------------------------------------- the filter evaluation


def run_filter(env, key, needed):
    """Tables I and II and the error windows, combined from per-sequence summaries (computed where each lives)."""
    start = time.perf_counter()
    parts = env.sequences.map(_filter_parts, None, env.executor.n_jobs, executor=env.executor)
    grids = {frame: combine_filter_grid([p["grids"][frame] for p in parts]) for frame in FRAMES}
    table_ii = combine_filter_settings_table([p["table_ii"] for p in parts])
    result = FilterResult(
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
    return Outcome(result)


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


def data_statistics(sequences):
    """The data's statistics (:func:`scene_statistics`) as JSON numbers and as text, from per-sequence parts."""
    summary, table = combine_statistics(sequences.map(_statistics_part))
    # The plain numbers and words of the summary; anything richer stays in the text.
    numbers = {
        key: value for key, value in native_params(summary).items() if isinstance(value, (bool, int, float, str))
    }
    return DataStatistics(summary=numbers, text=format_statistics(summary, table))


def _statistics_part(sequence):
    return statistics_parts(sequence.scenes)


# ----------------------------------------------------------------------------- the experiments


def run_experiment(env, key, needed):
    """Experiment ``key``: each repeat searched (or derived from #8's same repeat) and scored on the test half."""
    number = int(key)
    experiment = get_experiment(number)
    start = time.perf_counter()
    best = needed.get(str(BEST_STAGE1))
    # The fixed expert setting (#1) does not depend on a seed: it runs once whatever the repeats.
    repeats = env.repeats if experiment.tuned or experiment.derived_from is not None else 1
    stage1s = _stage1_settings(best, repeats)
    found = env.executor.map(
        _ExperimentRepeat(env, number, repeats, stage1s),
        range(repeats),
        on_done=_said_ended(env, repeats, f"#{number}") if experiment.tuned else None,
    )
    first = found[0]
    derived = None
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
        params={**paper_params(number), **first.params},
        v1_test=first.test.v1,
        n_clusters_test=first.test.n_clusters,
        wall_time_s=time.perf_counter() - start,
        stage1_params=(stage1s[0] or paper_params(BEST_STAGE1)) if experiment.stage == 2 else None,
        derived_from_8=derived,
        instance_test=first.test.instance,
        search=first.search,
        n_merges_test=first.test.n_merges,
        n_stage1_clusters_test=first.test.n_stage1,
        repeats=_repeat_records(env, found, paper_params(number)) if repeats > 1 else None,
    )
    summary = (
        f"    #{number}: test V1 {_spread(found, 'v1')} (paper {experiment.v1_percent:.2f} %), PQ {_spread(found)}"
    )
    return Outcome(result, summary, first.test.labels)


def _stage1_settings(best, repeats):
    """#8's ``cluster__`` setting for each repeat (repeat k builds on #8's repeat k); Nones when #8 did not run."""
    if best is None:
        return [None] * repeats
    settings = [_stage1_setting(r.params) for r in best.repeats or [best]]
    return settings if len(settings) == repeats else [_stage1_setting(best.params)] * repeats


def _stage1_setting(params):
    return {k: v for k, v in params.items() if k.startswith("cluster__")}


@dataclass(frozen=True)
class _ExperimentRepeat:
    """``job(executor, k)``: repeat ``k`` of experiment ``number`` (a class: joblib's processes pickle it)."""

    env: RunEnv
    number: int
    repeats: int
    stage1s: list

    def __call__(self, executor, k):
        start = time.perf_counter()
        env, number = self.env.on(executor), self.number
        experiment = get_experiment(number)
        stage1 = self.stage1s[k] if experiment.stage == 2 else None
        pipeline = experiment_pipeline(number, memory=env.cache, stage1_params=stage1)
        search = None
        if experiment.tuned:
            space = with_cluster_gate(search_space(number), experiment.stage, env.objective)
            label = _repeat_label(f"#{number}", k, self.repeats)
            seed = search_seed(env.seed + k, str(number))
            params, search = tune(env, str(number), pipeline, space, label, paper_params(number), seed=seed)
        elif experiment.derived_from is None:  # the expert setting (#1): the paper's, as it is
            params = {}
        else:  # #10, #11: #8's setting, transferred
            params = derived_params(number, self.stage1s[k])
        test = score_on_test(env, pipeline.set_params(**params))
        return Repeat(params, search, test, time.perf_counter() - start)


def _repeat_records(env, found, defaults=None):
    """One :class:`RepeatResult` per repeat, in order."""
    return [
        RepeatResult(
            seed=env.seed + k,
            params={**(defaults or {}), **f.params},
            v1_test=f.test.v1,
            n_clusters_test=f.test.n_clusters,
            search=f.search,
            instance_test=f.test.instance,
        )
        for k, f in enumerate(found)
    ]


def _spread(found, score="pq"):
    """``"71.55 %"`` / ``"0.412"`` for one repeat, mean and sd over several (``"71.20 +- 0.35 %"``)."""
    return values_cell([f.test.v1 if score == "v1" else f.test.instance.pq for f in found], score, sign="+-")


def _repeat_label(label, k, repeats):
    return label if repeats == 1 else f"{label} repeat {k + 1}/{repeats}"


def _said_ended(env, repeats, label=None):
    """``on_done`` of a step's repeats ``k`` (or jobs ``(label, k)``) beside other work: a line as each ends."""
    if env.executor.alone:
        return None
    return lambda job, _: env.progress.search_ended(_repeat_label(*((label, job) if label else job), repeats))


# ----------------------------------------------------------------------------- the filter's effect


def run_filter_effect(env, key, needed):
    """Clustering time and number of clusters with and without the filter, at #8's setting."""
    best = needed.get(str(BEST_STAGE1))
    params = _stage1_setting(best.params) if best else paper_params(BEST_STAGE1)
    found = env.sequences.map(_filter_effect_sequence, env.test, params, executor=env.executor)
    per_sequence, cost = {}, {}
    for filtered in (True, False):
        per_sequence[filtered] = {f["id"]: f[filtered][1] for f in found}
        # Each round's clustering time of the whole test half: the sequences' times of that round, summed.
        rounds = np.sum([f[filtered][0] for f in found], axis=0)
        cost[filtered] = ClusteringCost(
            clustering_s=float(np.median(rounds)),
            n_clusters=sum(f[filtered][1] for f in found),
            clustering_times_s=rounds.tolist(),
        )
    with_filter, without = per_sequence[True], per_sequence[False]
    fewer = [1 - with_filter[g] / without[g] for g in with_filter if without[g] > 0]
    filtered, unfiltered = cost[True], cost[False]
    result = FilterEffectResult(
        setting=params,
        setting_source=f"tuned #{BEST_STAGE1}" if best else f"paper's #{BEST_STAGE1}",
        filtered=filtered,
        unfiltered=unfiltered,
        measured=FilterEffectFigures(
            time_saving_percent=float(np.mean(time_savings_percent(filtered, unfiltered))),
            fewer_clusters_per_sequence_percent=100 * float(np.mean(fewer)) if fewer else float("nan"),
            fewer_clusters_overall_percent=100 * (1 - filtered.n_clusters / max(unfiltered.n_clusters, 1)),
        ),
    )
    return Outcome(result)


def _filter_effect_sequence(sequence, params):
    """One test sequence clustered with and without the filter: ``{filtered: (seconds per timing round, clusters)}``."""
    found = {"id": sequence.id}
    clusterers, prepared = {}, {}
    for filtered in (True, False):
        pipeline = experiment_pipeline(BEST_STAGE1 if filtered else BEST_STAGE1_UNFILTERED, params=params)
        prepared[filtered] = pipeline[:-1].fit_transform(sequence.X)
        clusterers[filtered] = pipeline[-1]
        labels = clusterers[filtered].fit(prepared[filtered]).labels_
        found[filtered] = ([], len(np.unique(labels[labels >= 0])))
    for k in range(TIMING_ROUNDS):
        for filtered in (True, False) if k % 2 == 0 else (False, True):
            start = time.perf_counter()
            clusterers[filtered].fit(prepared[filtered])
            found[filtered][0].append(time.perf_counter() - start)
    return found


# ----------------------------------------------------------------------------- the baselines


def run_baselines(env, key, needed):
    """The scikit-learn clusterers on the same FCS + filter input, budget and split; each repeat one executor job."""
    names = list(SKLEARN_BASELINES)
    jobs = [(name, k) for name in names for k in range(env.repeats)]
    found = env.executor.map(_BaselineRepeat(env), jobs, on_done=_said_ended(env, env.repeats))
    baselines, lines = {}, []
    for i, name in enumerate(names):
        repeats = found[i * env.repeats : (i + 1) * env.repeats]
        first = repeats[0]
        baselines[name] = BaselineResult(
            search=first.search,
            params=first.params,
            v1_test=first.test.v1,
            n_clusters_test=first.test.n_clusters,
            wall_time_s=sum(r.wall_time_s for r in repeats),
            instance_test=first.test.instance,
            repeats=_repeat_records(env, repeats) if env.repeats > 1 else None,
        )
        lines.append(f"    {name}: test V1 {_spread(repeats, 'v1')}, PQ {_spread(repeats)}")
    return Outcome(baselines, "\n".join(lines))


@dataclass(frozen=True)
class _BaselineRepeat:
    """``job(executor, (name, k))``: repeat ``k`` of baseline ``name`` (its search seeded by :func:`search_seed`)."""

    env: RunEnv

    def __call__(self, executor, job):
        start = time.perf_counter()
        name, k = job
        env = self.env.on(executor)
        pipeline = baseline_pipeline(name, memory=env.cache)
        space = SKLEARN_BASELINES[name][1]
        label, seed = _repeat_label(name, k, env.repeats), search_seed(env.seed + k, name)
        params, search = tune(env, BASELINES, pipeline, space, label, seed=seed)
        test = score_on_test(env, pipeline.set_params(**params))
        return Repeat(params, search, test, time.perf_counter() - start)


# ----------------------------------------------------------------------------- the object experiment


def run_objects(env, key, needed):
    """The object experiment, tuned for PQ whatever the objective: stage 1, stage 2 on it; tested offline, causally."""
    start = time.perf_counter()
    found = env.executor.map(_ObjectRepeat(env), range(env.repeats), on_done=_said_ended(env, env.repeats, OBJECTS))
    result = ObjectExperimentResult(
        stage1_search=found[0].stage1_search,
        search=found[0].search,
        kept=found[0].record,
        wall_time_s=time.perf_counter() - start,
        repeats=[f.record for f in found] if env.repeats > 1 else None,
    )
    offline = [f.record.instance_test.pq for f in found]
    causal = [f.record.causal_instance_test.pq for f in found]
    summary = (
        f"    objects: test PQ {values_cell(offline, 'pq', '+-')} offline, {values_cell(causal, 'pq', '+-')} causal"
    )
    return Outcome(result, summary)


@dataclass(frozen=True)
class _ObjectSearched:
    record: ObjectRepeat
    stage1_search: SearchRecord
    search: SearchRecord


@dataclass(frozen=True)
class _ObjectRepeat:
    """``job(executor, k)``: repeat ``k`` of the object experiment; each of its two searches has its own seed stream."""

    env: RunEnv

    def __call__(self, executor, k):
        env = dataclasses.replace(self.env.on(executor), objective="pq")
        label, seed = _repeat_label(OBJECTS, k, env.repeats), env.seed + k
        stage1, stage1_search = tune(
            env,
            OBJECTS,
            object_pipeline(1),
            object_search_space(1),
            f"{label} stage 1",
            seed=search_seed(seed, f"{OBJECTS} stage 1"),
        )
        pipeline = object_pipeline(2, stage1_params=stage1, memory=env.cache)
        stage2_seed = search_seed(seed, f"{OBJECTS} stage 2")
        params, search = tune(env, OBJECTS, pipeline, object_search_space(2), f"{label} stage 2", seed=stage2_seed)
        offline = score_on_test(env, pipeline.set_params(**params))
        causal = score_on_test(env, object_pipeline(2, stage1_params=stage1, params=params, causal=True))
        record = ObjectRepeat(
            seed=seed,
            stage1_params=stage1,
            params=params,
            v1_test=offline.v1,
            n_clusters_test=offline.n_clusters,
            instance_test=offline.instance,
            causal_v1_test=causal.v1,
            causal_instance_test=causal.instance,
        )
        return _ObjectSearched(record, stage1_search, search)


# ----------------------------------------------------------------------------- scoring and searching


def score_on_test(env, pipeline):
    """Fit-predict each test sequence: V1, object-level scores, summed counts, the labels of the sequence drawn."""
    parts = env.sequences.map(_score_sequence, env.test, pipeline, env.drawn, executor=env.executor)
    scores = combine_instance_parts([p["instance"] for p in parts])
    counts = {name: _sum_or_none([p[name] for p in parts]) for name in ("n_clusters", "n_merges", "n_stage1")}
    return TestScores(
        v1=combine_parts("v1", [p["v1"] for p in parts]),
        instance=InstanceScores(window_s=SCORE_WINDOW_S, **{name: float(scores[name]) for name in INSTANCE_FIELDS}),
        labels=next(p["labels"] for p in parts if p["labels"] is not None),
        **counts,
    )


def _sum_or_none(values):
    return None if any(v is None for v in values) else int(sum(values))


def _score_sequence(sequence, pipeline, drawn):
    """One test sequence's share of :func:`score_on_test` (its labels only when it is the one drawn)."""
    X = sequence.X
    fitted = clone(pipeline)
    labels = np.asarray(fitted.fit_predict(X))
    times = X["timestamp"].to_numpy(dtype=np.float64) * 1e-6
    found = {
        "v1": score_parts("v1", sequence.target, labels),
        "instance": instance_parts(sequence.target, labels, times=times, window=SCORE_WINDOW_S),
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


# ----------------------------------------------------------------------------- the table


def _experiment_step(number):
    experiment = get_experiment(number)
    needs = (str(BEST_STAGE1),) if experiment.derived_from == BEST_STAGE1 else ()
    kind = "stage 2" if number in STAGE2 else "stage 1"
    return Step(run_experiment, needs, kind if experiment.tuned else SCORING)


#: Every step by key, in run order: its function, the steps whose results it reads, its kind of work.
#: #10 and #11 (#8's setting transferred), stage 2 (#12, #13: merging #8's clusters) and the filter's effect (at
#: #8's setting) need #8; the tracking step the settings it streams (objects, #1, #8, #12, #13) and the baselines
#: (whose SlidingDBSCAN setting it reuses when tuned for PQ); every other step needs
#: none (the object experiment tunes its own stage 1); the classification step the settings whose clusters it
#: classifies (#1, #3, #8, #13, the object experiment and the learned grouping) and the baselines (the strongest
#: one's clusters); the learned grouping the object experiment and the baselines (whose kept settings' errors it
#: sets beside its own).
STEPS = {
    FILTER: Step(run_filter, kind=FILTER),
    **{key: _experiment_step(int(key)) for key in ALL_EXPERIMENTS if key.isdigit()},
    OBJECTS: Step(run_objects, kind="stage 2"),
    FILTER_EFFECT: Step(run_filter_effect, (str(BEST_STAGE1),), kind=FILTER_EFFECT),
    BASELINES: Step(run_baselines, kind=BASELINES),
    TRACKING: Step(run_tracking, (*TRACKED, BASELINES), kind=TRACKING),
    CLASSIFICATION: Step(run_classification, (*(str(key) for key in CLASSIFIED), BASELINES), kind=CLASSIFICATION),
    LEARNED: Step(run_learned, (OBJECTS, BASELINES), kind=LEARNED),
}


def units(key, budget, repeats):
    """A step's units of work for the progress: its search iterations (with the two more scorings), else 1."""
    experiment = get_experiment(int(key)) if key.isdigit() else None
    if key == BASELINES:
        return len(SKLEARN_BASELINES) * repeats * (budget.n_iter + 2)
    if key == OBJECTS:  # two searches, two scorings of the test half
        return repeats * (2 * budget.n_iter + 2)
    if key == TRACKING:  # the baseline clusterer's search, the trackers' tuning, the test half
        return budget.n_iter + 2
    if experiment is not None and experiment.tuned:
        return repeats * (budget.n_iter + 2)
    if experiment is not None and experiment.derived_from is not None:
        return repeats
    return 1
