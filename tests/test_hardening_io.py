"""Hardening of the command line and the output folders (issue 15, items 4-8)."""

import hashlib
import json
import os
import signal
import stat
import subprocess
import sys
import time

import pytest

from sklearn_radar.cli import main
from sklearn_radar.datasets import make_scenes, write_radarscenes


@pytest.fixture(scope="module")
def small_folder(tmp_path_factory):
    path = tmp_path_factory.mktemp("data") / "small"
    write_radarscenes(make_scenes(n_sequences=1, duration=1.0, random_state=0), path)
    return path


def _one_line_error(capsys):
    err = capsys.readouterr().err
    assert err.startswith("sklearn-radar: error:"), err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    return err


# ----------------------------------------------------------------------------- item 4: params.json of 'cluster'

_GOOD_SETTING = {"experiment": 8, "v1_test": 0.5, "params": {"cluster__eps_xyv": 1.0}, "stage1_params": None}


def _setting(**changes):
    setting = {**_GOOD_SETTING, **changes}
    return {key: value for key, value in setting.items() if value is not _DROP}


_DROP = object()


@pytest.mark.parametrize(
    "document, named",
    [
        ({"best": "8", "experiments": {"8": _setting(params=_DROP)}}, "'params'"),
        ({"best": "8", "experiments": {"8": _setting(experiment=_DROP)}}, "'experiment'"),
        ({"best": "8", "experiments": {"8": _setting(params=["a"])}}, "'params'"),
        ({"best": "8", "experiments": {"8": _setting(params={"cluster__nosuch": 1})}}, "cluster__nosuch"),
        ({"best": "8", "experiments": {"8": _setting(params={"cluster__eps_xyv": "big"})}}, "eps_xyv"),
        ({"best": "8", "experiments": {"8": _setting(params={"cluster__eps_xyv": -1})}}, "eps_xyv"),
        ({"best": "8", "experiments": {"8": _setting(experiment="eight")}}, "'experiment'"),
        ({"best": "8", "experiments": {"8": _setting(experiment=99)}}, "'experiment'"),
        ({"best": "8", "experiments": {"8": _setting(experiment=True)}}, "'experiment'"),
        ({"best": "8", "experiments": {"8": _setting(experiment=2)}}, "'experiment'"),
        ({"best": "12", "experiments": {"12": _setting(experiment=12, stage1_params=[1])}}, "'stage1_params'"),
        ({"best": "8", "experiments": {"8": "setting"}}, "'8'"),
        ({"best": "8", "experiments": ["8"]}, "'experiments'"),
        ({"best": "9", "experiments": {"8": _setting()}}, "'best'"),
        ({"best": 8, "experiments": {"8": _setting()}}, "'best'"),
        ({"experiments": {"8": _setting()}}, "'best'"),
        ({"best": "8"}, "'experiments'"),
        ([1, 2], "top level"),
    ],
)
def test_bad_params_file_is_a_one_line_error_naming_the_key(small_folder, tmp_path, capsys, document, named):
    params = tmp_path / "params.json"
    params.write_text(json.dumps(document))
    out = tmp_path / "p.json"
    assert main(["cluster", "--data", str(small_folder), "--params", str(params), "--out", str(out)]) == 1
    err = _one_line_error(capsys)
    assert str(params) in err and named in err
    assert not out.exists()


def test_params_file_missing_the_chosen_experiment_names_it(small_folder, tmp_path, capsys):
    params = tmp_path / "params.json"
    params.write_text(json.dumps({"best": "8", "experiments": {"8": _setting()}}))
    argv = ["cluster", "--data", str(small_folder), "--params", str(params), "--out", str(tmp_path / "p.json")]
    assert main([*argv, "--experiment", "3"]) == 1
    err = _one_line_error(capsys)
    assert str(params) in err and "experiment 3" in err


def test_good_params_file_still_clusters(small_folder, tmp_path, capsys):
    params = tmp_path / "params.json"
    params.write_text(json.dumps({"best": "8", "experiments": {"8": _setting()}}))
    out = tmp_path / "p.json"
    assert main(["cluster", "--data", str(small_folder), "--params", str(params), "--out", str(out)]) == 0
    assert json.loads(out.read_text())["schema"] == 2


