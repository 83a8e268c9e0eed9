"""The object experiment's saved setting through ``params.json``, ``cluster`` and ``stream``."""

import json

import numpy as np
import pytest

from sklearn_radar.cli import main
from sklearn_radar.datasets import load_radarscenes, make_scenes, write_radarscenes
from sklearn_radar.experiments import object_pipeline
from sklearn_radar.experiments._saved import load_params, setting_pipeline

STAGE1 = {
    "cluster__eps_xyv": 1.2,
    "cluster__vr_scale": 2.0,
    "cluster__min_samples": 3,
    "cluster__vr_min": 0.5,
}
STAGE2 = {
    "merge__eps_d": 1.5,
    "merge__eps_phi": 0.4,
    "merge__eps_v": 1.0,
    "merge__eps_t2": 0.35,
    "merge__min_samples": 1,
}


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    path = tmp_path_factory.mktemp("data") / "two"
    write_radarscenes(make_scenes(n_sequences=2, duration=3.0, random_state=5), path)
    return path


def _params_file(path, **changes):
    setting = {"experiment": "objects", "v1_test": 0.5, "pq_test": 0.4, "params": STAGE2, "stage1_params": STAGE1}
    setting.update(changes)
    path.write_text(json.dumps({"best": "objects", "objective": "pq", "experiments": {"objects": setting}}))
    return path


def test_load_params_and_the_pipeline_of_the_object_setting(tmp_path):
    path = _params_file(tmp_path / "params.json")
    setting = load_params(path)
    assert setting["experiment"] == "objects" and load_params(path, "objects") == setting
    pipeline = setting_pipeline(setting, path)
    expected = object_pipeline(2, stage1_params=STAGE1, params=STAGE2)
    assert pipeline.get_params(deep=False).keys() == expected.get_params(deep=False).keys()
    assert repr(pipeline) == repr(expected)


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        ({"experiment": 13}, "must be 'objects'"),
        ({"stage1_params": None}, "stage1_params"),
        ({"params": {"merge__eps_q": 1.0}}, "merge__eps_q"),
        ({"params": {"merge__eps_d": -1.0}}, "eps_d"),
    ],
)
def test_a_bad_object_setting_is_named(tmp_path, changes, match):
    path = _params_file(tmp_path / "params.json", **changes)
    with pytest.raises(ValueError, match=match):
        setting_pipeline(load_params(path), path)


def _predicted_instances(out, scenes):
    written = json.loads(out.read_text())["predictions"]
    return np.array([written[uuid][1] for uuid in scenes.data["uuid"]])


def test_cluster_and_stream_apply_the_object_setting(folder, tmp_path, capsys):
    params = _params_file(tmp_path / "params.json")
    scenes = load_radarscenes(folder)
    labels = {}
    for command in ("cluster", "stream"):
        out = tmp_path / f"{command}.json"
        argv = [command, "--data", str(folder), "--params", str(params), "--out", str(out), "--experiment", "objects"]
        assert main(argv) == 0
        assert "experiment 'objects'" in capsys.readouterr().out
        labels[command] = _predicted_instances(out, scenes)
    # cluster: the partition of the pipeline run apart, offline.
    offline = object_pipeline(2, stage1_params=STAGE1, params=STAGE2).fit_predict(scenes.data)
    pairs = set(zip(labels["cluster"].tolist(), offline.tolist(), strict=True))
    assert len(pairs) == len(set(offline.tolist())) == len(set(labels["cluster"].tolist())) > 2
    # stream: the causal pipeline's clusters, each under one persistent object id (merged ones share the older id).
    causal = object_pipeline(2, stage1_params=STAGE1, params=STAGE2, causal=True).fit_predict(scenes.data)
    np.testing.assert_array_equal(labels["stream"] == -1, causal == -1)
    pairs = set(zip(causal.tolist(), labels["stream"].tolist(), strict=True))
    assert len(pairs) == len(set(causal.tolist())) > 2


def test_a_bad_experiment_option_names_objects(tmp_path, capsys):
    params = _params_file(tmp_path / "params.json")
    argv = ["cluster", "--data", str(tmp_path), "--params", str(params), "--out", str(tmp_path / "o.json")]
    assert main([*argv, "--experiment", "object"]) != 0
    assert "'objects'" in capsys.readouterr().err
