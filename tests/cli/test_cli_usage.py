"""The command line's usage (issue 46): help texts, usage errors, ``--out`` apart from ``--data``, what a run wrote."""

import json
import re
from pathlib import Path

import pytest

from sklearn_radar.cli._main import _parser, main

ROOT = Path(__file__).resolve().parents[2]


def _help(capsys, *argv):
    with pytest.raises(SystemExit) as exit_:
        main([*argv, "--help"])
    assert exit_.value.code == 0
    return capsys.readouterr().out


def _option_help(text, flag):
    """The help of ``flag`` in a ``--help`` text, its lines joined (argparse wraps them)."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if re.match(rf"  {re.escape(flag)}\b", line))
    block = [lines[start]]
    for line in lines[start + 1 :]:
        if not line.startswith(" " * 6) or re.match(r"  -", line):
            break
        block.append(line)
    return " ".join(" ".join(block).split())


# ----------------------------------------------------------------------------- help texts


def test_reproduce_help_lists_every_step_of_experiments(capsys):
    from sklearn_radar.reproduce._constants import ALL_EXPERIMENTS, NUMBERS

    listed = _option_help(_help(capsys, "reproduce"), "--experiments")
    for key in ALL_EXPERIMENTS:
        if key.isdigit():
            continue
        assert re.search(rf"(^|[ :,]){re.escape(key)}([ ,(]|$)", listed), f"{key} missing from: {listed}"
    assert f"{min(NUMBERS)}-{max(NUMBERS)}" in listed


def test_reproduce_help_says_when_to_use_n_jobs_workers_and_n_points(capsys):
    text = _help(capsys, "reproduce")
    n_jobs, workers, n_points = (_option_help(text, flag) for flag in ("--n-jobs", "--workers", "--n-points"))
    assert "one machine" in n_jobs and "results do not depend on it" in n_jobs
    assert "larger than the default run" in workers
    assert "guided search step" in n_points and "changes the search" in n_points
    epilog = " ".join(text.split("\n\n")[-1].split())
    assert epilog.startswith("Parallel work:")
    assert all(flag in epilog for flag in ("--n-jobs", "--workers", "--scheduler", "--n-points"))


def test_the_user_guides_synopsis_lists_every_option_of_every_command():
    text = (ROOT / "docs" / "user_guide" / "command_line.rst").read_text(encoding="utf-8")
    block = text.split("Synopsis\n========\n", 1)[1].split("\n\n", 2)[1]
    synopsis, command = {}, None
    for line in block.splitlines():
        words = line.split()
        if words[:1] == ["sklearn-radar"]:
            command = words[1]
        synopsis[command] = synopsis.get(command, "") + " " + line
    parser = _parser()
    commands = next(a for a in parser._actions if a.dest == "command").choices
    assert set(synopsis) == set(commands)
    for name, command_parser in commands.items():
        for action in command_parser._actions:
            for flag in action.option_strings:
                if flag not in ("-h", "--help"):
                    assert re.search(rf"{re.escape(flag)}\b", synopsis[name]), f"{name} {flag} not in the synopsis"


# ----------------------------------------------------------------------------- usage errors exit 2


def test_an_unknown_option_prints_the_commands_usage_and_exits_2(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["reproduce", "--bogus"])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: sklearn-radar reproduce ") and "unrecognized arguments: --bogus" in err


def test_a_bare_command_line_prints_the_usage_and_exits_2(capsys):
    assert main([]) == 2
    captured = capsys.readouterr()
    assert captured.err.startswith("usage: sklearn-radar ") and "reproduce" in captured.err and captured.out == ""


@pytest.mark.parametrize(
    "argv, flag",
    [
        (["reproduce", "--experiments", "1,99"], "--experiments"),
        (["reproduce", "--seed", str(2**32 - 1), "--repeats", "2"], "--seed"),
        (["cluster", "--data", "nowhere", "--out", "out.json"], "--params"),
        (
            ["cluster", "--data", "nowhere", "--classifier", "c.joblib", "--out", "o.json", "--experiment", "8"],
            "--params",
        ),
        (["stream", "--data", "nowhere", "--params", "p.json", "--out", "o.json", "--objects", "o.json"], "--objects"),
        (["simulate", "--out", "x", "--duration", "0"], "--duration"),
    ],
)
def test_options_that_do_not_go_together_are_usage_errors_exit_2(tmp_path, capsys, monkeypatch, argv, flag):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("sklearn-radar: error:") and len(err.strip().splitlines()) == 1 and flag in err, err
    assert list(tmp_path.iterdir()) == []


def test_errors_of_the_work_itself_still_exit_1(tmp_path, capsys):
    assert main(["stats", "--data", str(tmp_path / "nowhere")]) == 1


# ----------------------------------------------------------------------------- reproduce --out apart from --data


def _tree(root):
    return {p.relative_to(root).as_posix(): None if p.is_dir() else p.read_bytes() for p in sorted(root.rglob("*"))}


@pytest.mark.parametrize(
    "out, where",
    [(".", "is the"), ("report", "is inside the"), ("deeper/report", "is inside the"), ("..", "holds the")],
)
def test_reproduce_refuses_an_out_that_is_inside_or_holds_the_data(tiny_folder, tmp_path, capsys, out, where):
    data = tmp_path / "sim"
    data.symlink_to(tiny_folder, target_is_directory=True)  # the folder under another name: compared resolved
    before = _tree(tiny_folder)
    target = data / out
    assert main(["reproduce", "--data", str(data), "--out", str(target), "--experiments", "1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("sklearn-radar: error:") and len(err.strip().splitlines()) == 1, err
    assert "--out" in err and "--data" in err and f"{where} --data folder" in err
    assert _tree(tiny_folder) == before and not (tmp_path / "deeper").exists()


def test_check_apart_accepts_a_sibling_whose_name_starts_with_the_datas(tmp_path):
    from sklearn_radar.reproduce._io import check_apart

    check_apart(tmp_path / "sim", tmp_path / "sim2")
    check_apart(tmp_path / "sim", tmp_path / "report")
    with pytest.raises(ValueError, match=r"out .* is inside the data folder"):
        check_apart(tmp_path / "sim", tmp_path / "sim" / ".." / "sim" / "report")


def test_the_public_reproduce_refuses_an_out_inside_the_data(tiny_folder):
    from sklearn_radar.reproduce import reproduce

    with pytest.raises(ValueError, match=r"out .* is inside the data folder"):
        reproduce(tiny_folder, tiny_folder / "report", experiments="1")
    assert not (tiny_folder / "report").exists()


# ----------------------------------------------------------------------------- a filter-only run


@pytest.fixture(scope="module")
def filter_run(tiny_folder, tmp_path_factory):
    import contextlib
    import io

    out = tmp_path_factory.mktemp("filter") / "out"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        code = main(["reproduce", "--data", str(tiny_folder), "--out", str(out), "--experiments", "filter"])
    assert code == 0
    return out, printed.getvalue().splitlines()


def test_a_filter_only_run_says_only_the_files_it_wrote(filter_run):
    out, lines = filter_run
    assert not (out / "params.json").exists()
    written = json.loads((out / "run.json").read_text())["files"]
    figures = [name for name in written if name.endswith(".png")]
    assert figures and "params.json" not in lines[-1]
    assert lines[-1].startswith(f"wrote {out}: report.md, results.json and {len(figures)} figure")
    assert all((out / name).is_file() for name in written)


def test_a_filter_only_run_is_one_step_and_ends_at_100_percent(filter_run):
    _, lines = filter_run
    assert any(line.startswith("the run's work: 1 step, 0 search iterations in all;") for line in lines), lines
    complete = next(line for line in lines if line.startswith("run complete;"))
    assert re.search(r"\| run 100 %, \d+:\d\d elapsed$", complete), complete
