"""Tune stage 1 as the paper does and measure what caching saves.

Run: ``python benchmarks/bench_tuning.py [--n-sequences 8] [--duration 30] [--experiment 8] [--n-iter 100]``
(``--parts paper,caching,sequence`` chooses the measurements below; all by default).

Scheiner et al. 2019 split their data by sequence into two halves of almost
equal size, tune each clustering stage on one half with 100 iterations of
Bayesian optimisation (30 random, 70 guided) and report the V-measure on the
other half.  This script does the same on simulated data:

1. ``make_scenes`` data split with :func:`sequence_train_test_split`; the
   target is the pre-clustered ground truth (:func:`precluster_target`).
2. The expert setting #1 (CCS, and the same setting in FCS) and the paper's
   optimum of the tuned experiment are scored on the test half.
3. Stage 1 of the experiment is tuned on the training half with
   :func:`make_bayes_search` (3-fold GroupKFold, ``Pipeline(memory=...)``);
   the tuned setting is scored on the test half.  Wall time is reported.
4. Caching: the same random candidates (no Gaussian process, so only the
   evaluation is timed) run without a cache and with a cold cache, for stage
   1 (``Pipeline(memory=...)``: frame transform and filter once per data
   subset) and for stage 2 (#13; additionally ``ClusterMerger(memory=...)``:
   stage 1 once per data subset).
5. ``sequence``: the same search (``--n-iter``, ``--n-initial-points``,
   ``--cv``, ``--seed``, skopt's default acquisition) by
   :class:`~sklearn_radar.model_selection.SequenceSearchCV` (one fit per
   candidate and sequence, stage 0 once per sequence) and by
   :func:`make_bayes_search` with a cold ``Pipeline(memory=...)`` cache, both
   with BLAS on one thread and without refit, interleaved
   ``--sequence-repeats`` times (the order alternating): wall seconds, their
   ratio, and whether both found the same candidates and scores.

Every score is the radar V-measure (0-1) of ``radar_v_measure_scorer``:
the pipeline is fitted on, and scored against, the half it is evaluated on.
"""

import argparse
import os
import shutil
import tempfile
import time

import numpy as np
from threadpoolctl import threadpool_limits

from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import PIPELINE_COLUMNS, experiment_pipeline, get_experiment, search_space
from sklearn_radar.metrics import precluster_target, radar_v_measure_scorer
from sklearn_radar.model_selection import SequenceSearchCV, make_bayes_search, sequence_train_test_split

PARTS = ("paper", "caching", "sequence")


def _timed_search(pipeline, space, n_candidates, X, y, groups, seed, cv):
    """Seconds for ``n_candidates`` random candidates (GroupKFold, no refit), and the search."""
    search = make_bayes_search(
        pipeline, space, n_iter=n_candidates, n_initial_points=n_candidates, cv=cv, random_state=seed
    )
    search.set_params(refit=False)
    start = time.perf_counter()
    search.fit(X, y, groups=groups)
    return time.perf_counter() - start, search


def _sequence_against_bayes_search(number, X, y, groups, args, cache, add):
    """Part 5: SequenceSearchCV against make_bayes_search, the same search, interleaved; adds one row per repeat."""
    options = {"n_iter": args.n_iter, "n_initial_points": args.n_initial_points, "cv": args.cv}
    options["random_state"] = args.seed

    def sequence_search():
        search = SequenceSearchCV(experiment_pipeline(number), search_space(number), refit=False, **options)
        return search.set_params(n_jobs=args.n_jobs).fit(X, y, groups)

    def bayes_search(repeat):
        pipeline = experiment_pipeline(number, memory=os.path.join(cache, f"sequence{repeat}"))  # cold
        search = make_bayes_search(pipeline, search_space(number), n_jobs=args.n_jobs, **options)
        with threadpool_limits(limits=1, user_api="blas"):
            return search.set_params(refit=False).fit(X, y, groups=groups)

    ratios = []
    for repeat in range(args.sequence_repeats):
        seconds = {}
        for name in ("sequence", "bayes") if repeat % 2 == 0 else ("bayes", "sequence"):
            start = time.perf_counter()
            found = sequence_search() if name == "sequence" else bayes_search(repeat)
            seconds[name] = (time.perf_counter() - start, found)
        (fast_s, fast), (plain_s, plain) = seconds["sequence"], seconds["bayes"]
        ratios.append(plain_s / fast_s)
        same = _same_search(fast.cv_results_, plain.cv_results_)
        add(
            f"SequenceSearchCV vs make_bayes_search #{number}, repeat {repeat + 1}",
            fast.best_score_,
            None,
            fast_s,
            f"BayesSearchCV {plain_s:.1f} s: {ratios[-1]:.2f}x; same candidates and scores: {same}",
        )
    print(f"   SequenceSearchCV speed-up, median of {len(ratios)}: {np.median(ratios):.2f}x", flush=True)