# ----------------------------------------------------------------------------- item 6: the umask


@pytest.fixture(params=[0o022, 0o027, 0o077], ids=["022", "027", "077"])
def umask(request):
    old = os.umask(request.param)
    yield request.param
    os.umask(old)


def _modes(root):
    """{relative path: permission bits} of ``root`` and everything below it."""
    return {str(p.relative_to(root)): stat.S_IMODE(p.stat().st_mode) for p in [root, *root.rglob("*")]}


def test_simulate_honours_the_umask(tmp_path, umask, capsys):
    out = tmp_path / "sim"
    assert main(["simulate", "--out", str(out), "--n-sequences", "1", "--duration", "1"]) == 0
    modes = _modes(out)
    expected = {name: (0o777 if (out / name).is_dir() else 0o666) & ~umask for name in modes}
    assert modes == expected
    # ...also when an existing folder is replaced
    assert main(["simulate", "--out", str(out), "--n-sequences", "1", "--duration", "1", "--overwrite"]) == 0
    assert _modes(out) == expected


def test_cluster_predictions_and_reproduce_files_honour_the_umask(small_folder, tmp_path, umask, capsys):
    from sklearn_radar._files import atomic_write_text, check_writable

    params = tmp_path / "params.json"
    params.write_text(json.dumps({"best": "8", "experiments": {"8": _setting()}}))
    out = tmp_path / "p.json"
    assert main(["cluster", "--data", str(small_folder), "--params", str(params), "--out", str(out)]) == 0
    assert stat.S_IMODE(out.stat().st_mode) == 0o666 & ~umask
    folder = tmp_path / "report" / "deeper"
    check_writable(folder)
    atomic_write_text(folder / "results.json", "{}")
    assert stat.S_IMODE(folder.stat().st_mode) == 0o777 & ~umask
    assert stat.S_IMODE((folder / "results.json").stat().st_mode) == 0o666 & ~umask


# ----------------------------------------------------------------------------- item 7: the output folder of a run

# Runs the command line in a child process that SIGKILLs itself when a chosen file is about to be renamed into
# place (the atomic writes end with os.replace), or when the writer of a data folder writes its second HDF5 file.
_KILLER = """
import os, signal, sys
kill_at, argv = sys.argv[1], sys.argv[2:]
real_replace = os.replace
def replace(src, dst, *args, **kwargs):
    if kill_at != "h5" and str(dst).endswith(kill_at):
        os.kill(os.getpid(), signal.SIGKILL)
    return real_replace(src, dst, *args, **kwargs)
os.replace = replace
if kill_at == "h5":
    from sklearn_radar.datasets import _radarscenes_writer
    real_write, calls = _radarscenes_writer._write_radar_data_h5, []
    def write(*args):
        calls.append(args)
        if len(calls) == 2:
            os.kill(os.getpid(), signal.SIGKILL)
        real_write(*args)
    _radarscenes_writer._write_radar_data_h5 = write
from sklearn_radar.cli import main
sys.exit(main(argv))
"""


def _killed(kill_at, argv):
    result = subprocess.run(
        [sys.executable, "-c", _KILLER, kill_at, *argv], capture_output=True, text=True, timeout=600, check=False
    )
    assert result.returncode == -signal.SIGKILL, result.stderr
    return result


@pytest.fixture(scope="module")
def two_folder(tmp_path_factory):
    path = tmp_path_factory.mktemp("data") / "two"
    write_radarscenes(make_scenes(n_sequences=2, duration=2.0, random_state=1), path)
    return path


def _reproduce_argv(data, out):
    return ["reproduce", "--data", str(data), "--out", str(out), "--experiments", "1"]


def _run_marker(out):
    return json.loads((out / "run.json").read_text())


def _assert_complete_and_unmixed(out):
    marker = _run_marker(out)
    assert marker["complete"] is True and marker["status"] == "complete"
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted([*marker["files"], "run.json"]), "files of another run, or temporary files, remain"
    for name, digest in marker["files"].items():
        assert hashlib.sha256((out / name).read_bytes()).hexdigest() == digest, name
    assert "wall_time_s" in json.loads((out / "results.json").read_text())["meta"]


