"""The reproduce run's classification step: the classifier on each setting's clusters, its semantic scores."""

import contextlib
import io
import json

import numpy as np
import pytest

from sklearn_radar.classification import road_user_class
from sklearn_radar.cli import main
from sklearn_radar.datasets import load_radarscenes
from sklearn_radar.experiments import SKLEARN_BASELINES
from sklearn_radar.metrics import semantic_scores
from sklearn_radar.reproduce._classification import (
    POINT_WISE,
    ClassificationResult,
    ClassifiedSetting,
    SemanticScores,
    strongest_offline_baseline,
)
from sklearn_radar.reproduce._results import RunResults
from sklearn_radar.reproduce._sections._classification import _verdict, answer_lines, markdown


@pytest.fixture(scope="module")
def classified(tiny_folder, tmp_path_factory):
    """A run of #1, #13, the baselines and the classification step (#3 and #8 take the paper's settings)."""
    return _reproduced(tiny_folder, tmp_path_factory.mktemp("classification") / "out", "1,13,baselines,classification")


def _reproduced(folder, out, experiments, *options):
    """``out`` after a quiet ``sklearn-radar reproduce`` of ``experiments`` on ``folder`` (2 iterations)."""
    with contextlib.redirect_stdout(io.StringIO()):
        code = main(
            [
                "reproduce",
                "--data",
                str(folder),
                "--out",
                str(out),
                "--n-iter",
                "2",
                "--experiments",
                experiments,
                *options,
            ]
        )
    assert code == 0
    return out


def test_the_step_classifies_every_setting_and_the_point_wise_baseline(classified):
    results = json.loads((classified / "results.json").read_text())
    assert results["meta"]["completed"] == ["1", "13", "baselines", "classification"]
    settings = results["classification"]["settings"]
    best = strongest_offline_baseline(RunResults.read(classified / "results.json").baselines)
    assert list(settings) == ["#1", "#3", "#8", "#13", best[0], POINT_WISE]
    sources = {name: entry["setting_source"] for name, entry in settings.items()}
    assert sources["#1"] == "fixed #1" and sources["#13"] == "tuned #13"
    assert sources["#3"] == "paper's #3" and sources["#8"] == "paper's #8"
    assert settings["#13"]["params"] == {
        **results["experiments"]["13"]["stage1_params"],
        **results["experiments"]["13"]["params"],
    }
    for name, entry in settings.items():
        scores = entry["scores"]
        for key in ("pq", "sq", "rq", "map", "macro_f1", "mcov"):
            assert 0.0 <= scores[key] <= 1.0, (name, key)
        assert 0.0 <= entry["background_share_after"] <= 1.0
        assert entry["n_training_examples"] > 0
        n_test = len(results["classification"]["test_sequences"])
        assert all(len(values) == n_test for values in entry["per_sequence"].values())
    assert settings[POINT_WISE]["background_share_before"] is None
    assert all(settings[name]["background_share_before"] is not None for name in list(settings)[:-1])


def test_the_results_read_back_and_the_report_has_the_section(classified):
    results = RunResults.read(classified / "results.json")
    assert isinstance(results.classification, ClassificationResult)
    again = RunResults.from_json_dict(json.loads(json.dumps(results.to_json_dict())))
    assert again.classification == results.classification
    report = (classified / "report.md").read_text()
    assert "## Beyond the paper: classifying the clusters" in report
    assert "published, real RadarScenes data" in report and "86.97 %" in report


def test_the_pooled_scores_are_those_of_the_whole_test_half(classified, tiny_folder):
    """The step's pooled figures = semantic_scores of the test half at once, with a classifier trained here."""
    from sklearn_radar.reproduce._classification import classifier_model

    results = RunResults.read(classified / "results.json")
    entry = results.classification.settings["#1"]
    test = results.classification.test_sequences
    every = np.unique(load_radarscenes(tiny_folder).data["sequence"])
    train = sorted(set(every.tolist()) - set(test))
    from sklearn_radar.experiments import experiment_pipeline

    pipeline = experiment_pipeline(1).set_params(**entry.params)
    model = classifier_model(pipeline)
    train_data = load_radarscenes(tiny_folder, sequences=train).data
    model.fit(train_data.drop(columns=["uuid", "label_id"]), road_user_class(train_data["label_id"]))
    test_scenes = load_radarscenes(tiny_folder, sequences=test)
    data = test_scenes.data
    found = model[-1].predict_instances(model[:-1].transform(data.drop(columns=["uuid", "label_id"])))
    assert len(found) == len(data)  # rows in = rows out
    scores = semantic_scores(
        road_user_class(data["label_id"]),
        np.asarray(test_scenes.target),
        found["class"].to_numpy(),
        found["instance"].to_numpy(),
        found["confidence"].to_numpy(),
        times=data["timestamp"].to_numpy(dtype=np.float64) * 1e-6,
        groups=data["sequence"].to_numpy(),
        window=0.5,
    )
    for key in ("pq", "map", "macro_f1", "mcov"):
        assert getattr(entry.scores, key) == pytest.approx(scores[key], abs=1e-9), key


