"""Nothing that this package did not write is deleted or replaced (issue 26, part 2).

``simulate``/``write_radarscenes`` replace only a data folder whose manifest
lists every file in it; ``reproduce`` replaces only a run's files in a run's
folder; ``cluster``/``write_predictions`` replace only a predictions file.
"""

import hashlib
import json

import pytest

from sklearn_radar.cli import main
from sklearn_radar.datasets import make_scenes, write_radarscenes
from sklearn_radar.datasets._output_folder import MANIFEST
from sklearn_radar.experiments import paper_params


def _tree(root):
    """{relative path: bytes or None (a folder)} of everything below ``root``."""
    return {p.relative_to(root).as_posix(): None if p.is_dir() else p.read_bytes() for p in sorted(root.rglob("*"))}


def _one_line_error(capsys):
    err = capsys.readouterr().err
    assert err.startswith("sklearn-radar: error:"), err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    return err


def _simulate(out, *options):
    return ["simulate", "--out", str(out), "--n-sequences", "1", "--duration", "1", *options]


@pytest.fixture(scope="module")
def small_folder(tmp_path_factory):
    path = tmp_path_factory.mktemp("data") / "small"
    write_radarscenes(make_scenes(n_sequences=1, duration=1.0, random_state=0), path)
    return path


@pytest.fixture(scope="module")
def two_folder(tmp_path_factory):
    """Two sequences: the least a run splits into training and test."""
    path = tmp_path_factory.mktemp("data") / "two"
    write_radarscenes(make_scenes(n_sequences=2, duration=2.0, random_state=1), path)
    return path


# ----------------------------------------------------------------------------- simulate / write_radarscenes


def test_the_writer_leaves_a_manifest_of_exactly_what_it_wrote(small_folder):
    manifest = json.loads((small_folder / MANIFEST).read_text())
    written = {p.relative_to(small_folder).as_posix() for p in small_folder.rglob("*") if p.is_file()}
    assert sorted([*manifest["files"], MANIFEST]) == sorted(written)


def test_overwrite_replaces_a_previous_output(tmp_path, capsys):
    out = tmp_path / "sim"
    assert main(_simulate(out, "--seed", "1")) == 0
    before = _tree(out)
    assert main(_simulate(out, "--seed", "2", "--overwrite")) == 0
    assert _tree(out) != before and (out / MANIFEST).is_file()


@pytest.mark.parametrize("overwrite", [False, True], ids=["plain", "--overwrite"])
def test_a_user_file_in_a_simulated_folder_keeps_the_folder(tmp_path, capsys, overwrite):
    out = tmp_path / "sim"
    assert main(_simulate(out)) == 0
    (out / "notes.txt").write_text("mine")
    (out / "sequence_1" / "plot.png").write_bytes(b"mine too")
    before = _tree(out)
    capsys.readouterr()
    assert main(_simulate(out, *(["--overwrite"] if overwrite else []))) == 1
    err = _one_line_error(capsys)
    assert str(out) in err and ("notes.txt" in err or "plot.png" in err)
    assert _tree(out) == before


def test_a_plain_file_is_never_replaced_even_with_overwrite(tmp_path, capsys):
    afile = tmp_path / "afile"
    afile.write_text("mine")
    assert main(_simulate(afile, "--overwrite")) == 1
    err = _one_line_error(capsys)
    assert "is a file" in err and afile.read_text() == "mine"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


@pytest.mark.parametrize("content", ["unrelated", "radarscenes"])
def test_a_folder_without_the_manifest_is_never_replaced(tmp_path, small_folder, capsys, content):
    out = tmp_path / "data"
    if content == "radarscenes":  # the very layout the writer writes, e.g. a real download: still not ours
        write_radarscenes(make_scenes(n_sequences=1, duration=1.0, random_state=0), out)
        (out / MANIFEST).unlink()
    else:
        (out / "deep").mkdir(parents=True)
        (out / "deep" / "thesis.tex").write_text("mine")
    before = _tree(out)
    assert main(_simulate(out, "--overwrite")) == 1
    assert MANIFEST in _one_line_error(capsys)
    assert _tree(out) == before


def test_a_symbolic_link_is_never_replaced(tmp_path, capsys):
    target = tmp_path / "target"
    assert main(_simulate(target)) == 0
    link = tmp_path / "link"
    link.symlink_to(target)
    before = _tree(target)
    assert main(_simulate(link, "--overwrite")) == 1
    assert "symbolic link" in _one_line_error(capsys)
    assert link.is_symlink() and _tree(target) == before


def test_a_manifest_that_lists_a_folder_as_a_file_does_not_cover_it(tmp_path, capsys):
    out = tmp_path / "sim"
    assert main(_simulate(out)) == 0
    scenes = out / "sequence_1" / "scenes.json"
    scenes.unlink()
    scenes.mkdir()
    (scenes / "mine.txt").write_text("mine")
    assert main(_simulate(out, "--overwrite")) == 1
    _one_line_error(capsys)
    assert (scenes / "mine.txt").read_text() == "mine"


