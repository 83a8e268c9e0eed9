"""make_bayes_search and the radar scorer inside BayesSearchCV, GridSearchCV and RandomizedSearchCV; caching."""

import io
import re

import numpy as np
import pytest
from joblib import Memory
from scipy.stats import uniform
from sklearn.model_selection import GridSearchCV, GroupKFold, RandomizedSearchCV
from skopt.utils import create_result

from sklearn_radar import DopplerDensityFilter, FrameTransform, RadarDBSCAN
from sklearn_radar._skopt import BayesSearchCV
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import PIPELINE_COLUMNS, experiment_pipeline, search_space
from sklearn_radar.metrics import precluster_target, radar_v_measure_scorer
from sklearn_radar.model_selection import ProgressPrinter, make_bayes_search

LINE = re.compile(r"^\[exp 8\] iteration +(\d+)/6  score (\d\.\d{4})  best (\d\.\d{4})  elapsed \d+\.\d s$")


@pytest.fixture(scope="module")
def scenes():
    data = make_scenes(n_sequences=4, duration=6.0, random_state=0)
    data.y = precluster_target(data.data, data.target)
    data.X = data.data[list(PIPELINE_COLUMNS)]  # what cached pipelines should be fed (cheap to hash)
    return data


def test_defaults_are_the_papers_protocol():
    search = make_bayes_search(experiment_pipeline(8), search_space(8))
    assert isinstance(search, BayesSearchCV)
    assert search.n_iter == 100
    assert search.optimizer_kwargs == {"n_initial_points": 30}
    assert isinstance(search.cv, GroupKFold) and search.cv.get_n_splits() == 3
    assert search.scoring is radar_v_measure_scorer
    assert search.error_score == 0.0
    assert search.verbose == 0 and not search.progress
    # get_params/clone keep the added parameter (sklearn estimator contract).
    assert make_bayes_search(experiment_pipeline(8), search_space(8), verbose=1).get_params()["progress"] is True
    # verbose=1: our progress lines only; verbose=2: scikit-learn's level-1 messages as well.
    assert make_bayes_search(experiment_pipeline(8), search_space(8), verbose=1).verbose == 0
    assert make_bayes_search(experiment_pipeline(8), search_space(8), verbose=2).verbose == 1
    extra = make_bayes_search(experiment_pipeline(8), search_space(8), optimizer_kwargs={"acq_optimizer": "sampling"})
    assert extra.optimizer_kwargs == {"acq_optimizer": "sampling", "n_initial_points": 30}
    assert make_bayes_search(experiment_pipeline(8), search_space(8), cv=GroupKFold(5)).cv.get_n_splits() == 5


def test_bayes_search_with_grouped_cv_on_simulated_data(scenes, capsys):
    scored_sequences = []

    def recording_scorer(estimator, X, y):
        scored_sequences.append(X["sequence"].to_numpy())
        return radar_v_measure_scorer(estimator, X, y)

    search = make_bayes_search(
        experiment_pipeline(8), search_space(8), n_iter=6, n_initial_points=3, cv=2, random_state=0, verbose=1
    )
    search.set_params(scoring=recording_scorer, progress="exp 8")
    search.fit(scenes.data, scenes.y, groups=scenes.groups)

    scores = np.asarray(search.cv_results_["mean_test_score"])
    assert len(scores) == 6
    assert np.all(np.isfinite(scores)) and np.all((0.0 <= scores) & (scores <= 1.0))
    assert 0.5 < search.best_score_ <= 1.0  # on this data even random settings cluster well
    for key, dimension in search_space(8).items():
        assert search.best_params_[key] in dimension
    # Grouped CV: every scored test fold holds whole sequences (all their detections).
    sizes = dict(zip(*np.unique(scenes.groups, return_counts=True), strict=True))
    assert len(scored_sequences) == 6 * 2
    for sequence in scored_sequences:
        ids, counts = np.unique(sequence, return_counts=True)
        assert len(ids) == 2 and all(counts[k] == sizes[i] for k, i in enumerate(ids))

    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 6
    parsed = [LINE.match(line) for line in lines]
    assert all(parsed), lines
    assert [int(m.group(1)) for m in parsed] == list(range(1, 7))
    assert [float(m.group(2)) for m in parsed] == pytest.approx(scores, abs=5e-5)
    assert [float(m.group(3)) for m in parsed] == pytest.approx(np.maximum.accumulate(scores), abs=5e-5)


def test_progress_printer_prints_one_line_per_candidate_of_a_batch():
    stream = io.StringIO()
    printer = ProgressPrinter(4, label="x", stream=stream)
    printer(create_result([[0.1], [0.2]], [-0.5, -0.7]))  # skopt minimises the negated score
    assert printer(create_result([[0.1], [0.2], [0.3], [0.4]], [-0.5, -0.7, -0.6, -0.9])) is None  # never stops
    lines = stream.getvalue().splitlines()
    assert [line.split("  elapsed")[0] for line in lines] == [
        "[x] iteration 1/4  score 0.5000  best 0.5000",
        "[x] iteration 2/4  score 0.7000  best 0.7000",
        "[x] iteration 3/4  score 0.6000  best 0.7000",
        "[x] iteration 4/4  score 0.9000  best 0.9000",
    ]
    assert printer.scores == [0.5, 0.7, 0.6, 0.9] and printer.best_score == 0.9


def test_progress_printer_appends_the_status_of_each_iteration():
    stream = io.StringIO()
    printer = ProgressPrinter(3, label="x", stream=stream, status=lambda i, n: f"run {i} of {n}")
    printer(create_result([[0.1], [0.2]], [-0.5, -0.7]))
    lines = stream.getvalue().splitlines()
    assert [line.rsplit(" | ", 1)[1] for line in lines] == ["run 1 of 3", "run 2 of 3"]
    assert "\r" not in stream.getvalue()


