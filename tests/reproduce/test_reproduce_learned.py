"""The learned grouping in 'sklearn-radar reproduce': its record, its model file, params.json, cluster and stream."""

import contextlib
import io
import json

import numpy as np
import pandas as pd
import pytest
from sklearn.metrics import adjusted_rand_score

import sklearn_radar.reproduce._learned as learned_step
import sklearn_radar.reproduce._sections._learned as learned_section
from sklearn_radar.cli import main
from sklearn_radar.datasets import load_radarscenes
from sklearn_radar.experiments._learned import learned_pipeline, load_learned
from sklearn_radar.metrics import instance_errors, panoptic_quality, precluster_target
from sklearn_radar.reproduce._results import RunResults
from sklearn_radar.reproduce._run import parse_experiments

#: Few boosting iterations: the tests check the plumbing, not the model.
SMALL = {"link__max_iter": 10}
#: What the run does not measure (it does not depend on the data).
_LABEL_COLUMNS = ("uuid", "track_id", "label_id")


@pytest.fixture(scope="module")
def learned_run(tiny_folder, tmp_path_factory):
    out = tmp_path_factory.mktemp("learned") / "out"
    patch = pytest.MonkeyPatch()
    patch.setattr(learned_step, "LEARNED_PARAMS", SMALL)
    args = ["reproduce", "--data", str(tiny_folder), "--out", str(out), "--n-iter", "2", "--objective", "pq"]
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            assert main([*args, "--experiments", "objects,learned,baselines"]) == 0
    finally:
        patch.undo()
    return out


def _sequence_table(folder, number):
    """One sequence as the run reads it: its measured columns and pre-clustered target, and its rows' uuids."""
    scenes = load_radarscenes(folder, sequences=number)
    X = scenes.data[[c for c in scenes.data.columns if c not in _LABEL_COLUMNS]]
    return X, precluster_target(scenes.data, scenes.target), scenes.data


def _direct_model(folder, results, causal=False):
    """LinkClustering fitted on the run's training half here, apart from the reproduce code."""
    tables = [_sequence_table(folder, n) for n in results["meta"]["data"]["train_sequences"]]
    X = pd.concat([X for X, _, _ in tables], ignore_index=True)
    y = np.concatenate([y for _, y, _ in tables])
    params = {**(learned_step.LEARNED_CAUSAL_PARAMS if causal else {}), **SMALL, "link__window": 0.5}
    params.update({"link__random_state": results["meta"]["seed"], "link__n_jobs": 1})
    return learned_pipeline({**params, "link__causal": causal, "filter__causal": causal}).fit(X, y)


def _test_scores(folder, results, model):
    """(target, labels, times, groups) of the run's test half labelled by ``model``."""
    targets, labels, times, groups = [], [], [], []
    for number in results["meta"]["data"]["test_sequences"]:
        X, target, data = _sequence_table(folder, number)
        targets.append(target)
        labels.append(model.predict(X))
        times.append(data["timestamp"].to_numpy(dtype=np.float64) * 1e-6)
        groups.append(np.full(len(X), number))
    return tuple(map(np.concatenate, (targets, labels, times, groups)))


def test_learned_is_not_in_the_default_run_but_can_be_chosen():
    assert "learned" not in parse_experiments(None)
    assert parse_experiments("objects,learned,baselines") == ["objects", "baselines", "learned"]


def test_the_record_scores_what_a_directly_fitted_model_labels(learned_run, tiny_folder):
    results = json.loads((learned_run / "results.json").read_text())
    record = results["learned"]
    assert record["model_file"] == "learned.joblib" and (learned_run / "learned.joblib").is_file()
    model = _direct_model(tiny_folder, results)
    assert record["link_threshold"] == model[-1].link_threshold_
    assert record["min_cluster_size"] == model[-1].min_cluster_size_
    test = results["meta"]["data"]["test_sequences"]
    targets, labels, times, groups = [], [], [], []
    for number in test:
        X, target, data = _sequence_table(tiny_folder, number)
        targets.append(target)
        labels.append(model.predict(X))
        times.append(data["timestamp"].to_numpy(dtype=np.float64) * 1e-6)
        groups.append(np.full(len(X), number))
    target, label, time, group = map(np.concatenate, (targets, labels, times, groups))
    assert record["instance_test"]["pq"] == pytest.approx(panoptic_quality(target, label, times=time, groups=group).pq)
    errors = instance_errors(target, label, times=time, groups=group)
    assert record["errors"]["learned grouping"] == pytest.approx(errors, nan_ok=True)
    assert set(record["errors"]) >= {"learned grouping", "object experiment"} and len(record["errors"]) == 3