def _setting(name, per_sequence, before=0.5):
    mean = float(np.mean(per_sequence))
    scores = SemanticScores(window_s=0.5, pq=mean, sq=1.0, rq=mean, map=mean, macro_f1=mean, mcov=mean, per_class={})
    return ClassifiedSetting(
        name=name,
        setting_source="tuned",
        params={},
        scores=scores,
        per_sequence={key: list(per_sequence) for key in ("pq", "map", "macro_f1", "mcov")},
        background_share_before=before,
        background_share_after=0.1,
        n_training_examples=10,
    )


def test_the_answer_says_higher_only_beyond_two_standard_errors(classified):
    """Hand-made per-sequence scores: consistent gains hold, a gain within the spread cannot tell."""
    results = RunResults.read(classified / "results.json")
    clear = {"#1": _setting("#1", [0.5, 0.52, 0.48, 0.5]), "#13": _setting("#13", [0.6, 0.61, 0.59, 0.62])}
    noisy = {"#1": _setting("#1", [0.5, 0.7, 0.3, 0.5]), "#13": _setting("#13", [0.6, 0.2, 0.8, 0.5])}
    assert results.experiments[1].search is None  # the fixed #1 has no CV score: #13 is the one chosen
    for settings, expected in ((clear, "yes, it is higher"), (noisy, "cannot tell")):
        results.classification = ClassificationResult(settings=settings, test_sequences=[0, 1, 2, 3], wall_time_s=1.0)
        lines = [line for line in answer_lines(results) if "best cross-validated V1 of those classified (#13" in line]
        assert len(lines) == 2 and all(expected in line for line in lines), lines
    assert markdown(results)[1] == "## Beyond the paper: classifying the clusters"


def test_the_strongest_offline_baseline_skips_the_causal_one(classified):
    results = RunResults.read(classified / "results.json")
    name, result = strongest_offline_baseline(results.baselines)
    assert "sliding" not in name
    offline = {n: r.search.cv_best for n, r in results.baselines.items() if "sliding" not in n}
    assert result.search.cv_best == max(offline.values())  # chosen on the training half, not by a test score
    assert strongest_offline_baseline(None) is None


def test_the_run_saves_each_tuned_settings_classifier_for_the_cluster_command(classified, tiny_folder, tmp_path):
    """Saved beside params.json, listed there and in run.json; `cluster --classifier` applies it (devkit classes)."""
    from sklearn_radar.classification import load_classifier

    results = RunResults.read(classified / "results.json")
    settings = results.classification.settings
    assert settings["#1"].classifier_file == "classifier_1.joblib"
    assert settings["#13"].classifier_file == "classifier_13.joblib"
    assert settings["#8"].classifier_file is None  # the paper's setting: no params.json entry to go with it
    assert settings[POINT_WISE].classifier_file is None
    saved = sorted(p.name for p in classified.glob("*.joblib"))
    assert saved == sorted(results.saved_classifiers())
    params = json.loads((classified / "params.json").read_text())
    assert params["experiments"]["13"]["classifier"] == "classifier_13.joblib"
    marker = json.loads((classified / "run.json").read_text())
    assert set(saved) <= set(marker["files"])
    model = load_classifier(classified / "classifier_13.joblib")
    assert model[-1].n_training_examples_ == settings["#13"].n_training_examples
    out = tmp_path / "predictions.json"
    with contextlib.redirect_stdout(io.StringIO()):
        code = main(
            [
                "cluster",
                "--data",
                str(tiny_folder),
                "--classifier",
                str(classified / "classifier_13.joblib"),
                "--out",
                str(out),
            ]
        )
    assert code == 0
    document = json.loads(out.read_text())
    assert document["new_label_names"]["5"] == "STATIC"  # the devkit's class numbering, not NOISE / CLUSTERED
    entries = {key: value for key, value in document.items() if isinstance(value, dict) and len(value) > 20}
    (predictions,) = entries.values()
    data = load_radarscenes(tiny_folder).data
    assert set(predictions) == set(data["uuid"].astype(str)) and len(predictions) == len(data)


