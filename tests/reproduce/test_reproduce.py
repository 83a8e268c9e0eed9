"""End-to-end tests of 'sklearn-radar reproduce' and 'sklearn-radar cluster' on a tiny data set."""

import contextlib
import io
import json
import re

import numpy as np
import pytest

from sklearn_radar.cli import main
from sklearn_radar.datasets import make_scenes, write_radarscenes
from sklearn_radar.reproduce import parse_experiments


@pytest.fixture(scope="module")
def tiny_report(tiny_folder, tmp_path_factory):
    out = tmp_path_factory.mktemp("report") / "out"
    steps = "filter,1,2,8,10,11,13,objects,filter-effect,baselines,tracking,classification"
    printed = io.StringIO()  # the progress output, as a file would receive it
    with contextlib.redirect_stdout(printed):
        code = main(
            ["reproduce", "--data", str(tiny_folder), "--out", str(out), "--n-iter", "2", "--experiments", steps]
        )
    assert code == 0
    (out.parent / "stdout.txt").write_text(printed.getvalue())
    return out


def test_reproduce_writes_report_results_params_and_figures(tiny_report):
    names = {p.name for p in tiny_report.iterdir()}
    assert {
        "report.md",
        "results.json",
        "params.json",
        "table1_heatmap.png",
        "filter_scene.png",
        "v1_ours_vs_paper.png",
        "fig6_scene.png",
        "convergence.png",
        "tracks.png",
    } <= names
    assert not [n for n in names if n.endswith(".tmp")]
    results = json.loads((tiny_report / "results.json").read_text())
    assert results["meta"]["completed"] == [
        "filter",
        "1",
        "2",
        "8",
        "10",
        "11",
        "13",
        "objects",
        "filter-effect",
        "baselines",
        "tracking",
        "classification",
    ]
    assert list(results["experiments"]) == ["1", "2", "8", "10", "11", "13"]
    assert len(results["experiments"]["2"]["convergence"]) == 2
    assert set(results["baselines"]) == {
        "sklearn DBSCAN per 0.25 s window",
        "sklearn HDBSCAN per 0.25 s window",
        "sklearn DBSCAN per sequence (x, y, v_r, t) with Doppler gate",
        "sklearn HDBSCAN per sequence (x, y, v_r, t) with Doppler gate",
        "sklearn DBSCAN over a sliding past window (x, y, v_r, t) with Doppler gate, causal",
    }
    report = (tiny_report / "report.md").read_text()
    for heading in (
        "Table I",
        "Table II",
        "Point clustering (Table III)",
        "Cluster merging (Table IV)",
        "The filter's effect",
        "Beyond the paper",
        "checked",
    ):
        assert heading in report


def _rescore(folder, results, key):
    """Test V1 of the saved setting of experiment ``key``, computed apart from the reproduce code.

    The test half is taken from the sequence numbers that results.json
    records, the pipeline from the experiment's number and its saved
    parameters (as ``sklearn-radar cluster`` builds it), the score from the
    metric itself.
    """
    from sklearn_radar.datasets import load_radarscenes
    from sklearn_radar.experiments import experiment_pipeline, get_experiment
    from sklearn_radar.metrics import precluster_target, radar_v_measure

    saved = json.loads((results / "params.json").read_text())["experiments"][key]
    test_sequences = json.loads((results / "results.json").read_text())["meta"]["data"]["test_sequences"]
    scenes = load_radarscenes(folder)
    test = np.flatnonzero(np.isin(scenes.groups, test_sequences))
    target = precluster_target(scenes.data, scenes.target)[test]
    number = saved["experiment"]
    stage1 = saved["stage1_params"] if get_experiment(number).stage == 2 else None
    pipeline = experiment_pipeline(number, stage1_params=stage1).set_params(**saved["params"])
    labels = pipeline.fit_predict(scenes.data.iloc[test])
    return radar_v_measure(target, labels, groups=scenes.groups[test])


@pytest.mark.parametrize("key", ["1", "2", "11", "13"])
def test_saved_setting_rescored_on_the_test_half_gives_the_reported_v1(tiny_report, tiny_folder, key):
    # The expert setting, a tuned one, one derived from #8 and a stage-2 one on top of #8's.
    results = json.loads((tiny_report / "results.json").read_text())
    v1 = _rescore(tiny_folder, tiny_report, key)
    assert results["experiments"][key]["v1_test"] == pytest.approx(v1, abs=1e-9)
    # ...and the report's table prints that score in the experiment's row.
    record = results["experiments"][key]
    row = f"| {key} | {record['method']} | {'CCS' if record['frame'] == 'car' else 'FCS'} | yes | {100 * v1:.2f} % |"
    assert row in (tiny_report / "report.md").read_text()


