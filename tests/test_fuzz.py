"""Property tests on random detection tables (issue 15): the estimators and a Pipeline never crash.

Random tables with NaN and infinity, duplicate rows, extreme values, wrong
dtypes, missing columns, empty tables and occasionally a bad parameter are
fed to FrameTransform, DopplerDensityFilter, RadarDBSCAN, ClusterMerger and
a Pipeline of all four.  Every case either succeeds with

* as many rows out as in, one label per row (the clusterers),
* no cluster spanning two ``sequence`` values,
* labels (or transformed rows) that follow a permutation of the rows (labels
  up to renaming),

or raises a ValueError that names a column or parameter.  Any other
exception is a crash.  CI runs a small sample (``test_fuzz_sample``); the
long run, at least 1,000 tables per estimator and per Pipeline, is marked
``slow`` and deselected by default::

    python -m pytest -m slow tests/test_fuzz.py -s

which prints, per target, the cases tried, the clean errors and the crashes.
"""

import collections
import re
import traceback

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from sklearn.pipeline import Pipeline

from sklearn_radar import ClusterMerger, DopplerDensityFilter, FrameTransform, RadarDBSCAN

_RAW = {
    "range_sc": [1.0, 5.0, 10.0, 20.0, 50.0],
    "azimuth_sc": [-0.5, 0.0, 0.3],
    "vr": [-5.0, -0.5, 0.0, 3.0, 8.0],
    "sensor_x": [3.6, 0.0],
    "sensor_y": [-0.7, 0.7],
    "sensor_yaw": [-1.2, 0.0, 1.3],
    "ego_x_seq": [0.0, 1.5],
    "ego_y_seq": [0.0, -2.0],
    "ego_yaw_seq": [0.0, 0.4],
    "ego_vx": [0.0, 8.0],
    "ego_yaw_rate": [0.0, 0.1],
    "heading": [0.0, 0.0, 0.7],
    "v_r": [-3.0, 4.0, 5.0, 5.5],
}
_EXTREME = [1e-300, 5e-324, 1e15, -1e15, -0.0, 1e300, -1e300, 1e154, 1.7e308]
_DTYPES = ["str", "object", "bool", "float32", "int64", "category", "complex", "datetime"]


def _corrupt(table, kind, column, row, draw, extreme):
    """``table`` with one corruption applied; ``column`` and ``row`` say where, ``extreme`` the values to use."""
    table = table.copy()
    numeric = column in table.columns and pd.api.types.is_numeric_dtype(table[column].dtype)
    if kind in ("nan", "inf", "-inf", "extreme", "dtype") and not numeric:
        return table  # an earlier corruption already made the column non-numeric (or dropped it)
    if kind in ("nan", "inf", "-inf", "extreme"):
        value = {"nan": np.nan, "inf": np.inf, "-inf": -np.inf}.get(kind)
        if value is None:
            value = draw(st.sampled_from(extreme))
        if len(table):
            values = table[column].to_numpy(dtype=np.float64, copy=True)
            values[row % len(table)] = value
            table[column] = values
    elif kind == "duplicate":
        if len(table):
            table = pd.concat([table, table.iloc[[row % len(table)] * draw(st.integers(1, 3))]], ignore_index=True)
    elif kind == "dtype":
        dtype = draw(st.sampled_from(_DTYPES))
        values = table[column]
        if dtype == "str":
            table[column] = values.astype(str)
        elif dtype == "object":
            table[column] = values.astype(object)
        elif dtype == "category":
            table[column] = values.astype("category")
        elif dtype == "complex":
            table[column] = values.astype(np.complex128)
        elif dtype == "datetime":
            microseconds = np.nan_to_num(values.to_numpy(dtype=np.float64), posinf=0, neginf=0).clip(-1e15, 1e15)
            table[column] = pd.to_datetime(microseconds.astype(np.int64), unit="us")
        elif dtype == "int64":
            finite = np.nan_to_num(values.to_numpy(dtype=np.float64), posinf=0, neginf=0).clip(-1e15, 1e15)
            table[column] = np.round(finite).astype(np.int64)
        else:
            table[column] = values.astype(dtype)
    elif kind == "drop":
        table = table.drop(columns=[column])
    elif kind == "empty":
        table = table.iloc[:0]
    return table


