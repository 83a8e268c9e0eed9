"""The converter of the reproduce records (``reproduce._records``): every record read back as written, bad files."""

import dataclasses
import json
import sys
import types
import typing
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sklearn_radar.reproduce._budget import Budget
from sklearn_radar.reproduce._experiment_records import ExperimentResult
from sklearn_radar.reproduce._records import JsonRecord
from sklearn_radar.reproduce._results import FigureRecord, RunResults

DEFAULT_RUN = Path(__file__).parents[1] / "data" / "results_default_run.json"
# Every record (importing RunResults imports them all); a slotted dataclass replaces the class it was made from.
RECORDS = sorted(
    {getattr(sys.modules[cls.__module__], cls.__name__) for cls in JsonRecord.__subclasses__()},
    key=lambda cls: cls.__name__,
)

# ----------------------------------------------------------------------------- every record, generated


def _optional_of(hint):
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        (inner,) = [arg for arg in typing.get_args(hint) if arg is not type(None)]
        return inner
    return None


_JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=5),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=5), inner, max_size=3),
    max_leaves=6,
)


def _values(hint):
    """Values of a field's type: floats with nan and +-inf, None for optional types, short lists and dicts."""
    inner = _optional_of(hint)
    if inner is not None:
        return st.none() | _values(inner)
    if dataclasses.is_dataclass(hint):
        return _records(hint)
    origin, args = typing.get_origin(hint) or hint, typing.get_args(hint)
    if origin is dict:
        key, item = args or (str, typing.Any)
        return st.dictionaries(st.integers() if key is int else st.text(max_size=5), _values(item), max_size=2)
    if origin is list:
        return st.lists(_values(args[0] if args else typing.Any), max_size=3)
    return {float: st.floats(), int: st.integers(), str: st.text(max_size=8), bool: st.booleans()}.get(
        hint, _JSON_VALUES
    )


def _special(cls, name):
    """The fields whose values are constrained, or None."""
    if cls is Budget and name in ("n_sequences", "duration"):
        return st.none()  # not in the JSON form: read back as None
    if cls is FigureRecord and name == "drawn":  # the figure names share the object with "missing"
        return st.dictionaries(st.text(max_size=5).filter(lambda key: key != "missing"), st.text(max_size=5))
    if cls is RunResults and name == "experiments":  # filed under their numbers
        return st.lists(_records(ExperimentResult), max_size=2).map(lambda found: {r.number: r for r in found})
    return None


def _records(cls):
    hints = typing.get_type_hints(cls)
    fields = {f.name: _special(cls, f.name) for f in dataclasses.fields(cls)}
    return st.builds(cls, **{name: _values(hints[name]) if s is None else s for name, s in fields.items()})


def _write(record):
    document = record.to_json_dict(figures=True) if isinstance(record, RunResults) else record.to_json_dict()
    return json.dumps(document, indent=1)


@pytest.mark.parametrize("cls", RECORDS, ids=lambda cls: cls.__name__)
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(data=st.data())
def test_every_record_reads_back_what_it_wrote(cls, data):
    record = data.draw(_records(cls))
    text = _write(record)
    read = cls.from_json_dict(json.loads(text))
    # repr compares nan as equal to nan, which == does not.
    assert repr(read) == repr(record)
    assert _write(read) == text


@settings(max_examples=40, deadline=None)
@given(record=_records(ExperimentResult))
def test_an_optional_field_left_none_is_absent_and_a_search_is_flat(record):
    document = record.to_json_dict()
    for f in dataclasses.fields(record):
        if f.default is None and getattr(record, f.name) is None:
            assert f.name not in document
    assert "search" not in document
    if record.search is not None:
        assert {"cv_best", "convergence", "best_source", "search_wall_time_s"} <= set(document)


# ----------------------------------------------------------------------------- bad files


def _bad_file(tmp_path, change):
    document = json.loads(DEFAULT_RUN.read_text())
    change(document)
    path = tmp_path / "results.json"
    path.write_text(json.dumps(document))
    return path


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda d: d["experiments"]["2"].update(v1_test="0.5"), "experiments.2.v1_test should be a number, not str"),
        (lambda d: d["experiments"]["2"].pop("v1_test"), "experiments.2 lacks the key 'v1_test'"),
        (lambda d: d["meta"]["data"].pop("n_test"), "meta.data lacks the key 'n_test'"),
        (lambda d: d["experiments"]["2"].update(v1=0.5), "experiments.2 has the key 'v1', which ExperimentResult"),
        (
            lambda d: next(iter(d["baselines"].values())).pop("cv_best"),
            "baselines.sklearn DBSCAN per 0.25 s window lacks the key 'cv_best' (SearchRecord)",
        ),
        (lambda d: d["meta"].update(seed=True), "meta.seed should be an integer, not bool"),
        (lambda d: d["meta"]["completed"].append(3), "meta.completed.16 should be a string, not int"),
        (lambda d: d["filter"].update(table_ii={}), "filter.table_ii should be a list, not dict"),
        (lambda d: d.update(experiments={"x": {}}), "experiments has the key 'x', which is not an integer"),
        (lambda d: d["experiments"].update({"3": d["experiments"]["2"]}), "experiment '3' holds the record of #2"),
        (lambda d: d.update(meta=[]), "meta should be an object (RunMeta), not list"),
    ],
)
def test_a_bad_file_gives_a_value_error_naming_the_file_and_the_key(tmp_path, change, message):
    path = _bad_file(tmp_path, change)
    with pytest.raises(ValueError, match=r"results\.json") as error:
        RunResults.read(path)
    assert str(error.value).startswith(f"{path}: ")
    assert message in str(error.value)


def test_a_file_that_is_not_json_gives_a_value_error_naming_it(tmp_path):
    path = tmp_path / "results.json"
    path.write_text('{"meta": ')
    with pytest.raises(ValueError, match=r"results\.json: not JSON"):
        RunResults.read(path)