@pytest.fixture(scope="module")
def classified_twice(tiny_folder, tmp_path_factory):
    """#8, #13, the baselines and the classification step, each search repeated twice."""
    out = tmp_path_factory.mktemp("classification_repeats") / "out"
    _reproduced(tiny_folder, out, "1,8,13,baselines,classification", "--repeats", "2")
    return RunResults.read(out / "results.json")


def test_with_repeats_each_repeats_setting_is_classified(classified_twice):
    from sklearn_radar.reproduce._classification import classified_settings

    results = classified_twice
    settings = results.classification.settings
    assert settings["#1"].repeats is None  # the fixed expert setting runs once
    assert settings[POINT_WISE].repeats is None
    for name in ("#8", "#13", strongest_offline_baseline(results.baselines)[0]):
        assert len(settings[name].repeats) == 2, name
        assert settings[name].repeats[0] == settings[name].scores
    needed = {"8": results.experiments[8], "13": results.experiments[13], "baselines": results.baselines}
    pipelines = dict((name, p) for name, _, p, _ in classified_settings(needed))
    second_8 = results.experiments[8].repeats[1].params
    stage1 = pipelines["#13"][1][-1].stage1.get_params()
    assert all(
        stage1[key.removeprefix("cluster__")] == value for key, value in second_8.items() if key.startswith("cluster__")
    )  # repeat 2 of #13 merges repeat 2 of #8's clusters
    table = "\n".join(markdown(results))
    pq_8 = [s.pq for s in settings["#8"].repeats]
    assert f"{np.mean(pq_8):.3f} \u00b1 {np.std(pq_8, ddof=1):.3f}" in table
    said = _verdict(settings["#8"], settings["#13"], "#13", "pq", "class PQ")
    assert "over the 2 repeats" in said  # both repeated alike: paired by repeat
    said = _verdict(settings["#8"], settings["#1"], "#1", "pq", "class PQ")
    assert f"over the {len(results.classification.test_sequences)} test sequences" in said


def _result(v1, cv=None, bg=0.5):
    """An experiment's or baseline's result as the report reads it: test V1, CV score (None: no search), bg share."""
    from types import SimpleNamespace

    search = None if cv is None else SimpleNamespace(cv_best=cv)
    instance = SimpleNamespace(pq=0.1, background_segment_share=bg)
    return SimpleNamespace(repeats=None, search=search, v1_test=v1, instance_test=instance)


def test_the_answer_chooses_the_clustering_by_its_cv_score_and_names_ties():
    """Not by test V1: #1 (no search) and #11 (not classified) score higher on the test half, #13 ties #8 on CV."""
    from types import SimpleNamespace

    experiments = {1: _result(0.70), 8: _result(0.60, cv=0.75), 11: _result(0.66, cv=0.70), 13: _result(0.62, 0.75)}
    settings = {
        "#1": _setting("#1", [0.05, 0.06, 0.04]),
        "#8": _setting("#8", [0.102, 0.104, 0.100]),
        "#13": _setting("#13", [0.2, 0.2, 0.2]),
    }
    results = SimpleNamespace(
        meta=SimpleNamespace(objective="v1"),
        experiments=experiments,
        baselines={},
        classification=ClassificationResult(settings=settings, test_sequences=[0, 1, 2], wall_time_s=1.0),
    )
    lines = answer_lines(results)
    said = "\n".join(lines)
    assert "best test" not in said
    questions = [line for line in lines if line.startswith("- Does")]
    assert len(questions) == 2
    assert all("best cross-validated V1 of those classified (#8, CV V1 75.00 %; #13 ties it" in q for q in questions)
    assert all("for the best other, #1" in q for q in questions)  # #13 tied: not a rival
    (map_line,) = [q for q in questions if "by mAP@0.5?" in q]
    assert "mAP@0.5 10.2 % against 5.0 %" in map_line and "+5.2 points" in map_line  # percent, as in the table
    assert "without a search (#1)" in said and "no cross-validated PQ to choose by" in said


