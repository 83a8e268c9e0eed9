"""The learned experiment's pipeline and its params.json entry, without a run."""

import json

import pytest

from sklearn_radar.cluster import LinkClustering
from sklearn_radar.experiments import object_pipeline
from sklearn_radar.experiments._learned import learned_pipeline
from sklearn_radar.experiments._saved import load_params, setting_pipeline


def test_the_pipeline_is_the_object_experiment_s_front_and_link_clustering():
    pipeline = learned_pipeline({"link__max_iter": 7})
    assert [name for name, _ in pipeline.steps] == ["frame", "filter", "link"]
    assert isinstance(pipeline[-1], LinkClustering) and pipeline[-1].max_iter == 7
    assert repr(pipeline[:2]) == repr(object_pipeline(1)[:2])


def _params_file(path, **changes):
    entry = {"experiment": "learned", "v1_test": 0.5, "pq_test": 0.4, "cv_pq": None, "params": {}}
    entry.update({"stage1_params": None, "model": "learned.joblib", **changes})
    path.write_text(json.dumps({"best": "learned", "objective": "pq", "experiments": {"learned": entry}}))
    return path


def test_load_params_reads_the_entry_and_no_pipeline_is_built_from_it(tmp_path):
    path = _params_file(tmp_path / "params.json")
    setting = load_params(path, "learned")
    assert setting["model"] == "learned.joblib" and load_params(path) == setting
    with pytest.raises(ValueError, match="'learned' names no causal model"):
        setting_pipeline(setting, path)


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        ({"model": None}, "must name its fitted model's file in the key 'model'"),
        ({"experiment": "objects"}, "must be 'learned'"),
        ({"stage1_params": {"cluster__eps_xyv": 1.0}}, "stage1_params"),
    ],
)
def test_a_bad_entry_is_refused_naming_the_file(tmp_path, changes, match):
    path = _params_file(tmp_path / "params.json", **changes)
    with pytest.raises(ValueError, match=match) as raised:
        load_params(path, "learned")
    assert str(path) in str(raised.value)
