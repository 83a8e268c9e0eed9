"""The per-sequence search (``model_selection._sequence_search``): a task per candidate and sequence."""

import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.base import clone
from sklearn.model_selection import GroupKFold

from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import experiment_pipeline
from sklearn_radar.metrics import panoptic_quality_scorer, precluster_target, radar_v_measure_scorer
from sklearn_radar.metrics._parts import FailedPart, combine_parts
from sklearn_radar.model_selection._sequence_search import (
    SearchData,
    balanced_blocks,
    candidate_parts,
    candidate_scores,
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