def test_the_causal_record_scores_what_a_directly_fitted_causal_model_labels(learned_run, tiny_folder):
    results = json.loads((learned_run / "results.json").read_text())
    record = results["learned"]["causal"]
    assert record["model_file"] == "learned_causal.joblib" and (learned_run / "learned_causal.joblib").is_file()
    model = _direct_model(tiny_folder, results, causal=True)
    assert record["link_threshold"] == model[-1].link_threshold_
    assert record["min_cluster_size"] == model[-1].min_cluster_size_
    target, label, time, group = _test_scores(tiny_folder, results, model)
    assert record["instance_test"]["pq"] == pytest.approx(panoptic_quality(target, label, times=time, groups=group).pq)
    assert load_learned(learned_run / "learned_causal.joblib")[-1].causal is True
    link = model[-1].get_params()
    assert {k.removeprefix("link__"): v for k, v in record["params"].items() if k.startswith("link__")} == link
    expected = {**learned_step.LEARNED_CAUSAL_PARAMS, **SMALL}  # (the test run's smaller model)
    assert all(record["params"][key] == value for key, value in expected.items())
    assert record["params"]["link__cluster_window"] is None


def test_the_report_says_what_a_causal_models_cluster_window_does(learned_run):
    # A run whose causal model had a cluster context (the main job's for a round; a run of one's own): the report
    # names the setting and says in words what it does.
    results = RunResults.read(learned_run / "results.json")
    results.learned.causal.params["link__cluster_window"] = 0.5
    paragraph = "\n".join(learned_section.markdown(results)).split("The causal learned grouping", 1)[1]
    assert "cluster_window=0.5" in paragraph
    assert "also sees the cluster its earlier detection already belongs to, over the last 0.5 s" in paragraph


def test_params_json_points_to_the_model_with_the_front(learned_run):
    saved = json.loads((learned_run / "params.json").read_text())
    entry = saved["experiments"]["learned"]
    assert entry["model"] == "learned.joblib" and entry["cv_pq"] is None
    assert entry["causal_model"] == "learned_causal.joblib"
    assert entry["params"]["filter__vr_threshold"] == 0.1 and not any(k.startswith("link__") for k in entry["params"])
    assert saved["best"] == "objects"  # the learned grouping is not ranked
    marker = json.loads((learned_run / "run.json").read_text())
    assert "learned.joblib" in marker["files"] and "learned_causal.joblib" in marker["files"]
    assert RunResults.read(learned_run / "results.json").to_json_dict() == json.loads(
        (learned_run / "results.json").read_text()
    )


def test_report_section(learned_run):
    report = (learned_run / "report.md").read_text()
    assert "### The learned grouping" in report
    causal = json.loads((learned_run / "results.json").read_text())["learned"]["causal"]
    assert f"| learned grouping, causal | past only | {causal['instance_test']['pq']:.3f} |" in report
    assert "| object experiment, causal | past only |" in report
    paragraph = report.split("The causal learned grouping", 1)[1].split("\n", 1)[0]
    assert "its settings unlike the offline model's: " in paragraph and "max_links_per_detection=16" in paragraph
    assert "cluster_window" not in paragraph  # (the main job's causal model has no cluster context)
    errors = json.loads((learned_run / "results.json").read_text())["learned"]["errors"]["learned grouping"]
    assert f"| learned grouping | {errors['n_true']} | {errors['missed']} | {errors['noise']} |" in report


def test_at_a_glance_names_the_learned_grouping(learned_run):
    report = (learned_run / "report.md").read_text()
    glance = report.split("## At a glance", 1)[1].split("\n## ", 1)[0]
    learned = json.loads((learned_run / "results.json").read_text())["learned"]
    assert "- the learned grouping (fitted on the training half's labels): test PQ " in glance
    assert f"test PQ {learned['instance_test']['pq']:.3f} offline" in glance
    assert f", {learned['causal']['instance_test']['pq']:.3f} causal against " in glance
    assert f"missed ground-truth segments {learned['errors']['learned grouping']['missed']}" in glance


def test_cluster_applies_the_saved_model_to_the_run_s_test_labels(learned_run, tiny_folder, tmp_path):
    results = json.loads((learned_run / "results.json").read_text())
    model = _direct_model(tiny_folder, results)
    out = tmp_path / "predictions.json"
    args = ["cluster", "--data", str(tiny_folder), "--params", str(learned_run / "params.json"), "--out", str(out)]
    with contextlib.redirect_stdout(io.StringIO()) as said:
        assert main([*args, "--experiment", "learned"]) == 0
    assert "applied experiment 'learned'" in said.getvalue()
    _assert_predictions_are_the_models(out, model, results, tiny_folder)


