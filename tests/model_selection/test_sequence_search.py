"""The per-sequence search (``model_selection._sequence_search``): a task per candidate and sequence."""

import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.base import clone
from sklearn.model_selection import GroupKFold

from sklearn_radar._skopt import Integer, Real
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import experiment_pipeline, search_space
from sklearn_radar.metrics import panoptic_quality_scorer, precluster_target, radar_v_measure_scorer
from sklearn_radar.metrics._parts import FailedPart, combine_parts
from sklearn_radar.model_selection import SequenceSearchCV, make_bayes_search
from sklearn_radar.model_selection._sequence_search import (
    SearchData,
    balanced_blocks,
    bayes_search,
    candidate_parts,
    candidate_scores,
    fixed_prefix,
    sequence_folds,
    sized_sequence_folds,
)

SCORERS = {"v1": radar_v_measure_scorer, "pq": panoptic_quality_scorer}


@pytest.fixture(scope="module")
def scenes():
    scenes = make_scenes(n_sequences=4, duration=4.0, random_state=3)
    X = scenes.data[[c for c in scenes.data.columns if c not in ("uuid", "track_id", "label_id")]]
    return X, precluster_target(scenes.data, scenes.target), scenes.groups


def test_folds_hold_the_sequences_of_group_k_fold(scenes):
    _, _, groups = scenes
    folds = sequence_folds(groups, 3)
    reference = [np.unique(groups[rows]) for _, rows in GroupKFold(n_splits=3).split(groups, groups=groups)]
    assert [f.tolist() for f in folds] == [r.tolist() for r in reference]
    assert sequence_folds(groups[groups == groups[0]], 3)[0].tolist() == [groups[0]]  # one sequence: one fold


@pytest.mark.parametrize("objective", ["v1", "pq"])
@pytest.mark.parametrize("number", [3, 8, 13])
def test_a_fold_combined_from_its_sequences_scores_as_the_scorer_on_the_whole_fold(scenes, number, objective):
    X, target, groups = scenes
    pipeline = experiment_pipeline(number)
    data = SearchData.place(X, target, groups)
    folds = sequence_folds(groups, 2)
    (score,) = candidate_scores(data, pipeline, [{}], folds, objective)
    whole = [SCORERS[objective](clone(pipeline), X[np.isin(groups, f)], target[np.isin(groups, f)]) for f in folds]
    assert 0.0 < score <= 1.0
    assert score == pytest.approx(np.mean(whole), rel=1e-12, abs=1e-12)


def test_a_failing_candidate_scores_zero_and_a_search_that_always_fails_raises(scenes):
    X, target, groups = scenes
    pipeline = experiment_pipeline(3)
    data = SearchData.place(X, target, groups)
    folds = sequence_folds(groups, 2)
    bad = {"cluster__eps_xy": -1.0}  # rejected by the estimator's parameter validation inside the task
    good = candidate_scores(data, pipeline, [{}], folds, "v1")[0]
    assert candidate_scores(data, pipeline, [{}, bad], folds, "v1") == [good, 0.0]
    failed = candidate_parts(pipeline, bad, data.blocks[0][0], "v1")
    assert isinstance(failed, FailedPart) and "eps_xy" in failed.error
    with pytest.raises(ValueError, match="every fit of 1 candidate"):
        candidate_scores(data, pipeline, [bad], folds, "v1")


def test_joblib_workers_give_the_same_scores_and_tasks_pickle(scenes):
    X, target, groups = scenes
    pipeline = experiment_pipeline(8)
    candidates = [{}, {"cluster__eps_xyv": 2.0}, {"cluster__min_samples": 6}]
    folds = sequence_folds(groups, 2)
    here = candidate_scores(SearchData.place(X, target, groups), pipeline, candidates, folds, "v1")
    parallel = candidate_scores(SearchData.place(X, target, groups, n_jobs=2), pipeline, candidates, folds, "v1")
    assert here == parallel
    assert len(set(here)) == 3  # the candidates differ: the comparison could fail
    data = SearchData.place(X, target, groups)
    parts = candidate_parts(pipeline, {}, data.blocks[0][0], "v1")
    assert combine_parts("v1", [pickle.loads(pickle.dumps(parts))]) == combine_parts("v1", [parts])


