"""The reproduce run's tracking step: the settings streamed online, their ids' IDF1 / ID switches / MOTA."""

import contextlib
import io
import json

import numpy as np
import pytest

from sklearn_radar.cli import main
from sklearn_radar.datasets import load_radarscenes
from sklearn_radar.experiments import experiment_pipeline
from sklearn_radar.metrics import tracking_scores
from sklearn_radar.online import OnlinePipeline
from sklearn_radar.online._replay import replay
from sklearn_radar.reproduce._results import RunResults


@pytest.fixture(scope="module")
def tracked(tiny_folder, tmp_path_factory):
    """A run of #1, #13 and the tracking step: #1 and #13 stream the run's settings, #8 and #12 the paper's."""
    out = tmp_path_factory.mktemp("tracking") / "out"
    with contextlib.redirect_stdout(io.StringIO()):
        code = main(
            [
                "reproduce",
                "--data",
                str(tiny_folder),
                "--out",
                str(out),
                "--n-iter",
                "2",
                "--experiments",
                "1,13,tracking",
            ]
        )
    assert code == 0
    return out


def test_the_step_streams_every_tracked_setting(tracked):
    results = json.loads((tracked / "results.json").read_text())
    assert results["meta"]["completed"] == ["1", "13", "tracking"]
    tracking = results["tracking"]
    assert list(tracking) == ["1", "8", "12", "13"]
    sources = {key: entry["setting_source"] for key, entry in tracking.items()}
    assert sources == {"1": "fixed #1", "8": "paper's #8", "12": "paper's #12", "13": "tuned #13"}
    for entry in tracking.values():
        for scores in (entry["reported"], entry["final"]):
            assert 0.0 <= scores["idf1"] <= 1.0 and scores["mota"] <= 1.0
            assert scores["n_matches"] + scores["misses"] == scores["n_objects"] > 0
    assert tracking["13"]["params"] == {
        **results["experiments"]["13"]["stage1_params"],
        **results["experiments"]["13"]["params"],
    }


def test_the_scores_are_those_of_the_whole_test_half(tracked, tiny_folder):
    """Summed per sequence = tracking_scores over all test sequences at once (tracks never cross sequences)."""
    results = RunResults.read(tracked / "results.json")
    test = results.meta.data.test_sequences
    scenes = load_radarscenes(tiny_folder)
    entry = results.tracking[1]
    pipeline = experiment_pipeline(1, params=entry.params)
    ids, rows = [], []
    for number in test:
        part = np.flatnonzero(scenes.data["sequence"].to_numpy() == number)
        ids.append(replay(OnlinePipeline(pipeline), scenes.data.iloc[part])["object_ids"])
        rows.append(part)
    rows = np.concatenate(rows)
    expected = tracking_scores(
        np.asarray(scenes.target)[rows],
        np.concatenate(ids),
        times=scenes.data["timestamp"].to_numpy()[rows] * 1e-6,
        groups=scenes.data["sequence"].to_numpy()[rows],
        window=0.5,
    )
    final = entry.final
    assert (final.idf1, final.mota, final.id_switches, final.n_objects) == pytest.approx(
        (expected["idf1"], expected["mota"], expected["id_switches"], expected["n_objects"]), abs=1e-12
    )


def test_the_report_has_the_tracking_section(tracked):
    report = (tracked / "report.md").read_text()
    assert "## Beyond the paper: object tracking online" in report
    section = report.split("## Beyond the paper: object tracking online")[1]
    assert "| #13 " in section and "(tuned #13)" in section and "(paper's #8)" in section


def test_the_tracking_table_names_what_its_count_of_objects_counts(tracked):
    """The MOTA denominator, objects summed over frames: not the data section's object instances, and said so."""
    results = RunResults.read(tracked / "results.json")
    report = (tracked / "report.md").read_text()
    section = report.split("## Beyond the paper: object tracking online")[1].split("\n## ")[0]
    header = next(line for line in section.splitlines() if line.startswith("| setting |"))
    columns = [cell.strip() for cell in header.strip("|").split("|")]
    assert "objects" not in columns and "object-windows" in columns
    assert "*object-windows* counts each annotated moving road user once in every 0.5 s window it is seen in" in section
    for number, result in results.tracking.items():
        row = next(line for line in section.splitlines() if line.startswith(f"| #{number} "))
        cells = [cell.strip() for cell in row.strip("|").split("|")]
        assert cells[columns.index("object-windows")] == str(result.final.n_objects)


def test_results_without_tracking_still_load():
    """Older results files have no 'tracking' key: it reads as None and the section is left out."""
    from pathlib import Path

    from sklearn_radar.reproduce._sections import _tracking

    for path in sorted((Path(__file__).parents[1] / "data").glob("results_*.json")):
        results = RunResults.read(path)
        assert results.tracking is None
        assert _tracking.markdown(results) == []
