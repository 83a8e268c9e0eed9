"""iter_scans: the scans of a detection table in arrival order, as ``sklearn-radar stream`` replays them."""

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import experiment_pipeline
from sklearn_radar.online import OnlinePipeline, iter_scans
from sklearn_radar.online._replay import replay


@pytest.fixture(scope="module")
def data():
    """Two sequences recorded at the same time on a 40 ms grid (sensors and sequences share times), rows shuffled."""
    data = make_scenes(n_sequences=2, duration=3.0, random_state=5).data.copy()
    start = data.groupby("sequence")["timestamp"].transform("min")
    data["timestamp"] = (data["timestamp"] - start) // 40_000 * 40_000
    return data.sample(frac=1.0, random_state=0)


def test_the_scans_are_pandas_groups_of_timestamp_and_sequence_in_time_order(data):
    # Reference: pandas groupby, which sorts the keys (timestamp first) and keeps the rows' order in each group.
    expected = [group for _, group in data.groupby(["timestamp", "sequence"], sort=True)]
    scans = list(iter_scans(data))
    assert len(scans) == len(expected)
    for scan, group in zip(scans, expected, strict=True):
        pd.testing.assert_frame_equal(scan, group)
    assert max(scan["sensor_id"].nunique() for scan in scans) > 1  # sensors of one time go together
    assert data.groupby("timestamp")["sequence"].nunique().max() > 1  # and sequences share times, apart


def test_feeding_them_gives_what_stream_replays(data):
    # The same labels as the replay of ``sklearn-radar stream`` (online/_replay.py), which has its own loop.
    online = OnlinePipeline(experiment_pipeline(13))
    labels = pd.Series(-2, index=data.index)
    for scan in iter_scans(data):
        labels.loc[scan.index] = online.update(scan, objects=False).labels
    streamed = replay(OnlinePipeline(experiment_pipeline(13)), data)["labels"]
    np.testing.assert_array_equal(labels.to_numpy(), streamed)


def test_without_a_sequence_column_the_table_is_one_sequence():
    data = pd.DataFrame({"timestamp": [30, 10, 30, 20, 10], "value": [0, 1, 2, 3, 4]})
    assert [scan["value"].tolist() for scan in iter_scans(data)] == [[1, 4], [3], [0, 2]]
    assert list(iter_scans(data.iloc[:0])) == []


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_the_order_of_the_rows_does_not_change_the_scans(seed):
    rng = np.random.default_rng(seed)
    data = pd.DataFrame({"timestamp": rng.integers(0, 4, 12) * 60_000, "sequence": rng.integers(0, 2, 12)})
    shuffled = data.sample(frac=1.0, random_state=int(seed % 1000))
    first = [sorted(scan.index) for scan in iter_scans(data)]
    assert [sorted(scan.index) for scan in iter_scans(shuffled)] == first
    keys = [(scan["timestamp"].iloc[0], scan["sequence"].iloc[0]) for scan in iter_scans(data)]
    assert keys == sorted(set(zip(data["timestamp"], data["sequence"], strict=True)))


@pytest.mark.parametrize(
    "change, match",
    [
        (lambda d: d.drop(columns="timestamp"), "no 'timestamp' column"),
        (lambda d: d.assign(timestamp=np.nan), "'timestamp' holds values that are not finite"),
        (lambda d: d.assign(sequence="a"), "'sequence' must hold numbers"),
    ],
)
def test_bad_tables_raise_when_called(change, match):
    data = pd.DataFrame({"timestamp": [0, 1], "sequence": [0, 0]})
    with pytest.raises(ValueError, match=match):
        iter_scans(change(data))  # at the call, before any scan is taken