def test_a_run_killed_while_drawing_figures_is_marked_incomplete_and_cleaned_next_time(two_folder, tmp_path, capsys):
    out = tmp_path / "out"
    _killed(".png", _reproduce_argv(two_folder, out))
    assert not (out / "report.md").exists()
    assert _run_marker(out)["complete"] is False
    results = json.loads((out / "results.json").read_text())
    assert "wall_time_s" not in results["meta"], "results.json must not look finished while report.md is missing"
    assert [p for p in out.iterdir() if p.name.startswith(".")], "the killed run should have left its temporary files"
    assert main(_reproduce_argv(two_folder, out)) == 0
    _assert_complete_and_unmixed(out)


def test_a_new_run_never_sits_beside_the_old_runs_report(two_folder, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(_reproduce_argv(two_folder, out)) == 0
    _assert_complete_and_unmixed(out)
    old = _run_marker(out)
    _killed("results.json", _reproduce_argv(two_folder, out))
    names = {p.name for p in out.iterdir() if not p.name.startswith(".")}
    assert names == {"run.json"}, f"the old run's files remain beside the new run's: {names}"
    marker = _run_marker(out)
    assert marker["complete"] is False and marker["run_id"] != old["run_id"]


def test_stale_temporary_files_are_removed_and_live_ones_kept(two_folder, tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    finished = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    dead = int(finished.stdout)
    stale = out / f".sklearn-radar-tmp-{dead}-cache-abc"
    (stale / "joblib").mkdir(parents=True)
    (stale / "joblib" / "big.npy").write_bytes(b"0" * 1000)
    (out / f".sklearn-radar-tmp-{dead}-results.json.x.tmp").write_text("{")
    legacy = out / ".report.md.k3j2.tmp"  # the name of a temporary file before the prefix
    legacy.write_text("old")
    live = out / f".sklearn-radar-tmp-{os.getppid()}-results.json.y.tmp"
    live.write_text("{")
    mine = out / "notes.txt"  # not a run's file: left alone
    mine.write_text("mine")
    assert main(_reproduce_argv(two_folder, out)) == 0
    hidden = sorted(p.name for p in out.iterdir() if p.name.startswith("."))
    assert hidden == [live.name]
    assert mine.read_text() == "mine"


def test_a_killed_simulate_leaves_no_hidden_folder_after_the_next_write(tmp_path, capsys):
    out = tmp_path / "sim"
    argv = ["simulate", "--out", str(out), "--n-sequences", "2", "--duration", "1"]
    _killed("h5", argv)
    assert not out.exists()
    assert main(argv) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sim"]


# ----------------------------------------------------------------------------- item 8: smaller things


def test_simulate_onto_a_file_says_it_is_a_file_and_names_the_option(tmp_path, capsys):
    afile = tmp_path / "afile"
    afile.write_text("mine")
    assert main(["simulate", "--out", str(afile), "--n-sequences", "1", "--duration", "1"]) == 1
    err = _one_line_error(capsys)
    assert "is a file" in err and "--overwrite" in err and "overwrite=True" not in err
    assert afile.read_text() == "mine"
    full = tmp_path / "full"
    (full / "x").mkdir(parents=True)
    assert main(["simulate", "--out", str(full), "--n-sequences", "1", "--duration", "1"]) == 1
    err = _one_line_error(capsys)
    assert "not written by sklearn-radar" in err and "--overwrite" in err and "overwrite=True" not in err
    assert main(["simulate", "--out", str(afile / "sim"), "--n-sequences", "1", "--duration", "1"]) == 1
    err = _one_line_error(capsys)
    assert f"{afile} is a file" in err and "Errno" not in err


@pytest.mark.parametrize("below", [False, True], ids=["the file", "below it"])
def test_reproduce_out_on_a_file_says_it_is_a_file(two_folder, tmp_path, capsys, below):
    afile = tmp_path / "afile"
    afile.write_text("mine")
    assert main(_reproduce_argv(two_folder, afile / "r" if below else afile)) == 1
    err = _one_line_error(capsys)
    assert "is a file" in err and "Errno" not in err and afile.read_text() == "mine"


@pytest.mark.parametrize("where", ["missing folder", "a folder", "a file as folder"])
def test_cluster_out_errors_name_the_file_not_a_temporary_one(small_folder, tmp_path, capsys, where):
    params = tmp_path / "params.json"
    params.write_text(json.dumps({"best": "8", "experiments": {"8": _setting()}}))
    (tmp_path / "afile").write_text("")
    out = {
        "missing folder": tmp_path / "nowhere" / "p.json",
        "a folder": tmp_path,
        "a file as folder": tmp_path / "afile" / "p.json",
    }[where]
    assert main(["cluster", "--data", str(small_folder), "--params", str(params), "--out", str(out)]) == 1
    err = _one_line_error(capsys)
    assert str(out) in err and ".tmp" not in err and "Errno" not in err


def test_reproduce_with_missing_data_leaves_no_output_folder(tmp_path, capsys):
    out = tmp_path / "r1" / "r2"
    assert main(["reproduce", "--data", str(tmp_path / "nosuchdir"), "--out", str(out)]) == 1
    _one_line_error(capsys)
    assert list(tmp_path.iterdir()) == []


def test_stats_into_a_closed_pipe_is_quiet(small_folder):
    process = subprocess.Popen(
        [sys.executable, "-m", "sklearn_radar", "stats", "--data", str(small_folder)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    process.stdout.close()  # the reader is gone before anything is written: as 'sklearn-radar stats | head -0'
    _, err = process.communicate(timeout=300)
    assert process.returncode == 0 and err.decode() == ""


def test_data_under_a_non_utf8_path_is_reported(two_folder, tmp_path, capsys):
    import shutil

    data = tmp_path / os.fsdecode(b"d\xffata")
    shutil.copytree(two_folder, data)
    out = tmp_path / os.fsdecode(b"o\xfeut")
    assert main(["stats", "--data", str(data)]) == 0
    assert main(_reproduce_argv(data, out)) == 0, capsys.readouterr().err
    _assert_complete_and_unmixed(out)
    report = (out / "report.md").read_text(encoding="utf-8")
    assert "d\\xffata" in report


def test_n_jobs_help_gives_the_default(capsys):
    with pytest.raises(SystemExit):
        main(["reproduce", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    options = text.split(" options: ", 1)[1]  # past the usage line
    n_jobs = options[options.index("--n-jobs J") :].split(" --")[0]
    assert "default" in n_jobs


def test_an_interrupt_during_the_start_up_imports_is_one_line(monkeypatch, capsys):
    import sklearn_radar.cli._main as cli

    def interrupted():
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "_import_the_estimators", interrupted)
    assert cli.main(["stats", "--data", "anywhere"]) == 130  # --version no longer imports them
    assert capsys.readouterr().err == "sklearn-radar: interrupted\n"


@pytest.mark.slow  # timing-dependent: on a loaded machine the signal can land in Python's own start-up
def test_sigint_during_the_start_up_imports_prints_no_traceback(small_folder):
    process = subprocess.Popen(
        [sys.executable, "-m", "sklearn_radar", "stats", "--data", str(small_folder)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    time.sleep(0.4)
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=60)
    assert "Traceback" not in err.decode(), err.decode()
    assert process.returncode == 130


@pytest.mark.parametrize("error, status, code", [(KeyboardInterrupt, "interrupted", 130), (ValueError, "failed", 1)])
def test_an_interrupted_or_failed_run_is_marked_so(two_folder, tmp_path, monkeypatch, capsys, error, status, code):
    import dataclasses

    from sklearn_radar.reproduce._steps import STEPS

    def fail(*args, **kwargs):
        raise error("stopped here")

    monkeypatch.setitem(STEPS, "filter-effect", dataclasses.replace(STEPS["filter-effect"], run=fail))
    out = tmp_path / "out"
    argv = ["reproduce", "--data", str(two_folder), "--out", str(out), "--experiments", "1,filter-effect"]
    assert main(argv) == code
    marker = _run_marker(out)
    assert marker["status"] == status and marker["complete"] is False
    assert not [p for p in out.iterdir() if p.name.startswith(".")]
