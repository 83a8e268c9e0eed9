"""``params.json``'s best setting is chosen by the cross-validated training score, never a test score (issue 46)."""

import json
from pathlib import Path

import pytest

from sklearn_radar.cli import main
from sklearn_radar.datasets import make_scenes, write_radarscenes
from sklearn_radar.experiments import paper_params
from sklearn_radar.experiments._saved import load_params
from sklearn_radar.reproduce._results import RunResults

DEFAULT_RUN = Path(__file__).resolve().parents[1] / "data" / "results_default_run.json"


def _cv_best(document):
    """Each experiment's kept cross-validated score as results.json holds it (None where no search ran)."""
    return {key: record.get("cv_best") for key, record in document["experiments"].items()}


def test_the_best_is_the_highest_cross_validated_score_however_the_test_scores_rank():
    document = json.loads(DEFAULT_RUN.read_text())
    # Test scores that would pick another setting: #10 (no search of its own) and #8 come out on top.
    document["experiments"]["10"]["v1_test"] = 0.99
    document["experiments"]["8"]["v1_test"] = 0.98
    saved = RunResults.from_json_dict(document).to_params_dict()
    cv = _cv_best(document)
    searched = {key: score for key, score in cv.items() if score is not None}
    assert saved["best"] == max(searched, key=searched.get) != "10"
    assert {key: entry["cv_v1"] for key, entry in saved["experiments"].items()} == cv
    assert cv["1"] is None and cv["10"] is None and cv["11"] is None  # not searched: not candidates
    assert saved["best_reason"] == (
        f"the best of {len(searched)} searched settings by cross-validated V1 on the training half "
        f"({searched[saved['best']]:.3f})"
    )


def _results(keys):
    document = json.loads(DEFAULT_RUN.read_text())
    document["experiments"] = {key: document["experiments"][key] for key in keys}
    return RunResults.from_json_dict(document)


def test_a_run_without_a_cross_validated_setting_names_no_best(tmp_path):
    saved = _results(["1", "10"]).to_params_dict()
    assert saved["best"] is None and "no setting of the run has a cross-validated V1" in saved["best_reason"]
    path = tmp_path / "params.json"
    path.write_text(json.dumps(saved))
    with pytest.raises(ValueError, match=r"names no best setting .*choose one by its experiment number"):
        load_params(path)
    assert load_params(path, 10)["experiment"] == 10


def test_a_run_of_one_setting_names_it():
    saved = _results(["1"]).to_params_dict()
    assert (saved["best"], saved["best_reason"]) == ("1", "the run's only setting")


# ----------------------------------------------------------------------------- what cluster says


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    path = tmp_path_factory.mktemp("data") / "small"
    write_radarscenes(make_scenes(n_sequences=1, duration=1.0, random_state=0), path)
    return path


def _params_file(tmp_path, **top):
    setting = {"experiment": 8, "v1_test": 0.5, "cv_v1": 0.71, "params": paper_params(8), "stage1_params": None}
    path = tmp_path / "params.json"
    path.write_text(json.dumps({"best": "8", "experiments": {"8": setting}, **top}))
    return path


@pytest.mark.parametrize("command", ["cluster", "stream"])
def test_the_command_says_why_it_applies_the_files_best(folder, tmp_path, capsys, command):
    reason = "the best of 9 searched settings by cross-validated V1 on the training half (0.710)"
    params = _params_file(tmp_path, best_reason=reason)
    argv = [command, "--data", str(folder), "--params", str(params), "--out", str(tmp_path / "p.json")]
    assert main(argv) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith(f"{'applied' if command == 'cluster' else 'streamed'} experiment #8 of {params}: ")
    assert lines[1] == f"  chosen as {reason}"
    assert main([*argv, "--experiment", "8"]) == 0  # chosen by the user: nothing to explain
    assert "chosen as" not in capsys.readouterr().out


def test_a_file_that_does_not_explain_its_best_is_applied_with_a_caveat(folder, tmp_path, capsys):
    params = _params_file(tmp_path)
    assert main(["cluster", "--data", str(folder), "--params", str(params), "--out", str(tmp_path / "p.json")]) == 0
    assert "  chosen as the file's 'best', which it does not explain (older versions chose it by the test score)" in (
        capsys.readouterr().out
    )


def test_a_best_reason_that_is_no_text_is_refused(tmp_path):
    with pytest.raises(ValueError, match="'best_reason'"):
        load_params(_params_file(tmp_path, best_reason=3))