def test_the_output_folder_is_checked_before_the_simulation(tmp_path, capsys, monkeypatch):
    import sklearn_radar.datasets as datasets

    def not_now(**kwargs):
        raise AssertionError("simulated before the output folder was checked")

    monkeypatch.setattr(datasets, "make_scenes", not_now)
    (tmp_path / "afile").write_text("mine")
    assert main(_simulate(tmp_path / "afile", "--overwrite")) == 1
    _one_line_error(capsys)


def test_write_radarscenes_refuses_a_foreign_folder_even_with_overwrite(tmp_path):
    out = tmp_path / "data"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    with pytest.raises(FileExistsError, match="not written by sklearn-radar"):
        write_radarscenes(make_scenes(n_sequences=1, duration=1.0, random_state=0), out, overwrite=True)
    assert _tree(out) == {"notes.txt": b"mine"}


# ----------------------------------------------------------------------------- reproduce --out


def _reproduce_argv(data, out, *options):
    return ["reproduce", "--data", str(data), "--out", str(out), "--experiments", "1", *options]


@pytest.mark.parametrize("name", ["report.md", "params.json", "run.json", "convergence.png"])
def test_reproduce_refuses_a_folder_with_a_run_file_that_no_run_wrote(small_folder, tmp_path, capsys, name):
    out = tmp_path / "thesis"
    out.mkdir()
    (out / name).write_text("my own " + name)
    (out / "notes.txt").write_text("mine")
    before = _tree(out)
    assert main(_reproduce_argv(small_folder, out)) == 1
    err = _one_line_error(capsys)
    assert name in err and str(out) in err
    assert _tree(out) == before, "nothing may be written or removed in a folder that is not a run's"


def test_reproduce_refuses_a_foreign_folder_before_making_the_data(tmp_path, capsys):
    out = tmp_path / "thesis"
    out.mkdir()
    (out / "report.md").write_text("mine")
    # No --data: the run would simulate a data set first, for seconds; the refusal comes before it.
    assert main(["reproduce", "--out", str(out), "--experiments", "1", "--n-iter", "1"]) == 1
    assert "report.md" in _one_line_error(capsys)
    assert _tree(out) == {"report.md": b"mine"}


def test_the_public_reproduce_refuses_a_foreign_folder(tmp_path):
    from sklearn_radar.reproduce import reproduce

    out = tmp_path / "thesis"
    out.mkdir()
    (out / "results.json").write_text("{}")
    with pytest.raises(FileExistsError, match=r"results\.json"):
        reproduce(None, out, experiments="1")
    assert _tree(out) == {"results.json": b"{}"}