def _same_search(found, expected, rtol=1e-9):
    """Whether two cv_results_ hold the same candidates in the same order with the same mean scores."""
    if len(found["params"]) != len(expected["params"]):
        return False
    same_params = all(
        np.isclose(float(a[name]), float(b[name]), rtol=rtol, atol=0.0)
        for a, b in zip(found["params"], expected["params"], strict=True)
        for name in b
    )
    return same_params and np.allclose(found["mean_test_score"], expected["mean_test_score"], rtol=rtol, atol=1e-12)


def _format_row(row, width):
    name, cv_score, score, seconds, note = row
    cv_text = f"{cv_score:13.4f}" if cv_score is not None else " " * 13
    score_text = f"{score:7.4f}" if score is not None else " " * 7
    seconds_text = f"{seconds:6.1f}" if seconds is not None else " " * 6
    return f"| {name:<{width}} | {cv_text} | {score_text} | {seconds_text} | {note}"


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--n-sequences", type=int, default=8)
    parser.add_argument("--duration", type=float, default=30.0, help="s per sequence")
    parser.add_argument("--experiment", type=int, default=8, help="stage-1 experiment to tune (2-9)")
    parser.add_argument("--n-iter", type=int, default=100)
    parser.add_argument("--n-initial-points", type=int, default=30)
    parser.add_argument(
        "--acq-optimizer",
        default="auto",
        choices=["auto", "lbfgs", "sampling"],
        help="skopt's acquisition optimiser (auto = skopt's default, L-BFGS for a GP)",
    )
    parser.add_argument("--cv", type=int, default=3, help="GroupKFold folds inside the training half")
    parser.add_argument("--n-candidates", type=int, default=10, help="candidates per stage-1 caching measurement")
    parser.add_argument(
        "--n-stage2-candidates",
        type=int,
        default=10,
        help="candidates per stage-2 caching measurement (0: skip stage 2)",
    )
    parser.add_argument(
        "--stage2-base",
        default="paper",
        choices=["paper", "tuned"],
        help="stage-1 setting under stage 2: #8 of Table III (the paper's base for #12/#13) or the tuned one",
    )
    parser.add_argument("--n-jobs", type=int, default=None, help="parallel fits of the tuning run")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--parts", default=",".join(PARTS), help=f"comma-separated, of {', '.join(PARTS)}")
    parser.add_argument("--sequence-repeats", type=int, default=2, help="interleaved repeats of part 5")
    parser.add_argument("--quiet", action="store_true", help="no per-iteration progress lines")
    args = parser.parse_args()
    if get_experiment(args.experiment).stage != 1 or not search_space(args.experiment):
        parser.error("--experiment must be a tuned stage-1 experiment (2-9)")
    parts = set(args.parts.split(","))
    if parts - set(PARTS):
        parser.error(f"--parts: unknown {sorted(parts - set(PARTS))}, choose from {', '.join(PARTS)}")
    if args.stage2_base == "tuned" and "paper" not in parts:
        parser.error("--stage2-base tuned needs the part paper (the tuning run)")

    scenes = make_scenes(n_sequences=args.n_sequences, duration=args.duration, random_state=args.seed)
    y = precluster_target(scenes.data, scenes.target)  # per object, so the same on the whole set as on each half
    # Only the columns the pipelines read: the caches hash their whole input, and uuid/track_id are strings.
    X, groups = scenes.data[list(PIPELINE_COLUMNS)], scenes.groups
    train, test = sequence_train_test_split(groups, random_state=args.seed)
    X_train, y_train, g_train = X.iloc[train], y[train], groups[train]
    X_test, y_test = X.iloc[test], y[test]
    print(
        f"data: {args.n_sequences} sequences x {args.duration:g} s = {len(X):,} detections "
        f"({np.sum(y != -1):,} in {len(np.unique(y[y != -1])):,} target clusters); "
        f"train {len(np.unique(g_train))} sequences / {len(train):,} detections, "
        f"test {len(np.unique(groups[test]))} sequences / {len(test):,} detections; {os.cpu_count()} CPUs",
        flush=True,
    )
    width = 70
    rows = []  # (setting, CV V1 on the training half, V1 on the test half, wall s, note)

    def add(*row):
        rows.append(row)
        print(_format_row(row, width), flush=True)

    def test_score(pipeline):
        return radar_v_measure_scorer(pipeline, X_test, y_test)

    number = args.experiment
    add("#1 expert setting (CCS, box)", None, test_score(experiment_pipeline(1)), None, "paper: 67.57 %")
    add(
        "#1 expert setting in FCS", None, test_score(experiment_pipeline(1, params={"frame__frame": "frame"})), None, ""
    )
    add(
        f"#{number} paper's optimum",
        None,
        test_score(experiment_pipeline(number)),
        None,
        f"paper: {get_experiment(number).v1_percent} %",
    )

    cache = tempfile.mkdtemp(prefix="bench_tuning_")
    try:
        if "paper" in parts:
            tuned = _paper_tuning_run(number, X_train, y_train, g_train, test_score, args, cache, add)
        if "caching" in parts:
            _caching(
                number, X_train, y_train, g_train, test_score, args, cache, add, tuned if "paper" in parts else None
            )
        if "sequence" in parts:
            _sequence_against_bayes_search(number, X_train, y_train, g_train, args, cache, add)
    finally:
        shutil.rmtree(cache, ignore_errors=True)

    print()
    print(f"| {'setting':<{width}} | CV V1 (train) | test V1 | wall s | note")
    print(f"|{'-' * (width + 2)}|---------------|---------|--------|-----")
    for row in rows:
        print(_format_row(row, width))