def test_silent_by_default_and_callbacks_are_kept(scenes, capsys):
    seen = []
    search = make_bayes_search(
        experiment_pipeline(3), search_space(3), n_iter=2, n_initial_points=2, cv=2, random_state=1
    )
    search.fit(scenes.data, scenes.y, groups=scenes.groups, callback=lambda result: seen.append(len(result.func_vals)))
    assert capsys.readouterr().out == ""
    assert seen == [1, 2]


def test_candidates_run_in_parallel_with_a_shared_cache(scenes, tmp_path, capsys):
    search = make_bayes_search(
        experiment_pipeline(3, memory=str(tmp_path)),
        search_space(3),
        n_iter=4,
        n_initial_points=4,
        cv=2,
        n_jobs=2,
        n_points=2,
        random_state=0,
        verbose=1,
    )
    search.fit(scenes.X, scenes.y, groups=scenes.groups)
    scores = search.cv_results_["mean_test_score"]
    assert len(scores) == 4 and np.all((0.0 <= scores) & (scores <= 1.0)) and np.all(scores > 0.0)
    assert len(capsys.readouterr().out.splitlines()) == 4  # two batches of two candidates, one line each
    assert any(tmp_path.rglob("output.pkl"))  # the worker processes wrote to the shared cache


@pytest.mark.parametrize("make_search", ["grid", "randomized"])
def test_sklearn_searches_run_unchanged_with_the_scorer_and_groups(scenes, make_search):
    pipeline = experiment_pipeline(3)
    if make_search == "grid":
        search = GridSearchCV(
            pipeline,
            {"cluster__eps_xy": [0.6, 1.0], "cluster__vr_min": [0.25]},
            scoring=radar_v_measure_scorer,
            cv=GroupKFold(n_splits=2),
            error_score=0.0,
        )
    else:
        search = RandomizedSearchCV(
            pipeline,
            {"cluster__eps_xy": uniform(0.2, 2.8), "cluster__eps_vr": uniform(0.5, 19.5)},
            n_iter=2,
            scoring=radar_v_measure_scorer,
            cv=GroupKFold(n_splits=2),
            error_score=0.0,
            random_state=0,
        )
    search.fit(scenes.data, scenes.y, groups=scenes.groups)
    scores = search.cv_results_["mean_test_score"]
    assert len(scores) == 2 and np.all((0.0 <= scores) & (scores <= 1.0)) and np.all(scores > 0.3)
    assert search.best_estimator_.named_steps["cluster"].eps_xy == search.best_params_["cluster__eps_xy"]


def _count_calls(monkeypatch, cls, method):
    calls = []
    original = getattr(cls, method)

    def counted(self, *args, **kwargs):
        calls.append(1)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(cls, method, counted)
    return calls


def test_pipeline_memory_computes_frame_and_filter_once_per_data_subset(scenes, tmp_path, monkeypatch):
    grid = {"cluster__eps_xy": [0.5, 0.8, 1.1], "cluster__min_samples": [2, 3]}  # 6 candidates
    results = {}
    for memory in (None, str(tmp_path / "cache")):
        # FrameTransform's transform and fit_transform both compute the working columns in _transformed.
        frame_calls = _count_calls(monkeypatch, FrameTransform, "_transformed")
        filter_calls = _count_calls(monkeypatch, DopplerDensityFilter, "transform")
        search = GridSearchCV(
            experiment_pipeline(3, memory=memory),
            grid,
            scoring=radar_v_measure_scorer,
            cv=GroupKFold(n_splits=2),
            refit=False,
        )
        search.fit(scenes.X, scenes.y, groups=scenes.groups)
        results[memory is not None] = (len(frame_calls), len(filter_calls), search.cv_results_["mean_test_score"])
        monkeypatch.undo()
    # Without a cache: per candidate and fold, once for the training and once for the test fold.
    assert results[False][:2] == (6 * 2 * 2, 6 * 2 * 2)
    # With it: once per distinct subset (2 folds x training/test), whatever the number of candidates.  The
    # filter may run once more per subset: joblib hashes FrameTransform's fresh output DataFrame differently
    # from the same frame loaded back from the cache (memory layout), so the first candidate misses.
    assert results[True][0] == 2 * 2
    assert 2 * 2 <= results[True][1] <= 2 * 2 * 2
    np.testing.assert_allclose(results[True][2], results[False][2], rtol=0, atol=0)


def test_cluster_merger_memory_computes_stage1_once_per_data_subset(scenes, tmp_path, monkeypatch):
    grid = {"merge__eps_d": [0.5, 2.0], "merge__eps_v": [1.0, 3.0]}  # 4 stage-2 candidates
    results = {}
    for memory in (None, Memory(tmp_path / "cache", verbose=0)):
        stage1_fits = _count_calls(monkeypatch, RadarDBSCAN, "fit")
        search = GridSearchCV(
            experiment_pipeline(13, memory=memory),
            grid,
            scoring=radar_v_measure_scorer,
            cv=GroupKFold(n_splits=2),
            refit=False,
        )
        search.fit(scenes.X, scenes.y, groups=scenes.groups)
        results[memory is not None] = (len(stage1_fits), search.cv_results_["mean_test_score"])
        monkeypatch.undo()
    assert results[False][0] == 4 * 2 * 2
    # With it: once per distinct data subset.  Two folds of four sequences have only two subsets (the
    # training part of one fold is the test part of the other) and the stage-1 cache key is the data alone.
    assert results[True][0] == 2
    np.testing.assert_allclose(results[True][1], results[False][1], rtol=0, atol=0)
