"""hota_scores against hand-computed cases and against TrackEval's HOTA on the same per-window IoU matrices."""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sklearn_radar.metrics import hota_scores

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    trackeval_hota = pytest.importorskip("trackeval.metrics.hota")

FIELDS = ("hota", "deta", "assa", "loca", "detre", "detpr", "assre", "asspr")


def test_a_perfect_track():
    scores = hota_scores([0, 0, 1, 1], [3, 3, 4, 4], times=[0.0, 0.6, 0.0, 0.6])
    for field in FIELDS:
        assert scores[field] == 1.0, field


def test_an_id_switch_by_hand():
    # One object over two windows, tracked as 5 then as 7: every detection matches (DetA 1); each match's ids share
    # 1 of the 2 + 1 - 1 windows of either id, so AssA = 1/2 and HOTA = sqrt(1/2) at every threshold.
    scores = hota_scores([0, 0, 0, 0], [5, 5, 7, 7], times=[0.0, 0.1, 0.6, 0.7])
    assert scores["deta"] == 1.0 and scores["assa"] == pytest.approx(0.5)
    assert scores["hota"] == pytest.approx(np.sqrt(0.5))


def test_a_partial_match_counts_up_to_its_iou():
    # Two of four detections: IoU 0.5, a match for alpha <= 0.5 (10 of 19 thresholds), else a miss and a false
    # positive.  Matched: DetA 1, AssA 1, LocA 0.5; unmatched: DetA 0.
    scores = hota_scores([0, 0, 0, 0], [1, 1, -1, -1], times=[0.0] * 4)
    assert np.array_equal(scores["deta_alpha"], np.r_[np.ones(10), np.zeros(9)])
    assert scores["hota"] == pytest.approx(10 / 19)
    assert scores["loca"] == pytest.approx((10 * 0.5 + 9 * 1.0) / 19)  # TrackEval's LocA is 1 without matches


def test_nothing_predicted():
    scores = hota_scores([0, 0, -1], [-1, -1, -1], times=[0.0, 0.1, 0.2])
    assert scores["hota"] == 0.0 and scores["deta"] == 0.0 and scores["loca"] == 1.0


def test_lengths_must_agree():
    with pytest.raises(ValueError, match="equal lengths"):
        hota_scores([0, 0], [0], times=[0.0, 0.1])


def trackeval_scores(truth, pred, times, groups, window=0.5):
    """The reference: TrackEval's HOTA fed, window by window, the ids present and their IoU matrix."""
    metric = trackeval_hota.HOTA()
    results = {}
    for number in np.unique(groups):
        rows = groups == number
        t, g, p = times[rows], truth[rows], pred[rows]
        cell = np.floor((t - t.min()) / window).astype(int)
        g_codes = np.unique(g[g >= 0])
        p_codes = np.unique(p[p >= 0])
        data = {"gt_ids": [], "tracker_ids": [], "similarity_scores": []}
        for c in range(cell.max() + 1):
            here = cell == c
            gi = np.unique(g[here & (g >= 0)])
            pi = np.unique(p[here & (p >= 0)])
            sim = np.zeros((len(gi), len(pi)))
            for a, i in enumerate(gi):
                for b, j in enumerate(pi):
                    inter = np.sum(here & (g == i) & (p == j))
                    union = np.sum(here & (g == i)) + np.sum(here & (p == j)) - inter
                    sim[a, b] = inter / union
            data["gt_ids"].append(np.searchsorted(g_codes, gi))
            data["tracker_ids"].append(np.searchsorted(p_codes, pi))
            data["similarity_scores"].append(sim)
        data["num_gt_ids"], data["num_tracker_ids"] = len(g_codes), len(p_codes)
        data["num_gt_dets"] = sum(len(x) for x in data["gt_ids"])
        data["num_tracker_dets"] = sum(len(x) for x in data["tracker_ids"])
        results[int(number)] = metric.eval_sequence(data)
    combined = metric.combine_sequences(results)
    return {
        field: float(np.mean(combined[name]))
        for field, name in zip(
            FIELDS, ("HOTA", "DetA", "AssA", "LocA", "DetRe", "DetPr", "AssRe", "AssPr"), strict=True
        )
    }


def assert_like_trackeval(truth, pred, times, groups):
    truth, pred, times, groups = map(np.asarray, (truth, pred, times, groups))
    ours = hota_scores(truth, pred, times=times, groups=groups)
    reference = trackeval_scores(truth, pred, times, groups)
    for field in FIELDS:
        assert ours[field] == pytest.approx(reference[field], abs=1e-12), field


def test_equals_trackeval_on_a_two_sequence_case():
    truth = [0, 0, 0, 1, 1, -1, 0, 0, 1]
    pred = [4, 4, 5, 5, 5, 6, 2, 2, 2]
    times = [0.0, 0.1, 0.6, 0.6, 0.7, 0.1, 0.0, 0.6, 0.6]
    groups = [1, 1, 1, 1, 1, 1, 2, 2, 2]
    assert_like_trackeval(truth, pred, times, groups)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.tuples(st.integers(-1, 3), st.integers(-1, 4), st.integers(0, 7), st.integers(0, 1)),
        min_size=1,
        max_size=60,
    )
)
def test_equals_trackeval_on_random_tables(rows):
    truth, pred, tenth, groups = (np.array(column) for column in zip(*rows, strict=True))
    assert_like_trackeval(truth, pred, tenth * 0.2, groups)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.tuples(st.integers(-1, 3), st.integers(-1, 4), st.integers(0, 7), st.integers(0, 2)),
        min_size=1,
        max_size=60,
    )
)
def test_per_sequence_counts_combine_to_the_scores_with_groups(rows):
    """hota_counts of each sequence, combined: hota_scores of all of them with groups (what the runner sums)."""
    from sklearn_radar.metrics._hota import combine_hota_counts, hota_counts

    truth, pred, tenth, groups = (np.array(column) for column in zip(*rows, strict=True))
    times = tenth * 0.2
    parts = [hota_counts(truth[groups == g], pred[groups == g], times[groups == g]) for g in np.unique(groups)]
    combined = combine_hota_counts(parts)
    expected = hota_scores(truth, pred, times=times, groups=groups)
    for name in ("hota", "deta", "assa", "loca"):
        assert combined[name] == pytest.approx(expected[name], abs=1e-12)