def test_stage0_per_sequence_equals_stage0_on_the_whole_half(scenes):
    X, target, groups = scenes
    pipeline = experiment_pipeline(8)
    stage0 = pipeline[:-1]
    prepared = SearchData.place(X, target, groups).prepare(stage0)
    whole = clone(stage0).fit_transform(X)
    assert prepared.sequence_ids == sorted(np.unique(groups))
    for (sequence_id,), [(rows, sequence_target)] in zip(prepared.ids, prepared.blocks, strict=True):
        mask = groups == sequence_id
        assert list(rows.columns) == list(whole.columns)
        np.testing.assert_array_equal(rows.to_numpy(), whole[mask].to_numpy())
        assert np.array_equal(sequence_target, target[mask])


def test_a_start_setting_is_scored_after_the_search_on_the_same_folds_and_changes_nothing_else(scenes):
    X, target, groups = scenes
    pipeline, space = experiment_pipeline(3), search_space(3)
    data, folds = SearchData.place(X, target, groups), sequence_folds(groups, 2)
    options = {"objective": "v1", "n_iter": 3, "n_initial_points": 2, "random_state": 0}
    start = {"cluster__eps_xy": 1.5, "cluster__min_samples": 3}
    plain = bayes_search(pipeline, space, data, folds, **options)
    started = bayes_search(pipeline, space, data, folds, start_from=start, **options)
    assert plain.start_score is None
    assert started.start_score == candidate_scores(data, pipeline, [start], folds, "v1")[0]
    assert (started.candidates, started.fold_scores) == (plain.candidates, plain.fold_scores)


def test_blocks_are_balanced_and_hold_every_sequence_once():
    sizes = [50, 10, 40, 30, 20, 5]
    blocks = balanced_blocks(sizes, 2)
    assert sorted(p for block in blocks for p in block) == list(range(6))
    totals = sorted(sum(sizes[p] for p in block) for block in blocks)
    assert totals == [75, 80]  # largest first, each to the lightest block: 40+30+5 and 50+20+10
    assert all(block == sorted(block) for block in blocks)
    assert balanced_blocks([3, 4], 5) == [[1], [0]]  # never more blocks than sequences


@settings(max_examples=200, deadline=None)
@given(
    sizes=st.lists(st.integers(1, 6), min_size=1, max_size=12),
    n_folds=st.integers(2, 5),
)
def test_folds_from_sizes_equal_group_k_fold(sizes, n_folds):
    # Small sizes give many ties: GroupKFold's order of equal sequences must be kept too.
    ids = np.arange(len(sizes)) * 3 + 1
    groups = np.repeat(ids, sizes)
    folds = sized_sequence_folds(ids, sizes, n_folds)
    if len(ids) < 2:
        assert [list(f) for f in folds] == [list(ids)]
        return
    expected = [np.unique(groups[rows]) for _, rows in GroupKFold(min(n_folds, len(ids))).split(groups, groups=groups)]
    assert [list(f) for f in folds] == [list(f) for f in expected]


# SequenceSearchCV, the public form: the same search as make_bayes_search's BayesSearchCV, fitted per sequence.

#: cv_results_ keys of BayesSearchCV that SequenceSearchCV leaves out: its fits are per sequence, not per fold.
TIME_KEYS = {"mean_fit_time", "std_fit_time", "mean_score_time", "std_score_time"}


def _oracle(pipeline, space, X, target, groups, scoring, **options):
    return make_bayes_search(pipeline, space, scoring=SCORERS[scoring], cv=2, **options).fit(X, target, groups=groups)