def test_a_new_run_removes_only_what_the_previous_run_wrote(two_folder, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(_reproduce_argv(two_folder, out)) == 0
    marker = json.loads((out / "run.json").read_text())
    # A file an older version wrote, listed in the marker with its digest; and one listed but changed since.
    old, changed = out / "old_figure.png", out / "edited.txt"
    old.write_bytes(b"figure")
    changed.write_bytes(b"edited by hand")
    marker["files"][old.name] = hashlib.sha256(b"figure").hexdigest()
    marker["files"][changed.name] = hashlib.sha256(b"as written").hexdigest()
    outside = tmp_path / "precious.txt"  # a marker naming a file outside the folder: never followed
    outside.write_bytes(b"x")
    marker["files"]["../precious.txt"] = hashlib.sha256(b"x").hexdigest()
    (out / "run.json").write_text(json.dumps(marker))
    (out / "notes.txt").write_text("mine")
    assert main(_reproduce_argv(two_folder, out)) == 0
    assert not old.exists(), "a previous run's unchanged file stays"
    assert changed.read_bytes() == b"edited by hand" and (out / "notes.txt").read_text() == "mine"
    assert outside.read_bytes() == b"x"
    assert json.loads((out / "run.json").read_text())["complete"] is True


# ----------------------------------------------------------------------------- cluster --out


_SETTING = {"experiment": 8, "v1_test": 0.5, "params": {"cluster__eps_xyv": 1.0}, "stage1_params": None}


@pytest.fixture
def params_file(tmp_path):
    params = tmp_path / "params.json"
    params.write_text(json.dumps({"best": "8", "experiments": {"8": _SETTING}}))
    return params


def _cluster_argv(data, params, out):
    return ["cluster", "--data", str(data), "--params", str(params), "--out", str(out)]


def test_cluster_never_replaces_the_params_file_or_another_file(small_folder, params_file, tmp_path, capsys):
    before = params_file.read_bytes()
    assert main(_cluster_argv(small_folder, params_file, params_file)) == 1
    err = _one_line_error(capsys)
    assert str(params_file) in err and "not a predictions file" in err
    assert params_file.read_bytes() == before
    h5 = small_folder / "sequence_1" / "radar_data.h5"
    h5_before = h5.read_bytes()
    assert main(_cluster_argv(small_folder, params_file, h5)) == 1
    _one_line_error(capsys)
    assert h5.read_bytes() == h5_before
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")], "no temporary file is left"


def test_cluster_replaces_its_own_predictions_and_an_empty_file(small_folder, params_file, tmp_path, capsys):
    out = tmp_path / "predictions.json"
    out.touch()  # as mktemp leaves it: nothing to lose
    assert main(_cluster_argv(small_folder, params_file, out)) == 0
    first = out.read_bytes()
    assert main(_cluster_argv(small_folder, params_file, out)) == 0
    assert out.read_bytes() == first and json.loads(first)["schema"] == 2


def test_cluster_never_replaces_a_symbolic_link(small_folder, params_file, tmp_path, capsys):
    target = tmp_path / "target.json"
    assert main(_cluster_argv(small_folder, params_file, target)) == 0
    link = tmp_path / "link.json"
    link.symlink_to(target)
    assert main(_cluster_argv(small_folder, params_file, link)) == 1
    assert "symbolic link" in _one_line_error(capsys)
    assert link.is_symlink()


def test_write_predictions_refuses_a_foreign_file(tmp_path):
    from sklearn_radar.reproduce import write_predictions

    out = tmp_path / "notes.json"
    out.write_text('{"mine": 1}')
    with pytest.raises(FileExistsError, match="not a predictions file"):
        write_predictions(["a"], [0], out)
    assert out.read_text() == '{"mine": 1}'
    write_predictions(["a"], [0], tmp_path / "p.json")
    write_predictions(["b"], [-1], tmp_path / "p.json")  # its own file: replaced
    assert list(json.loads((tmp_path / "p.json").read_text())["predictions"]) == ["b"]


def test_a_file_appearing_during_the_write_is_kept(tmp_path):
    from sklearn_radar._files import atomic_write
    from sklearn_radar.cli._cluster import check_predictions_file

    out = tmp_path / "p.json"

    def write(stream):
        stream.write(b"predictions")
        out.write_text("someone else's")  # created while the predictions were being written

    with pytest.raises(FileExistsError):
        atomic_write(out, write, replaceable=check_predictions_file)
    assert out.read_text() == "someone else's"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.json"]


# ----------------------------------------------------------------------------- params.json: stage1_params


@pytest.mark.parametrize(
    "setting, problem",
    [
        ({"experiment": 12, "params": {}, "stage1_params": None}, "null"),
        ({"experiment": 13, "params": {}}, "lacks it"),
        ({"experiment": 8, "params": {}, "stage1_params": {"cluster__eps_xyv": 1.0}}, "must be null"),
    ],
    ids=["stage 2 null", "stage 2 missing", "stage 1 given"],
)
def test_stage1_params_must_match_the_experiments_stage(small_folder, tmp_path, capsys, setting, problem):
    params = tmp_path / "params.json"
    key = str(setting["experiment"])
    params.write_text(json.dumps({"best": key, "experiments": {key: setting}}))
    out = tmp_path / "p.json"
    assert main(_cluster_argv(small_folder, params, out)) == 1
    err = _one_line_error(capsys)
    assert str(params) in err and "'stage1_params'" in err and problem in err
    assert not out.exists()


def test_load_params_refuses_null_stage1_params_of_a_stage2_experiment(tmp_path):
    from sklearn_radar.reproduce import load_params

    params = tmp_path / "params.json"
    params.write_text(
        json.dumps({"best": "12", "experiments": {"12": {"experiment": 12, "params": {}, "stage1_params": None}}})
    )
    with pytest.raises(ValueError, match="stage1_params"):
        load_params(params)


def test_cluster_prints_the_setting_it_applied(small_folder, tmp_path, capsys):
    stage1 = {k: v for k, v in paper_params(8).items() if k != "cluster__eps_t"}
    setting = {"experiment": 12, "params": {"merge__eps_d": 1.5}, "stage1_params": stage1}
    params = tmp_path / "params.json"
    params.write_text(json.dumps({"best": "12", "experiments": {"12": setting}}))
    assert main(_cluster_argv(small_folder, params, tmp_path / "p.json")) == 0
    printed = capsys.readouterr().out.splitlines()
    assert printed[0].startswith("applied experiment #12 of") and "merge__eps_d=1.5" in printed[0]
    stage1_line = next(line for line in printed if line.startswith("  with stage 1:"))  # after why it was chosen
    assert "cluster__eps_xyv=1.04" in stage1_line
