"""The object experiment in 'sklearn-radar reproduce': its searches, its saved setting rescored, its report section."""

import contextlib
import io
import json

import numpy as np
import pytest

from sklearn_radar.cli import main
from sklearn_radar.reproduce._results import RunResults
from sklearn_radar.reproduce._sections._objects import verdict


@pytest.fixture(scope="module")
def objects_report(tiny_folder, tmp_path_factory):
    out = tmp_path_factory.mktemp("objects") / "out"
    args = ["reproduce", "--data", str(tiny_folder), "--out", str(out), "--n-iter", "2", "--repeats", "2"]
    with contextlib.redirect_stdout(io.StringIO()):
        assert main([*args, "--experiments", "objects"]) == 0
    return out


def _rescored_pq(folder, results, record, causal):
    """Test PQ of a saved object setting, computed apart from the reproduce code (pipeline, data, metric)."""
    from sklearn_radar.datasets import load_radarscenes
    from sklearn_radar.experiments import object_pipeline
    from sklearn_radar.metrics import panoptic_quality, precluster_target

    test_sequences = results["meta"]["data"]["test_sequences"]
    scenes = load_radarscenes(folder)
    test = np.flatnonzero(np.isin(scenes.groups, test_sequences))
    target = precluster_target(scenes.data, scenes.target)[test]
    pipeline = object_pipeline(2, stage1_params=record["stage1_params"], params=record["params"], causal=causal)
    X = scenes.data.iloc[test]
    labels = pipeline.fit_predict(X)
    times = X["timestamp"].to_numpy(dtype=np.float64) * 1e-6
    return panoptic_quality(target, labels, times=times, groups=scenes.groups[test]).pq


def test_both_repeats_search_both_stages_and_the_saved_settings_rescore(objects_report, tiny_folder):
    results = json.loads((objects_report / "results.json").read_text())
    objects = results["objects"]
    assert len(objects["repeats"]) == 2 and [r["seed"] for r in objects["repeats"]] == [0, 1]
    assert len(objects["stage1_search"]["convergence"]) == 2 and len(objects["search"]["convergence"]) == 2
    assert set(objects["stage1_params"]) == {
        "cluster__eps_xyv",
        "cluster__vr_scale",
        "cluster__min_samples",
        "cluster__alpha_r",
        "cluster__vr_min",
    }
    assert {key.split("__")[0] for key in objects["params"]} == {"merge"}
    for record in objects["repeats"]:
        for causal, key in ((False, "instance_test"), (True, "causal_instance_test")):
            pq = _rescored_pq(tiny_folder, results, record, causal)
            assert record[key]["pq"] == pytest.approx(pq, abs=1e-9)
    assert objects["instance_test"] == objects["repeats"][0]["instance_test"]


def test_results_read_back_as_written(objects_report):
    path = objects_report / "results.json"
    document = json.loads(path.read_text())
    assert RunResults.read(path).to_json_dict() == document


def test_report_section_gives_offline_and_causal_scores(objects_report):
    report = (objects_report / "report.md").read_text()
    assert "## Beyond the paper: the framework set up for objects" in report
    results = json.loads((objects_report / "results.json").read_text())
    pq = [r["instance_test"]["pq"] for r in results["objects"]["repeats"]]
    assert f"| object experiment | past and future | PQ | {np.mean(pq):.3f} \u00b1 {np.std(pq, ddof=1):.3f} |" in report
    assert "| object experiment, causal | the past | PQ |" in report
    assert "The baselines did not run" in report