def test_stream_runs_the_causal_model(learned_run, tiny_folder, tmp_path):
    # The stream's final ids are the causal model's offline labels (predict on each whole sequence).
    results = json.loads((learned_run / "results.json").read_text())
    model = load_learned(learned_run / "learned_causal.joblib")
    assert model.get_params()["filter__causal"] is True
    from sklearn_radar.online import OnlinePipeline

    online = OnlinePipeline.from_params(learned_run / "params.json", "learned")
    assert online.learned and online.experiment == "learned" and online.pipeline[-1].causal
    out = tmp_path / "predictions.json"
    args = ["stream", "--data", str(tiny_folder), "--params", str(learned_run / "params.json"), "--out", str(out)]
    with contextlib.redirect_stdout(io.StringIO()):
        assert main([*args, "--experiment", "learned"]) == 0
    _assert_predictions_are_the_models(out, model, results, tiny_folder)


def test_stream_of_a_learned_entry_without_a_causal_model_names_it(learned_run, tiny_folder, tmp_path, capsys):
    saved = json.loads((learned_run / "params.json").read_text())
    del saved["experiments"]["learned"]["causal_model"]
    run = tmp_path / "run"
    run.mkdir()
    (run / "params.json").write_text(json.dumps(saved))
    (run / "learned.joblib").write_bytes((learned_run / "learned.joblib").read_bytes())
    args = ["stream", "--data", str(tiny_folder), "--params", str(run / "params.json"), "--experiment", "learned"]
    assert main([*args, "--out", str(tmp_path / "p.json")]) == 1
    assert "names no causal model" in capsys.readouterr().err
    assert not (tmp_path / "p.json").exists()


def test_a_foreign_or_damaged_model_file_is_refused_naming_it(learned_run, tiny_folder, tmp_path, capsys):
    run = tmp_path / "run"
    run.mkdir()
    (run / "params.json").write_text((learned_run / "params.json").read_text())
    raw = (learned_run / "learned.joblib").read_bytes()
    args = ["cluster", "--data", str(tiny_folder), "--params", str(run / "params.json"), "--experiment", "learned"]
    for content, problem in ((raw[:-10], "truncated"), (b"not a model", "not a learned grouping file")):
        (run / "learned.joblib").write_bytes(content)
        assert main([*args, "--out", str(tmp_path / "p.json")]) == 1
        error = capsys.readouterr().err
        assert str(run / "learned.joblib") in error and problem in error
    (run / "learned.joblib").unlink()
    assert main([*args, "--out", str(tmp_path / "p.json")]) == 1
    assert "learned grouping file not found" in capsys.readouterr().err
    assert not (tmp_path / "p.json").exists()


def test_a_classifier_file_is_not_a_learned_model(tmp_path):
    from sklearn.pipeline import make_pipeline

    from sklearn_radar import DopplerDensityFilter, FrameTransform
    from sklearn_radar.classification import ClusterClassifier, road_user_class, save_classifier
    from sklearn_radar.cluster import RadarDBSCAN
    from sklearn_radar.datasets import make_scenes

    scenes = make_scenes(n_sequences=2, duration=3.0, random_state=3)
    model = make_pipeline(FrameTransform(), DopplerDensityFilter(), ClusterClassifier(RadarDBSCAN(min_samples=3)))
    save_classifier(model.fit(scenes.data, road_user_class(scenes.data["label_id"])), tmp_path / "c.joblib")
    with pytest.raises(ValueError, match=r"c\.joblib: must hold a fitted LinkClustering .*ending in ClusterClassifier"):
        load_learned(tmp_path / "c.joblib")


def _assert_predictions_are_the_models(out, model, results, folder):
    """The predictions file ``out`` clusters each test sequence as ``model.predict`` does (the same partition)."""
    predictions = json.loads(out.read_text())["predictions"]
    for number in results["meta"]["data"]["test_sequences"]:
        X, _, data = _sequence_table(folder, number)
        expected = model.predict(X)
        found = np.array([predictions[u][1] for u in data["uuid"]])
        assert np.array_equal(found >= 0, expected >= 0)
        assert adjusted_rand_score(expected[expected >= 0], found[found >= 0]) == pytest.approx(1.0)
