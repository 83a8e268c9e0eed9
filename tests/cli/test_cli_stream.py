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
from sklearn_radar.online import OnlinePipeline, Tracker
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


TRACKER = {"min_hits": 2, "max_age": 1.0, "gate": 5.0}


def _with_tracker(params_file, tracker):
    saved = json.loads(params_file.read_text())
    saved["tracker"] = {"params": tracker, "tuned_on": "objects", "criterion": "MOTA", "train_score": 0.1}
    params_file.write_text(json.dumps(saved))
    return params_file


def test_stream_track_writes_the_saved_trackers_ids(folder, params_file, tmp_path, capsys):
    """--track: each detection's instance is the saved Tracker's id at its scan, as OnlinePipeline(tracker=...)."""
    _with_tracker(params_file, TRACKER)
    out = tmp_path / "predictions.json"
    assert main(_argv(folder, params_file, out, "--track")) == 0
    printed = capsys.readouterr().out
    assert "tracked with the saved Tracker (min_hits=2, max_age=1.0, gate=5.0):" in printed
    predictions = json.loads(out.read_text())["predictions"]
    data = load_radarscenes(folder).data
    online = OnlinePipeline(setting_pipeline(load_params(params_file), params_file), tracker=Tracker(**TRACKER))
    expected = replay(online, data)["track_id"]
    assert (expected >= 0).any()
    got = np.array([predictions[u][1] for u in data["uuid"]])
    np.testing.assert_array_equal(got, expected)
    np.testing.assert_array_equal([predictions[u][0] for u in data["uuid"]], (expected >= 0).astype(int))
    n_tracks = len(np.unique(np.c_[data["sequence"].to_numpy()[expected >= 0], expected[expected >= 0]], axis=0))
    assert f": {n_tracks} tracks" in printed


def test_stream_without_track_ignores_the_saved_tracker(folder, params_file, tmp_path):
    """The saved tracker changes nothing unless --track asks for it: the final object ids, as before."""
    out, plain = tmp_path / "with.json", tmp_path / "plain.json"
    assert main(_argv(folder, params_file, plain)) == 0
    _with_tracker(params_file, TRACKER)
    assert main(_argv(folder, params_file, out)) == 0
    assert out.read_bytes() == plain.read_bytes()


def test_stream_track_needs_a_saved_tracker(folder, params_file, tmp_path, capsys):
    out = tmp_path / "predictions.json"
    assert main(_argv(folder, params_file, out, "--track")) == 1
    err = _one_line_error(capsys)
    assert "saves no tuned tracker (the key 'tracker')" in err and str(params_file) in err
    assert not out.exists()


@pytest.mark.parametrize(
    ("tracker", "said"),
    [({"min_hits": 0}, "does not take"), ({"speed": 3.0}, "does not take"), ([1, 2], "must be an object")],
)
def test_stream_track_refuses_a_bad_saved_tracker(folder, params_file, tmp_path, capsys, tracker, said):
    saved = json.loads(params_file.read_text())
    saved["tracker"] = {"params": tracker} if isinstance(tracker, dict) else tracker
    params_file.write_text(json.dumps(saved))
    out = tmp_path / "predictions.json"
    assert main(_argv(folder, params_file, out, "--track")) == 1
    err = _one_line_error(capsys)
    assert said in err and "'tracker'" in err and str(params_file) in err
    assert not out.exists()


def test_stream_track_does_not_go_with_a_classifier(tmp_path, capsys):
    argv = ["stream", "--data", "d", "--classifier", "c", "--out", str(tmp_path / "o.json"), "--track"]
    assert main(argv) == 2
    assert "--track does not go with --classifier" in _one_line_error(capsys)
    assert list(tmp_path.iterdir()) == []
