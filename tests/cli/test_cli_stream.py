"""``sklearn-radar stream``: options checked before writing, no foreign file replaced, predictions as ``cluster``."""

import json

import numpy as np
import pandas as pd
import pytest

from sklearn_radar.cli import main
from sklearn_radar.cli._stream import OBJECTS_HEADER
from sklearn_radar.datasets import load_radarscenes, make_scenes, write_radarscenes
from sklearn_radar.experiments import paper_params
from sklearn_radar.experiments._saved import load_params, setting_pipeline
from sklearn_radar.online import OnlinePipeline
from sklearn_radar.online._replay import replay

STAGE1 = {key.split("__", 1)[1]: value for key, value in paper_params(8).items()}


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    path = tmp_path_factory.mktemp("data") / "two"
    write_radarscenes(make_scenes(n_sequences=2, duration=2.0, random_state=4), path)
    return path


@pytest.fixture
def params_file(tmp_path):
    setting = {"experiment": 13, "v1_test": 0.5, "params": paper_params(13), "stage1_params": STAGE1}
    path = tmp_path / "params.json"
    path.write_text(json.dumps({"best": "13", "experiments": {"13": setting}}))
    return path


def _argv(data, params, out, *options):
    return ["stream", "--data", str(data), "--params", str(params), "--out", str(out), *options]


def _one_line_error(capsys):
    err = capsys.readouterr().err
    assert err.startswith("sklearn-radar: error:") and len(err.strip().splitlines()) == 1, err
    return err


def test_a_bad_option_writes_nothing(tmp_path, capsys):
    assert main(_argv("nowhere", "nowhere.json", tmp_path / "out.json", "--experiment", "0")) == 2
    assert "--experiment" in _one_line_error(capsys)
    assert list(tmp_path.iterdir()) == []


def test_a_missing_params_file_writes_nothing(folder, tmp_path, capsys):
    assert main(_argv(folder, tmp_path / "absent.json", tmp_path / "out.json")) == 1
    assert "parameter file not found" in _one_line_error(capsys)
    assert list(tmp_path.iterdir()) == []


def test_stream_writes_the_predictions_and_objects_it_prints(folder, params_file, tmp_path, capsys):
    out, objects = tmp_path / "predictions.json", tmp_path / "objects.csv"
    assert main(_argv(folder, params_file, out, "--objects", str(objects))) == 0
    printed = capsys.readouterr().out
    assert "latency per scan (wall): p50" in printed and "(cpu): p50" in printed and "real-time factor" in printed
    predictions = json.loads(out.read_text())["predictions"]
    data = load_radarscenes(folder).data
    assert set(predictions) == set(data["uuid"])
    # The instances are the final object ids of a replay of the same folder with the same setting.
    online = OnlinePipeline(setting_pipeline(load_params(params_file), params_file))
    expected = replay(online, data)["object_ids"]
    got = np.array([predictions[u][1] for u in data["uuid"]])
    np.testing.assert_array_equal(got, expected)
    np.testing.assert_array_equal([predictions[u][0] for u in data["uuid"]], (expected >= 0).astype(int))
    assert objects.read_text().splitlines()[0] == OBJECTS_HEADER
    table = pd.read_csv(objects)
    assert len(table) > 0 and table["n_detections"].min() >= 1
    # Run again: both files are ours, so they are replaced, with the same content.
    first = out.read_bytes(), objects.read_bytes()
    assert main(_argv(folder, params_file, out, "--objects", str(objects))) == 0
    assert (out.read_bytes(), objects.read_bytes()) == first


@pytest.mark.parametrize("which", ["out", "objects"])
def test_stream_never_replaces_another_file(folder, params_file, tmp_path, capsys, which):
    out, objects = tmp_path / "predictions.json", tmp_path / "objects.csv"
    foreign = {"out": out, "objects": objects}[which]
    foreign.write_text("mine\n")
    assert main(_argv(folder, params_file, out, "--objects", str(objects))) == 1
    assert str(foreign) in _one_line_error(capsys)
    assert foreign.read_text() == "mine\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["params.json", foreign.name])


def test_objects_and_out_must_differ(folder, params_file, tmp_path, capsys):
    out = tmp_path / "predictions.json"
    assert main(_argv(folder, params_file, out, "--objects", str(out))) == 2  # a usage error
    assert "same file" in _one_line_error(capsys)
    assert not out.exists()


def test_from_params_builds_the_saved_pipeline(params_file):
    online = OnlinePipeline.from_params(params_file)
    saved = setting_pipeline(load_params(params_file), params_file)
    leaves = [
        {
            key: value
            for key, value in pipeline.get_params().items()
            if not hasattr(value, "get_params") and key != "steps"
        }
        for pipeline in (online.pipeline, saved)
    ]
    assert leaves[0] == leaves[1]
    merger = online.pipeline.steps[-1][1]
    assert merger.eps_d == paper_params(13)["merge__eps_d"] and merger.stage1.eps_xyv == STAGE1["eps_xyv"]
