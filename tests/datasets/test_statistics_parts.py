"""Per-sequence statistics parts: combined, they give scene_statistics of the whole data set (issue 14)."""

import math
import pickle

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.utils import Bunch

from sklearn_radar.datasets import make_scenes, scene_statistics
from sklearn_radar.datasets._statistics import StatisticsPart, combine_statistics, statistics_parts


@pytest.fixture(scope="module")
def scenes():
    return make_scenes(n_sequences=3, duration=5.0, random_state=0)


def _by_sequence(bunch, blocks=None):
    """The bunch split into whole sequences (or into the given blocks of sequence numbers)."""
    sequence = bunch.data["sequence"].to_numpy()
    blocks = blocks if blocks is not None else [[value] for value in np.unique(sequence)]
    parts = []
    for block in blocks:
        rows = np.isin(sequence, block)
        parts.append(Bunch(data=bunch.data[rows], target=np.asarray(bunch.target)[rows]))
    return parts


def _assert_same(whole, combined):
    summary, table = whole
    got_summary, got_table = combined
    assert list(got_summary) == list(summary)
    for key, value in summary.items():
        got = got_summary[key]
        assert type(got) is type(value), key
        if isinstance(value, float) and math.isnan(value):
            assert math.isnan(got), key
        else:
            assert got == value, key  # exact: the same operations on the same integer counts
    pd.testing.assert_frame_equal(got_table, table, check_exact=True)


def _variants(scenes):
    """The data set as is, with sequence 2 without objects, and with sequence 3 without background."""
    sequence = scenes.data["sequence"].to_numpy()
    no_objects = np.where(sequence == 2, -1, scenes.target)
    keep = ~((sequence == 3) & (scenes.target == -1))
    return {
        "as simulated": scenes,
        "a sequence without objects": Bunch(data=scenes.data, target=no_objects),
        "a sequence without background": Bunch(data=scenes.data[keep], target=scenes.target[keep]),
        "no objects at all": Bunch(data=scenes.data, target=np.full(len(scenes.target), -1)),
    }


@pytest.mark.parametrize("variant", ["as simulated", "a sequence without objects", "a sequence without background"])
def test_parts_combine_to_the_whole_statistics(scenes, variant):
    bunch = _variants(scenes)[variant]
    whole = scene_statistics(bunch)
    parts = [statistics_parts(part) for part in _by_sequence(bunch)]
    _assert_same(whole, combine_statistics(parts))
    _assert_same(whole, combine_statistics(parts[::-1]))  # order does not matter
    _assert_same(whole, combine_statistics([statistics_parts(bunch)]))  # one part is the whole


def test_no_objects_at_all(scenes):
    bunch = _variants(scenes)["no objects at all"]
    whole = scene_statistics(bunch)
    assert whole[0]["instances"] == 0 and whole[1].empty
    _assert_same(whole, combine_statistics([statistics_parts(part) for part in _by_sequence(bunch)]))


def test_blocks_of_sequences_and_other_range_bins(scenes):
    bins = (0, 5, 40, 80)  # integer edges: the table's columns keep pd.cut's interval dtype
    whole = scene_statistics(scenes, range_bins=bins)
    parts = [statistics_parts(part, range_bins=bins) for part in _by_sequence(scenes, [[1, 3], [2]])]
    _assert_same(whole, combine_statistics(parts))


def test_a_part_is_small_and_picklable(scenes):
    part = statistics_parts(scenes)
    again = pickle.loads(pickle.dumps(part))
    _assert_same(combine_statistics([part]), combine_statistics([again]))
    assert len(pickle.dumps(part)) < 20_000  # a few rows per sequence and per (class, range bin), not per detection
    assert len(part.sequences) == 3


def test_bad_parts(scenes):
    parts = [statistics_parts(part) for part in _by_sequence(scenes)]
    with pytest.raises(ValueError, match="parts must not be empty"):
        combine_statistics([])
    with pytest.raises(ValueError, match="parts"):
        combine_statistics([parts[0], "not a part"])
    with pytest.raises(ValueError, match=r"sequence\(s\) \[1\]"):
        combine_statistics([parts[0], parts[0]])
    with pytest.raises(ValueError, match="range_bins"):
        combine_statistics([parts[0], statistics_parts(_by_sequence(scenes)[1], range_bins=(0, 50, 100))])
    with pytest.raises(ValueError, match="target"):
        statistics_parts(Bunch(data=scenes.data, target=scenes.target[:-1]))
    with pytest.raises(ValueError, match="sequence"):
        statistics_parts(Bunch(data=scenes.data.drop(columns="sequence"), target=scenes.target))


@st.composite
def _data_sets(draw):
    """Small random detection tables: 1-4 sequences, objects unique across sequences, some classes unknown."""
    n = draw(st.integers(1, 40))
    sequence = draw(st.lists(st.integers(1, 4), min_size=n, max_size=n))
    timestamp = draw(st.lists(st.integers(0, 6).map(lambda k: 60_000 * k), min_size=n, max_size=n))
    range_sc = draw(st.lists(st.floats(-5.0, 130.0, width=32), min_size=n, max_size=n))
    label_id = draw(st.lists(st.integers(0, 12), min_size=n, max_size=n))  # 12: not a RadarScenes class
    local = draw(st.lists(st.integers(-1, 2), min_size=n, max_size=n))
    data = pd.DataFrame(
        {
            "sequence": np.array(sequence, dtype=np.int64),
            "timestamp": np.array(timestamp, dtype=np.int64) + 10**11 * np.array(sequence),
            "range_sc": np.array(range_sc, dtype=np.float32),
            "label_id": np.array(label_id, dtype=np.int64),
        }
    )
    target = np.where(np.array(local) < 0, -1, 10 * np.array(sequence) + np.array(local))
    blocks = draw(st.lists(st.integers(0, 2), min_size=4, max_size=4))  # block of each sequence number
    return Bunch(data=data, target=target), blocks


@settings(max_examples=150, deadline=None)
@given(_data_sets())
def test_parts_combine_to_the_whole_on_random_data(case):
    bunch, blocks = case
    present = np.unique(bunch.data["sequence"])
    grouping = [[s for s in present if blocks[s - 1] == b] for b in range(3)]
    pieces = _by_sequence(bunch, [block for block in grouping if block])
    parts = [statistics_parts(piece) for piece in pieces]
    assert all(isinstance(part, StatisticsPart) for part in parts)
    _assert_same(scene_statistics(bunch), combine_statistics(parts))
