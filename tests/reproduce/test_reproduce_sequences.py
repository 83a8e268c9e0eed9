"""The run's data per sequence (reproduce._sequences): the same tables, split and searches as the whole."""

import numpy as np
import pandas as pd
import pytest
from sklearn.metrics.cluster import contingency_matrix

from sklearn_radar.datasets import load_radarscenes, make_scenes
from sklearn_radar.experiments import experiment_pipeline
from sklearn_radar.metrics import precluster_target
from sklearn_radar.model_selection import sequence_train_test_split
from sklearn_radar.model_selection._sequence_search import SearchData, candidate_scores, sequence_folds
from sklearn_radar.reproduce._sequences import LABEL_COLUMNS, RunSequences

#: The fixtures' simulation: make_scenes(n_sequences=4, duration=3.0, random_state=5), whole and per sequence.
SIMULATION = (4, 3.0, 5)


@pytest.fixture(scope="module")
def scenes():
    n_sequences, duration, seed = SIMULATION
    return make_scenes(n_sequences=n_sequences, duration=duration, random_state=seed)


@pytest.fixture(scope="module")
def sequences():
    return RunSequences.simulated(*SIMULATION)


def _same_partition(a, b):
    """Whether two labellings group the rows alike (ids may differ), -1 being the same class in both."""
    table = contingency_matrix(a, b)
    return np.all((table > 0).sum(axis=0) == 1) and np.all((table > 0).sum(axis=1) == 1)


@pytest.mark.parametrize("seed", [0, 1, 7])
def test_split_equals_sequence_train_test_split(scenes, sequences, seed):
    train, test = sequences.split(random_state=seed)
    train_rows, test_rows = sequence_train_test_split(scenes.groups, random_state=seed)
    assert train == sorted(np.unique(scenes.groups[train_rows]).tolist())
    assert test == sorted(np.unique(scenes.groups[test_rows]).tolist())


def test_one_sequence_cannot_be_split():
    with pytest.raises(ValueError, match="at least 2 sequences"):
        RunSequences.simulated(1, 1.0, 0).split(random_state=0)


def test_a_folder_loads_per_sequence_as_the_whole_folder_does(tiny_folder):
    sequences = RunSequences.from_folder(tiny_folder)
    whole = load_radarscenes(tiny_folder)
    joined = pd.concat([sequences.fetch(i).scenes.data for i in sequences.ids], ignore_index=True)
    pd.testing.assert_frame_equal(joined, whole.data.reset_index(drop=True))
    assert sequences.sizes == [int((whole.groups == i).sum()) for i in sequences.ids]
    objects = set()
    for i in sequences.ids:
        target = sequences.fetch(i).scenes.target
        assert _same_partition(target, whole.target[whole.groups == i])
        ids = set(np.unique(target[target >= 0]).tolist())
        assert ids and not ids & objects  # unique across sequences, as in the whole folder's load
        objects |= ids


def test_a_folder_without_sequences_is_named(tmp_path, tiny_folder):
    for name in ("sensors.json",):
        (tmp_path / name).write_bytes((tiny_folder / name).read_bytes())
    (tmp_path / "sequences.json").write_text('{"sequences": {}}')
    with pytest.raises(ValueError, match=r"sequences\.json: field 'sequences' lists no sequence"):
        RunSequences.from_folder(tmp_path)


def test_search_data_scores_candidates_as_the_whole_table_does(scenes, sequences):
    train = sequences.ids[:3]
    rows = np.isin(scenes.groups, train)
    X = scenes.data.loc[rows, [c for c in scenes.data.columns if c not in LABEL_COLUMNS]]
    target = precluster_target(scenes.data, scenes.target)[rows]
    folds = sequence_folds(scenes.groups[rows], 3)
    pipeline = experiment_pipeline(8)
    candidates = [{}, {"cluster__eps_xyv": 0.6}]
    expected = candidate_scores(SearchData.place(X, target, scenes.groups[rows]), pipeline, candidates, folds, "v1")
    found = candidate_scores(sequences.search_data(train), pipeline, candidates, folds, "v1")
    np.testing.assert_allclose(found, expected, rtol=0, atol=1e-12)


def _sizes_and_ids(sequence, extra):
    return sequence.id, len(sequence), extra


def test_map_runs_in_order_on_the_sequences_asked_for(sequences):
    asked = [sequences.ids[2], sequences.ids[0]]
    found = sequences.map(_sizes_and_ids, asked, "x")
    assert found == [(i, sequences.size([i]), "x") for i in asked]


@pytest.mark.parametrize("difficulty", ["easy", "realistic", "radarscenes"])
def test_sequences_simulated_one_by_one_are_make_scenes_ones(difficulty):
    whole = make_scenes(n_sequences=3, duration=2.0, random_state=11, difficulty=difficulty)
    sequences = RunSequences.simulated(3, 2.0, 11, difficulty)
    assert sequences.ids == [1, 2, 3]
    joined = pd.concat([sequences.fetch(i).scenes.data for i in sequences.ids], ignore_index=True)
    pd.testing.assert_frame_equal(joined, whole.data)
    objects = set()
    for i in sequences.ids:
        sequence = sequences.fetch(i)
        rows = whole.groups == i
        assert _same_partition(sequence.scenes.target, whole.target[rows])
        assert _same_partition(sequence.target, precluster_target(whole.data, whole.target)[rows])
        pd.testing.assert_frame_equal(
            sequence.scenes.odometry, whole.odometry[whole.odometry["sequence"] == i].reset_index(drop=True)
        )
        assert not set(LABEL_COLUMNS) & set(sequence.X.columns)
        ids = set(np.unique(sequence.scenes.target[sequence.scenes.target >= 0]).tolist())
        assert not ids & objects
        objects |= ids
    assert sequences.sizes == [int((whole.groups == i).sum()) for i in sequences.ids]
    assert sequences.n_detections == len(whole.data)