def test_the_best_saved_setting_is_the_one_with_the_highest_cross_validated_v1(tiny_report):
    # Never the test score: the kept settings' cross-validated V1 on the training half, as results.json has it.
    saved = json.loads((tiny_report / "params.json").read_text())
    results = json.loads((tiny_report / "results.json").read_text())
    cv = {key: record["cv_best"] for key, record in results["experiments"].items() if "cv_best" in record}
    assert saved["best"] == max(cv, key=cv.get)
    assert saved["experiments"]["objects"]["cv_v1"] is None  # tuned for PQ in a V1 run: not comparable
    assert saved["experiments"]["1"]["cv_v1"] is None and saved["experiments"]["2"]["cv_v1"] == cv["2"]


def test_params_file_drives_the_cluster_command_and_the_devkit_reads_its_output(
    tiny_report, tiny_folder, tmp_path, capsys
):
    saved = json.loads((tiny_report / "params.json").read_text())
    assert saved["best"] in saved["experiments"]
    out = tmp_path / "predictions.json"
    params = str(tiny_report / "params.json")
    assert (
        main(["cluster", "--data", str(tiny_folder), "--params", params, "--out", str(out), "--experiment", "13"]) == 0
    )
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
        {u: [int(label >= 0), int(label)] for u, label in zip(uuids, labels, strict=True)},
        str(tmp_path / "devkit.json"),
        translation,
        PredictionFileSchemas.InstSeg,
    )
    ours = json.loads((tmp_path / "ours.json").read_text())
    devkit = json.loads((tmp_path / "devkit.json").read_text())
    assert ours["predictions"] == devkit["predictions"] and ours["schema"] == devkit["schema"]
    assert ours["label_mapping"] == devkit["label_mapping"]


@pytest.mark.parametrize(
    "argv, message, code",
    [
        (["reproduce", "--data", "/nonexistent/radarscenes"], "/nonexistent/radarscenes", 1),
        (["reproduce", "--experiments", "1,42"], "unknown experiment '42'", 2),  # usage errors exit 2
        (["reproduce", "--out", "/proc/forbidden"], "cannot write to the output folder", 1),
        (["reproduce", "--n-iter", "0"], "--n-iter", 2),
        (["cluster", "--data", "/nonexistent", "--params", "/nonexistent.json", "--out", "x.json"], "not found", 1),
    ],
)
def test_bad_input_is_a_one_line_error(argv, message, code, capsys):
    assert main(argv) == code
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_malformed_params_file_is_a_one_line_error(tiny_folder, tmp_path, capsys):
    bad = tmp_path / "params.json"
    bad.write_text("{not json")
    assert main(["cluster", "--data", str(tiny_folder), "--params", str(bad), "--out", str(tmp_path / "p.json")]) == 1
    assert "not a JSON parameter file" in capsys.readouterr().err