def test_average_precision_by_class_is_in_percent_as_the_tables_map():
    import dataclasses

    from sklearn_radar.reproduce._sections._classification import _per_class

    row = _setting("#8", [0.1, 0.1])
    row = dataclasses.replace(row, scores=dataclasses.replace(row.scores, per_class={"car": {"ap": 0.3125}}))
    assert _per_class(row, "ap") == "car 31.2 %"


def test_the_background_share_before_classifying_is_the_object_level_tables(classified):
    """One figure printed once: the classification table prints the object-level table's (not a second figure)."""
    import dataclasses

    results = RunResults.read(classified / "results.json")
    settings = results.classification.settings
    ran = {"#1": results.experiments[1], "#13": results.experiments[13], **results.baselines}
    ran = {name: result for name, result in ran.items() if name in settings}
    assert len(ran) == 3  # #1, #13 and the strongest baseline
    for name in ran:  # a second figure that differs, as the raw target gave it before
        settings[name] = dataclasses.replace(settings[name], background_share_before=0.999)
    report = "\n".join(markdown(results))
    assert "99.9 %" not in report
    for name, result in ran.items():
        cell = f"{100 * result.instance_test.background_segment_share:.1f} %"
        row = next(line for line in report.splitlines() if line.startswith(f"| {name}, "))
        assert f"| {cell} / " in row, name


def test_the_step_counts_background_against_the_target_of_the_object_level_scores(tiny_folder):
    """The classification step's own share uses the pre-clustered target (``sequence.target``), as instance_test."""
    from sklearn_radar.experiments import experiment_pipeline
    from sklearn_radar.metrics import background_share
    from sklearn_radar.reproduce._classification import (
        _classified_setting,
        classified_sequence,
        classifier_model,
        model_input,
    )
    from sklearn_radar.reproduce._sequences import Sequence

    scenes = load_radarscenes(tiny_folder)
    numbers = np.unique(scenes.data["sequence"])
    train = load_radarscenes(tiny_folder, sequences=[int(numbers[0])]).data
    model = classifier_model(experiment_pipeline(1))
    model.fit(model_input(train), road_user_class(train["label_id"]))
    test = load_radarscenes(tiny_folder, sequences=[int(numbers[1])])
    raw = np.asarray(test.target)
    target = np.where(np.isin(raw, np.unique(raw[raw >= 0])[::2]), -1, raw)  # every other object made background
    part = classified_sequence(Sequence(id=int(numbers[1]), scenes=test, target=target), model)
    setting = _classified_setting("#1", "fixed #1", {}, model, [part], None)
    times = test.data["timestamp"].to_numpy(dtype=np.float64) * 1e-6
    expected = background_share(target, part["clusters"], times=times, window=0.5).background_segment_share
    wrong = background_share(raw, part["clusters"], times=times, window=0.5).background_segment_share
    assert expected != wrong  # the two targets tell apart
    assert setting.background_share_before == pytest.approx(expected, abs=1e-12)


def _section(report, title):
    """The lines of the report's section whose heading contains ``title``."""
    start = next(i for i, line in enumerate(report.splitlines()) if line.startswith("## ") and title in line)
    lines = report.splitlines()[start + 1 :]
    return lines[: next((i for i, line in enumerate(lines) if line.startswith("## ")), len(lines))]


def test_the_data_section_names_the_librarys_class_of_each_label_it_shows(classified):
    from sklearn_radar import LABELS
    from sklearn_radar.classification import CLASS_OF_LABEL, ROAD_USER_CLASSES

    report = (classified / "report.md").read_text()
    data = "\n".join(_section(report, "The data"))
    shown = [label for label, name in LABELS.items() if f"\n{name} " in data]
    assert shown  # the per-class table lists the data's labels
    for label in shown:
        assert f"{ROAD_USER_CLASSES[CLASS_OF_LABEL[label]]}: " in data and LABELS[label] in data.split("```")[-1]


