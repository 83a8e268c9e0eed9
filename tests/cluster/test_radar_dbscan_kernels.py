"""The typed interface between RadarDBSCAN and its numba kernels, and the shared union-find of stage 2."""

import numba
import numpy as np
import pytest
from sklearn.utils._param_validation import InvalidParameterError

from sklearn_radar.cluster import RadarDBSCAN, ScanStream, _radar_dbscan, min_points_at_range
from sklearn_radar.cluster._merge_kernels import merge_components
from sklearn_radar.cluster._radar_dbscan_kernels import (
    BOX,
    BOX_UNROTATED,
    XY,
    XYV,
    Criterion,
    criterion_of,
    points_of,
)


def test_criterion_holds_the_thresholds_as_floats():
    criterion = criterion_of(metric="xyv", eps_xy=1.5, eps_vr=2, vr_scale=3, eps_xyv=0.7, eps_t=0.3)
    assert criterion == Criterion(metric=XYV, eps_xy=1.5, eps_vr=2.0, vr_scale=3.0, eps_xyv=0.7, eps_t=0.3)
    assert all(type(value) is float for value in criterion[1:])
    assert criterion_of(metric="xy", eps_xy=1, eps_vr=1, vr_scale=1, eps_xyv=1, eps_t=None).eps_t == np.inf


def test_the_estimator_passes_its_parameters_as_plain_values():
    model = RadarDBSCAN(metric="xyv", eps_xy=1.5, eps_vr=2, vr_scale=3, eps_xyv=0.7, eps_t=None)
    expected = Criterion(metric=XYV, eps_xy=1.5, eps_vr=2.0, vr_scale=3.0, eps_xyv=0.7, eps_t=np.inf)
    assert model._kernel_criterion(np.zeros(4)) == expected


def test_the_kernel_module_reads_no_estimator():
    with pytest.raises(TypeError):
        criterion_of(RadarDBSCAN())  # keyword values only


@pytest.mark.parametrize(
    "metric, heading, expected",
    [
        ("box", np.zeros(3), BOX_UNROTATED),
        ("box", np.array([0.0, 0.0, 0.1]), BOX),
        ("box", None, BOX),  # a stream: the headings of future scans are unknown
        ("xy", np.zeros(3), XY),
        ("xyv", np.array([0.0, 1.0]), XYV),
    ],
)
def test_the_box_needs_no_rotation_only_when_every_heading_is_zero(metric, heading, expected):
    assert RadarDBSCAN(metric=metric)._kernel_criterion(heading).metric == expected


def test_the_stream_uses_the_same_criterion_object():
    model = RadarDBSCAN(metric="xy", eps_xy=0.8, eps_t=None)
    assert ScanStream(model)._criterion == model._kernel_criterion()


def test_points_are_contiguous_float64_with_the_heading_as_cosine_and_sine():
    heading = np.array([0.0, np.pi / 2])
    points = points_of(x=[1, 2], y=[3, 4], v=np.array([5.0, 6.0])[::1], t=[0, 0.1], heading=heading)
    for values in points:
        assert values.dtype == np.float64 and values.flags.c_contiguous
    np.testing.assert_array_equal(points.cos_h, np.cos(heading))
    np.testing.assert_array_equal(points.sin_h, np.sin(heading))


def test_the_estimator_module_calls_no_numba_kernel_directly():
    dispatchers = [
        name for name, value in vars(_radar_dbscan).items() if isinstance(value, numba.core.dispatcher.Dispatcher)
    ]
    assert dispatchers == []


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"range_scaling": "reciprocl"}, "range_scaling"),
        ({"alpha_r": 1.5}, "alpha_r"),
        ({"min_samples": 0.5}, "min_samples"),
    ],
)
def test_min_points_at_range_refuses_bad_parameters(kwargs, name):
    arguments = {"range_m": [10.0, 50.0], "min_samples": 3.0, "alpha_r": 0.5, **kwargs}
    with pytest.raises(InvalidParameterError, match=name):
        min_points_at_range(**arguments)
    assert issubclass(InvalidParameterError, ValueError)


def test_min_points_at_range_follows_eq_2():
    r = np.array([10.0, 25.0, 50.0, 100.0, 200.0])
    clipped = np.clip(r, 25.0, 125.0)
    np.testing.assert_allclose(min_points_at_range(r, 4, 0.5), 4 * (1 + 0.5 * (50.0 / clipped - 1)))
    np.testing.assert_allclose(min_points_at_range(r, 4, 0.5, "linear"), 4 * (1 + 0.5 * (clipped / 50.0 - 1)))


def _merge_components_reference(n_clusters, edges, min_samples):
    """The former pure-Python merge_components: core clusters joined, the smaller root survives."""
    degree = np.zeros(n_clusters, dtype=np.int64)
    for a, b in edges:
        degree[a] += 1
        degree[b] += 1
    core = degree + 1 >= min_samples
    parent = list(range(n_clusters))

    def find(i):
        while parent[i] != i:
            i = parent[i]
        return i

    for a, b in edges:
        if core[a] and core[b]:
            ra, rb = find(a), find(b)
            parent[max(ra, rb)] = min(ra, rb)
    root = np.array([find(i) for i in range(n_clusters)], dtype=np.int64)
    for a, b in edges:
        if core[a] and not core[b] and root[b] == b:
            root[b] = root[a]
        elif core[b] and not core[a] and root[a] == a:
            root[a] = root[b]
    return root


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("min_samples", [1, 2, 3])
def test_merge_components_uses_the_shared_union_find_with_the_same_roots(seed, min_samples):
    rng = np.random.default_rng(seed)
    n_clusters = int(rng.integers(1, 80))
    a, b = rng.integers(0, n_clusters, (2, int(rng.integers(0, 120))))
    edges = [(int(i), int(j)) for i, j in zip(a, b, strict=True) if i != j]
    root = merge_components(n_clusters, edges, min_samples)
    np.testing.assert_array_equal(root, _merge_components_reference(n_clusters, edges, min_samples))
    assert root.dtype == np.int64


def test_merge_components_without_edges_keeps_every_cluster():
    np.testing.assert_array_equal(merge_components(3, [], 1), [0, 1, 2])
    assert merge_components(0, [], 1).shape == (0,)
