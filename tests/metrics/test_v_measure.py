"""The radar V-measure: the four properties of our reading, the scorer, and the pre-clustered target."""

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.metrics import homogeneity_completeness_v_measure

from sklearn_radar import RadarDBSCAN
from sklearn_radar.metrics import (
    precluster_target,
    radar_homogeneity_completeness_v_measure,
    radar_v_measure,
    radar_v_measure_scorer,
)

labelings = st.integers(4, 60).flatmap(
    lambda n: st.tuples(
        st.lists(st.integers(-1, 4), min_size=n, max_size=n), st.lists(st.integers(-1, 5), min_size=n, max_size=n)
    )
)


@settings(max_examples=100, deadline=None)
@given(labelings)
def test_property_1_clustering_background_never_lowers_the_score(case):
    truth, pred = (np.array(v) for v in case)
    background = np.flatnonzero(truth == -1)
    split = pred.copy()
    split[background] = 100 + np.arange(len(background))  # each background detection its own cluster
    assert radar_v_measure(truth, split) >= radar_v_measure(truth, pred) - 1e-12


def test_property_2_background_in_an_object_cluster_lowers_homogeneity():
    truth = np.array([0, 0, 0, 0, -1, -1, -1, -1])
    clean = np.array([0, 0, 0, 0, -1, -1, -1, -1])
    polluted = np.array([0, 0, 0, 0, 0, -1, -1, -1])
    h_clean, c_clean, _ = radar_homogeneity_completeness_v_measure(truth, clean)
    h_polluted, c_polluted, _ = radar_homogeneity_completeness_v_measure(truth, polluted)
    assert h_polluted < h_clean == 1.0
    assert c_polluted == c_clean == 1.0


@pytest.mark.parametrize("split", [[0, 0, 1, 1, 2, 2, -1, -1], [0, 0, 0, -1, 2, 2, -1, -1]])
def test_property_3_splitting_an_object_or_losing_it_to_noise_lowers_completeness(split):
    truth = np.array([0, 0, 0, 0, 1, 1, -1, -1])
    whole = np.array([0, 0, 0, 0, 2, 2, -1, -1])
    _, c_whole, v_whole = radar_homogeneity_completeness_v_measure(truth, whole)
    _, c_split, v_split = radar_homogeneity_completeness_v_measure(truth, np.array(split))
    assert c_split < c_whole == 1.0
    assert v_split < v_whole


@settings(max_examples=150, deadline=None)
@given(labelings)
def test_property_4_without_background_it_is_sklearns_v_measure(case):
    truth, pred = (np.array(v) for v in case)
    truth = truth + 1  # no -1 left: no background
    assert radar_homogeneity_completeness_v_measure(truth, pred) == pytest.approx(
        homogeneity_completeness_v_measure(truth, pred), abs=0, rel=0
    )


@settings(max_examples=60, deadline=None)
@given(labelings, st.sampled_from([0.25, 0.5, 2.0, 4.0]))
def test_beta_weights_homogeneity_as_in_sklearn(case, beta):
    truth, pred = (np.array(v) for v in case)
    truth = truth + 1  # no background: scikit-learn's V-measure with the same beta is the reference
    assert radar_homogeneity_completeness_v_measure(truth, pred, beta=beta) == pytest.approx(
        homogeneity_completeness_v_measure(truth, pred, beta=beta), abs=1e-12
    )


def test_beta_by_hand_with_background():
    # Every cluster is pure (h = 1).  Completeness over the objects [0, 0, 1, 1] -> [0, 0, 1, 2]:
    # H(K) = 1.5 ln 2, H(K|C) = 0.5 ln 2, so c = 1 - 1/3 = 2/3.
    # V_beta = (1 + beta) h c / (beta h + c); beta = 2: 3 * 2/3 / (2 + 2/3) = 0.75
    # (weighting completeness instead would give 3 * 2/3 / (1 + 4/3) = 6/7).
    truth = np.array([0, 0, 1, 1, -1, -1])
    pred = np.array([0, 0, 1, 2, -1, 3])
    h, c, v = radar_homogeneity_completeness_v_measure(truth, pred, beta=2.0)
    assert (h, c, v) == pytest.approx((1.0, 2 / 3, 0.75), abs=1e-12)
    assert radar_v_measure(truth, pred, beta=2.0) == pytest.approx(0.75, abs=1e-12)


def test_cluster_ids_of_different_sequences_are_different_clusters():
    truth = np.array([0, 0, 1, 1])
    pred = np.array([0, 0, 0, 0])  # the same id in two sequences
    groups = np.array([1, 1, 2, 2])
    assert radar_v_measure(truth, pred, groups=groups) == pytest.approx(1.0)
    assert radar_v_measure(truth, pred) < 1.0


def test_all_noise_scores_zero():
    assert radar_v_measure(np.array([0, 0, 1, -1]), np.array([-1, -1, -1, -1])) == 0.0


class _Failing(RadarDBSCAN):
    def fit(self, X, y=None):
        raise RuntimeError("boom")


def test_scorer_fits_on_the_data_and_never_raises():
    X = pd.DataFrame({"x": [0.0, 0.3, 5.0, 5.3], "y": 0.0, "v_r": 3.0, "t": 0.0, "sequence": [1, 1, 1, 1]})
    y = np.array([0, 0, 1, 1])
    good = radar_v_measure_scorer(RadarDBSCAN(min_samples=2), X, y)
    assert good == pytest.approx(1.0)
    assert radar_v_measure_scorer(_Failing(), X, y) == 0.0
    assert radar_v_measure_scorer(RadarDBSCAN(min_samples=10), X, y) == 0.0


def _object(x0, times, instance, sequence=1, v=5.0):
    return [(x0 + v * t, 0.0, v, t, sequence, instance) for t in times]


def test_precluster_target_splits_an_absent_object_and_never_merges_objects():
    rows = (
        _object(0.0, [0.0, 0.06, 0.12], instance=0)  # first appearance
        + _object(0.0, [1.0, 1.06], instance=0)  # back after 0.88 s: a second target cluster
        + [(0.5, 0.0, 5.0, 0.06, 1, 1), (0.55, 0.0, 5.0, 0.12, 1, 1)]  # another object touching the first
        + [(40.0, 0.0, 5.0, 0.5, 1, 2)]  # a lone detection: nothing to cluster with
        + [(90.0, 0.0, 0.0, 0.0, 1, -1)]  # background
    )
    X = pd.DataFrame(rows, columns=["x", "y", "v_r", "t", "sequence", "instance"])
    target = precluster_target(X.drop(columns="instance"), X["instance"].to_numpy())
    first, second, other = target[:3], target[3:5], target[5:7]
    assert len(set(first)) == len(set(second)) == len(set(other)) == 1
    assert len({first[0], second[0], other[0]}) == 3
    assert target[7] == -1 and target[8] == -1


def test_precluster_target_accepts_the_raw_detection_table():
    from sklearn_radar.datasets import make_scenes

    scenes = make_scenes(n_sequences=2, duration=5.0, random_state=1)
    target = precluster_target(scenes.data, scenes.target)
    assert target.shape == scenes.target.shape
    np.testing.assert_array_equal(target[scenes.target == -1], -1)
    # Every target cluster lies inside one instance.
    pairs = pd.DataFrame({"t": target, "y": scenes.target})[target >= 0]
    assert (pairs.groupby("t")["y"].nunique() == 1).all()