def test_the_strongest_offline_baseline_is_chosen_by_its_cv_score_not_its_test_score():
    from types import SimpleNamespace

    def baseline(cv, pq):
        return SimpleNamespace(search=SimpleNamespace(cv_best=cv), instance_test=SimpleNamespace(pq=pq))

    dbscan, hdbscan = (name for name in SKLEARN_BASELINES if "per sequence" in name)
    baselines = {dbscan: baseline(cv=0.8, pq=0.3), hdbscan: baseline(cv=0.6, pq=0.5)}
    assert strongest_offline_baseline(baselines)[0] == dbscan


@pytest.fixture(scope="module")
def classified_objects(tiny_folder, tmp_path_factory):
    """The object experiment, the learned grouping and the classification step (the paper's settings beside)."""
    return _reproduced(
        tiny_folder, tmp_path_factory.mktemp("classified_objects") / "out", "objects,learned,classification"
    )


def test_the_settings_meant_for_objects_are_classified_and_their_classifiers_saved(classified_objects, tiny_folder):
    """The object experiment (PQ-tuned) and the learned grouping are rows, with a classifier `cluster` applies."""
    from sklearn_radar.classification import load_classifier
    from sklearn_radar.experiments._learned import load_learned

    results = RunResults.read(classified_objects / "results.json")
    settings = results.classification.settings
    assert list(settings) == ["#1", "#3", "#8", "#13", "objects", "learned", POINT_WISE]
    objects = settings["objects"]
    assert objects.params == {**results.objects.kept.stage1_params, **results.objects.kept.params}
    assert objects.classifier_file == "classifier_objects.joblib"
    assert settings["learned"].classifier_file == "classifier_learned.joblib"
    params = json.loads((classified_objects / "params.json").read_text())
    assert params["experiments"]["objects"]["classifier"] == "classifier_objects.joblib"
    assert params["experiments"]["learned"]["classifier"] == "classifier_learned.joblib"
    # The learned row classifies the saved model's clusters: its clusterer labels as the saved pipeline does.
    learned = load_learned(classified_objects / "learned.joblib")
    classifier = load_classifier(classified_objects / "classifier_learned.joblib")
    data = load_radarscenes(tiny_folder).data
    working = classifier[:-1].transform(data[[c for c in data.columns if c not in ("uuid", "label_id")]])
    expected = learned[-1].predict(working[list(learned[-1].feature_names_in_)])
    np.testing.assert_array_equal(classifier[-1]._cluster(working, len(working)), expected)
    report = "\n".join(_section((classified_objects / "report.md").read_text(), "classifying the clusters"))
    for name in ("objects", "learned"):
        row = next(line for line in report.splitlines() if line.startswith(f"| {name}, "))
        assert "| - |" not in row.split("|", 3)[2], row  # the clustering's test V1 is shown
    for name in ("objects", "learned"):
        out = tiny_folder.parent / f"predictions_{name}.json"
        with contextlib.redirect_stdout(io.StringIO()):
            code = main(
                [
                    "cluster",
                    "--data",
                    str(tiny_folder),
                    "--classifier",
                    str(classified_objects / f"classifier_{name}.joblib"),
                    "--out",
                    str(out),
                ]
            )
        assert code == 0, name
        document = json.loads(out.read_text())
        assert document["new_label_names"]["5"] == "STATIC"


def test_the_precision_recall_curves_are_saved_drawn_and_shown(classified_objects):
    """Per class, the curve whose mean is the AP (to the 3 decimals kept); the figure in the section."""
    results = RunResults.read(classified_objects / "results.json")
    for name, row in results.classification.settings.items():
        curves = row.scores.precision_at_recall
        assert curves and set(curves) <= set(row.scores.per_class), name
        for cls, precision in curves.items():
            assert len(precision) == 101 and all(0.0 <= p <= 1.0 for p in precision)
            assert np.all(np.diff(precision) <= 1e-12)  # interpolated: never rising with recall
            assert np.mean(precision) == pytest.approx(row.scores.per_class[cls]["ap"], abs=1e-3), (name, cls)
    assert (classified_objects / "classification_precision_recall.png").stat().st_size > 0
    report = "\n".join(_section((classified_objects / "report.md").read_text(), "classifying the clusters"))
    assert "![precision-recall per class](classification_precision_recall.png)" in report