def test_verdict_needs_repeats_and_a_difference_beyond_two_standard_errors():
    # One run: a difference is quoted, never judged.
    assert "cannot tell" in verdict([0.60], [0.50], "B")
    # Paired differences 0.10, 0.12, 0.08: mean 0.10, sd 0.02, se 0.0115; 0.10 > 2 x 0.0115.
    said = verdict([0.60, 0.62, 0.58], [0.50, 0.50, 0.50], "B")
    assert said.startswith("PQ +0.100 \u00b1 0.012") and said.endswith("higher.")
    # Differences +0.05, -0.03, +0.01: mean 0.01, se 0.023: within the noise.
    assert "cannot tell (within the noise)" in verdict([0.55, 0.47, 0.51], [0.50, 0.50, 0.50], "B")
    assert verdict([0.40, 0.41], [0.50, 0.50], "B").endswith("lower.")


def test_baselines_tuned_for_another_objective_are_not_set_beside_the_object_experiment(objects_report):
    """Like with like: a run tuned for V1 sets no V1-tuned baseline beside the PQ-tuned experiment (issue 46, 8)."""
    import dataclasses
    from types import SimpleNamespace

    from sklearn_radar.reproduce._sections import _objects, _summary

    results = RunResults.read(objects_report / "results.json")
    assert results.meta.objective == "v1"
    search = SimpleNamespace(cv_best=0.1)  # every baseline has a search; the choice reads its CV score
    offline = SimpleNamespace(repeats=None, search=search, instance_test=SimpleNamespace(pq=0.116), v1_test=0.5)
    causal = SimpleNamespace(repeats=None, search=search, instance_test=SimpleNamespace(pq=0.09), v1_test=0.4)
    baselines = {"offline baseline": offline, f"causal baseline, {_objects.CAUSAL_MARK}": causal}
    v1_run = dataclasses.replace(results, baselines=baselines)
    section = "\n".join(_objects.markdown(v1_run))
    glance = "\n".join(_summary.markdown(v1_run))
    assert "0.116" not in glance and "0.116" not in section
    assert "baseline" not in section.replace(_objects.NOT_COMPARED, "") and _objects.NOT_COMPARED in section
    assert "not set beside the baselines, which this run tuned for V1" in glance
    assert "the framework set up for objects, tuned for PQ" in glance
    pq_run = dataclasses.replace(v1_run, meta=dataclasses.replace(results.meta, objective="pq"))
    section = "\n".join(_objects.markdown(pq_run))
    assert "| offline baseline | past and future | PQ | 0.116 |" in section and _objects.NOT_COMPARED not in section
    glance = "\n".join(_summary.markdown(pq_run))
    assert "against 0.116 for offline baseline, also tuned for PQ (one run: no verdict)" in glance


def test_the_baselines_beside_the_object_experiment_are_chosen_by_cv_score_not_test_score():
    from types import SimpleNamespace

    from sklearn_radar.reproduce._sections._objects import CAUSAL_MARK, _best_baselines

    def baseline(cv, pq):
        return SimpleNamespace(search=SimpleNamespace(cv_best=cv), instance_test=SimpleNamespace(pq=pq), repeats=None)

    baselines = {
        "per sequence A": baseline(cv=0.8, pq=0.3),
        "per sequence B": baseline(cv=0.6, pq=0.5),
        f"window ({CAUSAL_MARK}) C": baseline(cv=0.4, pq=0.6),
        f"window ({CAUSAL_MARK}) D": baseline(cv=0.5, pq=0.2),
    }
    offline, causal = _best_baselines(SimpleNamespace(baselines=baselines))
    assert offline[0] == "per sequence A" and causal[0] == f"window ({CAUSAL_MARK}) D"


def test_the_glance_verdict_on_the_object_experiment_against_a_baseline_names_its_direction():
    from sklearn_radar.reproduce._sections._objects import _said

    assert _said([0.5], [0.6]) == "one run: no verdict"
    assert _said([0.50, 0.60, 0.55], [0.40, 0.49, 0.45]) == "3 repeats: higher beyond 2 standard errors"
    assert _said([0.40, 0.49, 0.45], [0.50, 0.60, 0.55]) == "3 repeats: lower beyond 2 standard errors"
    assert _said([0.50, 0.40, 0.45], [0.45, 0.45, 0.45]) == "3 repeats: within the noise"