@st.composite
def _tables(draw, extreme):
    """A detection table with the raw and the working columns, possibly corrupted; (table, corruptions)."""
    n = draw(st.integers(1, 16))
    column = lambda values: draw(st.lists(st.sampled_from(values), min_size=n, max_size=n))  # noqa: E731
    timestamp = np.array(column([0, 60_000, 120_000, 180_000, 240_000]), dtype=np.int64)
    table = pd.DataFrame({name: np.array(column(values), dtype=np.float64) for name, values in _RAW.items()})
    table["timestamp"] = timestamp
    table["sequence"] = np.array(column([1, 2]), dtype=np.int64)
    table["x"] = np.array(draw(st.lists(st.integers(0, 40), min_size=n, max_size=n))) / 10
    table["y"] = np.array(draw(st.lists(st.integers(0, 20), min_size=n, max_size=n))) / 10
    table["t"] = timestamp * 1e-6
    table["keep"] = np.array(column([True, True, False]))
    table["range_sc"] = np.hypot(table["x"], table["y"]) + 0.5
    kinds = st.sampled_from(["nan", "inf", "-inf", "extreme", "extreme", "duplicate", "duplicate", "dtype", "drop"])
    kinds = kinds | st.just("empty") if draw(st.integers(0, 9)) == 0 else kinds  # an empty table now and then
    corruptions = draw(
        st.lists(st.tuples(kinds, st.sampled_from(sorted(table.columns)), st.integers(0, 99)), max_size=3)
    )
    for kind, name, row in corruptions:
        if name in table.columns:
            table = _corrupt(table, kind, name, row, draw, extreme)
    return table, corruptions


_BAD_PARAMS = [
    ("eps_xy", -1.0),
    ("min_samples", 0),
    ("metric", "euclid"),
    ("eps_t", np.nan),
    ("eps_d", 0.0),
    ("mode", "fast"),
    ("d_xy", -2.0),
    ("frame", "world"),
    ("dt", np.inf),
]


def _stage1(draw):
    metric = draw(st.sampled_from(["box", "xy", "xyv"]))
    return RadarDBSCAN(
        metric=metric,
        eps_xy=draw(st.sampled_from([0.5, 1.0])),
        eps_xyv=draw(st.sampled_from([0.5, 1.0])),
        min_samples=draw(st.sampled_from([1, 2, 3])),
        vr_min=draw(st.sampled_from([-np.inf, 0.4])),
        eps_t=draw(st.sampled_from([0.1, 0.25, None])),
        causal=draw(st.sampled_from([False, False, True])),
    )


def _merger(draw):
    return ClusterMerger(
        mode=draw(st.sampled_from(["continuation", "velocity"])),
        eps_d=draw(st.sampled_from([0.94, 3.0])),
        min_samples=draw(st.sampled_from([1, 1, 2])),
        unknown_velocity=draw(st.sampled_from(["reject", "accept"])),
        stage1=_stage1(draw),
    )


_TARGETS = {
    "FrameTransform": lambda draw: FrameTransform(frame=draw(st.sampled_from(["frame", "car"]))),
    "DopplerDensityFilter": lambda draw: DopplerDensityFilter(causal=draw(st.booleans())),
    "RadarDBSCAN": _stage1,
    "ClusterMerger": _merger,
    "Pipeline": lambda draw: Pipeline(
        [("frame", FrameTransform()), ("filter", DopplerDensityFilter()), ("cluster", _merger(draw))]
    ),
}


@st.composite
def _cases(draw, target, extreme=tuple(_EXTREME)):
    model = _TARGETS[target](draw)
    if draw(st.integers(0, 19)) == 0:  # now and then a bad parameter value
        name, value = draw(st.sampled_from(_BAD_PARAMS))
        params = model.get_params()
        keys = [key for key, current in params.items() if not hasattr(current, "get_params")]  # not a step
        key = next((key for key in keys if key == name or key.endswith("__" + name)), None)
        if key is not None:
            model.set_params(**{key: value})
    table, corruptions = draw(_tables(extreme))
    return model, table, corruptions, draw(st.randoms(use_true_random=False))


COUNTS = collections.defaultdict(collections.Counter)


def _names(model):
    """Parameter names (with their nested forms) and estimator names that an error message may name."""
    names = set()
    for key in model.get_params():
        names.update(key.split("__"))
    return names


def _run(model, table):
    """Labels (clusterers) or the transformed table."""
    if hasattr(model, "fit_predict") and not isinstance(model, (FrameTransform, DopplerDensityFilter)):
        return np.asarray(model.fit_predict(table))
    return model.fit_transform(table)


CRASHES = collections.defaultdict(dict)  # target -> {(exception type, message): first model and table}