@pytest.mark.parametrize(("number", "scoring", "n_points"), [(3, "v1", 1), (8, "v1", 3), (3, "pq", 1), (8, "pq", 2)])
def test_same_candidates_in_the_same_order_and_scores_as_bayes_search_cv(scenes, number, scoring, n_points):
    X, target, groups = scenes
    pipeline, space = experiment_pipeline(number), search_space(number)
    options = {"n_iter": 6, "n_initial_points": 3, "n_points": n_points, "random_state": 1}
    fast = SequenceSearchCV(pipeline, space, cv=2, scoring=scoring, refit=False, **options).fit(X, target, groups)
    plain = _oracle(pipeline, space, X, target, groups, scoring, **options)
    expected, found = plain.cv_results_, fast.cv_results_
    # Equal scores of the random candidates would leave the Gaussian process a zero spread of targets (normalised
    # by it), where last-bit differences decide: the data must separate them.
    assert len(set(np.round(expected["mean_test_score"][:3], 9))) == 3
    # A fold's score combined from its sequences may differ from the whole fold's in the last bit; the Gaussian
    # process's acquisition optimum (L-BFGS) moves with it at about 1e-13.
    assert found["params"] == [pytest.approx({name: _native(v) for name, v in p.items()}) for p in expected["params"]]
    assert set(expected) - set(found) == TIME_KEYS and set(found) <= set(expected)
    for key in ("split0_test_score", "split1_test_score", "mean_test_score", "std_test_score"):
        np.testing.assert_allclose(found[key], expected[key], rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(found["rank_test_score"], expected["rank_test_score"])
    for name in space:
        assert list(found[f"param_{name}"]) == pytest.approx([_native(v) for v in expected[f"param_{name}"]])
    assert fast.best_params_ == pytest.approx({name: _native(value) for name, value in plain.best_params_.items()})
    assert fast.best_index_ == plain.best_index_
    assert fast.best_score_ == pytest.approx(plain.best_score_, rel=1e-12)
    assert fast.n_splits_ == plain.n_splits_ == 2


def _native(value):
    return value.item() if hasattr(value, "item") else value


def test_a_space_over_stage_0_searches_the_whole_pipeline_per_sequence(scenes):
    # Tuning the filter (stage 0) leaves no fixed prefix: the whole pipeline is fitted per candidate and sequence.
    X, target, groups = scenes
    pipeline = experiment_pipeline(8)
    space = {"filter__d_xy": Real(0.8, 2.5), "cluster__min_samples": Integer(2, 6)}
    assert fixed_prefix(pipeline, space) is None and fixed_prefix(pipeline, {"cluster__min_samples": 2}) is not None
    options = {"n_iter": 4, "n_initial_points": 2, "random_state": 0}
    fast = SequenceSearchCV(pipeline, space, cv=2, refit=False, **options).fit(X, target, groups)
    plain = _oracle(pipeline, space, X, target, groups, "v1", **options)
    np.testing.assert_allclose(fast.cv_results_["mean_test_score"], plain.cv_results_["mean_test_score"], rtol=1e-12)


def test_each_fold_score_is_the_scorer_on_whole_sequences(scenes):
    X, target, groups = scenes
    pipeline = experiment_pipeline(3)
    search = SequenceSearchCV(pipeline, search_space(3), n_iter=2, n_initial_points=2, cv=3, refit=False)
    search.fit(X, target, groups)
    folds = sequence_folds(groups, 3)
    assert sorted(np.concatenate(folds).tolist()) == sorted(np.unique(groups).tolist())  # each sequence once
    for row, params in enumerate(search.cv_results_["params"]):
        for k, fold in enumerate(folds):
            rows = np.isin(groups, fold)
            expected = radar_v_measure_scorer(clone(pipeline).set_params(**params), X[rows], target[rows])
            assert search.cv_results_[f"split{k}_test_score"][row] == pytest.approx(expected, rel=1e-12, abs=1e-12)


def test_refit_fits_the_best_candidate_on_all_the_data(scenes):
    X, target, groups = scenes
    pipeline = experiment_pipeline(3)
    search = SequenceSearchCV(pipeline, search_space(3), n_iter=3, n_initial_points=3, cv=2, random_state=2)
    search.fit(X, target, groups)
    expected = clone(pipeline).set_params(**search.best_params_).fit_predict(X)
    np.testing.assert_array_equal(search.best_estimator_[-1].labels_, expected)
    assert search.best_estimator_.get_params()["cluster__eps_xy"] == search.best_params_["cluster__eps_xy"]
    assert search.refit_time_ >= 0.0 and search.best_score_ == max(search.cv_results_["mean_test_score"])
    unfitted = clone(search).set_params(refit=False).fit(X, target, groups)
    assert not hasattr(unfitted, "best_estimator_") and unfitted.best_params_ == search.best_params_


def test_verbose_prints_a_line_per_candidate_and_a_callback_stops_the_search(scenes, capsys):
    X, target, groups = scenes
    search = SequenceSearchCV(experiment_pipeline(3), search_space(3), n_iter=4, n_initial_points=2, cv=2, verbose=1)
    seen = []
    search.fit(X, target, groups, callback=lambda result: seen.append(len(result.func_vals)) or len(seen) == 3)
    assert seen == [1, 2, 3]  # the third call stops it
    assert len(search.cv_results_["params"]) == 3
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[1] for line in lines] == ["1/4", "2/4", "3/4"]


