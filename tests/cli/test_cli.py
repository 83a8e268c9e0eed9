"""End-to-end tests of the sklearn-radar command line."""

import subprocess
import sys

import pytest

from sklearn_radar.cli import main
from sklearn_radar.datasets import load_radarscenes, make_scenes


def test_help_lists_the_subcommands(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["--help"])
    assert exit_.value.code == 0
    out = capsys.readouterr().out
    assert "simulate" in out and "stats" in out


def test_python_dash_m_runs_the_same_command_line():
    result = subprocess.run([sys.executable, "-m", "sklearn_radar", "--help"], capture_output=True, text=True)
    assert result.returncode == 0
    assert "simulate" in result.stdout


def test_simulate_writes_a_loadable_data_set_equal_to_make_scenes(tmp_path, capsys):
    out = tmp_path / "sim"
    assert main(["simulate", "--out", str(out), "--n-sequences", "2", "--duration", "2", "--seed", "5"]) == 0
    printed = capsys.readouterr().out
    assert "static share" in printed and str(out) in printed
    loaded = load_radarscenes(out)
    expected = make_scenes(n_sequences=2, duration=2.0, random_state=5)
    assert loaded.data.equals(expected.data)


@pytest.mark.parametrize("difficulty", ["easy", "realistic", "radarscenes"])
def test_simulate_difficulty_is_that_of_make_scenes(tmp_path, capsys, difficulty):
    out = tmp_path / "sim"
    argv = ["simulate", "--out", str(out), "--n-sequences", "1", "--duration", "2", "--seed", "3"]
    assert main([*argv, "--difficulty", difficulty]) == 0
    expected = make_scenes(n_sequences=1, duration=2.0, random_state=3, difficulty=difficulty)
    assert load_radarscenes(out).data.equals(expected.data)
    other = make_scenes(
        n_sequences=1, duration=2.0, random_state=3, difficulty={"easy": "realistic"}.get(difficulty, "easy")
    )
    assert not load_radarscenes(out).data.equals(other.data)


def test_stats_prints_the_statistics_of_a_data_folder(tmp_path, capsys):
    main(["simulate", "--out", str(tmp_path / "sim"), "--n-sequences", "1", "--duration", "2"])
    capsys.readouterr()
    assert main(["stats", "--data", str(tmp_path / "sim")]) == 0
    printed = capsys.readouterr().out
    assert "detections per second" in printed
    assert "annotated per scan" in printed and "RadarScenes about 4.2" in printed


def test_existing_output_is_a_one_line_error_without_traceback(tmp_path, capsys):
    out = tmp_path / "sim"
    main(["simulate", "--out", str(out), "--n-sequences", "1", "--duration", "1"])
    capsys.readouterr()
    assert main(["simulate", "--out", str(out), "--n-sequences", "1", "--duration", "1"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("sklearn-radar: error:") and len(err.strip().splitlines()) == 1
    assert "Traceback" not in err


def test_missing_data_folder_is_a_one_line_error(tmp_path, capsys):
    assert main(["stats", "--data", str(tmp_path / "nowhere")]) == 1
    err = capsys.readouterr().err
    assert "nowhere" in err and len(err.strip().splitlines()) == 1


def test_bad_simulation_parameter_is_a_one_line_error_naming_the_option(tmp_path, capsys):
    assert main(["simulate", "--out", str(tmp_path / "x"), "--n-sequences", "0"]) == 2
    assert "--n-sequences" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_reproduce_accepts_every_difficulty_preset():
    from sklearn_radar.cli._main import _parser
    from sklearn_radar.datasets._presets import DIFFICULTY_PRESETS

    for difficulty in DIFFICULTY_PRESETS:
        assert _parser().parse_args(["reproduce", "--difficulty", difficulty]).difficulty == difficulty
    with pytest.raises(SystemExit):
        _parser().parse_args(["reproduce", "--difficulty", "hard"])
