"""bounds_reached: which tuned parameters stopped at an end of their range, by hand-made cases."""

from sklearn_radar._skopt import Integer, Real
from sklearn_radar.model_selection._bounds import bounds_reached

SPACE = {
    "a__eps": Real(0.2, 3.0),
    "a__scale": Real(0.1, 100.0, prior="log-uniform"),
    "a__min_samples": Integer(1, 8),
    "a__vr_min": Real(0.0, 1.5),
    "a__alpha_r": Real(0.0, 1.0),
}


def test_values_inside_are_not_reached():
    assert bounds_reached({"a__eps": 1.0, "a__scale": 3.0, "a__min_samples": 4, "a__vr_min": 0.7}, SPACE) == []


def test_real_ends_within_one_percent_of_the_span():
    # Span 2.8 m: 1 % is 0.028 m.
    assert bounds_reached({"a__eps": 2.975}, SPACE) == ["a__eps"]
    assert bounds_reached({"a__eps": 0.227}, SPACE) == ["a__eps"]
    assert bounds_reached({"a__eps": 0.23}, SPACE) == []


def test_log_uniform_ends_on_the_log_scale():
    # log(1000) = 6.91; 1 % of it is 0.069, so within a factor exp(0.069) = 1.072 of an end.
    assert bounds_reached({"a__scale": 0.107}, SPACE) == ["a__scale"]
    assert bounds_reached({"a__scale": 0.108}, SPACE) == []
    assert bounds_reached({"a__scale": 94.0}, SPACE) == ["a__scale"]


def test_integers_at_an_end_and_natural_limits_not_counted():
    assert bounds_reached({"a__min_samples": 8}, SPACE) == ["a__min_samples"]
    assert bounds_reached({"a__min_samples": 1}, SPACE) == []  # 1 point is min_samples' own limit
    assert bounds_reached({"a__vr_min": 0.0, "a__alpha_r": 1.0}, SPACE) == []
    assert bounds_reached({"a__vr_min": 1.5}, SPACE) == ["a__vr_min"]
    assert bounds_reached({"a__vr_min": 0.0}, SPACE, natural={}) == ["a__vr_min"]


def test_a_minimum_cluster_size_of_one_or_two_is_its_own_limit():
    space = {"merge__min_cluster_size": Integer(1, 300, prior="log-uniform"), "c__min_cluster_size": Integer(2, 40)}
    assert bounds_reached({"merge__min_cluster_size": 1, "c__min_cluster_size": 2}, space) == []  # off; HDBSCAN's 2
    assert bounds_reached({"merge__min_cluster_size": 300, "c__min_cluster_size": 40}, space) == [
        "merge__min_cluster_size",
        "c__min_cluster_size",
    ]


def test_parameters_without_a_dimension_are_ignored():
    assert bounds_reached({"b__eps": 3.0}, SPACE) == []