def _check(target, model, table, random, *, collect=False):
    """Run one case; a crash raises, or with ``collect`` is recorded in CRASHES and the run goes on."""
    counts = COUNTS[target]
    counts["tried"] += 1
    try:
        out = _run(model, table)
    except ValueError as error:
        message = str(error)
        named = _names(model) | set(map(str, table.columns)) | {"X"}
        assert any(re.search(rf"(?<![A-Za-z0-9_]){re.escape(name)}(?![A-Za-z0-9_])", message) for name in named), (
            f"{target}: the ValueError names no column or parameter: {message!r}"
        )
        counts["clean ValueError"] += 1
        return
    except Exception as error:
        counts["crash"] += 1
        if not collect:
            raise
        frames = [
            f"{frame.filename.rsplit('/', 1)[-1]}:{frame.lineno}" for frame in traceback.extract_tb(error.__traceback__)
        ]
        where = next((frame for frame in reversed(frames) if not frame.startswith("test_fuzz")), "?")
        ours = [frame for frame in traceback.extract_tb(error.__traceback__) if "/sklearn_radar/" in frame.filename]
        where = f"{ours[-1].filename.split('/sklearn_radar/')[-1]}:{ours[-1].lineno}" if ours else where
        kind = f"{type(error).__name__} at {where}"
        CRASHES[target].setdefault((kind, str(error)), (repr(model), table.to_dict("list")))
        counts[f"crash: {kind}: {error}"] += 1
        return
    counts["succeeded"] += 1
    assert len(out) == len(table)
    permutation = list(range(len(table)))
    random.shuffle(permutation)
    permutation = np.array(permutation, dtype=np.int64)
    out_permuted = _run(model, table.iloc[permutation])
    if isinstance(out, np.ndarray):
        assert out.shape == (len(table),) and out.dtype.kind == "i"
        sequence = table["sequence"].to_numpy() if "sequence" in table.columns else np.zeros(len(table))
        for label in np.unique(out[out >= 0]):
            assert len(np.unique(sequence[out == label])) == 1, "a cluster spans two sequences"
        back = np.empty_like(out_permuted)
        back[permutation] = out_permuted
        pairs = set(zip(out.tolist(), back.tolist(), strict=True))
        assert len(pairs) == len(set(out.tolist())) == len(set(back.tolist())), "labels follow the row order"
    else:
        back = out_permuted.iloc[np.argsort(permutation)]
        assert list(back.columns) == list(out.columns)
        for name in out.columns:
            a, b = out[name].to_numpy(), back[name].to_numpy()
            if a.dtype.kind == "f":
                np.testing.assert_allclose(a, b, rtol=1e-12, atol=0, equal_nan=True, err_msg=name)
            else:
                np.testing.assert_array_equal(a, b, err_msg=name)


def _report(target):
    counts = COUNTS[target]
    print(
        f"\n{target}: {counts['tried']} cases tried, {counts['succeeded']} succeeded, "
        f"{counts['clean ValueError']} clean ValueErrors, {counts['crash']} crashes"
    )
    for key, count in sorted(counts.items()):
        if key.startswith("crash: "):
            print(f"  {count} x {key}")


# Derandomized: CI runs the same sample every time.
_FAST = settings(
    max_examples=25, deadline=None, database=None, derandomize=True, suppress_health_check=list(HealthCheck)
)
_LONG = settings(max_examples=1000, deadline=None, database=None, suppress_health_check=list(HealthCheck))


@pytest.mark.parametrize("target", sorted(_TARGETS))
def test_fuzz_sample(target):
    @_FAST
    @given(case=_cases(target))
    def check(case):
        model, table, _corruptions, random = case
        _check(target, model, table, random)

    check()
    _report(target)


@pytest.mark.slow
@pytest.mark.parametrize("target", sorted(_TARGETS))
def test_fuzz_long(target):
    @_LONG
    @given(case=_cases(target))
    def check(case):
        model, table, _corruptions, random = case
        _check(target, model, table, random, collect=True)

    check()
    _report(target)
    assert COUNTS[target]["tried"] >= 1000
    assert not CRASHES[target], "\n".join(
        f"{kind}: {message}\n  first case: {model}\n  {table}"
        for (kind, message), (model, table) in CRASHES[target].items()
    )


@pytest.mark.parametrize("model", [DopplerDensityFilter(), RadarDBSCAN()], ids=lambda model: type(model).__name__)
def test_coordinates_beyond_the_grid_are_a_clean_error(model):
    X = pd.DataFrame({"x": [1e300, 0.0], "y": 0.0, "v_r": 5.0, "t": 0.0})
    with pytest.raises(ValueError, match="column 'x'"):
        model.fit_predict(X) if isinstance(model, RadarDBSCAN) else model.fit_transform(X)
