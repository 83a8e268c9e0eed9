"""The command line starts without the heavy imports, and checks every option before anything is written (issue 26)."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from sklearn_radar.cli import main

ROOT = Path(__file__).resolve().parents[2]

#: Modules that ``--help`` and ``--version`` must not import: they make every call take seconds.
HEAVY = ("sklearn", "numpy", "pandas", "numba", "scipy", "h5py", "matplotlib", "joblib")

# Runs ``python -m sklearn_radar ARGS`` in this process and prints the heavy modules it imported.
_IMPORTED = """
import json, runpy, sys
heavy, sys.argv, code = json.loads(sys.argv[1]), ["sklearn-radar", *sys.argv[2:]], None
try:
    runpy.run_module("sklearn_radar", run_name="__main__", alter_sys=True)
except SystemExit as exit_:
    code = exit_.code
print(json.dumps({"code": code, "imported": sorted(m for m in sys.modules if m.split(".")[0] in heavy)}))
"""


@pytest.mark.parametrize(
    "argv",
    [
        ["--version"],
        ["--help"],
        ["simulate", "--help"],
        ["stats", "--help"],
        ["reproduce", "--help"],
        ["cluster", "--help"],
    ],
)
def test_help_and_version_import_no_heavy_module(argv):
    result = subprocess.run(
        [sys.executable, "-c", _IMPORTED, json.dumps(HEAVY), *argv], capture_output=True, text=True, cwd=ROOT
    )
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout.strip().splitlines()[-1])
    assert report["code"] == 0
    assert report["imported"] == [], f"{argv} imported {report['imported']}"


def test_the_subprocess_check_sees_heavy_imports():
    # The check above could pass by never seeing an import: a command that does import them must show them.
    script = _IMPORTED.replace(
        'runpy.run_module("sklearn_radar", run_name="__main__", alter_sys=True)', "import sklearn"
    )
    result = subprocess.run([sys.executable, "-c", script, json.dumps(HEAVY)], capture_output=True, text=True, cwd=ROOT)
    assert "sklearn" in json.loads(result.stdout)["imported"]


def test_a_command_still_imports_the_estimators_where_an_interrupt_is_caught(monkeypatch, capsys):
    import sklearn_radar.cli._main as cli

    def interrupted():
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "_import_the_estimators", interrupted)
    assert cli.main(["stats", "--data", "anywhere"]) == 130
    assert capsys.readouterr().err == "sklearn-radar: interrupted\n"


def test_an_interrupt_while_parsing_is_one_line(monkeypatch, capsys):
    import sklearn_radar.cli._main as cli

    def interrupted():
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "_parser", interrupted)
    assert cli.main(["--version"]) == 130
    assert capsys.readouterr().err == "sklearn-radar: interrupted\n"


# ----------------------------------------------------------------------------- every option, before any write


def _simulate(out, *options):
    return ["simulate", "--out", str(out), "--n-sequences", "1", "--duration", "1", *options]


def _reproduce(out, *options):
    return ["reproduce", "--out", str(out), "--experiments", "1", *options]


def _cluster(out, *options):
    return ["cluster", "--data", "nowhere", "--params", "nowhere.json", "--out", str(out), *options]


@pytest.mark.parametrize(
    "command, options, flag",
    [
        (_simulate, ["--n-sequences", "0"], "--n-sequences"),
        (_simulate, ["--n-sequences", "two"], "--n-sequences"),
        (_simulate, ["--duration", "0"], "--duration"),
        (_simulate, ["--duration", "nan"], "--duration"),
        (_simulate, ["--duration", "inf"], "--duration"),
        (_simulate, ["--seed", "-1"], "--seed"),
        (_simulate, ["--seed", str(2**32)], "--seed"),
        (_simulate, ["--seed", "1.5"], "--seed"),
        (_reproduce, ["--n-jobs", "0"], "--n-jobs"),
        (_reproduce, ["--n-jobs", "all"], "--n-jobs"),
        (_reproduce, ["--n-iter", "0"], "--n-iter"),
        (_reproduce, ["--n-iter", "1e3"], "--n-iter"),
        (_reproduce, ["--repeats", "0"], "--repeats"),
        (_reproduce, ["--n-points", "0"], "--n-points"),
        (_reproduce, ["--seed", "-3"], "--seed"),
        (_reproduce, ["--seed", str(2**32 - 1), "--repeats", "2"], "--seed"),
        (_reproduce, ["--seed", str(2**32 - 2), "--full"], "--seed"),
        (_reproduce, ["--experiments", "1,99"], "--experiments"),
        (_reproduce, ["--experiments", ","], "--experiments"),
        (_reproduce, ["--workers", "0"], "--workers"),
        (_cluster, ["--experiment", "0"], "--experiment"),
        (_cluster, ["--workers", "-1"], "--workers"),
    ],
)
def test_a_bad_option_is_one_line_naming_it_and_nothing_is_written(tmp_path, capsys, command, options, flag):
    out = tmp_path / "out"
    assert main(command(out, *options)) == 2
    err = capsys.readouterr().err
    assert err.startswith("sklearn-radar: error:") and len(err.strip().splitlines()) == 1, err
    assert flag in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == [], "an option error must leave nothing behind"


def test_options_are_checked_before_the_estimators_are_imported(monkeypatch, capsys):
    import sklearn_radar.cli._main as cli

    def not_yet():
        raise AssertionError("imported before the options were checked")

    monkeypatch.setattr(cli, "_import_the_estimators", not_yet)
    assert cli.main(["reproduce", "--n-jobs", "0"]) == 2
    assert "--n-jobs" in capsys.readouterr().err


def test_negative_n_jobs_is_accepted_as_joblib_reads_it(capsys, monkeypatch):
    import sklearn_radar.reproduce as reproduce_module

    seen = {}
    monkeypatch.setattr(reproduce_module, "reproduce", lambda *args, **kwargs: seen.update(kwargs))
    assert main(["reproduce", "--n-jobs", "-1", "--experiments", "1"]) == 0
    assert seen["n_jobs"] == -1


@pytest.mark.parametrize(
    "kwargs",
    [{"n_jobs": 0}, {"seed": 2**32}, {"seed": 2**32 - 1, "repeats": 2}, {"experiments": "1,99"}, {"workers": 0}],
)
def test_the_public_reproduce_refuses_bad_arguments_before_writing(tmp_path, kwargs):
    from sklearn_radar.reproduce import reproduce

    with pytest.raises(ValueError):
        reproduce(None, tmp_path / "out", **kwargs)
    assert list(tmp_path.iterdir()) == []
