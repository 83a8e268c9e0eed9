"""sequence_train_test_split: whole sequences, balanced detection counts, deterministic."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sklearn_radar.datasets import make_scenes
from sklearn_radar.model_selection import sequence_train_test_split


def _check_split(groups, train, test):
    groups = np.asarray(groups)
    assert train.dtype.kind == "i" and test.dtype.kind == "i"
    assert np.array_equal(np.sort(np.r_[train, test]), np.arange(len(groups)))  # every row once: disjoint, complete
    assert np.all(np.diff(train) > 0) and np.all(np.diff(test) > 0)
    assert not set(groups[train]) & set(groups[test])  # whole sequences
    assert len(train) > 0 and len(test) > 0


@settings(max_examples=200, deadline=None)
@given(st.lists(st.integers(1, 500), min_size=2, max_size=12), st.integers(0, 2**16))
def test_halves_are_whole_sequences_and_within_the_largest_sequence(sizes, seed):
    groups = np.random.RandomState(seed).permutation(np.repeat(np.arange(len(sizes)) * 7 + 3, sizes))
    train, test = sequence_train_test_split(groups, random_state=seed)
    _check_split(groups, train, test)
    assert abs(len(train) - len(test)) <= max(sizes)


def test_simulated_data_split_in_almost_equal_halves():
    scenes = make_scenes(n_sequences=6, duration=4.0, random_state=0)
    train, test = sequence_train_test_split(scenes.groups, random_state=0)
    _check_split(scenes.groups, train, test)
    largest = np.unique(scenes.groups, return_counts=True)[1].max()
    assert abs(len(train) - len(test)) <= largest
    assert len(np.unique(scenes.groups[train])) >= 2 and len(np.unique(scenes.groups[test])) >= 2


def test_greedy_balance_on_a_known_case():
    # Largest first to the emptier side: 50 | 40 -> 50 | 40+30 -> 50+20 | 70.
    groups = np.repeat(["a", "b", "c", "d"], [50, 40, 30, 20])
    train, test = sequence_train_test_split(groups, random_state=0)
    assert len(train) == len(test) == 70
    halves = {frozenset(np.unique(groups[train])), frozenset(np.unique(groups[test]))}
    assert halves == {frozenset("ad"), frozenset("bc")}


def test_deterministic_for_an_int_seed_and_ties_depend_on_it():
    groups = np.repeat(np.arange(8), 100)  # all sizes equal: everything is a tie
    first = sequence_train_test_split(groups, random_state=3)
    again = sequence_train_test_split(groups, random_state=3)
    assert all(np.array_equal(a, b) for a, b in zip(first, again, strict=True))
    assert len(first[0]) == len(first[1]) == 400
    tests = {tuple(np.unique(groups[sequence_train_test_split(groups, random_state=s)[1]])) for s in range(10)}
    assert len(tests) > 1


@pytest.mark.parametrize("test_size, expected", [(0.25, 250), (0.75, 750)])
def test_test_size_is_a_share_of_detections(test_size, expected):
    groups = np.repeat(np.arange(10), 100)
    train, test = sequence_train_test_split(groups, test_size=test_size, random_state=0)
    _check_split(groups, train, test)
    assert abs(len(test) - expected) <= 100


def test_each_side_gets_a_sequence_even_for_an_extreme_test_size():
    groups = np.repeat([0, 1, 2], [1000, 10, 10])
    train, test = sequence_train_test_split(groups, test_size=0.001, random_state=0)
    _check_split(groups, train, test)
    assert len(test) == 10


@pytest.mark.parametrize("groups", [[], [4, 4, 4], np.zeros((3, 2))])
def test_bad_groups_raise_naming_groups(groups):
    with pytest.raises(ValueError, match="groups"):
        sequence_train_test_split(groups)


@pytest.mark.parametrize("test_size", [0.0, 1.0, -0.5, 2, "half", True])
def test_bad_test_size_raises(test_size):
    with pytest.raises(ValueError, match="test_size"):
        sequence_train_test_split([1, 1, 2, 2], test_size=test_size)