def _paper_tuning_run(number, X_train, y_train, g_train, test_score, args, cache, add):
    """Part 3: the paper's tuning run with make_bayes_search; returns the tuned setting."""
    search = make_bayes_search(
        experiment_pipeline(number, memory=os.path.join(cache, "run")),
        search_space(number),
        n_iter=args.n_iter,
        n_initial_points=args.n_initial_points,
        cv=args.cv,
        n_jobs=args.n_jobs,
        random_state=args.seed,
        verbose=0 if args.quiet else 1,
        optimizer_kwargs={"acq_optimizer": args.acq_optimizer},
    )
    search.set_params(progress=False if args.quiet else f"#{number}")
    start = time.perf_counter()
    search.fit(X_train, y_train, groups=g_train)
    wall = time.perf_counter() - start
    tuned = dict(search.best_params_)
    evaluation = float(np.sum(search.cv_results_["mean_fit_time"] + search.cv_results_["mean_score_time"]) * args.cv)
    add(
        f"#{number} tuned: {args.n_iter} it. ({args.n_initial_points} random), {args.cv}-fold GroupKFold",
        search.best_score_,
        test_score(experiment_pipeline(number, params=tuned)),
        wall,
        f"{wall / args.n_iter:.1f} s/it.; fits+scoring {evaluation:.0f} s, rest skopt; "
        f"acq_optimizer={args.acq_optimizer}, n_jobs={args.n_jobs}",
    )
    print(
        "   tuned setting: " + ", ".join(f"{k.split('__')[1]}={v:.3g}" for k, v in sorted(tuned.items())),
        flush=True,
    )
    shutil.rmtree(os.path.join(cache, "run"), ignore_errors=True)
    return tuned


def _caching(number, X_train, y_train, g_train, test_score, args, cache, add, tuned):
    """Part 4: the same random candidates without and with the caches, stage 1 and stage 2."""
    timings = {}
    for label, memory in (("no cache", None), ("Pipeline(memory)", os.path.join(cache, "s1"))):
        seconds, timed = _timed_search(
            experiment_pipeline(number, memory=memory),
            search_space(number),
            args.n_candidates,
            X_train,
            y_train,
            g_train,
            args.seed,
            args.cv,
        )
        timings[label] = seconds
        add(
            f"stage 1 #{number}, {args.n_candidates} random candidates, {label}",
            max(timed.cv_results_["mean_test_score"]),
            None,
            seconds,
            "" if memory is None else f"speed-up {timings['no cache'] / seconds:.2f}x (cold cache)",
        )

    # stage 2 (#13): ClusterMerger(memory=...)
    if args.n_stage2_candidates > 0:
        if args.stage2_base == "tuned":
            stage1 = experiment_pipeline(number, params=tuned).named_steps["cluster"].get_params()
            stage1.pop("n_jobs")
        else:
            stage1 = dict(get_experiment(8).params)
        add(
            f"#13 paper's stage-2 setting on the {args.stage2_base} stage 1",
            None,
            test_score(experiment_pipeline(13, stage1_params=stage1)),
            None,
            "paper: 71.79 % (on #8)",
        )
        timings = {}
        for label in ("no cache", "Pipeline(memory) only", "Pipeline + ClusterMerger(memory)"):
            memory = None if label == "no cache" else os.path.join(cache, "s2" + str(len(timings)))
            pipeline = experiment_pipeline(13, memory=memory, stage1_params=stage1)
            if label == "Pipeline(memory) only":
                pipeline.set_params(merge__memory=None)
            seconds, timed = _timed_search(
                pipeline, search_space(13), args.n_stage2_candidates, X_train, y_train, g_train, args.seed, args.cv
            )
            timings[label] = seconds
            add(
                f"stage 2 #13, {args.n_stage2_candidates} random candidates, {label}",
                max(timed.cv_results_["mean_test_score"]),
                None,
                seconds,
                "" if memory is None else f"speed-up {timings['no cache'] / seconds:.2f}x (cold cache)",
            )


if __name__ == "__main__":
    main()
