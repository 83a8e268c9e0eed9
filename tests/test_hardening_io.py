"""Hardening of the command line and the output folders (issue 15, items 4-8)."""

import json
import os
import stat

import pytest

from sklearn_radar._cli import main
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
    from sklearn_radar.reproduce._io import atomic_write_text, check_writable

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
