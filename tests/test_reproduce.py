"""End-to-end tests of 'sklearn-radar reproduce' and 'sklearn-radar cluster' on a tiny data set."""

import json

import numpy as np
import pytest

from sklearn_radar._cli import main
from sklearn_radar.datasets import make_scenes, write_radarscenes
from sklearn_radar.reproduce import parse_experiments


@pytest.fixture(scope="module")
def tiny_folder(tmp_path_factory):
    path = tmp_path_factory.mktemp("data") / "tiny"
    write_radarscenes(make_scenes(n_sequences=4, duration=4.0, random_state=3), path)
    return path


@pytest.fixture(scope="module")
def tiny_report(tiny_folder, tmp_path_factory):
    out = tmp_path_factory.mktemp("report") / "out"
    code = main(["reproduce", "--data", str(tiny_folder), "--out", str(out), "--n-iter", "2",
                 "--experiments", "filter,1,2,8,10,11,13,filter-effect,baselines"])  # fmt: skip
    assert code == 0
    return out


def test_reproduce_writes_report_results_params_and_figures(tiny_report):
    names = {p.name for p in tiny_report.iterdir()}
    assert {"report.md", "results.json", "params.json", "table1_heatmap.png", "fig6_scene.png", "convergence.png"} <= names
    assert not [n for n in names if n.endswith(".tmp")]
    results = json.loads((tiny_report / "results.json").read_text())
    assert results["meta"]["completed"] == ["filter", "1", "2", "8", "10", "11", "13", "filter-effect", "baselines"]
    for key in ("1", "2", "8", "10", "11", "13"):
        record = results["experiments"][key]
        assert 0.0 <= record["v1_test"] <= 1.0 and record["paper_v1_percent"] > 60
    assert len(results["experiments"]["2"]["convergence"]) == 2
    assert set(results["baselines"]) == {"sklearn DBSCAN per 0.25 s window", "sklearn HDBSCAN per 0.25 s window"}
    report = (tiny_report / "report.md").read_text()
    for heading in ("Table I", "Table II", "Point clustering (Table III)", "Cluster merging (Table IV)",
                    "The filter's effect", "Beyond the paper", "checked"):  # fmt: skip
        assert heading in report
    assert "71.55 %" in report  # the paper's #8 beside ours


def test_params_file_drives_the_cluster_command_and_the_devkit_reads_its_output(tiny_report, tiny_folder, tmp_path, capsys):
    saved = json.loads((tiny_report / "params.json").read_text())
    assert saved["best"] in saved["experiments"]
    out = tmp_path / "predictions.json"
    assert main(["cluster", "--data", str(tiny_folder), "--params", str(tiny_report / "params.json"), "--out", str(out),
                 "--experiment", "13"]) == 0  # fmt: skip
    written = json.loads(out.read_text())
    from sklearn_radar.datasets import load_radarscenes

    uuids = load_radarscenes(tiny_folder).data["uuid"]
    assert written["schema"] == 2 and set(written["predictions"]) == set(uuids)
    classes, instances = np.array(list(written["predictions"].values())).T
    assert set(classes.tolist()) <= {0, 1} and ((instances >= 0) == (classes == 1)).all()


def test_our_prediction_file_equals_the_devkits(tmp_path):
    from radar_scenes.evaluation import PredictionFileSchemas, per_point_predictions_to_json

    from sklearn_radar._schema import LABELS
    from sklearn_radar.reproduce import write_predictions

    uuids = np.array(["a1", "b2", "c3"])
    labels = np.array([0, -1, 4])
    write_predictions(uuids, labels, tmp_path / "ours.json")
    translation = {label: (0 if label == 11 else 1) for label in LABELS}
    per_point_predictions_to_json(
        {u: [int(l >= 0), int(l)] for u, l in zip(uuids, labels)}, str(tmp_path / "devkit.json"), translation,
        PredictionFileSchemas.InstSeg,
    )  # fmt: skip
    ours = json.loads((tmp_path / "ours.json").read_text())
    devkit = json.loads((tmp_path / "devkit.json").read_text())
    assert ours["predictions"] == devkit["predictions"] and ours["schema"] == devkit["schema"]
    assert ours["label_mapping"] == devkit["label_mapping"]


@pytest.mark.parametrize(
    "argv, message",
    [
        (["reproduce", "--data", "/nonexistent/radarscenes"], "/nonexistent/radarscenes"),
        (["reproduce", "--experiments", "1,42"], "unknown experiment '42'"),
        (["reproduce", "--out", "/proc/forbidden"], "cannot write to the output folder"),
        (["reproduce", "--n-iter", "0"], "--n-iter"),
        (["cluster", "--data", "/nonexistent", "--params", "/nonexistent.json", "--out", "x.json"], "not found"),
    ],
)
def test_bad_input_is_a_one_line_error(argv, message, capsys):
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_malformed_params_file_is_a_one_line_error(tiny_folder, tmp_path, capsys):
    bad = tmp_path / "params.json"
    bad.write_text("{not json")
    assert main(["cluster", "--data", str(tiny_folder), "--params", str(bad), "--out", str(tmp_path / "p.json")]) == 1
    assert "not a JSON parameter file" in capsys.readouterr().err


def test_interrupted_run_keeps_finished_results(tiny_folder, tmp_path, monkeypatch):
    import sklearn_radar.reproduce._run as run_module

    def interrupt(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setitem(run_module._RUNNERS, "filter-effect", interrupt)
    out = tmp_path / "out"
    assert main(["reproduce", "--data", str(tiny_folder), "--out", str(out), "--experiments", "1,filter-effect"]) == 130
    results = json.loads((out / "results.json").read_text())
    assert results["meta"]["completed"] == ["1"] and results["meta"]["interrupted"]
    assert "interrupted" in (out / "report.md").read_text()


def test_experiment_lists_parse_ranges_in_run_order():
    assert parse_experiments("baselines,3-5,filter") == ["filter", "3", "4", "5", "baselines"]
    with pytest.raises(ValueError, match="range"):
        parse_experiments("5-2")


def test_a_single_training_sequence_is_tuned_on_one_fold(tmp_path):
    folder = tmp_path / "two"
    write_radarscenes(make_scenes(n_sequences=2, duration=3.0, random_state=4), folder)
    assert main(["reproduce", "--data", str(folder), "--out", str(tmp_path / "out"), "--n-iter", "2", "--experiments", "3"]) == 0
    results = json.loads((tmp_path / "out" / "results.json").read_text())
    assert results["meta"]["data"]["train_sequences"] and len(results["experiments"]["3"]["convergence"]) == 2


def test_the_report_says_reduced_budget_only_for_a_reduced_run(tiny_report, tmp_path):
    from sklearn_radar.reproduce._report import write_report

    results = json.loads((tiny_report / "results.json").read_text())
    assert "reduced budget" in (tiny_report / "report.md").read_text()  # 2 iterations
    results["meta"]["budget"]["n_iter"] = 100
    write_report(tmp_path, results)
    assert "reduced budget" not in (tmp_path / "report.md").read_text()
