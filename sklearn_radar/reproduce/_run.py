"""``sklearn-radar reproduce``: re-run the paper's experiments and write a report.

Every experiment is a Pipeline of this package's estimators
(:func:`sklearn_radar.experiments.experiment_pipeline`) tuned by Bayesian
optimisation on the training half of the sequences (grouped cross-validation)
and scored on the held-out half with the radar V-measure against the
pre-clustered target.  Results are written after every experiment, atomically,
so an interrupted run keeps what it finished.
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from sklearn.base import clone
from sklearn.model_selection import GroupKFold
from threadpoolctl import threadpool_limits

from .. import __version__
from .._skopt import Integer, Real
from ..cluster import WindowedDBSCAN, WindowedHDBSCAN
from ..datasets import load_radarscenes, make_scenes
from ..evaluation import filter_grid, filter_settings_table
from ..experiments import derived_params, experiment_pipeline, get_experiment, paper_params, search_space
from ..metrics import precluster_target, radar_v_measure, radar_v_measure_scorer
from ..model_selection import ProgressPrinter, make_bayes_search, sequence_train_test_split
from ._io import atomic_write_text, check_writable
from ._report import write_figures, write_report

#: Every experiment key, in the order they run.
ALL_EXPERIMENTS = ("filter",) + tuple(str(n) for n in range(1, 14)) + ("filter-effect", "baselines")


@dataclass
class Budget:
    """Data size and optimisation budget of a run."""

    n_sequences: int
    duration: float  # s per simulated sequence
    n_iter: int
    n_initial_points: int
    cv: int
    label: str

    @classmethod
    def default(cls, n_iter=None):
        n_iter = 10 if n_iter is None else n_iter
        return cls(4, 20.0, n_iter, max(1, round(0.3 * n_iter)), 2, "reduced (default run)")

    @classmethod
    def full(cls, n_iter=None):
        n_iter = 100 if n_iter is None else n_iter
        return cls(17, 30.0, n_iter, max(1, round(0.3 * n_iter)), 3, "the paper's (--full)")


@dataclass
class Run:
    """State of one reproduce run: data, split, targets and the results gathered so far."""

    out: Path
    budget: Budget
    seed: int
    n_jobs: int | None
    stream: object
    results: dict = field(default_factory=dict)
    started: float = field(default_factory=time.perf_counter)


def parse_experiments(text):
    """``"filter,1-8,13,baselines"`` -> the experiment keys, in run order; ValueError names unknown ones."""
    if text is None:
        return list(ALL_EXPERIMENTS)
    chosen = set()
    for part in (p.strip() for p in text.split(",") if p.strip()):
        if "-" in part and part not in ALL_EXPERIMENTS:
            low, _, high = part.partition("-")
            if not (low.isdigit() and high.isdigit()) or not 1 <= int(low) <= int(high) <= 13:
                raise ValueError(f"unknown experiment range {part!r}; experiments are 1-13, filter, filter-effect, baselines")
            chosen.update(str(n) for n in range(int(low), int(high) + 1))
        elif part in ALL_EXPERIMENTS:
            chosen.add(part)
        else:
            raise ValueError(f"unknown experiment {part!r}; choose from {', '.join(ALL_EXPERIMENTS)} (ranges like 1-8 work)")
    if not chosen:
        raise ValueError("--experiments is empty")
    return [key for key in ALL_EXPERIMENTS if key in chosen]


def reproduce(data=None, out="sklearn-radar-report", *, n_iter=None, n_jobs=None, experiments=None, full=False,
              seed=0, stream=None):  # fmt: skip
    """Run the paper's experiments and write ``report.md``, ``results.json``, ``params.json`` and figures.

    Parameters
    ----------
    data : str or path-like, default=None
        A RadarScenes data folder; None simulates one (:func:`make_scenes`).
    out : str or path-like, default="sklearn-radar-report"
        Output folder (created).
    n_iter : int, default=None
        Bayesian-optimisation iterations per tuned experiment; None: 10, or
        100 with ``full`` (30 % of them random, as the paper's 30 + 70).
    n_jobs : int, default=None
        Candidates evaluated in parallel.
    experiments : str, default=None
        Comma-separated keys (``filter``, ``1``-``13``, ranges such as
        ``2-9``, ``filter-effect``, ``baselines``); None runs all.
    full : bool, default=False
        The paper's budget on about a million simulated detections.
    seed : int, default=0
    stream : file-like, default=None
        Progress output; None: standard output.

    Returns
    -------
    results : dict
        What ``results.json`` holds.
    """
    keys = parse_experiments(experiments)
    out = Path(out)
    check_writable(out)
    budget = Budget.full(n_iter) if full else Budget.default(n_iter)
    run = Run(out=out, budget=budget, seed=seed, n_jobs=n_jobs, stream=stream or sys.stdout)
    scenes, source = _data(data, budget, seed)
    run.results = {"meta": _meta(run, scenes, source), "experiments": {}}
    train, test = sequence_train_test_split(scenes.groups, random_state=seed)
    run.results["meta"]["data"].update(
        n_train=int(len(train)), n_test=int(len(test)),
        train_sequences=sorted(int(s) for s in np.unique(scenes.groups[train])),
        test_sequences=sorted(int(s) for s in np.unique(scenes.groups[test])),
    )  # fmt: skip
    _say(run, f"data: {source}, {len(scenes.data):,} detections in {len(np.unique(scenes.groups))} sequences; "
              f"train {len(train):,} / test {len(test):,}; budget: {budget.label}, {budget.n_iter} iterations")  # fmt: skip
    target = precluster_target(scenes.data, scenes.target)
    # The estimators' input: the measured columns only (no labels, no strings: cheap to hash for caching).
    X = scenes.data[[c for c in scenes.data.columns if c not in ("uuid", "track_id", "label_id")]]
    context = {"scenes": scenes, "X": X, "train": train, "test": test, "target": target, "labels": {}}
    with tempfile.TemporaryDirectory(prefix="sklearn-radar-cache-") as cache:
        context["cache"] = cache
        try:
            for position, key in enumerate(keys, start=1):
                _say(run, f"[{position}/{len(keys)}] {_title(key)}")
                start = time.perf_counter()
                _RUNNERS[_runner_of(key)](run, context, key)
                run.results["meta"]["completed"].append(key)
                _say(run, f"[{position}/{len(keys)}] {_title(key)} done in {time.perf_counter() - start:.1f} s")
                _save(run)
        except KeyboardInterrupt:
            run.results["meta"]["interrupted"] = True
            _say(run, "interrupted: writing the finished results")
            _finish(run, context)
            raise
    _finish(run, context)
    return run.results


def _finish(run, context):
    run.results["meta"]["wall_time_s"] = time.perf_counter() - run.started
    _save(run)
    write_figures(run.out, run.results, context)
    write_report(run.out, run.results)


def _data(data, budget, seed):
    if data is None:
        scenes = make_scenes(n_sequences=budget.n_sequences, duration=budget.duration, random_state=seed)
        return scenes, f"simulated ({budget.n_sequences} sequences x {budget.duration:g} s, seed {seed})"
    return load_radarscenes(data), f"RadarScenes folder {data}"


def _meta(run, scenes, source):
    return {
        "version": __version__,
        "seed": run.seed,
        "budget": {"label": run.budget.label, "n_iter": run.budget.n_iter,
                   "n_initial_points": run.budget.n_initial_points, "cv_folds": run.budget.cv},
        "data": {"source": source, "n_detections": int(len(scenes.data)),
                 "n_sequences": int(len(np.unique(scenes.groups)))},
        "completed": [],
        "interrupted": False,
    }  # fmt: skip


def _say(run, text):
    print(text, file=run.stream, flush=True)


def _save(run):
    atomic_write_text(run.out / "results.json", json.dumps(run.results, indent=1, default=_json_default))
    experiments = {key: {"experiment": value["number"], "v1_test": value["v1_test"], "params": value["params"],
                         "stage1_params": value.get("stage1_params")}
                   for key, value in run.results["experiments"].items()}  # fmt: skip
    if experiments:
        best = max(experiments, key=lambda key: experiments[key]["v1_test"])
        saved = {"best": best, "experiments": experiments}
        atomic_write_text(run.out / "params.json", json.dumps(saved, indent=1, default=_json_default))


def _json_default(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def _title(key):
    if key.isdigit():
        return f"experiment #{key}: {get_experiment(int(key)).method}"
    return {"filter": "filter evaluation (Tables I and II)", "filter-effect": "the filter's effect on clustering",
            "baselines": "scikit-learn baselines (DBSCAN, HDBSCAN per 0.25 s window)"}[key]  # fmt: skip


def _runner_of(key):
    return "experiment" if key.isdigit() else key


# ----------------------------------------------------------------------------- the experiments


def _run_filter(run, context, key):
    scenes = context["scenes"]
    start = time.perf_counter()
    grids = {frame: filter_grid(scenes.data, scenes.target, frame=frame, n_jobs=run.n_jobs, verbose=0)
             for frame in ("frame", "car")}  # fmt: skip
    table_ii = filter_settings_table(scenes.data, scenes.target, n_jobs=run.n_jobs)
    context["filter_grids"] = grids
    run.results["filter"] = {
        "table_i": {frame: {"errors": g.errors.to_dict(orient="split"),
                            "background_removed": g.background_removed.to_dict(orient="split")}
                    for frame, g in grids.items()},  # fmt: skip
        "table_ii": table_ii.to_dict(orient="records"),
        "best_removal_with_zero_errors": {
            frame: _best_removal(g, 0) for frame, g in grids.items()
        },
        "wall_time_s": time.perf_counter() - start,
    }


def _best_removal(grid, max_errors):
    allowed = grid.background_removed.where(grid.errors <= max_errors)
    if not allowed.notna().any().any():
        return None
    vr, d_xy = allowed.stack().idxmax()
    return {"vr_threshold": float(vr), "d_xy": float(d_xy), "background_removed": float(allowed.loc[vr, d_xy])}


def _score(context, pipeline):
    """Fit-predict on the test half; radar V-measure against the pre-clustered target."""
    scenes, test = context["scenes"], context["test"]
    labels = pipeline.fit_predict(context["X"].iloc[test])
    return radar_v_measure(context["target"][test], labels, groups=scenes.groups[test]), labels


def _tune(run, context, estimator, space, label, start_from=None):
    """Bayesian optimisation on the training half with grouped CV; returns (best params, search record).

    ``start_from`` (e.g. the paper's optimum) is scored on the same folds as
    one more candidate and wins when the search found nothing better: a
    short search should not report a worse setting than a known one.
    """
    scenes, train = context["scenes"], context["train"]
    budget = run.budget
    groups = scenes.groups[train]
    n_folds = min(budget.cv, len(np.unique(groups)))
    # A clusterer labels the data it is fitted on, and the scorer fits on the scored fold: fitting the
    # "training" side of a fold first would be wasted work, so each fold is its own training side.
    # With a single training sequence the one fold is all of it.
    if n_folds < 2:
        cv = [(np.arange(len(train)), np.arange(len(train)))]
    else:
        cv = [(rows, rows) for _, rows in GroupKFold(n_splits=n_folds).split(train, groups=groups)]
    search = make_bayes_search(
        estimator, space, n_iter=budget.n_iter, n_initial_points=budget.n_initial_points,
        cv=cv, n_jobs=run.n_jobs, random_state=run.seed,
    )  # fmt: skip
    printer = ProgressPrinter(budget.n_iter, label=label, stream=run.stream)
    start = time.perf_counter()
    # The Gaussian process works on tiny matrices, where multi-threaded BLAS was 20x slower (measured).
    with threadpool_limits(limits=1, user_api="blas"):
        search.fit(context["X"].iloc[train], context["target"][train], groups=groups, callback=printer)
    scores = [float(s) for s in search.cv_results_["mean_test_score"]]
    best = {k: (v.item() if isinstance(v, np.generic) else v) for k, v in search.best_params_.items()}
    record = {"cv_best": float(search.best_score_), "convergence": scores, "best_source": "search"}
    if start_from:
        X, target = context["X"].iloc[train], context["target"][train]
        candidate = clone(estimator).set_params(**start_from)
        known = float(np.mean([radar_v_measure_scorer(clone(candidate), X.iloc[rows], target[rows]) for _, rows in cv]))
        record["cv_start_from"] = known
        if known >= record["cv_best"]:
            best = {key: start_from[key] for key in space if key in start_from}
            record.update(cv_best=known, best_source="the paper's setting (scored beside the search)")
    record["search_wall_time_s"] = time.perf_counter() - start
    return best, record


def _run_experiment(run, context, key):
    number = int(key)
    experiment = get_experiment(number)
    best8 = context.get("best8", {})
    stage1_params = None
    record = {"number": number, "method": experiment.method, "frame": experiment.frame,
              "filtered": experiment.filtered, "stage": experiment.stage,
              "paper_v1_percent": experiment.v1_percent, "paper_params": paper_params(number)}  # fmt: skip
    start = time.perf_counter()
    if experiment.stage == 2:
        stage1_params = best8 or None
        record["stage1_params"] = stage1_params or paper_params(8)
    pipeline = experiment_pipeline(number, memory=context["cache"], stage1_params=stage1_params)
    if number == 1:
        params = {}
    elif number in (10, 11):
        params = derived_params(number, best8 or None)
        record["derived_from_8"] = "tuned #8" if best8 else "paper's #8 (experiment 8 not run)"
    else:
        params, search = _tune(run, context, pipeline, search_space(number), f"#{number}", paper_params(number))
        record.update(search)
    pipeline.set_params(**params)
    v1, labels = _score(context, pipeline)
    record.update(params={**paper_params(number), **params} if number != 1 else paper_params(1),
                  v1_test=v1, wall_time_s=time.perf_counter() - start,
                  n_clusters_test=int(labels.max() + 1))  # fmt: skip
    context["labels"][number] = labels
    if number == 8:
        context["best8"] = {k: v for k, v in record["params"].items() if k.startswith("cluster__")}
    run.results["experiments"][key] = record
    _say(run, f"    #{number}: test V1 {100 * v1:.2f} % (paper {experiment.v1_percent:.2f} %)")


def _run_filter_effect(run, context, key):
    """Clustering time and number of clusters with and without the filter, at #8's setting."""
    scenes, test = context["scenes"], context["test"]
    params = context.get("best8") or paper_params(8)
    record = {"setting": params, "setting_source": "tuned #8" if context.get("best8") else "paper's #8"}
    per_sequence = {}
    for filtered in (True, False):
        pipeline = experiment_pipeline(8 if filtered else 10, params=params)
        prepared = pipeline[:-1].fit_transform(context["X"].iloc[test])
        clusterer = pipeline[-1]
        clusterer.fit(prepared)  # warm-up: JIT compilation is not clustering time
        times = []
        for _ in range(3):
            start = time.perf_counter()
            labels = clusterer.fit(prepared).labels_
            times.append(time.perf_counter() - start)
        groups = scenes.groups[test]
        per_sequence[filtered] = {int(g): int(len(np.unique(labels[(groups == g) & (labels >= 0)]))) for g in np.unique(groups)}
        record["filtered" if filtered else "unfiltered"] = {"clustering_s": min(times), "n_clusters": int(labels.max() + 1)}
    fewer = [1 - per_sequence[True][g] / per_sequence[False][g] for g in per_sequence[True] if per_sequence[False][g] > 0]
    record.update(
        time_saving_percent=100 * (1 - record["filtered"]["clustering_s"] / record["unfiltered"]["clustering_s"]),
        fewer_clusters_per_sequence_percent=100 * float(np.mean(fewer)) if fewer else float("nan"),
        fewer_clusters_overall_percent=100 * (1 - record["filtered"]["n_clusters"] / max(record["unfiltered"]["n_clusters"], 1)),
        paper={"time_saving_percent": 3.1, "fewer_clusters_per_sequence_percent": 23.6, "fewer_clusters_overall_percent": 28.6},
    )  # fmt: skip
    run.results["filter_effect"] = record


_BASELINES = {
    "sklearn DBSCAN per 0.25 s window": (
        WindowedDBSCAN,
        {"cluster__eps": Real(0.2, 3.0, name="cluster__eps"), "cluster__min_samples": Integer(2, 8, name="cluster__min_samples"),
         "cluster__vr_scale": Real(0.3, 20.0, prior="log-uniform", name="cluster__vr_scale")},
    ),
    "sklearn HDBSCAN per 0.25 s window": (
        WindowedHDBSCAN,
        {"cluster__min_cluster_size": Integer(2, 10, name="cluster__min_cluster_size"),
         "cluster__min_samples": Integer(1, 8, name="cluster__min_samples"),
         # cluster_selection_epsilon stays 0: scikit-learn 1.9.1's epsilon search crashed on this data.
         "cluster__vr_scale": Real(0.3, 20.0, prior="log-uniform", name="cluster__vr_scale")},
    ),
}  # fmt: skip


def _run_baselines(run, context, key):
    """The clusterers a user would otherwise pick, on the same FCS + filter input, same budget and split."""
    run.results["baselines"] = {}
    for name, (clusterer, space) in _BASELINES.items():
        start = time.perf_counter()
        pipeline = experiment_pipeline(3, memory=context["cache"])
        pipeline.steps[-1] = ("cluster", clusterer())
        params, record = _tune(run, context, pipeline, space, name)
        pipeline.set_params(**params)
        v1, labels = _score(context, pipeline)
        record.update(params=params, v1_test=v1, wall_time_s=time.perf_counter() - start,
                      n_clusters_test=int(labels.max() + 1))  # fmt: skip
        run.results["baselines"][name] = record
        _say(run, f"    {name}: test V1 {100 * v1:.2f} %")


_RUNNERS = {
    "filter": _run_filter,
    "experiment": _run_experiment,
    "filter-effect": _run_filter_effect,
    "baselines": _run_baselines,
}

__all__ = ["ALL_EXPERIMENTS", "parse_experiments", "reproduce"]