def test_interrupted_run_keeps_finished_results(tiny_folder, tmp_path, monkeypatch):
    import dataclasses

    from sklearn_radar.reproduce._steps import STEPS

    def interrupt(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setitem(STEPS, "filter-effect", dataclasses.replace(STEPS["filter-effect"], run=interrupt))
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
    assert (
        main(
            ["reproduce", "--data", str(folder), "--out", str(tmp_path / "out"), "--n-iter", "2", "--experiments", "3"]
        )
        == 0
    )
    results = json.loads((tmp_path / "out" / "results.json").read_text())
    assert results["meta"]["data"]["train_sequences"] and len(results["experiments"]["3"]["convergence"]) == 2


def _typed(report_folder):
    """The tiny run's results, typed, with the figures it drew (results.json is saved before they are drawn)."""
    from sklearn_radar.reproduce._results import RunResults

    results = RunResults.from_json_dict(json.loads((report_folder / "results.json").read_text()))
    names = {
        "table1_heatmap": "table1_heatmap.png",
        "filter_scene": "filter_scene.png",
        "tracks": "tracks.png",
        "precision_recall": "classification_precision_recall.png",
        "v1_bars": "v1_ours_vs_paper.png",
        "scene": "fig6_scene.png",
        "convergence": "convergence.png",
    }
    results.figures.drawn.update({name: file for name, file in names.items() if (report_folder / file).exists()})
    return results


def test_the_report_says_reduced_budget_only_for_a_reduced_run(tiny_report, tmp_path):
    from sklearn_radar.reproduce._report import write_report

    results = _typed(tiny_report)
    assert "reduced budget" in (tiny_report / "report.md").read_text()  # 2 iterations
    results.meta.budget.n_iter = 100
    write_report(tmp_path, results)
    assert "reduced budget" not in (tmp_path / "report.md").read_text()


def test_results_json_round_trips_through_the_typed_results_byte_for_byte(tiny_report):
    from sklearn_radar.reproduce._experiment_records import ExperimentResult, SearchRecord
    from sklearn_radar.reproduce._results import RunResults

    text = (tiny_report / "results.json").read_text()
    results = RunResults.from_json_dict(json.loads(text))
    assert json.dumps(results.to_json_dict(), indent=1) == text
    assert isinstance(results.experiments[2], ExperimentResult) and isinstance(
        results.experiments[2].search, SearchRecord
    )
    assert results.experiments[1].search is None and results.experiments[11].derived_from_8 == "tuned #8"
    assert results.experiments[13].stage1_params == {
        k: v for k, v in results.experiments[8].params.items() if k.startswith("cluster__")
    }
    # params.json is derived from the same typed results.
    assert json.dumps(results.to_params_dict(), indent=1) == (tiny_report / "params.json").read_text()
    # With the figures (what reproduce() returns) it round-trips too.
    typed = _typed(tiny_report)
    document = typed.to_json_dict(figures=True)
    assert document["figures"] == {
        "table1_heatmap": "table1_heatmap.png",
        "filter_scene": "filter_scene.png",
        "tracks": "tracks.png",
        "precision_recall": "classification_precision_recall.png",
        "v1_bars": "v1_ours_vs_paper.png",
        "scene": "fig6_scene.png",
        "convergence": "convergence.png",
    }
    assert RunResults.from_json_dict(document).to_json_dict(figures=True) == document


def test_the_report_is_rebuilt_from_results_json_identically(tiny_report, tmp_path):
    from sklearn_radar.reproduce._report import write_report

    write_report(tmp_path, _typed(tiny_report))
    assert (tmp_path / "report.md").read_text() == (tiny_report / "report.md").read_text()


def test_every_section_renders_the_tiny_run_and_stays_out_when_its_step_did_not_run(tiny_report):
    from sklearn_radar.reproduce._results import RunResults
    from sklearn_radar.reproduce._sections import SECTIONS

    results = _typed(tiny_report)
    report = (tiny_report / "report.md").read_text()
    assert len({section.name for section in SECTIONS}) == len(SECTIONS)
    for section in SECTIONS:
        lines = section.markdown(results)
        if section.name == "learned":  # not a step of the default run (its section: test_reproduce_learned.py)
            assert lines == [] and results.learned is None
            continue
        assert lines and all(isinstance(line, str) for line in lines), section.name
        assert "\n".join(lines) in report, section.name
    bare = RunResults(meta=results.meta)
    shown = {section.name for section in SECTIONS if section.markdown(bare)}
    assert shown == {"header", "figures"}


def test_a_missing_or_renamed_field_fails_where_the_results_are_built(tiny_report):
    from sklearn_radar.reproduce._experiment_records import ExperimentResult
    from sklearn_radar.reproduce._results import RunResults

    document = json.loads((tiny_report / "results.json").read_text())
    renamed = json.loads(json.dumps(document))
    renamed["experiments"]["2"]["v1"] = renamed["experiments"]["2"].pop("v1_test")
    with pytest.raises(ValueError, match="v1"):
        RunResults.from_json_dict(renamed)
    missing = json.loads(json.dumps(document))
    del missing["meta"]["data"]["n_test"]
    with pytest.raises(ValueError, match="n_test"):
        RunResults.from_json_dict(missing)
    renamed_search = json.loads(json.dumps(document))
    renamed_search["baselines"]["sklearn DBSCAN per 0.25 s window"].pop("cv_best")
    with pytest.raises(ValueError, match="cv_best"):
        RunResults.from_json_dict(renamed_search)
    record = dict(document["experiments"]["1"])
    del record["n_clusters_test"]
    with pytest.raises(TypeError, match="n_clusters_test"):
        ExperimentResult(**record)
    with pytest.raises(TypeError):  # keyword-only: no silent mix-up of positions
        ExperimentResult(*document["experiments"]["1"].values())
    result = ExperimentResult.from_json_dict(document["experiments"]["1"])
    with pytest.raises(AttributeError):  # slots: a misspelt attribute is not a new one
        result.v1_tset = 0.5


def test_experiment_numbers_come_from_the_papers_metadata():
    from sklearn_radar.experiments import get_experiment
    from sklearn_radar.reproduce import ALL_EXPERIMENTS
    from sklearn_radar.reproduce._constants import BEST_STAGE1, DERIVED_FROM_BEST, EXPERT, STAGE1, STAGE2

    assert (EXPERT, BEST_STAGE1, DERIVED_FROM_BEST, STAGE2) == (1, 8, (10, 11), (12, 13))
    assert STAGE1 == tuple(range(1, 12)) and get_experiment(EXPERT).method == "Expert Setting"
    assert ALL_EXPERIMENTS == (
        "filter",
        *(str(n) for n in range(1, 14)),
        "objects",
        "filter-effect",
        "baselines",
        "learned",
        "tracking",
        "classification",
    )


def _brute_force_pq(target, labels, times, groups, window=0.5):
    """Per-window panoptic quality written plainly: segments as sets of row numbers, IoU > 0.5 matches."""
    segments = {"true": {}, "pred": {}}
    start = {g: min(t for t, h in zip(times, groups, strict=True) if h == g) for g in set(groups)}
    for row, (true, pred, t, g) in enumerate(zip(target, labels, times, groups, strict=True)):
        key = (g, int((t - start[g]) // window))
        if true >= 0:
            segments["true"].setdefault((*key, true), set()).add(row)
        if pred >= 0:
            segments["pred"].setdefault((*key, pred), set()).add(row)
    ious = []
    for t_key, t_rows in segments["true"].items():
        for p_key, p_rows in segments["pred"].items():
            if t_key[:2] == p_key[:2]:
                iou = len(t_rows & p_rows) / len(t_rows | p_rows)
                if iou > 0.5:
                    ious.append(iou)
    tp, n_true, n_pred = len(ious), len(segments["true"]), len(segments["pred"])
    if tp == 0:
        return 0.0
    return (sum(ious) / tp) * tp / (tp + (n_pred - tp) / 2 + (n_true - tp) / 2)


def test_objective_pq_is_searched_reported_and_ranks_the_saved_best(tiny_folder, tmp_path):
    from sklearn_radar.datasets import load_radarscenes
    from sklearn_radar.experiments import experiment_pipeline
    from sklearn_radar.metrics import precluster_target

    out = tmp_path / "pq"
    argv = ["reproduce", "--data", str(tiny_folder), "--out", str(out), "--n-iter", "2", "--objective", "pq"]
    assert main([*argv, "--experiments", "1,3,baselines"]) == 0
    results = json.loads((out / "results.json").read_text())
    saved = json.loads((out / "params.json").read_text())
    assert results["meta"]["objective"] == "pq" and saved["objective"] == "pq"
    cv = {key: record["cv_best"] for key, record in results["experiments"].items() if "cv_best" in record}
    assert saved["best"] == max(cv, key=cv.get) == "3"  # #1 has no search: no cross-validated PQ
    assert saved["experiments"]["3"]["cv_pq"] == cv["3"] and saved["experiments"]["1"]["cv_pq"] is None
    # The reported PQ of #3 equals a plain per-window matcher on the saved setting's test labels.
    scenes = load_radarscenes(tiny_folder)
    test = np.flatnonzero(np.isin(scenes.groups, results["meta"]["data"]["test_sequences"]))
    target = precluster_target(scenes.data, scenes.target)[test]
    labels = (
        experiment_pipeline(3).set_params(**saved["experiments"]["3"]["params"]).fit_predict(scenes.data.iloc[test])
    )
    times = scenes.data["timestamp"].to_numpy()[test] * 1e-6
    expected = _brute_force_pq(target.tolist(), labels.tolist(), times.tolist(), scenes.groups[test].tolist())
    assert results["experiments"]["3"]["instance_test"]["pq"] == pytest.approx(expected, abs=1e-12)
    for record in results["baselines"].values():
        assert 0.0 <= record["instance_test"]["pq"] <= 1.0
    assert "## Beyond the paper: object-level scores" in (out / "report.md").read_text()


def test_results_without_an_objective_read_back_as_the_papers():
    from sklearn_radar.reproduce._results import RunMeta

    document = RunMeta(
        version="0",
        seed=0,
        budget=_typed_budget(),
        data=_typed_data(),
    ).to_json_dict()
    document.pop("objective")
    assert RunMeta.from_json_dict(document).objective == "v1"


def _typed_budget():
    from sklearn_radar.reproduce._budget import Budget

    return Budget.default(2)


def _typed_data():
    from sklearn_radar.reproduce._results import DataMeta

    return DataMeta(
        source="s", n_detections=1, n_sequences=1, n_train=1, n_test=0, train_sequences=[1], test_sequences=[]
    )


def test_the_scene_figure_marks_exactly_the_clusters_without_an_object_detection():
    from sklearn_radar.reproduce._sections._figures import _background_only

    labels = np.array([0, 0, 1, 1, 2, -1, 3])
    target = np.array([5, -1, -1, -1, 7, 5, -1])
    # cluster 0 holds an object detection, 1 and 3 do not, 2 does; noise is never marked
    np.testing.assert_array_equal(_background_only(labels, target), [False, False, True, True, False, False, True])


def test_table_iii_marks_where_each_setting_comes_from_and_shows_the_cv_score(tiny_report):
    from sklearn_radar.reproduce._constants import SOURCE_PAPER

    results = json.loads((tiny_report / "results.json").read_text())
    report = (tiny_report / "report.md").read_text()
    rows = {line.split(" | ")[0].strip("| "): line for line in report.splitlines() if line.startswith("| ")}
    for key, record in results["experiments"].items():
        cells = [cell.strip() for cell in rows[key].strip("|").split("|")]
        v1, cv, setting = cells[4], cells[6], cells[7]
        assert v1 == f"{100 * record['v1_test']:.2f} %"
        if "best_source" in record:  # tuned: the CV score of the kept setting beside the test score
            assert cv == f"{100 * record['cv_best']:.2f} %"
            assert setting == ("paper's \u2020" if record["best_source"] == SOURCE_PAPER else "search")
        else:
            assert cv == "-" and setting in ("fixed", "#8's")
    assert "\u2020` the paper's setting, scored beside the search" in report  # the legend of the mark
    for name, record in results["baselines"].items():
        assert f"| {name} | {100 * record['v1_test']:.2f} % | {100 * record['cv_best']:.2f} % |" in report


def test_stage2_records_its_merges_and_says_when_it_merged_nothing(tiny_report, tiny_folder):
    from sklearn_radar.datasets import load_radarscenes
    from sklearn_radar.experiments import experiment_pipeline

    results = json.loads((tiny_report / "results.json").read_text())
    record = results["experiments"]["13"]
    # Recount on the test half with the saved setting, as `sklearn-radar cluster` builds the pipeline.
    scenes = load_radarscenes(tiny_folder)
    test = np.flatnonzero(np.isin(scenes.groups, results["meta"]["data"]["test_sequences"]))
    pipeline = experiment_pipeline(13, stage1_params=record["stage1_params"]).set_params(**record["params"])
    pipeline.fit(scenes.data.iloc[test])
    merger = pipeline[-1]
    assert record["n_merges_test"] == len(merger.merges_)
    assert record["n_stage1_clusters_test"] == len(np.unique(merger.stage1_labels_[merger.stage1_labels_ >= 0]))
    report = (tiny_report / "report.md").read_text()
    if record["n_merges_test"] == 0:
        assert "#13 merged no pair of stage-1 clusters on the test half" in report
    else:
        assert f"#13 merged {record['n_merges_test']:,} pairs" in report
    assert "| stage-1 clusters | merges |" in report


def test_the_report_holds_the_data_statistics_and_explains_the_filter_errors(tiny_report, tiny_folder):
    from sklearn_radar.datasets import format_statistics, load_radarscenes, scene_statistics

    report = (tiny_report / "report.md").read_text()
    assert format_statistics(*scene_statistics(load_radarscenes(tiny_folder))) in report
    results = json.loads((tiny_report / "results.json").read_text())
    windows = results["filter"]["windows"]
    # Two code paths count the errors at the chosen setting: Table II's row and the window listing.
    row = next(
        r
        for r in results["filter"]["table_ii"]
        if r["frame"] == "frame" and r["vr_threshold"] == 0.1 and r["d_xy"] == 1.4
    )
    assert windows["n_errors"] == row["errors"] and windows["n_windows"] > windows["n_errors"]
    assert f"{windows['n_errors']:,} of {windows['n_windows']:,} (object, 150 ms) windows are errors" in report
    assert "*objects removed (ours)*:" in report and "the asterisk (*) is the paper's chosen setting" in report
    assert "the chosen filter setting (FCS, eta_1 = 0.10 m/s, d_xy = 1.4 m) loses no object window" in report


def test_results_of_an_older_version_without_the_new_fields_still_load(tiny_report):
    from sklearn_radar.reproduce._report import report_markdown
    from sklearn_radar.reproduce._results import RunResults

    document = json.loads((tiny_report / "results.json").read_text())
    document.pop("statistics")
    document["filter"].pop("windows")
    for record in document["experiments"].values():
        record.pop("n_merges_test", None)
        record.pop("n_stage1_clusters_test", None)
    results = RunResults.from_json_dict(document)
    assert (
        results.statistics is None and results.filter.windows is None and results.experiments[13].n_merges_test is None
    )
    text = report_markdown(results)
    assert "## The data" not in text and "## Cluster merging (Table IV)" in text


def test_the_report_shows_every_figure_it_drew_with_a_caption(tiny_report):
    report = (tiny_report / "report.md").read_text()
    shown = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", report)
    drawn = sorted(p.name for p in tiny_report.glob("*.png"))
    assert sorted(shown) == drawn and len(drawn) == 7
    for match in re.finditer(r"!\[[^\]]*\]\(([^)]+)\)", report):  # a caption (a paragraph) right above each
        caption = report[: match.start()].rstrip().rsplit("\n\n", 1)[-1]
        assert len(caption) > 40 and not caption.startswith(("|", "!", "#")), match.group(1)
    glance = report.split("## At a glance", 1)[1].split("\n## ", 1)[0]
    assert all(f"]({name})" in glance for name in drawn)  # the summary links every figure
    assert "- best point clustering by test V1 (the searches tuned for V1): #" in glance  # says the objective
    findings = report.split("## The paper's findings, checked", 1)[1]
    verdicts = re.findall(r"\*\*(holds|does not hold|cannot tell)\*\*", findings.split("\n\nThe rule", 1)[0])
    n = {verdict: verdicts.count(verdict) for verdict in ("holds", "does not hold", "cannot tell")}
    assert (
        f"the paper's findings, {len(verdicts)} checked: {n['holds']} hold, {n['does not hold']} do not hold, "
        f"{n['cannot tell']} cannot tell (they compare single searches" in glance
    )
    assert "background-only" in report and "drawn in dark grey" in report


def test_a_single_run_gives_no_verdict_on_any_experiment_in_the_findings_or_the_summary(tiny_report):
    report = (tiny_report / "report.md").read_text()
    findings = report.split("## The paper's findings, checked", 1)[1].split("\n\nThe rule", 1)[0].strip()
    about_experiments = [line for line in findings.splitlines() if re.search(r"\(#\d+ [<>]", line)]
    assert len(about_experiments) == 3  # #2 > #1, #11 < #8, #13 > #8 (#8 > #9 and #10 needs #9, not run)
    assert all("**cannot tell** from this single run" in line for line in about_experiments)
    about_the_filter = [line for line in findings.splitlines() if line not in about_experiments]
    assert about_the_filter and not any("cannot tell" in line for line in about_the_filter)  # fixed tables
    glance = report.split("## At a glance", 1)[1].split("\n## ", 1)[0]
    held = sum("**holds**" in line for line in about_the_filter)
    assert f"{held} hold, {len(about_the_filter) - held} do not hold, 3 cannot tell" in glance


def test_convergence_curves_never_share_a_colour_and_line_style():
    from sklearn_radar.reproduce._sections._figures import curve_styles

    for n in (1, 14, 20, 40):
        styles = curve_styles(n)
        assert len(set(styles)) == n


def test_progress_estimates_the_run_and_shows_overall_progress_in_plain_lines(tiny_report):
    text = (tiny_report.parent / "stdout.txt").read_text()
    assert "\r" not in text and "\x1b" not in text  # readable in a file: no carriage returns, no escapes
    lines = text.splitlines()
    assert re.match(r"the run's work: 12 steps, \d+ search iterations in all; the progress lines estimate", lines[1])
    left = r"(about (\d+:)?\d+:\d\d left|time left unknown \(not timed yet: [^)]+\))"
    status = re.compile(r"\| run (\d+) %, (\d+:)?\d+:\d\d elapsed(, " + left + ")?$")
    done = [line for line in lines if re.match(r"\[\d+/12\] .* done in ", line)]
    iterations = [line for line in lines if " iteration " in line]
    assert len(done) == 12 and iterations
    shares = [int(status.search(line).group(1)) for line in done]
    assert all(status.search(line) for line in iterations)
    assert shares == sorted(shares) and shares[0] < shares[-1] == 100  # every step ended: the run's steps are done
    assert "about" in done[-2] or "unknown" in done[-2]
    assert re.match(r"run complete; drawing the figures and writing the report \| run 100 %", lines[-3])
    assert re.match(r"report written after \d+:\d\d in all$", lines[-2])


def test_progress_counts_units_and_prices_the_work_left_at_each_kinds_measured_rate(monkeypatch):
    from sklearn_radar.reproduce import _progress
    from sklearn_radar.reproduce._progress import RunProgress, duration

    assert (duration(0), duration(75), duration(4000)) == ("0:00", "1:15", "1:06:40")
    clock = [0.0]
    monkeypatch.setattr(_progress.time, "perf_counter", lambda: clock[0])
    work = {
        "data": ("data", 1),
        "filter": ("filter", 1),
        "1": ("scoring", 1),
        "2": ("stage 1", 10),
        "3": ("stage 1", 10),
    }
    progress = RunProgress(work, started=0.0)
    clock[0] = 4.0
    progress.finish("data", 4.0)
    assert progress.left() is None  # the data step prices nothing
    progress.start("filter")
    clock[0] = 6.0
    progress.finish("filter")  # 2 s; scoring and stage 1 are not timed yet: no estimate of them
    assert progress.left() is None and progress.untimed() == ["scoring", "stage 1"]
    progress.start("1")
    clock[0] = 7.0
    progress.finish("1")  # 1 s a scoring pass: still no price of a stage-1 iteration
    assert progress.left() is None and progress.untimed() == ["stage 1"]
    progress.start("2")
    for _ in range(4):  # 4 iterations of 0.5 s: the stage-1 rate
        clock[0] += 0.5
        progress.advance("2")
    assert progress.left() == pytest.approx(16 * 0.5)
    # The share weighs each unit by its kind's rate: (2 + 1 + 4 * 0.5) / (2 + 1 + 20 * 0.5) = 5 / 13.
    assert progress.status() == "run 38 %, 0:09 elapsed, about 0:08 left"
    # Work that ran at once: its 6 units took 11 s while the clock moved on by less, so that the measured
    # seconds (20) exceed the time elapsed (19): the rate, (2 + 11) / 10 s, is scaled by 19 / 20.
    progress.finish("2", 11.0)
    clock[0] = 19.0
    assert progress.left() == pytest.approx(10 * (13.0 / 10) * 19.0 / 20.0)


def test_progress_share_never_goes_back(monkeypatch):
    from sklearn_radar.reproduce import _progress
    from sklearn_radar.reproduce._progress import RunProgress

    clock = [0.0]
    monkeypatch.setattr(_progress.time, "perf_counter", lambda: clock[0])
    progress = RunProgress({"1": ("scoring", 1), "2": ("stage 1", 1), "3": ("stage 1", 100)}, started=0.0)
    progress.start("1")
    clock[0] = 1.0
    progress.finish("1")
    clock[0] = 1.01
    progress.finish("2", 0.01)  # a fast first iteration: 100 more at 0.01 s, 1 s left
    assert progress.status().startswith("run 50 %")
    progress.start("3")
    clock[0] = 11.01
    progress.advance("3")  # a slow one: 99 more at 5 s each, the share would drop to 2 %
    assert progress.status().startswith("run 50 %")


# ----------------------------------------------------------------------------- what the figures show


def test_the_table_i_heatmaps_share_one_colour_scale_from_0_rows_in_the_tables_order(tiny_report):
    import matplotlib.pyplot as plt

    from sklearn_radar.reproduce._sections._filter import CHOSEN, heatmap_figure

    results = _typed(tiny_report)
    fig = heatmap_figure(results)
    fig.canvas.draw()  # the tick labels
    panels = [ax for ax in fig.axes if ax.images]
    grids = [results.filter.table_i[frame].errors.to_frame() for frame in ("frame", "car")]
    assert len(panels) == 2 and len(fig.axes) == 3  # the two grids and one colour bar for both
    highest = max(float(grid.to_numpy().max()) for grid in grids)
    assert [ax.images[0].get_clim() for ax in panels] == [(0, max(highest, 1.0))] * 2
    for ax, grid in zip(panels, grids, strict=True):
        # The first row of the markdown table on top: y grows downwards, the labels in the table's order.
        bottom, top = ax.get_ylim()
        assert bottom > top
        assert list(ax.get_yticks()) == list(range(len(grid.index)))
        assert [t.get_text() for t in panels[0].get_yticklabels()] == [f"{v:.2f}" for v in grid.index]  # shared
        assert ax.get_ylabel() in ("eta_1 (m/s)", "")  # one name for eta_1, as in the tables
        star = next(t for t in ax.texts if t.get_text() == "*")
        i, j = list(grid.index).index(CHOSEN[0]), list(grid.columns).index(CHOSEN[1])
        x, y = star.get_position()
        assert x == j and abs(y - i) < 0.5  # centred across its cell, inside it
    plt.close(fig)


def test_the_v1_bars_start_at_0_and_the_legend_is_readable(tiny_report):
    import matplotlib.pyplot as plt

    from sklearn_radar.reproduce._sections._figures import v1_bars_figure

    fig = v1_bars_figure(_typed(tiny_report))
    (ax,) = fig.axes
    assert ax.get_ylim() == (0, 100)
    assert all(text.get_fontsize() >= 10 for text in ax.get_legend().get_texts())
    plt.close(fig)


def test_coinciding_convergence_curves_differ_in_marker_and_the_legend_is_readable(tiny_report):
    import matplotlib.pyplot as plt

    from sklearn_radar.reproduce._sections._figures import convergence_curves, convergence_figure

    results = _typed(tiny_report)
    curves = convergence_curves(results)
    flat = {name: [[0.5] * 3] for name in curves}  # every search the same curve: only the styles tell them apart
    fig = convergence_figure(flat, results)
    assert len(fig.axes) == 2  # the paper's experiments above the baselines
    for ax in fig.axes:  # within a panel no two curves alike, each with markers, each's at other places
        lines = [line for line in ax.get_lines() if not line.get_label().startswith("#8 ")]
        styles = [(line.get_color(), line.get_linestyle(), line.get_marker()) for line in lines]
        assert len(set(styles)) == len(styles) and all(line.get_marker() not in ("", "None") for line in lines)
        assert len({line.get_markevery()[0] for line in lines}) == len(lines)
    shown = [line.get_label().replace(" \u2020", "") for ax in fig.axes for line in ax.get_lines()]  # dagger apart
    assert sorted(shown) == sorted(name if name != "#8" else "#8 (the paper's best)" for name in curves)
    assert all(t.get_fontsize() >= 10 for ax in fig.axes for t in ax.get_legend().get_texts())
    plt.close(fig)


def test_the_filters_time_saving_is_a_finding_only_beyond_the_noise_of_its_timing_rounds():
    from sklearn_radar.reproduce._filter_records import ClusteringCost, FilterEffectFigures, FilterEffectResult
    from sklearn_radar.reproduce._sections._filter_effect import time_saving_text

    def effect(filtered, unfiltered):
        costs = [
            ClusteringCost(clustering_s=float(np.median(t)), n_clusters=10, clustering_times_s=t)
            for t in (filtered, unfiltered)
        ]
        figures = FilterEffectFigures(
            time_saving_percent=0.0, fewer_clusters_per_sequence_percent=1.0, fewer_clusters_overall_percent=1.0
        )
        return FilterEffectResult(
            setting={}, setting_source="tuned #8", filtered=costs[0], unfiltered=costs[1], measured=figures
        )

    steady = effect([0.080, 0.081, 0.079, 0.080], [0.100, 0.101, 0.099, 0.100])  # 20 % in every round
    assert time_saving_text(steady).startswith("Filtering saves clustering time") and "+20.0 \u00b1 " in (
        time_saving_text(steady)
    )
    noisy = effect([0.03, 0.06, 0.04, 0.05], [0.05, 0.04, 0.06, 0.03])  # -4.8 % one round, +20 % the next
    assert time_saving_text(noisy).startswith("The time saving cannot be measured on this data")
    old = effect([0.03], [0.04])
    old.filtered.clustering_times_s = old.unfiltered.clustering_times_s = None  # an older version's results
    assert time_saving_text(old).startswith("The time saving cannot be measured from these results")


def test_the_header_counts_in_the_singular_for_one(tiny_report):
    import dataclasses

    from sklearn_radar.reproduce._sections import _header
    from sklearn_radar.reproduce._sections._base import counted

    assert (counted(1, "iteration"), counted(10, "iteration"), counted(1234, "sequence")) == (
        "1 iteration",
        "10 iterations",
        "1,234 sequences",
    )
    results = _typed(tiny_report)
    results.meta.budget = dataclasses.replace(results.meta.budget, n_iter=1)
    text = "\n".join(_header.markdown(results))
    assert "1 Bayesian-optimisation iteration per tuned experiment" in text and "4 sequences" in text


def test_the_summary_names_every_figure_the_tiny_run_drew_in_words(tiny_report):
    from sklearn_radar.reproduce._sections._summary import FIGURE_NAMES

    drawn = _typed(tiny_report).figures.drawn
    assert drawn and set(drawn) <= set(FIGURE_NAMES)
    glance = (tiny_report / "report.md").read_text().split("## At a glance", 1)[1].split("\n## ", 1)[0]
    assert all(f"[{FIGURE_NAMES[name]}]({file})" in glance for name, file in drawn.items())