@pytest.mark.parametrize(
    ("params", "fit_kwargs", "message"),
    [
        ({"n_iter": 0}, {}, "n_iter"),
        ({"n_initial_points": -1}, {}, "n_initial_points"),
        ({"n_points": 0}, {}, "n_points"),
        ({"cv": 1}, {}, "cv"),
        ({"scoring": "accuracy"}, {}, "scoring"),
        ({"refit": "yes"}, {}, "refit"),
        ({"search_spaces": {"cluster__nope": Real(0.0, 1.0)}}, {}, "cluster__nope"),
        ({"search_spaces": {}}, {}, "search_spaces"),
        ({"cv": 5}, {}, "cv=5"),
        ({}, {"groups": None}, "groups"),
        ({}, {"y": None}, "requires y"),
    ],
)
def test_bad_parameters_raise_a_value_error_naming_them(scenes, params, fit_kwargs, message):
    X, target, groups = scenes
    search = SequenceSearchCV(experiment_pipeline(3), search_space(3), n_iter=2, n_initial_points=2, cv=2)
    search.set_params(**params)
    with pytest.raises(ValueError, match=message):
        search.fit(X, **{"y": target, "groups": groups, **fit_kwargs})


def test_rows_of_unequal_lengths_are_refused(scenes):
    X, target, groups = scenes
    search = SequenceSearchCV(experiment_pipeline(3), search_space(3), n_iter=2, n_initial_points=2, cv=2)
    with pytest.raises(ValueError, match="inconsistent numbers of samples"):
        search.fit(X, target[:-1], groups[:-1])


def test_what_the_common_checks_cannot_call_holds_with_groups(scenes):
    # The estimator checks call fit without groups (expected failures in tests/test_common.py): the same
    # properties with groups.  Fitting returns self, is idempotent, leaves the parameters alone and pickles.
    X, target, groups = scenes
    search = SequenceSearchCV(experiment_pipeline(3), search_space(3), n_iter=2, n_initial_points=2, cv=2)
    search.set_params(random_state=4, refit=False)
    params = search.get_params()
    assert search.fit(X, target, groups) is search
    first = search.cv_results_
    search.fit(X, target, groups)
    assert search.cv_results_["params"] == first["params"]
    np.testing.assert_array_equal(search.cv_results_["mean_test_score"], first["mean_test_score"])
    assert search.get_params() == params
    restored = pickle.loads(pickle.dumps(search))
    assert restored.best_params_ == search.best_params_ and restored.best_score_ == search.best_score_
